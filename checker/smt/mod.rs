//! The SMT stage: the only module that names `z3`. It decides the predicate
//! obligations the earlier stages leave ([`crate::obligation`]).
//!
//! Each obligation is split into parts ([`goals`]), one satisfiability query each:
//! the part holds when its query is unsatisfiable, fails with a model (shown in the
//! user's names) when it is satisfiable, and is unknown — never a pass — when Z3 times
//! out, gives up, or the encoding cannot express it ([`encode`]).
//!
//! - **Folding.** Syntactically trivial obligations never reach Z3, and separation is
//!   first tried with boxes from interval arithmetic ([`crate::bounds`]).
//! - **Caching.** Results are cached by the query's SMT-LIB text.
//! - **Parallelism.** Obligations are discharged on `jobs` worker threads, each with
//!   its own Z3 context (the `z3` crate's thread-local context).
//! - **Timeouts.** Each query has a deadline enforced by a watchdog that interrupts
//!   the context (see [`check_with_deadline`] for why not Z3's own `timeout`).
//! - **Dumping.** With a dump directory, every query is written as an `.smt2` file
//!   named after its rule and source position.

mod encode;
pub mod goals;

use crate::hir::{Expr, Program};
use crate::obligation::{Goal, Obligation};
use goals::{Part, Plan, Query};
use serde::Serialize;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Duration;

pub use encode::Unsupported;

/// How the solver is run.
#[derive(Clone, Debug)]
pub struct SmtConfig {
    /// Per query; Z3 gives up and the part is unknown.
    pub timeout: Duration,
    /// Worker threads (each with its own Z3 context).
    pub jobs: usize,
    /// Write every query as SMT-LIB into this directory.
    pub dump_dir: Option<PathBuf>,
    /// Show a progress bar on a terminal.
    pub progress: bool,
}

/// The default per-query timeout: generous for the small queries mochi makes, short
/// enough that a hopeless nonlinear query does not hold up a run.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(10);

impl Default for SmtConfig {
    fn default() -> SmtConfig {
        SmtConfig {
            timeout: DEFAULT_TIMEOUT,
            jobs: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            dump_dir: None,
            progress: false,
        }
    }
}

/// Why an obligation was not decided.
#[derive(Clone, Debug, PartialEq)]
pub enum Why {
    Timeout(Duration),
    /// Z3 answered unknown, or its model relies on an over-approximation.
    Incomplete(String),
    /// A construct the encoding does not support.
    Unsupported(String),
}

impl std::fmt::Display for Why {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Why::Timeout(d) => write!(f, "Z3 timed out after {} ms (raise it with --timeout)", d.as_millis()),
            Why::Incomplete(s) => write!(f, "Z3 could not decide it: {s}"),
            Why::Unsupported(s) => write!(f, "the SMT encoding does not support {s}"),
        }
    }
}

pub use crate::diag::{Assignment, Overlap};

/// A failed part: what failed and the counterexample.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Failure {
    pub part: String,
    /// Which question failed (`None` when decided without a query).
    #[serde(skip)]
    pub which: Option<Part>,
    pub values: Vec<Assignment>,
    pub overlap: Option<Overlap>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    Holds,
    Fails(Vec<Assignment>),
    Unknown(Why),
}

/// The decision on one obligation.
#[derive(Clone, Debug, PartialEq)]
pub enum Decision {
    /// With a note on how (for example the inferred partition of a `*`).
    Holds(Option<String>),
    Fails(Failure),
    Unknown {
        part: String,
        why: Why,
    },
}

/// Counts for the report and the benchmark.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Stats {
    /// Parts that needed a query.
    pub queries: usize,
    /// Queries answered from the cache.
    pub cached: usize,
    /// Obligations settled without Z3 (trivial, or separated by boxes).
    pub folded: usize,
}

