//! `mochi simulate`: an independent check of verdicts by running the choreography.
//!
//! The simulator takes the program as the checks see it ([`crate::driver::prepare`]:
//! parsed, lowered, through the geometry stage) and runs it on concrete states (exact
//! rationals, [`crate::exact`]; enclosures where a value is irrational, such as `pi / 2`):
//!
//! - [`run`]: the global type as Def 4.11 consumes it. **Messages** happen in tree order,
//!   each as soon as its sender and receiver are free (a schedule consistent with
//!   happens-before); the guard is evaluated exactly and the payload is a model of the
//!   refinements (Z3, through [`crate::smt`]), replayed exactly; **choices** pick at
//!   random among the branches whose first guard holds; **recursion** is unrolled with
//!   its parameters until the step budget is spent.
//! - [`motion`]: **a joint motion** `dt<p_i: a_i>` checks each precondition ([TRAJ-BASE]),
//!   then asks Z3 for a witness trajectory: an end time in every duration, states at a
//!   few random times satisfying every guarantee, assumption (inputs connected) and
//!   invariant, and every postcondition at the end ([TRAJ-STEP], [NON-INTERRUPT],
//!   [INTERRUPT], [M-PAR]). None means the motion cannot run to its end: stuck. The
//!   witness is replayed exactly.
//! - [`par`]: **sides of `*`** run from the same time; each participant keeps its own
//!   clock, so their motions overlap in time as they would; motions of different sides
//!   are compared at times where both run.
//! - [`space`]: **collisions** at each sampled time: footprints with a predicate share a
//!   point (Z3 at the concrete states, replayed exactly); footprints and obstacles that
//!   are solids (meshes, URDF links, shapes, mounted on carriers) are placed at the
//!   concrete poses and their parry distance is at most 0. A robot's body must lie in its
//!   footprint (a mesh footprint read as the region its triangles bound, hollows outside).
//! - [`bodies`]: the **real bodies** (shapes, meshes, URDF links at the sampled joint
//!   values, mounted on their carriers) against every obstacle and every other body, those
//!   of the participants that wait included, at their last state.
//! - [`session`]: protocols without motion (MAVLink sessions) run as each participant's
//!   projection, with only what that participant knows: a read of a value it does not
//!   have is a finding.
//! - [`lockstep`]: in choreographies with motion, each participant's `process` runs in
//!   lockstep with the global type's run: its process decides the branch it chooses, the
//!   payload it sends and the primitive it moves with (refinement, Def 3.4, checked on the
//!   run); a process that does something else than its type is a violation. Both runners
//!   step processes through [`process`].
//!
//! This is testing, not proof: it samples a few trajectories at a few times. A finding
//! in a choreography mochi verified is a bug in mochi (or in the contracts' reading);
//! no finding proves nothing. Participants that have finished a motion and wait for
//! their next event have no footprint then: their bodies, at their last state, are
//! compared with the bodies that move (outside `*`).

mod bodies;
mod lockstep;
mod motion;
mod par;
mod process;
mod report;
mod run;
mod session;
mod space;

pub use report::{Finding, Kind, SimMessage, SimReport};

use crate::exact::{self, Num, Rat, Tri, Value};
use crate::hir::expr::map_vars;
use crate::hir::{Builtin, Expr, ExprKind, Global, Loc, Msg, Program, RoleId, Sort, Var};
use crate::smt::goals::witness;
use num_bigint::BigInt;
use num_traits::ToPrimitive;
use std::time::Duration;

/// How to simulate.
#[derive(Clone, Debug)]
pub struct SimConfig {
    pub runs: usize,
    pub seed: u64,
    /// Messages and motions per run (recursion is unrolled until they are spent).
    pub steps: usize,
    /// Times sampled in each motion (the end included).
    pub samples: usize,
    /// Per Z3 query.
    pub timeout: Duration,
}

