//! The SMT stage: the only module that names `z3`. It decides validity of predicate
//! obligations `hyps ⇒ goal` by asking Z3 whether `hyps ∧ ¬goal` is satisfiable:
//! unsat means the obligation holds, sat gives a counterexample in the user's terms,
//! and anything else (timeout, an unsupported construct, Z3's own "unknown") is
//! [`Verdict::Unknown`] with the reason — never a pass.
//!
//! **Status:** encoding and validity checking of [`Goal::Valid`](crate::obligation::Goal)
//! obligations over bool, int and real terms. Not yet called by the driver (part 2 wires
//! it in, with [AGCOMP], separation and refinement goals, caching and parallelism).
//!
//! The `z3` crate (0.22, on the system's libz3 4.8.12) keeps one context per thread, so
//! each worker thread that calls [`check_valid`] gets its own context.

mod encode;

use crate::hir::{Expr, Program};
use std::time::Duration;

pub use encode::Unsupported;

/// How the solver is run.
#[derive(Clone, Debug)]
pub struct SmtConfig {
    /// Per query; Z3 gives up and the obligation is unknown.
    pub timeout: Duration,
}

impl Default for SmtConfig {
    fn default() -> SmtConfig {
        SmtConfig { timeout: Duration::from_secs(5) }
    }
}

/// Why an obligation was not decided.
#[derive(Clone, Debug, PartialEq)]
pub enum Why {
    Timeout(Duration),
    /// Z3 answered unknown for another reason (its own words).
    Incomplete(String),
    /// A construct the encoding does not support yet.
    Unsupported(String),
}

/// The value of one variable in a counterexample, printed as the user writes it.
#[derive(Clone, Debug, PartialEq)]
pub struct Assignment {
    pub name: String,
    pub value: String,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    Holds,
    Fails(Vec<Assignment>),
    Unknown(Why),
}

/// Decides whether `hyps ⇒ goal` is valid.
pub fn check_valid(prog: &Program, hyps: &[Expr], goal: &Expr, cfg: &SmtConfig) -> Verdict {
    let mut enc = encode::Encoder::new(prog);
    let query = (|| {
        let hs: Vec<z3::ast::Bool> = hyps.iter().map(|h| enc.boolean(h)).collect::<Result<_, _>>()?;
        let g = enc.boolean(goal)?;
        Ok::<_, Unsupported>((hs, g))
    })();
    let (hs, g) = match query {
        Ok(q) => q,
        Err(Unsupported(what)) => return Verdict::Unknown(Why::Unsupported(what)),
    };
    let solver = z3::Solver::new();
    for h in hs.iter().chain(enc.side_conditions()) {
        solver.assert(h);
    }
    solver.assert(g.not());
    let (result, timed_out) = check_with_deadline(&solver, cfg.timeout);
    match result {
        z3::SatResult::Unsat => Verdict::Holds,
        z3::SatResult::Sat => Verdict::Fails(solver.get_model().map(|m| enc.assignments(&m)).unwrap_or_default()),
        z3::SatResult::Unknown if timed_out => Verdict::Unknown(Why::Timeout(cfg.timeout)),
        z3::SatResult::Unknown => Verdict::Unknown(Why::Incomplete(solver.get_reason_unknown().unwrap_or_default())),
    }
}

/// Runs `solver.check()` and interrupts it from a watchdog thread after `timeout`.
///
/// Z3's own `timeout` parameter is not used: in Z3 4.8.10-4.8.12 (Debian's libz3 is
/// 4.8.12) its thread-pool `scoped_timer` can deadlock (Z3Prover/z3 PR #5371, fixed
/// after 4.8.12); we saw `check()` hang forever with a 1 ms timeout. `Z3_interrupt` on
/// the context needs no timer thread of Z3's. If the interrupt lands just after the
/// check finished, the worst case is a later query on this thread reporting unknown.
fn check_with_deadline(solver: &z3::Solver, timeout: Duration) -> (z3::SatResult, bool) {
    let ctx = z3::Context::thread_local();
    let handle = ctx.handle();
    let (done, wait) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|scope| {
        let watchdog = scope.spawn(move || {
            if wait.recv_timeout(timeout) == Err(std::sync::mpsc::RecvTimeoutError::Timeout) {
                handle.interrupt();
                return true;
            }
            false
        });
        let result = solver.check();
        let _ = done.send(());
        let timed_out = watchdog.join().unwrap_or(false);
        (result, timed_out)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::lower_src;

    /// Lowers `const`s and a guard `[P]` of a message from A to B, returning it.
    fn pred(consts: &str, p: &str) -> (Program, Expr) {
        let src = format!(
            "{consts} robot R {{ state x: real, n: int, m: int, k: int, b: bool; }}
             system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{p}] go. end;"
        );
        let (prog, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("expected a sequence")
        };
        let crate::hir::Global::Msg(m) = &items[0] else { panic!("expected a message") };
        let g = m.guard.clone().expect("guard");
        (prog, g)
    }

    fn valid(consts: &str, p: &str) -> Verdict {
        let (prog, e) = pred(consts, p);
        check_valid(&prog, &[], &e, &SmtConfig::default())
    }

    #[test]
    fn linear_arithmetic_is_decided() {
        assert_eq!(valid("", "x > 1 => x > 0"), Verdict::Holds);
        assert_eq!(valid("const lane = 0.65;", "x >= lane => x > 0.6"), Verdict::Holds);
        assert_eq!(valid("", "n > 1 => 2 * n >= 4"), Verdict::Holds);
        assert_eq!(valid("", "(if b then x else 0 - x) >= 0 || (b && x < 0) || (!b && x > 0)"), Verdict::Holds);
        assert_eq!(valid("", "min(x, 1) <= 1 && abs(x) >= 0"), Verdict::Holds);
    }

    #[test]
    fn a_counterexample_names_the_variables() {
        let Verdict::Fails(model) = valid("", "x > 0") else { panic!("x > 0 is not valid") };
        let x = model.iter().find(|a| a.name == "A.x").expect("A.x in the model");
        let v: f64 = x.value.parse().unwrap_or(1.0);
        assert!(v <= 0.0, "the counterexample must falsify x > 0: {model:?}");
    }

    #[test]
    fn sqrt_and_powers_are_encoded_soundly() {
        assert_eq!(valid("", "x >= 0 => sqrt(x)^2 == x"), Verdict::Holds);
        assert_eq!(valid("", "x^2 >= 0"), Verdict::Holds);
        assert!(matches!(valid("", "sqrt(x) >= 1"), Verdict::Fails(_)));
    }

    #[test]
    fn unsupported_constructs_are_unknown_not_valid() {
        assert!(matches!(valid("", "sin(x) <= 1"), Verdict::Unknown(Why::Unsupported(_))));
    }

    #[test]
    fn a_timeout_is_unknown() {
        // Fermat's last theorem for cubes: true, but beyond Z3's nonlinear integer
        // reasoning, and given 1 ms. Whatever Z3 says, it must not be "holds" or "fails".
        let (prog, e) = pred("", "n > 0 && m > 0 && k > 0 => n^3 + m^3 != k^3");
        let cfg = SmtConfig { timeout: Duration::from_millis(1) };
        match check_valid(&prog, &[], &e, &cfg) {
            Verdict::Unknown(_) => {}
            other => panic!("expected unknown, got {other:?}"),
        }
    }
}