/// Decides whether `hyps ⇒ goal` is valid (one query, no cache).
pub fn check_valid(prog: &Program, hyps: &[Expr], goal: &Expr, cfg: &SmtConfig) -> Verdict {
    let ob = Obligation {
        rule: crate::obligation::Rule::TOut,
        span: Default::default(),
        what: String::new(),
        hyps: hyps.to_vec(),
        goal: Goal::Valid(goal.clone()),
    };
    let cache = Mutex::new(HashMap::new());
    let ctx = Worker { prog, cfg, cache: &cache, labels: &[], dumped: &AtomicUsize::new(0) };
    match ctx.decide(0, &ob).0 {
        Decision::Holds(_) => Verdict::Holds,
        Decision::Fails(f) => Verdict::Fails(f.values),
        Decision::Unknown { why, .. } => Verdict::Unknown(why),
    }
}

/// Decides every obligation, in parallel. `labels[i]` names obligation `i` in dumped
/// files (rule and position).
pub fn discharge(
    prog: &Program,
    obligations: &[Obligation],
    labels: &[String],
    cfg: &SmtConfig,
) -> (Vec<Decision>, Stats) {
    let cache = Mutex::new(HashMap::new());
    let dumped = AtomicUsize::new(0);
    if let Some(dir) = &cfg.dump_dir {
        let _ = std::fs::create_dir_all(dir);
    }
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<(Decision, Stats)>>> = Mutex::new(vec![None; obligations.len()]);
    let bar = progress_bar(cfg, obligations.len());
    let jobs = cfg.jobs.clamp(1, obligations.len().max(1));
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                let w = Worker { prog, cfg, cache: &cache, labels, dumped: &dumped };
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(ob) = obligations.get(i) else { break };
                    let r = w.decide(i, ob);
                    if let Ok(mut rs) = results.lock() {
                        rs[i] = Some(r);
                    }
                    if let Some(b) = &bar {
                        b.inc(1);
                    }
                }
            });
        }
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let mut stats = Stats::default();
    let decisions = results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| {
            let (d, s) = r.unwrap_or((
                Decision::Unknown { part: String::new(), why: Why::Incomplete("a worker thread stopped".into()) },
                Stats::default(),
            ));
            stats.queries += s.queries;
            stats.cached += s.cached;
            stats.folded += s.folded;
            d
        })
        .collect();
    (decisions, stats)
}

fn progress_bar(cfg: &SmtConfig, n: usize) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !cfg.progress || n < 20 || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(n as u64);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{spinner} checking obligations {pos}/{len} {wide_bar} {elapsed}")
    {
        bar.set_style(style);
    }
    Some(bar)
}

/// A cached answer to one query.
#[derive(Clone)]
enum Answer {
    Unsat,
    Sat { values: Vec<Assignment>, overlap: Option<Overlap> },
    Unknown(Why),
}

struct Worker<'a> {
    prog: &'a Program,
    cfg: &'a SmtConfig,
    cache: &'a Mutex<HashMap<String, Answer>>,
    labels: &'a [String],
    dumped: &'a AtomicUsize,
}

