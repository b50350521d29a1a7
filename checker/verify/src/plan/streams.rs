//! The streams' assumption, checked: a stream's invariant admits some reading (E0410).

use super::Contexts;
use crate::hir::expr::and_all;
use crate::hir::*;
use crate::obligation::{Enabled, Goal, Obligation, Rule};
use crate::sigma::Sigma;

impl<'a> Contexts<'a> {
    /// The streams' assumption, checked: every reading of a stream satisfies its fields'
    /// refinements (wire range, enum, the invariant), so some message of the stream must
    /// exist. An invariant no value of the field's type satisfies would make every step that
    /// reads the stream hold vacuously (a protocol whose first step can never be taken would
    /// verify with a warning): it is E0410 at the stream, as an `init` no state satisfies is.
    /// One query per stream: a stream's refinements read its own template values and
    /// constants only (E0211), so streams are independent of each other and of Σ.
    ///
    /// A `float` field's values are float32s, not reals (LANGUAGE.md, MAVLink messages): an
    /// invariant such as `0.1 < roll && roll < 0.1000000001` has real solutions and no
    /// float32 one. A stream with a float field is asked as "some reading exists" with the
    /// template values chosen ([`float_witness`]), where the SMT encoding decides a chosen
    /// float's format exactly; the others keep the satisfiability question.
    pub(super) fn streams(&mut self) {
        for s in &self.prog.streams {
            let facts: Vec<Expr> = s.fields.iter().filter_map(|f| f.refinement.clone()).collect();
            if facts.is_empty() {
                continue;
            }
            let to: Vec<&str> = s.to.iter().map(|&r| self.prog.role_name(r)).collect();
            let what = format!(
                "the invariant of the stream `{} -> {}: {}`",
                self.prog.role_name(s.from),
                to.join(", "),
                s.label
            );
            match float_witness(self.prog, &facts, s.loc, &what) {
                Some(ob) => self.obligations.push(ob),
                None => self.reachable(s.loc.0, what, &Sigma::from_facts(&facts), Vec::new(), false),
            }
        }
    }
}

/// When `facts` read a `float`/`double` value ([`Program::wire_floats`]): the question "some
/// values satisfy `facts`" with every value they read chosen (`∃ values. facts`), so that a
/// chosen float is encoded as a value of its format, exactly (the satisfiability question
/// assumes a float's format as `true`, a weaker fact, and so asks over the reals). Asked as
/// a progress goal with no hypotheses, under the rule of the satisfiability question it
/// replaces (E0410): it holds exactly when some values of the fields' types satisfy
/// `facts`. A participant's variable `facts` read (a MAVLink protocol has none) stays free,
/// universally quantified: a stronger question, so a pass is still sound. `None` when
/// `facts` read no float.
pub(super) fn float_witness(prog: &Program, facts: &[Expr], loc: Loc, what: &str) -> Option<Obligation> {
    let mut ids: Vec<ValueId> = Vec::new();
    for f in facts {
        f.visit_vars(&mut |v, _| {
            if let Var::Value(id, _) = v {
                if !ids.contains(id) {
                    ids.push(*id);
                }
            }
        });
    }
    if !ids.iter().any(|id| prog.wire_floats.contains_key(id)) {
        return None;
    }
    let fields = ids
        .iter()
        .map(|id| {
            let v = prog.value(*id);
            (*id, v.name.clone(), v.sort.clone())
        })
        .collect();
    let refinement = and_all(facts.iter().map(|f| crate::hir::expr::defined_and(f.clone())), loc);
    Some(Obligation {
        rule: Rule::Reachable,
        span: loc.0,
        what: what.to_string(),
        hyps: Vec::new(),
        goal: Goal::Progress { branches: vec![Enabled { what: what.to_string(), guard: None, fields, refinement }] },
    })
}
