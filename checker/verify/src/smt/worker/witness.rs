//! The witnesses a worker asks Z3 for beside a part's own query: the part's query again
//! with chosen values pinned (a MAVLink float rounded to its format, a candidate of the
//! interval search), each model replayed before it is shown. They only ever add a
//! counterexample: no model is no witness, never a pass.

use super::*;

impl Worker<'_> {
    /// The query of `part` again, with every MAVLink float value the model `exact` gives
    /// a value pinned to that value rounded to its field's format (`lower::round_to_float`,
    /// to nearest): a model of it is a counterexample whose floats are floats, for
    /// [`replay`] to confirm. `None` when no float value was pinned or no model came.
    pub(super) fn float_witness(
        &self,
        ob: &Obligation,
        part: &Part,
        exact: &replay::Valuation,
        stats: &mut Stats,
    ) -> Option<Answer> {
        let q = goals::build(self.prog, ob, part).ok()?;
        let mut pins = Vec::new();
        for (id, symbol) in q.enc.value_symbols() {
            let Some(format) = self.prog.wire_floats.get(id).and_then(|f| crate::lower::float_format(*f)) else {
                continue;
            };
            let Some(crate::exact::Value::Num(n)) = exact.get(symbol) else { continue };
            let Some(v) = n.value() else { continue };
            let Some(r) = crate::lower::round_to_float(v, format) else { continue };
            let Some((_, encode::Term::R(t))) = q.enc.terms().find(|(name, _)| *name == symbol) else { continue };
            pins.push(t.eq(encode::real_of_rational(&r)?));
        }
        if pins.is_empty() {
            return None;
        }
        stats.queries += 1;
        let m = self.model_with(&q, &pins)?;
        if q.enc.spurious_trig(&m) {
            return None;
        }
        let overlap = q.point.as_ref().map(|p| {
            Overlap::at(
                [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
                q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
            )
        });
        Some(Answer::Sat {
            values: q.enc.assignments(&m),
            overlap,
            bound: q.enc.shared_names(),
            exact: replay::valuation(&q.enc, &m),
        })
    }

    /// A model of the part's query `q` with `extra` asserted beside it, within the time
    /// limit; `None` when Z3 gives none (unsat, unknown or out of time): the witnesses
    /// above only ever add a counterexample, so no model means no witness, never a pass.
    pub(super) fn model_with(&self, q: &Query, extra: &[z3::ast::Bool]) -> Option<z3::Model> {
        let solver = solver_for(q);
        for a in q.assertions.iter().chain(q.enc.side_conditions()).chain(extra) {
            solver.assert(a);
        }
        let seq = self.watchdog.arm(self.timeout);
        let result = solver.check();
        self.watchdog.disarm(seq);
        match result {
            z3::SatResult::Sat => solver.get_model(),
            _ => None,
        }
    }

    /// The part's query with each of `pins` (a variable of the query by name, and a
    /// value) pinned: a model of it, replayed exactly against the part's goal, is a
    /// counterexample at those values (`collision::predicate`'s candidates). `None` when
    /// a name is not in the query, Z3 gives no model, or the model does not replay.
    pub(super) fn pinned_witness(
        &self,
        ob: &Obligation,
        part: &Part,
        pins: &crate::collision::predicate::Pins,
    ) -> Option<Answer> {
        let q = goals::build(self.prog, ob, part).ok()?;
        let mut eqs = Vec::new();
        for (name, v) in pins {
            let Some((_, encode::Term::R(t))) = q.enc.terms().find(|(n, _)| *n == name) else { return None };
            // The shortest decimal that reads back as the double: what the report shows.
            let value = crate::bounds::decimal(&format!("{v}")).and_then(|r| encode::real_of_rational(&r));
            eqs.push(t.eq(value.or_else(|| encode::real_of_f64(*v))?));
        }
        let m = self.model_with(&q, &eqs)?;
        let exact = replay::valuation(&q.enc, &m);
        if !matches!(replay::replay(self.prog, ob, part, &exact), replay::Replay::Falsifies) {
            return None;
        }
        let overlap = q.point.as_ref().map(|p| {
            Overlap::at(
                [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
                q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
            )
        });
        Some(Answer::Sat { values: q.enc.assignments(&m), overlap, bound: q.enc.shared_names(), exact })
    }
}