impl Default for SimConfig {
    fn default() -> SimConfig {
        SimConfig { runs: 10, seed: 0, steps: 40, samples: 3, timeout: Duration::from_secs(10) }
    }
}

/// `report` with one undecided finding saying why the program is not run: a refusal is
/// never a clean run.
fn refused(mut report: SimReport, message: String) -> SimReport {
    report.findings.push(report::Finding {
        kind: report::Kind::Undecided,
        run: 0,
        step: 0,
        time: "0".to_string(),
        message,
        trace: Vec::new(),
    });
    report
}

/// Simulates `prog`'s choreography `cfg.runs` times. `prog` is the program after the
/// geometry stage ([`crate::driver::prepare`]); without it, bodies that are solids are
/// not known and a comparison that needs them is undecided.
pub fn simulate(prog: &Program, cfg: &SimConfig) -> SimReport {
    let mut report = SimReport { runs: cfg.runs, ..SimReport::default() };
    let Some(chor) = &prog.choreography else { return report };
    let sessions = session::applies(&chor.body);
    // Streams (observed state) are drawn by the runner of protocols without motion
    // (`session`: a fresh reading at each send that reads one); a choreography with motion
    // that declares streams is refused as undecided, never a clean run.
    if let Some(s) = prog.streams.first().filter(|_| !sessions) {
        return refused(report, format!(
            "not supported yet: a choreography with motion declares streams (`stream {} -> ...: {}`), whose observed values the simulator draws only in protocols without motion; `mochi check` checks the protocol over fresh readings",
            prog.role_name(s.from),
            s.label
        ));
    }
    // Timeout branches are not simulated yet: a run would need a clock for the waiting
    // role. Refused as undecided, never a clean run.
    if let Some(a) = crate::typeck::first_timeout(&chor.body) {
        return refused(report, format!(
            "not supported yet: a choice has a timeout branch (`after {} ms by {}`), which the simulator does not run; `mochi check` checks the protocol",
            a.ms,
            prog.role_name(a.by)
        ));
    }
    witness::session(cfg.timeout, |sess| {
        for run in 0..cfg.runs {
            let mut r = run::Runner::new(prog, sess, cfg, run);
            if sessions {
                r.sessions();
            } else {
                r.go(&chor.body);
            }
            report.steps += r.steps;
            report.findings.extend(r.findings);
            report.messages.push(r.messages);
        }
        report.queries = sess.queries.get();
    });
    report
}

/// Resolves the file `root` already in `db` (its imports, URDFs and meshes read through
/// `load`) with the driver's stages up to geometry, and simulates it. `Err` holds the
/// errors that stopped it before a program existed. (`fsload::simulate_file` reads a file
/// from disk.)
pub fn simulate_loaded(
    db: &mut crate::source::SourceDb,
    root: crate::source::FileId,
    cfg: &SimConfig,
    load: &mut crate::syntax::ByteLoader<'_>,
) -> Result<SimReport, Vec<crate::diag::Diagnostic>> {
    let prog = crate::driver::prepare(db, root, load, crate::driver::Stage::Geometry)?;
    Ok(simulate(&prog, cfg))
}

/// The simulator's draws (`mochi_core::splitmix`): runs are reproducible from the seed.
struct Rng(mochi_core::splitmix::SplitMix64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    fn below(&mut self, n: usize) -> usize {
        self.0.below(n as u64) as usize
    }
    /// A rational in (0, 1) with denominator 1000.
    fn fraction(&mut self) -> Rat {
        Rat::new(BigInt::from(1 + self.next() % 999), BigInt::from(1000))
    }
}

/// The first message of a branch of a choice.
fn first_message(g: &Global) -> Option<&Msg> {
    match g {
        Global::Msg(m) => Some(m),
        Global::Seq(items, _) => items.first().and_then(first_message),
        _ => None,
    }
}

fn var_expr(v: Var, sort: Sort) -> Expr {
    Expr { kind: ExprKind::Var(v), sort, loc: Loc::default() }
}