impl Worker<'_> {
    /// Decides one obligation: every part must hold. A failing part wins over an
    /// unknown one (it is a definite answer).
    fn decide(&self, index: usize, ob: &Obligation) -> (Decision, Stats) {
        let mut stats = Stats::default();
        if ob.trivially_holds() {
            stats.folded += 1;
            return (Decision::Holds(None), stats);
        }
        let parts = match goals::plan(self.prog, ob) {
            Plan::Holds(note) => {
                stats.folded += 1;
                return (Decision::Holds(note), stats);
            }
            Plan::Fails(why) => {
                return (Decision::Fails(Failure { part: why, which: None, values: Vec::new(), overlap: None }), stats);
            }
            Plan::Unknown(Unsupported(what)) => {
                return (Decision::Unknown { part: String::new(), why: Why::Unsupported(what) }, stats);
            }
            Plan::Parts(parts) => parts,
        };
        let mut unknown = None;
        for (k, part) in parts.iter().enumerate() {
            stats.queries += 1;
            let answer = match goals::build(self.prog, ob, part) {
                Err(Unsupported(what)) => Answer::Unknown(Why::Unsupported(what)),
                Ok(q) => self.solve(q, index, k, &mut stats),
            };
            match answer {
                Answer::Unsat => {}
                Answer::Sat { values, overlap } => {
                    let which = Some(part.clone());
                    let part = describe(self.prog, ob, part);
                    return (Decision::Fails(Failure { part, which, values, overlap }), stats);
                }
                Answer::Unknown(why) => {
                    unknown.get_or_insert((describe(self.prog, ob, part), why));
                }
            }
        }
        match unknown {
            Some((part, why)) => (Decision::Unknown { part, why }, stats),
            None => (Decision::Holds(None), stats),
        }
    }

    fn solve(&self, q: Query, index: usize, k: usize, stats: &mut Stats) -> Answer {
        let solver = z3::Solver::new();
        for a in q.assertions.iter().chain(q.enc.side_conditions()) {
            solver.assert(a);
        }
        let text = solver.to_string();
        if let Some(dir) = &self.cfg.dump_dir {
            let label = self.labels.get(index).cloned().unwrap_or_else(|| format!("obligation-{index}"));
            let n = self.dumped.fetch_add(1, Ordering::Relaxed);
            let path = dir.join(format!("{n:05}-{label}-{k}.smt2"));
            let _ = std::fs::write(path, format!("; mochi: {label}, part {k}\n{text}(check-sat)\n"));
        }
        if let Some(a) = self.cache.lock().ok().and_then(|c| c.get(&text).cloned()) {
            stats.cached += 1;
            return a;
        }
        let (result, timed_out) = check_with_deadline(&solver, self.cfg.timeout);
        let answer = match result {
            z3::SatResult::Unsat => Answer::Unsat,
            z3::SatResult::Sat => match solver.get_model() {
                Some(m) if q.enc.spurious_trig(&m) => Answer::Unknown(Why::Incomplete(
                    "its counterexample gives sin/cos values the real functions do not take (the encoding encloses them)"
                        .into(),
                )),
                Some(m) => {
                    let overlap = q.point.as_ref().map(|p| Overlap {
                        point: [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
                        times: q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
                    });
                    Answer::Sat { values: q.enc.assignments(&m), overlap }
                }
                None => Answer::Sat { values: Vec::new(), overlap: None },
            },
            z3::SatResult::Unknown if timed_out => Answer::Unknown(Why::Timeout(self.cfg.timeout)),
            z3::SatResult::Unknown => {
                Answer::Unknown(Why::Incomplete(solver.get_reason_unknown().unwrap_or_else(|| "unknown".into())))
            }
        };
        // A timeout depends on the machine's load: do not cache it.
        if !matches!(answer, Answer::Unknown(Why::Timeout(_))) {
            if let Ok(mut c) = self.cache.lock() {
                c.insert(text, answer.clone());
            }
        }
        answer
    }
}

