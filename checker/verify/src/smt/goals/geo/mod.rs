//! What the geometric search ([`crate::geometry::search`]) asks Z3: whether some
//! configuration of a collision question's motions, within a box of its dimensions,
//! satisfies every constraint exactly (the context sliced as for [AGCOMP], each run started
//! and running). The search itself does not use the solver; it calls these three functions
//! for a contact's witness, a counterexample's values, and the confirmation that a search
//! which cut every box away was not misled by an enclosure.

use super::motion::Inst;
use super::query::{hyps, seeds_of, slice};
use super::Query;
use crate::collision::{Dim, Run};
use crate::diag::Assignment;
use crate::hir::{Expr, Program};
use crate::smt::encode::{real_of_f64, Encoder};
use z3::ast::{Bool, Real};

/// A collision question's configurations: its context, its runs and the dimensions of its
/// boxes.
pub(crate) struct Configs<'a> {
    pub prog: &'a Program,
    /// The obligation's hypotheses (the context).
    pub hyps: &'a [Expr],
    pub runs: &'a [Run],
    pub dims: &'a [Dim],
    /// [T-SESS]: the state is the start state (no run is started).
    pub initial: bool,
}

/// Whether a box holds a configuration that satisfies every constraint.
pub(crate) enum Exists {
    /// No configuration does (Z3 answered unsat).
    No,
    /// One does, with its values.
    Yes(Vec<Assignment>),
    /// Z3 could not tell, with its reason.
    Unknown(String),
    /// The constraints could not be put to Z3.
    NotPosed,
}

/// The Z3 query of the constraints: the context, each run started and running, and the
/// dimensions within `[lo, hi]`. Returns it with the terms of the dimensions.
fn constraints<'a>(c: &Configs<'a>, lo: &[f64], hi: &[f64]) -> Option<(Query<'a>, Vec<Real>)> {
    let prog = c.prog;
    let mut q = Query { enc: Encoder::new(prog), assertions: Vec::new(), point: None, times: Vec::new() };
    let mut terms: Vec<Option<Real>> = vec![None; c.dims.len()];
    if c.initial {
        hyps(&mut q, c.hyps).ok()?;
        for (i, d) in c.dims.iter().enumerate() {
            if let Dim::Now(r, slot) = d {
                let t = q.enc.role_var(*r, *slot).ok()?;
                terms[i] = Some(crate::smt::encode::as_real(t).ok()?);
            }
        }
    } else {
        let mut insts = Vec::new();
        let two = c.runs.iter().any(|r| r.clock == 1);
        let clocks: Vec<Real> = (0..c.runs.iter().map(|r| r.clock + 1).max().unwrap_or(1))
            .map(|k| q.enc.named_real(if two { ["time 1", "time 2"][k.min(1)] } else { "time" }))
            .collect();
        for r in c.runs {
            let seeds = seeds_of(prog, &[(r.role, r.app.clone())]);
            hyps(&mut q, &slice(prog, &r.hyps, seeds)).ok()?;
        }
        for r in c.runs {
            let tag = if clocks.len() > 1 { ["t1", "t2"][r.clock.min(1)] } else { "t" };
            insts.push(Inst::new(&mut q.enc, r.role, &r.app, clocks[r.clock].clone(), tag).ok()?);
        }
        if clocks.len() == 1 {
            super::agcomp::connect(&mut q, &mut insts);
        }
        for inst in &insts {
            inst.started(&mut q).ok()?;
            inst.running(&mut q).ok()?;
        }
        for (i, d) in c.dims.iter().enumerate() {
            match d {
                Dim::Clock(k) => terms[i] = clocks.get(*k).cloned(),
                Dim::Now(r, slot) => {
                    // A carrier that runs nothing here is not in the query: no witness.
                    let inst = insts.iter().find(|x| x.role == *r)?;
                    terms[i] = Some(crate::smt::encode::as_real(inst.frame.own.get(slot)?.clone()).ok()?);
                }
            }
        }
    }
    let terms: Vec<Real> = terms.into_iter().collect::<Option<_>>()?;
    for (i, t) in terms.iter().enumerate() {
        let (l, h) = (real_of_f64(lo[i])?, real_of_f64(hi[i])?);
        q.assertions.push(Bool::and(&[t.ge(&l), t.le(&h)]));
    }
    Some((q, terms))
}

/// Whether some configuration in `[lo, hi]` satisfies every constraint exactly.
pub(crate) fn exists(c: &Configs<'_>, lo: &[f64], hi: &[f64]) -> Exists {
    let Some((query, _)) = constraints(c, lo, hi) else { return Exists::NotPosed };
    let solver = crate::smt::solver_for(&query);
    for a in query.assertions.iter().chain(query.enc.side_conditions()) {
        solver.assert(a);
    }
    match solver.check() {
        z3::SatResult::Unsat => Exists::No,
        z3::SatResult::Sat => Exists::Yes(solver.get_model().map(|m| query.enc.assignments(&m)).unwrap_or_default()),
        z3::SatResult::Unknown => {
            Exists::Unknown(solver.get_reason_unknown().unwrap_or_else(|| "no reason given".into()))
        }
    }
}

/// A counterexample's values at the configuration `q` (a model of the constraints with the
/// dimensions pinned to `q`).
pub(crate) fn assignments(c: &Configs<'_>, q: &[f64]) -> Option<Vec<Assignment>> {
    match exists(c, q, q) {
        Exists::Yes(values) => Some(values),
        _ => None,
    }
}

/// A configuration in `[lo, hi]` that satisfies every constraint (the dimensions' values of
/// a Z3 model), if Z3 finds one whose `sin`/`cos` values the real functions take.
pub(crate) fn witness(c: &Configs<'_>, lo: &[f64], hi: &[f64]) -> Option<Vec<f64>> {
    let (query, terms) = constraints(c, lo, hi)?;
    let solver = crate::smt::solver_for(&query);
    for a in query.assertions.iter().chain(query.enc.side_conditions()) {
        solver.assert(a);
    }
    match solver.check() {
        z3::SatResult::Sat => {
            let m = solver.get_model()?;
            if query.enc.spurious_trig(&m) {
                return None;
            }
            terms.iter().map(|t| Encoder::value_of(&m, t)).collect()
        }
        _ => None,
    }
}