/// `Var::Own(slot)` as participant `r`'s variable (for the kind's invariant at `init`).
fn own_to_role(e: &Expr, r: RoleId) -> Expr {
    map_vars(e, &mut |v, sort| match v {
        Var::Own(slot) => {
            Some(Expr { kind: ExprKind::Var(Var::Role(r, *slot)), sort: sort.clone(), loc: Loc::default() })
        }
        _ => None,
    })
}

/// A value as a closed expression of `sort`; `None` for an enclosure (not exact).
fn value_expr(v: &Value, sort: &Sort, loc: Loc) -> Option<Expr> {
    let num = |n: &Num| n.value().map(|r| exact::literal(r, loc));
    Some(match v {
        Value::Bool(Tri::True) => Expr::bool(true, loc),
        Value::Bool(Tri::False) => Expr::bool(false, loc),
        Value::Bool(Tri::Unknown) => return None,
        Value::Num(n) => {
            let r = n.value()?;
            if *sort == Sort::Int && r.is_integer() {
                Expr { kind: ExprKind::Int(r.numer().to_i64()?), sort: Sort::Int, loc }
            } else {
                num(n)?
            }
        }
        Value::Vec3(c) => {
            let f = if *sort == Sort::Vector { Builtin::Vector } else { Builtin::Point };
            let args = vec![num(&c[0])?, num(&c[1])?, num(&c[2])?];
            Expr {
                kind: ExprKind::Call(f, args),
                sort: if *sort == Sort::Vector { Sort::Vector } else { Sort::Point },
                loc,
            }
        }
    })
}

/// `v` as the wire carries the field `id`: a value of a MAVLink `float` (`double`) field
/// rounded to the nearest float32 (float64), exactly; every other value as it is. The
/// second part says whether rounding changed it. Z3 draws payloads over the reals; the
/// checks model floats as finite float32 (LANGUAGE.md), so a drawn value is sent rounded.
pub(super) fn on_wire(prog: &Program, id: crate::hir::ValueId, v: Value) -> (Value, bool) {
    let Some(format) = prog.wire_floats.get(&id).and_then(|b| crate::lower::float_format(*b)) else {
        return (v, false);
    };
    match &v {
        Value::Num(n) if n.lo == n.hi => match crate::lower::round_to_float(&n.lo, format) {
            Some(r) if r != n.lo => (Value::rat(r), true),
            _ => (v, false),
        },
        _ => (v, false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mochi_core::splitmix::SplitMix64;

    #[test]
    fn exact_values_become_literals_and_enclosures_do_not() {
        let half = Value::rat(Rat::new(BigInt::from(1), BigInt::from(2)));
        let e = value_expr(&half, &Sort::Real, Loc::default()).expect("exact");
        assert!(matches!(&e.kind, ExprKind::Binary(_, a, b)
            if matches!((&a.kind, &b.kind), (ExprKind::Real(n), ExprKind::Real(d)) if n == "1" && d == "2")));
        // `pi / 2` is an enclosure: no literal stands for it (the argument's expression is
        // kept for Z3 instead, `motion::argument`).
        let pi = exact::pi();
        assert!(!pi.is_exact());
        assert!(value_expr(&Value::Num(pi), &Sort::Real, Loc::default()).is_none());
        assert!(value_expr(&Value::Bool(Tri::Unknown), &Sort::Bool, Loc::default()).is_none());
    }

    #[test]
    fn the_generator_is_reproducible_and_fractions_lie_in_the_open_unit_interval() {
        let (mut a, mut b) = (Rng(SplitMix64(7)), Rng(SplitMix64(7)));
        for _ in 0..100 {
            let (x, y) = (a.fraction(), b.fraction());
            assert_eq!(x, y);
            assert!(x > Rat::from_integer(BigInt::from(0)) && x < Rat::from_integer(BigInt::from(1)));
            assert!(a.below(3) < 3);
            b.below(3);
        }
    }
}