/// What a part checks, in the user's terms.
fn describe(prog: &Program, ob: &Obligation, part: &Part) -> String {
    let prim = |app: &crate::hir::PrimApp| crate::hir::print::prim_app(prog, app);
    match (&ob.goal, part) {
        (Goal::Compatible { parts }, Part::Pre(i)) => {
            format!(
                "the precondition of `{}` ({}) holds when the joint motion starts",
                prim(&parts[*i].1),
                prog.role_name(parts[*i].0)
            )
        }
        (Goal::Compatible { parts }, Part::Assume(i)) => format!(
            "the guarantees of the other primitives discharge the assumption of `{}` ({})",
            prim(&parts[*i].1),
            prog.role_name(parts[*i].0)
        ),
        (Goal::Compatible { parts }, Part::Disjoint(i, j)) => format!(
            "the footprints of `{}` ({}) and `{}` ({}) are disjoint at every time",
            prim(&parts[*i].1),
            prog.role_name(parts[*i].0),
            prim(&parts[*j].1),
            prog.role_name(parts[*j].0)
        ),
        (Goal::Compatible { parts }, Part::Within(n, j)) => format!(
            "the duration of the non-interruptible `{}` ({}) lies within that of `{}` ({})",
            prim(&parts[*n].1),
            prog.role_name(parts[*n].0),
            prim(&parts[*j].1),
            prog.role_name(parts[*j].0)
        ),
        (Goal::Compatible { .. }, Part::Meet) => "the durations of the primitives share a time".to_string(),
        (Goal::Separated { sides }, Part::Apart { a, ra, b, rb }) => {
            let (x, y) = (&sides[*a].runs[*ra], &sides[*b].runs[*rb]);
            format!(
                "the footprint of `{}` ({}) on side {} and that of `{}` ({}) on side {} never meet",
                prim(&x.app),
                prog.role_name(x.role),
                a + 1,
                prim(&y.app),
                prog.role_name(y.role),
                b + 1
            )
        }
        (Goal::Refines { concrete, abstract_, .. }, Part::Refine(item)) => {
            let abs: Vec<String> = abstract_.iter().map(prim).collect();
            format!("`{}` refines `{}`: {}", prim(concrete), abs.join(" /\\ "), item.text())
        }
        (Goal::InitiallyDisjoint, Part::InitiallyApart { r, s }) => {
            let firsts = goals::first_runs(prog);
            format!(
                "`{}` and `{}` start apart (their first footprints at time 0 are disjoint)",
                prog.role_name(firsts[*r].0),
                prog.role_name(firsts[*s].0)
            )
        }
        _ => ob.what.clone(),
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
        assert_eq!(valid("", "x == -0.5 => x < 0"), Verdict::Holds);
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
    fn trigonometry_is_enclosed_soundly() {
        assert_eq!(valid("", "sin(x)^2 + cos(x)^2 == 1"), Verdict::Holds);
        assert_eq!(valid("", "-1 <= sin(x) <= 1 && cos(x) <= 1"), Verdict::Holds);
        assert_eq!(valid("", "0 <= x <= 0.1 => sin(x) >= 0 && cos(x) >= 0.99"), Verdict::Holds);
        assert_eq!(valid("const yaw = 1.5708;", "cos(yaw) < 0.0001 && sin(yaw) > 0.9999"), Verdict::Holds);
        // False, with a real counterexample near 0 (the enclosure is tight there).
        assert!(matches!(valid("", "0 <= x <= 0.1 => sin(x) >= 0.05"), Verdict::Fails(_)));
        // True of the real functions but beyond the polynomial enclosure: never "fails".
        assert!(matches!(
            valid("", "sin(x) <= 0.999 || cos(x) <= 0.5 || cos(x) >= 0"),
            Verdict::Holds | Verdict::Unknown(_)
        ));
        assert!(!matches!(valid("", "cos(x) >= -0.5 || x^2 >= 4"), Verdict::Fails(_)));
    }

    #[test]
    fn points_and_vectors_are_triples() {
        assert_eq!(valid("", "norm2(vector(x, 0, 0)) == x^2"), Verdict::Holds);
        assert_eq!(valid("", "dot(point(1, 2, 3), vector(x, x, x)) == 6 * x"), Verdict::Holds);
        assert_eq!(valid("", "(point(x, 1, 2) - point(0, 1, 2)).x == x"), Verdict::Holds);
    }

    #[test]
    fn a_timeout_is_unknown() {
        // Fermat's last theorem for cubes: true, but beyond Z3's nonlinear integer
        // reasoning, and given 1 ms. Whatever Z3 says, it must not be "holds" or "fails".
        let (prog, e) = pred("", "n > 0 && m > 0 && k > 0 => n^3 + m^3 != k^3");
        let cfg = SmtConfig { timeout: Duration::from_millis(1), ..SmtConfig::default() };
        match check_valid(&prog, &[], &e, &cfg) {
            Verdict::Unknown(_) => {}
            other => panic!("expected unknown, got {other:?}"),
        }
    }
}
