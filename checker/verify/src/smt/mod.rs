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
//! - **Caching.** Results are cached by the query itself, read off its terms before any
//!   solver exists (exactly, and up to renaming: [`key`]), the vacuity guard's by the
//!   hypotheses, and a primitive shown able to end by one obligation witnesses its
//!   contract (E0409) for the others.
//! - **Guessing.** A sat question whose definitions give a point that satisfies it, checked
//!   in exact arithmetic, needs no solver ([`guess`]).
//! - [`SmtConfig::no_cache`] turns all of these off (every query asked of Z3 afresh;
//!   `mochi check --no-cache`), which the differential tests use to show that no verdict
//!   depends on an answer reused from another query or on a guessed point.
//! - **Parallelism.** Obligations are discharged on `jobs` worker threads, each with
//!   its own Z3 context (the `z3` crate's thread-local context), in a [`pool`].
//! - **Timeouts.** Each query has a limit enforced by a watchdog that interrupts the
//!   context (see [`Watchdog`] for why not Z3's own `timeout`), and, when Z3 does not
//!   stop, by abandoning its worker ([`pool`]): the limit holds whatever Z3 does.
//! - **No IO.** Dumps and progress go through callbacks in [`SmtConfig`] ([`DumpSink`],
//!   [`ProgressSink`]); the IO edge provides them (`crate::io`).

mod confirm;
mod encode;
pub mod goals;
mod guess;
pub mod hard;
mod key;
pub mod pool;
pub mod replay;

use crate::hir::{Expr, Program};
use crate::obligation::{Goal, Obligation};
use goals::{Part, Plan, Query};
use serde::Serialize;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

pub use encode::{Logic, Unsupported};
pub(crate) use pool::Watchdog;

/// Receives every query as it is asked: a label naming it (unique within a run, in the
/// order the queries were made: `00007-agcomp-fetch-chor-12-3-0`) and its SMT-LIB text (a
/// whole script, ending with `(check-sat)`). An error stops the dumping and is reported
/// with the obligation whose query it was ([`Stats::dump_error`]).
pub type DumpSink = Arc<dyn Fn(&str, &str) -> Result<(), String> + Send + Sync>;

/// Receives the progress of a run (on the thread that called [`discharge`]).
pub type ProgressSink = Arc<dyn Fn(ProgressEvent) + Send + Sync>;

/// What a [`ProgressSink`] is told.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressEvent {
    /// `total` obligations are about to be decided.
    Start { total: usize },
    /// `done` of `total` are decided.
    Decided { done: usize, total: usize },
    /// All are decided.
    Finish,
}

/// How the solver is run.
#[derive(Clone)]
pub struct SmtConfig {
    /// Per query; Z3 gives up and the part is unknown.
    pub timeout: Duration,
    /// Worker threads (each with its own Z3 context).
    pub jobs: usize,
    /// Where queries are dumped (none: not dumped).
    pub dump: Option<DumpSink>,
    /// Where progress is reported (none: not reported).
    pub on_progress: Option<ProgressSink>,
    /// Reuse no answer: no query answered from the cache (by its terms, or up to
    /// renaming), none by a guessed point, no vacuity guard answered by another obligation's with the same hypotheses, no
    /// contract (E0409) witnessed by another obligation's can-end question. Slower, and
    /// meant to give the same verdicts (tests/differential.rs checks it).
    pub no_cache: bool,
}

impl std::fmt::Debug for SmtConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SmtConfig")
            .field("timeout", &self.timeout)
            .field("jobs", &self.jobs)
            .field("dump", &self.dump.is_some())
            .field("on_progress", &self.on_progress.is_some())
            .field("no_cache", &self.no_cache)
            .finish()
    }
}

/// The default per-query timeout: generous for the small queries mochi makes, short
/// enough that a hopeless nonlinear query does not hold up a run.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(10);

impl Default for SmtConfig {
    fn default() -> SmtConfig {
        SmtConfig {
            timeout: DEFAULT_TIMEOUT,
            jobs: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            dump: None,
            on_progress: None,
            no_cache: false,
        }
    }
}

/// Why an obligation was not decided.
#[derive(Clone, Debug, PartialEq)]
pub enum Why {
    /// Z3 reached the time limit; what in the query makes it hard ([`hard`]).
    Timeout(Duration, Hard),
    /// Z3 answered unknown, or its model relies on an over-approximation; what in the
    /// query makes it hard, where that was read.
    Incomplete(String, Hard),
    /// The geometric procedure (parry's distances and contacts under interval branch
    /// and bound, [`crate::geometry::search::checks`]) stopped without deciding: why.
    Search(String),
    /// A construct the encoding does not support.
    Unsupported(String),
    /// Z3 did not stop when interrupted at the limit: its worker was abandoned after this
    /// long ([`pool`]).
    Abandoned(Duration),
    /// Not asked: the run gave up on the solver (why).
    NotRun(String),
}

impl std::fmt::Display for Why {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Why::Timeout(d, hard) => {
                write!(f, "Z3 timed out after {} ms (raise it with --timeout){}", d.as_millis(), hard.suffix())
            }
            Why::Incomplete(s, hard) => write!(f, "Z3 could not decide it: {s}{}", hard.suffix()),
            Why::Search(s) => {
                write!(f, "the geometric search (parry's distances under interval branch and bound) stopped: {s}")
            }
            Why::Unsupported(s) => write!(f, "the SMT encoding does not support {s}"),
            Why::Abandoned(d) => write!(
                f,
                "Z3 did not stop when asked at the time limit and was abandoned after {:.1} s",
                d.as_secs_f64()
            ),
            Why::NotRun(s) => write!(f, "not asked: {s}"),
        }
    }
}

pub use crate::diag::{Assignment, Overlap};
pub use hard::Hard;

/// A failed part: what failed and the counterexample.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Failure {
    pub part: String,
    /// Which question failed (`None` when decided without a query).
    #[serde(skip)]
    pub which: Option<Part>,
    pub values: Vec<Assignment>,
    pub overlap: Option<Overlap>,
    /// Values that share a name with another value of the counterexample: their symbol
    /// there (`v`, `v#2`), their name, and where each is bound.
    #[serde(skip)]
    pub bound: Vec<(String, String, crate::source::Span)>,
}

/// Whether a formula is valid: the answer to [`check_valid`].
#[derive(Clone, Debug, PartialEq)]
pub enum Validity {
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
    /// Sat questions answered by a point guessed from their definitions and checked
    /// exactly, without a solver (`guess.rs`).
    pub witnessed: usize,
    /// Obligations settled without Z3 (trivial, or separated by boxes).
    pub folded: usize,
    /// Parts decided by the geometric procedure (branch and bound; Z3 only for witnesses).
    pub geometric: usize,
    /// Time spent deciding (on the worker thread that did it).
    pub millis: f64,
    /// Obligations that held only because their hypotheses are unsatisfiable.
    pub vacuous: usize,
    /// Obligations that held but whose hypotheses could not be shown satisfiable.
    pub unsure: usize,
    /// The first error of the [`DumpSink`] (set on the obligation whose query it was;
    /// nothing is dumped after it).
    #[serde(skip)]
    pub dump_error: Option<String>,
}

impl Stats {
    pub fn add(&mut self, o: &Stats) {
        self.queries += o.queries;
        self.cached += o.cached;
        self.witnessed += o.witnessed;
        self.geometric += o.geometric;
        self.folded += o.folded;
        self.millis += o.millis;
        self.vacuous += o.vacuous;
        self.unsure += o.unsure;
        if self.dump_error.is_none() {
            self.dump_error.clone_from(&o.dump_error);
        }
    }
}

/// Decides whether `hyps ⇒ goal` is valid (one query, no cache).
pub fn check_valid(prog: &Program, hyps: &[Expr], goal: &Expr, cfg: &SmtConfig) -> Validity {
    let ob = Obligation {
        rule: crate::obligation::Rule::TOut,
        span: Default::default(),
        what: String::new(),
        hyps: hyps.to_vec(),
        goal: Goal::Valid(goal.clone()),
    };
    match discharge(prog, &[ob], &[], &SmtConfig { jobs: 1, ..cfg.clone() }).remove(0).0 {
        Decision::Holds(_) => Validity::Holds,
        Decision::Fails(f) => Validity::Fails(f.values),
        Decision::Unknown { why, .. } => Validity::Unknown(why),
    }
}

/// Decides every obligation, in parallel, and says how each went. `labels[i]` names
/// obligation `i` in dumped queries (rule and position).
pub fn discharge(
    prog: &Program,
    obligations: &[Obligation],
    labels: &[String],
    cfg: &SmtConfig,
) -> Vec<(Decision, Stats)> {
    let cfg = cfg.clone();
    let progress = cfg.on_progress.clone();
    let report = |e: ProgressEvent| {
        if let Some(p) = &progress {
            p(e)
        }
    };
    let total = obligations.len();
    report(ProgressEvent::Start { total });
    // A thread and its Z3 context cost milliseconds to start: no more workers than
    // there is work for.
    let jobs = cfg.jobs.clamp(1, total.div_ceil(4).max(1));
    // The workers own what they read (an abandoned one may outlive this call).
    let shared = pool::Shared::new(prog.clone(), obligations.to_vec(), labels.to_vec(), cfg, Caches::default());
    let results = pool::run(shared, jobs, work, &|done, total| report(ProgressEvent::Decided { done, total }));
    report(ProgressEvent::Finish);
    results
}

/// What the workers of one [`discharge`] share besides the pool.
#[derive(Default)]
struct Caches {
    /// Answers by query text (exact, and up to renaming).
    cache: Mutex<HashMap<String, Answer>>,
    /// The vacuity guard's answers, by hypotheses.
    contexts: Mutex<HashMap<Vec<Expr>, Answer>>,
    /// Primitives some obligation has shown able to end: a `dt` whose can-end question had a
    /// witness, or a refinement whose concrete primitive was realisable.
    witnessed: Mutex<HashSet<crate::hir::PrimId>>,
    /// Queries dumped so far (numbers the dump labels).
    dumped: AtomicUsize,
    /// Set when the dump sink failed: nothing more is dumped.
    dump_failed: AtomicBool,
}

/// One worker: decides obligations from the pool until there are none.
fn work(lease: &pool::Lease<Caches>) {
    let sh = lease.shared;
    let w = Worker {
        prog: &sh.prog,
        cfg: &sh.cfg,
        caches: &sh.extra,
        labels: &sh.labels,
        watchdog: lease.watchdog,
        timeout: sh.cfg.timeout,
    };
    while let Some(i) = lease.take() {
        let ob = &sh.obligations[i];
        let t = std::time::Instant::now();
        let (d, mut st) = match &ob.goal {
            // A primitive's contract (E0409) is witnessed by any use of it that
            // could end (the driver puts these obligations last).
            Goal::CanEnd { prim }
                if ob.rule == crate::obligation::Rule::Contract
                    && !sh.cfg.no_cache
                    && sh.extra.witnessed.lock().is_ok_and(|w| w.contains(prim)) =>
            {
                (Decision::Holds(None), Stats { folded: 1, ..Stats::default() })
            }
            _ => w.decide(i, ob),
        };
        if matches!(d, Decision::Holds(_)) && st.vacuous == 0 {
            let shown = witnesses(ob);
            if !shown.is_empty() {
                if let Ok(mut w) = sh.extra.witnessed.lock() {
                    w.extend(shown);
                }
            }
        }
        st.millis = t.elapsed().as_secs_f64() * 1000.0;
        lease.finish(i, (d, st));
    }
}

/// The primitives whose contracts an obligation that held non-vacuously has shown able to
/// end: every part of a `dt` (its joint can-end question had a witness), and the concrete
/// primitive of a refinement (its realisability question had one). Not a primitive refining
/// itself: that holds without the question.
fn witnesses(ob: &Obligation) -> Vec<crate::hir::PrimId> {
    match &ob.goal {
        Goal::Compatible { parts } => parts.iter().map(|(_, a)| a.prim).collect(),
        Goal::Refines { concrete, abstract_, .. } if abstract_.as_slice() != std::slice::from_ref(concrete) => {
            vec![concrete.prim]
        }
        _ => Vec::new(),
    }
}

/// A cached answer to one query.
#[derive(Clone)]
enum Answer {
    Unsat,
    /// `exact`: the model's values as rationals, for [`replay`]; `bound`: where each of
    /// two same-named values in the model is bound.
    Sat {
        values: Vec<Assignment>,
        overlap: Option<Overlap>,
        bound: Vec<(String, String, crate::source::Span)>,
        exact: replay::Valuation,
    },
    Unknown(Why),
}

#[derive(Clone, Copy)]
struct Worker<'a> {
    prog: &'a Program,
    cfg: &'a SmtConfig,
    caches: &'a Caches,
    labels: &'a [String],
    watchdog: &'a Watchdog,
    /// Per query: the configuration's, or less for a first quick pass
    /// ([`Worker::contains_turning`]).
    timeout: Duration,
}

/// The first pass's limit per query for body containment with a footprint that turns with
/// the state ([`Worker::contains_turning`]).
const QUICK: Duration = Duration::from_secs(1);

impl Worker<'_> {
    /// Decides one obligation: every part must hold. A failing part wins over an
    /// unknown one (it is a definite answer).
    fn decide(&self, index: usize, ob: &Obligation) -> (Decision, Stats) {
        if let Goal::Contains { prim } = ob.goal {
            if crate::space::enclose::turns(self.prog, prim) && !ob.trivially_holds() {
                return self.contains_turning(index, ob, prim);
            }
        }
        self.decide_parts(index, ob)
    }

    /// Body containment (E0512) with a footprint that turns with the state (its `cos`/`sin`,
    /// or the body's): first the interval search of `space::enclose` with a small budget
    /// (a footprint affine in the body's point, such as a square turned with the heading
    /// around a disc, is decided in a few hundred pieces, milliseconds); then Z3 for at most
    /// [`QUICK`] per query (most other such questions are linear once the heading is fixed,
    /// and answered in milliseconds); then, if the first search only ran out of pieces, the
    /// search with its full budget (about a second); then Z3 again with the full limit.
    /// Every answer is one of the procedures', each sound on its own.
    fn contains_turning(&self, index: usize, ob: &Obligation, prim: crate::hir::PrimId) -> (Decision, Stats) {
        use crate::space::enclose::{body_in_predicate, BUDGET, QUICK_BUDGET};
        let first = body_in_predicate(self.prog, prim, QUICK_BUDGET);
        let mut stats = Stats::default();
        let retry = match first {
            Ok(note) => {
                stats.geometric += 1;
                return (Decision::Holds(Some(note)), stats);
            }
            Err(u) => u.ran_out,
        };
        let quick = Worker { timeout: self.timeout.min(QUICK), ..*self };
        let (d, more) = quick.decide_parts(index, ob);
        stats.add(&more);
        if !matches!(d, Decision::Unknown { .. }) {
            return (d, stats);
        }
        if retry {
            if let Ok(note) = body_in_predicate(self.prog, prim, BUDGET) {
                stats.geometric += 1;
                return (Decision::Holds(Some(note)), stats);
            }
        }
        if quick.timeout == self.timeout {
            return (d, stats);
        }
        let (d, more) = self.decide_parts(index, ob);
        stats.add(&more);
        (d, stats)
    }

    fn decide_parts(&self, index: usize, ob: &Obligation) -> (Decision, Stats) {
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
                return (
                    Decision::Fails(Failure {
                        part: why,
                        which: None,
                        values: Vec::new(),
                        overlap: None,
                        bound: Vec::new(),
                    }),
                    stats,
                );
            }
            Plan::Unknown(Unsupported(what)) => {
                return (Decision::Unknown { part: String::new(), why: Why::Unsupported(what) }, stats);
            }
            Plan::Parts(parts) => parts,
        };
        let mut unknown = None;
        // E0243's example: a model of the context without the field's entry predicate.
        let mut admitted: Option<Vec<Assignment>> = None;
        // Set when a part held only because Σ is unsatisfiable; `sat` when a part's
        // witness showed Σ satisfiable (a sat question asked with all of Σ).
        let mut vacuous = false;
        let mut sat = false;
        for (k, part) in parts.iter().enumerate() {
            let answer = self.ask(ob, index, k, part, &mut stats);
            if part.is_sat_question() {
                // Satisfiable means it holds (a witness exists); unsat fails, unless the
                // point itself cannot be reached (an earlier step is to blame).
                let fails = match (answer, part) {
                    (Answer::Sat { .. }, _) => {
                        sat |= matches!(part, Part::CanEnd | Part::CanStart | Part::Context);
                        continue;
                    }
                    (Answer::Unknown(why), _) => {
                        unknown.get_or_insert((describe(self.prog, ob, part), why));
                        continue;
                    }
                    // A joint motion that cannot end: stuck if it can start. If it cannot,
                    // a precondition contradicts the context (the pre part's or
                    // [T-MOTION]'s to report), or Σ itself is unsatisfiable.
                    (Answer::Unsat, Part::CanEnd) => {
                        let mut fails = false;
                        for next in [Part::CanStart, Part::Context] {
                            match self.ask(ob, index, k, &next, &mut stats) {
                                Answer::Sat { .. } => {
                                    fails = next == Part::CanStart;
                                    break;
                                }
                                Answer::Unsat => vacuous = next == Part::Context,
                                Answer::Unknown(why) => {
                                    unknown.get_or_insert((describe(self.prog, ob, part), why));
                                    break;
                                }
                            }
                        }
                        fails
                    }
                    // Σ after a step is unsatisfiable: the step is to blame when every
                    // context before it is satisfiable.
                    (Answer::Unsat, Part::Context) => {
                        let Goal::Reachable { before, .. } = &ob.goal else { continue };
                        let mut blame = true;
                        for b in 0..before.len() {
                            match self.ask(ob, index, k, &Part::Before(b), &mut stats) {
                                // An enum-typed field (E0243): the context without its entry
                                // predicate has a model, whose value of the field is one the
                                // refinement admits and the enum does not: the example shown
                                // (in the failure's text: it falsifies no goal of its own, so
                                // it is not a counterexample).
                                Answer::Sat { values, .. } if ob.rule == crate::obligation::Rule::EnumEntry => {
                                    admitted = Some(values);
                                }
                                Answer::Sat { .. } => {}
                                // An `init` that no state satisfies, invariant or not.
                                Answer::Unsat if ob.rule == crate::obligation::Rule::InitInvariant => {
                                    let which = Some(Part::Before(b));
                                    let part = format!("some state satisfies {}", ob.what);
                                    return (
                                        Decision::Fails(Failure {
                                            part,
                                            which,
                                            values: Vec::new(),
                                            overlap: None,
                                            bound: Vec::new(),
                                        }),
                                        stats,
                                    );
                                }
                                Answer::Unsat => blame = false,
                                Answer::Unknown(why) => {
                                    unknown.get_or_insert((describe(self.prog, ob, part), why));
                                    blame = false;
                                }
                            }
                        }
                        if !blame {
                            vacuous = true;
                        }
                        blame
                    }
                    (Answer::Unsat, _) => true,
                };
                if fails {
                    let which = Some(part.clone());
                    let mut part = describe(self.prog, ob, part);
                    if let Some(values) = admitted.take().filter(|v| !v.is_empty()) {
                        let shown: Vec<String> = values.iter().map(|a| format!("{} = {}", a.name, a.value)).collect();
                        part =
                            format!("{part}; the refinement admits, for example, {}, and no entry", shown.join(", "));
                    }
                    return (
                        Decision::Fails(Failure { part, which, values: Vec::new(), overlap: None, bound: Vec::new() }),
                        stats,
                    );
                }
                continue;
            }
            match answer {
                Answer::Unsat => {}
                Answer::Sat { mut values, mut overlap, mut bound, exact } => {
                    // A counterexample is shown only if, evaluated exactly, it falsifies
                    // the part's own goal; one that does not is unknown, never a failure
                    // (the geometric procedure's contact is parry's, replayed there).
                    let geometric = crate::geometry::search::checks::applies(self.prog, ob, part);
                    let mut replayed =
                        if geometric { replay::Replay::Falsifies } else { replay::replay(self.prog, ob, part, &exact) };
                    // A hypothesis `float32(v)` is weakened to `true` in the encoding, so a
                    // model may give a MAVLink float a value no float has: ask again with
                    // each float value pinned to its value rounded to the field's format,
                    // and keep that model if it replays.
                    if !geometric && !matches!(replayed, replay::Replay::Falsifies) {
                        if let Some(Answer::Sat { values: v, overlap: o, bound: b, exact: e }) =
                            self.float_witness(ob, part, &exact, &mut stats)
                        {
                            if matches!(replay::replay(self.prog, ob, part, &e), replay::Replay::Falsifies) {
                                (values, overlap, bound, replayed) = (v, o, b, replay::Replay::Falsifies);
                            }
                        }
                    }
                    let why = match replayed {
                        replay::Replay::Falsifies => None,
                        // A float hypothesis (weakened to `true` in the encoding) the
                        // model breaks, and no model with the floats rounded to their
                        // format completes a counterexample (`float_witness`).
                        replay::Replay::Refuted(why) if why.contains("`float32(") || why.contains("`float64(") => Some(format!("its model gives a MAVLink float a value its format does not hold ({why}), and no model with the floats rounded to their format falsifies the goal: the encoding weakens `float32(v)` in hypotheses, so the question stays open")),
                        replay::Replay::Refuted(why) => Some(format!("its model does not falsify the goal in exact arithmetic ({why}); the encoding's enclosure of a pose turned by an angle that is not an exact multiple of `pi / 2` admits such models, otherwise please report this as a bug in mochi")),
                        replay::Replay::Undecided(why) => Some(format!("its model is not confirmed as a counterexample in exact arithmetic ({why}): the encoding's enclosures (of a pose's rotation, `sin`, `cos`, `sqrt`) may admit it where the real functions do not")),
                    };
                    if let Some(why) = why {
                        unknown.get_or_insert((describe(self.prog, ob, part), Why::Incomplete(why, Hard::default())));
                        continue;
                    }
                    // A joint motion's footprints: look for an earlier meeting, and
                    // prove a time before which they do not meet.
                    if !geometric && matches!(ob.goal, Goal::Compatible { .. }) {
                        if let Some(found) = overlap.as_ref().and_then(|o| o.times.first().copied()) {
                            let (not_before, better) = self.earliest(ob, part, found, &mut stats);
                            if let Some(Answer::Sat { values: v, overlap: o, bound: b, .. }) = better {
                                (values, overlap, bound) = (v, o, b);
                            }
                            if let Some(o) = overlap.as_mut() {
                                o.not_before = not_before;
                            }
                        }
                    }
                    let which = Some(part.clone());
                    // Say which engine found it: Z3's model, or the geometric procedure's
                    // contact (parry, at a configuration a Z3 model of the contracts gave).
                    let engine = if geometric {
                        " [found by the geometric procedure: parry's contact at a state and time Z3 showed the contracts allow]"
                    } else {
                        ""
                    };
                    let part = format!("{}{engine}", describe(self.prog, ob, part));
                    return (Decision::Fails(Failure { part, which, values, overlap, bound }), stats);
                }
                Answer::Unknown(why) => {
                    unknown.get_or_insert((describe(self.prog, ob, part), why));
                }
            }
        }
        if let Some((part, why)) = unknown {
            return (Decision::Unknown { part, why }, stats);
        }
        // The vacuity guard: an obligation proved from hypotheses proved nothing if the
        // hypotheses are unsatisfiable. One query per distinct context (cached by its
        // text, up to renaming); the obligations that ask about Σ itself need none.
        // Separation's queries use the contexts of its runs' `dt`s (whose can-end witness
        // shows them satisfiable), [T-SESS]'s the initial states (checked on their own).
        let covered = matches!(
            ob.goal,
            Goal::Reachable { .. } | Goal::CanEnd { .. } | Goal::Separated { .. } | Goal::InitiallyDisjoint { .. }
        );
        if !vacuous && !sat && !covered && !ob.hyps.is_empty() {
            // Obligations with the same hypotheses share the answer.
            let context = goals::context_of(self.prog, ob);
            let known = if self.cfg.no_cache {
                None
            } else {
                self.caches.contexts.lock().ok().and_then(|c| c.get(&context).cloned())
            };
            let answer = match known {
                Some(a) => {
                    stats.cached += 1;
                    a
                }
                None => {
                    let a = self.ask(ob, index, parts.len(), &Part::Context, &mut stats);
                    if !self.cfg.no_cache && !matches!(a, Answer::Unknown(Why::Timeout(..))) {
                        if let Ok(mut c) = self.caches.contexts.lock() {
                            c.insert(context, a.clone());
                        }
                    }
                    a
                }
            };
            match answer {
                Answer::Unsat => vacuous = true,
                Answer::Sat { .. } => {}
                // Undecided: the obligation's proof stands; only the count is unsure.
                Answer::Unknown(_) => stats.unsure += 1,
            }
        }
        if vacuous {
            stats.vacuous += 1;
        }
        (Decision::Holds(None), stats)
    }

    /// The query of `part` again, with every MAVLink float value the model `exact` gives
    /// a value pinned to that value rounded to its field's format (`lower::round_to_float`,
    /// to nearest): a model of it is a counterexample whose floats are floats, for
    /// [`replay`] to confirm. `None` when no float value was pinned or no model came.
    fn float_witness(
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
        let solver = solver_for(&q);
        for a in q.assertions.iter().chain(q.enc.side_conditions()).chain(&pins) {
            solver.assert(a);
        }
        let seq = self.watchdog.arm(self.timeout);
        let result = solver.check();
        self.watchdog.disarm(seq);
        let m = match result {
            z3::SatResult::Sat => solver.get_model()?,
            _ => return None,
        };
        if q.enc.spurious_trig(&m) {
            return None;
        }
        let overlap = q.point.as_ref().map(|p| Overlap {
            point: [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
            times: q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
            not_before: None,
        });
        Some(Answer::Sat {
            values: q.enc.assignments(&m),
            overlap,
            bound: q.enc.shared_names(),
            exact: replay::valuation(&q.enc, &m),
        })
    }

    /// Bisects the time of a joint motion's footprint meeting found at `found` s: each
    /// step asks the part's query with `time <= mid`. Unsat proves the footprints do not
    /// meet at or before `mid` (the encoding encloses, so its unsat is sound); a model
    /// that replays exactly is an earlier meeting and replaces the counterexample. Returns
    /// the proved bound (if any) and the earliest replayed model found (if any). A few
    /// steps only, each with the query's limit; an undecided step ends the search.
    fn earliest(&self, ob: &Obligation, part: &Part, found: f64, stats: &mut Stats) -> (Option<f64>, Option<Answer>) {
        const STEPS: usize = 6;
        let Ok(q) = goals::build(self.prog, ob, part) else { return (None, None) };
        let Some(time) = q.times.first().cloned() else { return (None, None) };
        let solver = solver_for(&q);
        for a in q.assertions.iter().chain(q.enc.side_conditions()) {
            solver.assert(a);
        }
        let (mut lo, mut hi) = (None::<f64>, found);
        let mut best = None;
        for step in 0..STEPS {
            // First whether they meet at the motion's start, then halves.
            let mid = if step == 0 { 0.0 } else { (lo.unwrap_or(0.0) + hi) / 2.0 };
            if !mid.is_finite() || mid >= hi {
                break;
            }
            let Some(bound) = encode::real_of_f64(mid) else { break };
            solver.push();
            solver.assert(time.le(&bound));
            stats.queries += 1;
            let seq = self.watchdog.arm(self.timeout);
            let result = solver.check();
            let timed_out = self.watchdog.disarm(seq);
            let model = if matches!(result, z3::SatResult::Sat) { solver.get_model() } else { None };
            solver.pop(1);
            match (result, model) {
                (z3::SatResult::Unsat, _) if !timed_out => lo = Some(mid),
                (z3::SatResult::Sat, Some(m)) if !q.enc.spurious_trig(&m) => {
                    let exact = replay::valuation(&q.enc, &m);
                    if !matches!(replay::replay(self.prog, ob, part, &exact), replay::Replay::Falsifies) {
                        break;
                    }
                    let at = encode::Encoder::value_of(&m, &time).unwrap_or(f64::NAN);
                    if at.is_nan() || at > mid {
                        break;
                    }
                    hi = at;
                    let overlap = q.point.as_ref().map(|p| Overlap {
                        point: [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
                        times: q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
                        not_before: None,
                    });
                    best = Some(Answer::Sat {
                        values: q.enc.assignments(&m),
                        overlap,
                        bound: q.enc.shared_names(),
                        exact,
                    });
                }
                _ => break,
            }
        }
        (lo, best)
    }

    /// Builds and solves one part's query.
    fn ask(&self, ob: &Obligation, index: usize, k: usize, part: &Part, stats: &mut Stats) -> Answer {
        // A context is often shown satisfiable without Z3, by a point that satisfies it.
        let context = match (part, &ob.goal) {
            (Part::Context, _) => Some(goals::context_of(self.prog, ob)),
            (Part::Before(b), Goal::Reachable { before, .. }) => before.get(*b).cloned(),
            _ => None,
        };
        // (Not for the context before an enum-typed field's entry predicate, E0243: asked
        // only when the field fails, and its model is the example the report shows.)
        let example = ob.rule == crate::obligation::Rule::EnumEntry && matches!(part, Part::Before(_));
        if !example && context.is_some_and(|c| goals::witnessed(self.prog, &c)) {
            return Answer::Sat { values: Vec::new(), overlap: None, bound: Vec::new(), exact: Default::default() };
        }
        // Bodies the solver cannot represent (URDF links, meshes, a participant riding on
        // another): the geometric procedure, Z3 asked only for witnesses.
        if crate::geometry::search::checks::applies(self.prog, ob, part) {
            stats.geometric += 1;
            return match crate::geometry::search::checks::decide(self.prog, ob, part, self.timeout) {
                crate::geometry::search::checks::GeoAnswer::Apart => Answer::Unsat,
                crate::geometry::search::checks::GeoAnswer::Contact { values, overlap } => {
                    Answer::Sat { values, overlap: Some(overlap), bound: Vec::new(), exact: Default::default() }
                }
                crate::geometry::search::checks::GeoAnswer::Unknown(why) => Answer::Unknown(Why::Search(why)),
            };
        }
        // A payload float chosen by the progress check: first with integer witnesses
        // only, a stronger question Z3 decides quickly; its unsat proves the part, and
        // anything else leaves the exact question to ask.
        let chooses = matches!(ob.goal, Goal::Progress { .. }) && !self.prog.wire_floats.is_empty();
        if let Some(Ok(q)) = chooses.then(|| goals::build_integer_witnesses(self.prog, ob, part)).flatten() {
            stats.queries += 1;
            if matches!(self.solve(q, index, k, false, false, stats), Answer::Unsat) {
                return Answer::Unsat;
            }
        }
        stats.queries += 1;
        match goals::build(self.prog, ob, part) {
            Err(Unsupported(what)) => Answer::Unknown(Why::Unsupported(what)),
            Ok(q) => self.solve(q, index, k, !part.is_sat_question() && *part != Part::Context, !example, stats),
        }
    }

    /// Solves `q`. Without `model`, a satisfiable answer found under other names serves
    /// (sat questions need the verdict, not the witness), and with `guess` too a point
    /// guessed from the query's definitions (`guess.rs`), whose values are not reported.
    fn solve(&self, q: Query, index: usize, k: usize, model: bool, guess: bool, stats: &mut Stats) -> Answer {
        let label = self.labels.get(index).cloned().unwrap_or_else(|| format!("obligation-{index}"));
        let solver_of = |q: &Query| {
            let solver = solver_for(q);
            for a in q.assertions.iter().chain(q.enc.side_conditions()) {
                solver.assert(a);
            }
            solver
        };
        // `--dump`: every query's text, answered from the cache or not.
        let mut solver = None;
        if let Some(dump) = &self.cfg.dump {
            if !self.caches.dump_failed.load(Ordering::Relaxed) {
                let s = solver.insert(solver_of(&q));
                let n = self.caches.dumped.fetch_add(1, Ordering::Relaxed);
                let name = format!("{n:05}-{label}-{k}");
                if let Err(e) = dump(&name, &format!("; mochi: {label}, part {k}\n{s}(check-sat)\n")) {
                    // The first failure is reported (with this obligation); later ones
                    // would only repeat it.
                    if !self.caches.dump_failed.swap(true, Ordering::Relaxed) {
                        stats.dump_error = Some(format!("{name}: {e}"));
                    }
                }
            }
        }
        // The exact key first (any answer); then the key up to renaming of the free
        // constants, which only answers without a model carry over (the model's names
        // differ). Both are read off the terms: a query answered here builds no solver.
        let keys = (!self.cfg.no_cache).then(|| key::of(&q, q.enc.logic()));
        let cached = |key: &String| self.caches.cache.lock().ok().and_then(|c| c.get(key).cloned());
        if let Some(keys) = &keys {
            if let Some(a) = cached(&keys.exact) {
                stats.cached += 1;
                // The same query may come from other values of the same names: where this
                // query's values are bound is this query's.
                return match a {
                    Answer::Sat { values, overlap, exact, .. } => {
                        Answer::Sat { values, overlap, bound: q.enc.shared_names(), exact }
                    }
                    other => other,
                };
            }
            if let Some(a) = keys.canonical.as_ref().and_then(cached) {
                if !model || !matches!(a, Answer::Sat { .. }) {
                    stats.cached += 1;
                    return a;
                }
            }
        }
        // A sat question whose definitions give a point that satisfies it: a model.
        if !model && guess && !self.cfg.no_cache && guess::satisfied(&q) {
            stats.witnessed += 1;
            return Answer::Sat { values: Vec::new(), overlap: None, bound: Vec::new(), exact: Default::default() };
        }
        let solver = solver.unwrap_or_else(|| solver_of(&q));
        let seq = self.watchdog.arm(self.timeout);
        #[cfg(test)]
        pool::maybe_hang(&label);
        let mut result = solver.check();
        let mut timed_out = self.watchdog.disarm(seq);
        // A sat question needs a genuine witness, and a model of a query that encloses
        // `sin`, `cos` or `pi` may give them values the real functions do not take
        // (`x == sin(1) && x == 0.8414709848078965` has such a model and no real
        // solution). The witness is confirmed in exact arithmetic ([`confirm`]); failing
        // that, one is looked for with every trigonometric argument 0, where the
        // enclosures are exact, and confirmed the same way. Neither: unknown.
        // (Counterexamples are replayed in exact arithmetic instead, [`replay`].)
        let mut unconfirmed = None;
        if !model && matches!(result, z3::SatResult::Sat) && q.enc.encloses() {
            let first = match solver.get_model() {
                Some(m) => confirm::confirm(&q, &m),
                None => Err("the solver gave no model".into()),
            };
            if let Err(why) = first {
                let mut second = Err(why);
                if q.enc.has_trig() {
                    for pin in q.enc.trig_at_zero() {
                        solver.assert(&pin);
                    }
                    let seq = self.watchdog.arm(self.timeout);
                    let r = solver.check();
                    timed_out |= self.watchdog.disarm(seq);
                    if matches!(r, z3::SatResult::Sat) {
                        if let Some(m) = solver.get_model() {
                            second = confirm::confirm(&q, &m);
                        }
                    }
                }
                if let Err(why) = second {
                    result = z3::SatResult::Unknown;
                    unconfirmed = Some(why);
                }
            }
        }
        let answer = match result {
            z3::SatResult::Unsat => Answer::Unsat,
            z3::SatResult::Sat => match solver.get_model() {
                // (A sat question's witness was confirmed above, whatever values the
                // model gives the enclosed functions.)
                Some(m) if model && q.enc.spurious_trig(&m) => Answer::Unknown(Why::Incomplete(
                    "its counterexample gives sin/cos values the real functions do not take (the encoding encloses them)"
                        .into(),
                    Hard::of(&q),
                )),
                Some(m) => {
                    let overlap = q.point.as_ref().map(|p| Overlap {
                        point: [0, 1, 2].map(|i| encode::Encoder::value_of(&m, &p[i]).unwrap_or(f64::NAN)),
                        times: q.times.iter().map(|t| encode::Encoder::value_of(&m, t).unwrap_or(f64::NAN)).collect(),
                        not_before: None,
                    });
                    Answer::Sat {
                        values: q.enc.assignments(&m),
                        overlap,
                        bound: q.enc.shared_names(),
                        exact: replay::valuation(&q.enc, &m),
                    }
                }
                None => Answer::Sat { values: Vec::new(), overlap: None, bound: Vec::new(), exact: Default::default() },
            },
            z3::SatResult::Unknown if timed_out => Answer::Unknown(Why::Timeout(self.timeout, Hard::of(&q))),
            z3::SatResult::Unknown if unconfirmed.is_some() => Answer::Unknown(Why::Incomplete(
                format!(
                    "its witness holds only of the encoding's enclosure of `sin`, `cos` or `pi`, not of the real functions' values ({})",
                    unconfirmed.unwrap_or_default()
                ),
                Hard::of(&q),
            )),
            z3::SatResult::Unknown => Answer::Unknown(Why::Incomplete(
                solver.get_reason_unknown().unwrap_or_else(|| "unknown".into()),
                Hard::of(&q),
            )),
        };
        // A timeout depends on the machine's load: do not cache it.
        if let Some(keys) = keys.filter(|_| !matches!(answer, Answer::Unknown(Why::Timeout(..)))) {
            if let Ok(mut c) = self.caches.cache.lock() {
                if let Some(canonical) = keys.canonical {
                    c.insert(canonical, answer.clone());
                }
                c.insert(keys.exact, answer.clone());
            }
        }
        answer
    }
}

/// A solver for `q`. Z3's default solver spends ~5 ms per check choosing a strategy;
/// naming the logic skips that (nlsat: complete for nonlinear real arithmetic). Queries
/// with integer variables keep the default solver. The encoder says which (it declared
/// the variables), not the query's text.
pub(crate) fn solver_for(q: &Query) -> z3::Solver {
    match q.enc.logic() {
        Logic::Nra => z3::Solver::new_for_logic("QF_NRA").unwrap_or_default(),
        Logic::WithIntegers => z3::Solver::new(),
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
        (Goal::Compatible { parts }, Part::CanEnd) => {
            let all: Vec<String> =
                parts.iter().map(|(r, a)| format!("`{}` ({})", prim(a), prog.role_name(*r))).collect();
            format!(
                "{} can end{}: from what is known when {} and the precondition{}, some time t in {} duration at which {} guarantee (at 0 and at t), postcondition and robot invariant hold together",
                all.join(", "),
                if parts.len() > 1 { " together" } else { "" },
                if parts.len() > 1 { "they start" } else { "it starts" },
                if parts.len() > 1 { "s" } else { "" },
                if parts.len() > 1 { "every part's" } else { "its" },
                if parts.len() > 1 { "every part's" } else { "its" },
            )
        }
        (Goal::CanEnd { prim: p }, Part::Occupies) => {
            format!(
                "the footprint of `{}` holds some point when it starts, for some arguments and start state its precondition and the invariant allow",
                prog.prim(*p).name
            )
        }
        (Goal::Contains { prim: p }, Part::Contains(k)) => {
            let prim = prog.prim(*p);
            let what =
                prog.kind(prim.kind).body.as_ref().and_then(|b| b.parts.get(*k)).map_or("?", |part| match part.shape {
                    crate::hir::body::Shape::Box(_) => "box",
                    crate::hir::body::Shape::Sphere(_) => "sphere",
                    crate::hir::body::Shape::Cylinder(..) => "cylinder",
                    crate::hir::body::Shape::Capsule(..) => "capsule",
                    crate::hir::body::Shape::Urdf { .. } => "URDF",
                    crate::hir::body::Shape::Mesh { .. } => "mesh",
                });
            format!(
                "the footprint of `{}` contains the robot's body (its {what}, part {} of `geometry:`) at every time and state its guarantee allows",
                prim.name,
                k + 1
            )
        }
        (Goal::CanEnd { prim: p }, _) => {
            let p = prog.prim(*p);
            format!(
                "`{}` can end: for some arguments and some start state allowed by its precondition and the invariant, some time t in its duration and an end state at which its guarantee (at 0 and at t), postcondition and invariant hold",
                p.name
            )
        }
        (Goal::Reachable { .. }, _) if ob.rule == crate::obligation::Rule::InitInvariant => {
            format!("some state satisfies both {} and the kind's invariant", ob.what)
        }
        (Goal::Reachable { .. }, _) if ob.rule == crate::obligation::Rule::EnumEntry => ob.what.clone(),
        (Goal::Reachable { .. }, _) => format!("{} is satisfiable", ob.what),
        (Goal::Valid(goal), Part::Conjunct(k)) => {
            format!("{}: `{}`", ob.what, crate::hir::print::expr(prog, None, goal.conjuncts()[*k]))
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
        (Goal::Compatible { parts }, Part::ClearOf { i, o }) => format!(
            "the footprint of `{}` ({}) never meets obstacle `{}`",
            prim(&parts[*i].1),
            prog.role_name(parts[*i].0),
            prog.obstacles.get(*o).map_or("?", |x| x.name.as_str())
        ),
        (Goal::Compatible { parts }, Part::Within(n, j)) => format!(
            "the duration of the non-interruptible `{}` ({}) lies within that of `{}` ({})",
            prim(&parts[*n].1),
            prog.role_name(parts[*n].0),
            prim(&parts[*j].1),
            prog.role_name(parts[*j].0)
        ),
        (Goal::Compatible { parts }, Part::CommonEnd(n, j)) => {
            let lasts = |i: usize| {
                let p = prog.prim(parts[i].1.prim);
                // The bounds with the arguments put in (`[d, d]` of `stroke(20)` is
                // `[20, 20]`), a constant printed as its value.
                let bound = |e: &crate::hir::Expr| {
                    let e = crate::sigma::instantiate(e, parts[i].0, &parts[i].1.args);
                    match crate::exact::eval(prog, &e, &|_: &crate::hir::Var| None) {
                        Ok(crate::exact::Value::Num(n))
                            if n.is_exact() && !crate::exact::decimal(&n.lo).starts_with('≈') =>
                        {
                            crate::exact::decimal(&n.lo)
                        }
                        _ => crate::hir::print::expr(prog, None, &e),
                    }
                };
                let lo = bound(&p.duration.lo);
                let hi = p.duration.hi.as_ref().map(bound);
                format!(
                    "`{}` ({}, duration [{lo}, {}])",
                    prim(&parts[i].1),
                    prog.role_name(parts[i].0),
                    hi.as_deref().unwrap_or("inf")
                )
            };
            format!(
                "the non-interruptible {} and {} end together: both durations are the same single instant (joint end)",
                lasts(*n),
                lasts(*j)
            )
        }
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
        (Goal::Separated { .. }, Part::RegionsApart(a, b)) => {
            format!("the regions of sides {} and {} of the written partition are disjoint", a + 1, b + 1)
        }
        (Goal::Separated { sides }, Part::InRegion { a, ra }) => {
            let run = &sides[*a].runs[*ra];
            format!(
                "the footprint of `{}` ({}) stays in the region the partition gives side {}",
                prim(&run.app),
                prog.role_name(run.role),
                a + 1
            )
        }
        (Goal::Refines { concrete, abstract_, .. }, Part::Refine(item)) => {
            let abs: Vec<String> = abstract_.iter().map(prim).collect();
            format!("`{}` refines `{}`: {}", prim(concrete), abs.join(" /\\ "), item.text())
        }
        (Goal::InitiallyDisjoint { firsts }, Part::InitiallyApart { r, s }) => {
            format!(
                "`{}` and `{}` start apart (their first footprints at time 0 are disjoint)",
                prog.role_name(firsts[*r].0),
                prog.role_name(firsts[*s].0)
            )
        }
        _ => ob.what.clone(),
    }
}

#[cfg(test)]
pub(crate) mod tests {
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

    fn valid(consts: &str, p: &str) -> Validity {
        let (prog, e) = pred(consts, p);
        check_valid(&prog, &[], &e, &SmtConfig::default())
    }

    #[test]
    fn linear_arithmetic_is_decided() {
        assert_eq!(valid("", "x > 1 => x > 0"), Validity::Holds);
        assert_eq!(valid("const lane = 0.65;", "x >= lane => x > 0.6"), Validity::Holds);
        assert_eq!(valid("", "n > 1 => 2 * n >= 4"), Validity::Holds);
        assert_eq!(valid("", "(if b then x else 0 - x) >= 0 || (b && x < 0) || (!b && x > 0)"), Validity::Holds);
        assert_eq!(valid("", "min(x, 1) <= 1 && abs(x) >= 0"), Validity::Holds);
        assert_eq!(valid("", "x == -0.5 => x < 0"), Validity::Holds);
    }

    /// Two payload fields named `v` are two values: two Z3 constants, shown as `v` and
    /// `v#2`. (Before, both were the constant `v`, so `v == 1` and `v == 2` were
    /// contradictory hypotheses and every goal held.)
    #[test]
    fn same_named_values_are_distinct_constants() {
        use crate::hir::expr::BinOp;
        use crate::hir::Sort;
        let src = "robot R { state x: real; }
             system S { participant A: R; participant B: R; }
             choreography G = A -> B : first(v: real {v == 1}). A -> B : second(v: real {v == 2}). end;";
        let (prog, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("expected a sequence")
        };
        let hyps: Vec<Expr> = items
            .iter()
            .filter_map(|g| match g {
                crate::hir::Global::Msg(m) => m.payload[0].refinement.clone(),
                _ => None,
            })
            .collect();
        assert_eq!(hyps.len(), 2);
        // Goal: first + second == 3 - 1, which fails (it is 3); read as one `v`, the
        // hypotheses contradict each other and it "holds".
        let lhs = |e: &Expr| match &e.kind {
            crate::hir::ExprKind::Binary(_, a, _) => (**a).clone(),
            _ => panic!("an equation"),
        };
        let bin = |op, a: Expr, b: Expr| Expr {
            kind: crate::hir::ExprKind::Binary(op, Box::new(a), Box::new(b)),
            sort: if op == BinOp::Eq { Sort::Bool } else { Sort::Real },
            loc: crate::hir::Loc::default(),
        };
        let two = Expr { kind: crate::hir::ExprKind::Int(2), sort: Sort::Int, loc: crate::hir::Loc::default() };
        let goal = bin(BinOp::Eq, bin(BinOp::Add, lhs(&hyps[0]), lhs(&hyps[1])), two);
        let Validity::Fails(model) = check_valid(&prog, &hyps, &goal, &SmtConfig::default()) else {
            panic!("v + v#2 == 2 does not follow from v == 1 and v#2 == 2: two values, not one")
        };
        let value = |n: &str| model.iter().find(|a| a.name == n).map(|a| a.value.clone());
        assert_eq!(value("v").as_deref(), Some("1"), "{model:?}");
        assert_eq!(value("v#2").as_deref(), Some("2"), "{model:?}");
    }

    #[test]
    fn a_counterexample_names_the_variables() {
        let Validity::Fails(model) = valid("", "x > 0") else { panic!("x > 0 is not valid") };
        let x = model.iter().find(|a| a.name == "A.x").expect("A.x in the model");
        let v: f64 = x.value.parse().unwrap_or(1.0);
        assert!(v <= 0.0, "the counterexample must falsify x > 0: {model:?}");
    }

    #[test]
    fn sqrt_and_powers_are_encoded_soundly() {
        assert_eq!(valid("", "x >= 0 => sqrt(x)^2 == x"), Validity::Holds);
        assert_eq!(valid("", "x^2 >= 0"), Validity::Holds);
        // (Guarded: a model with `x < 0`, where `sqrt(x)` is undefined, falsifies nothing.)
        assert!(matches!(valid("", "x >= 0 => sqrt(x) >= 1"), Validity::Fails(_)));
    }

    #[test]
    fn trigonometry_is_enclosed_soundly() {
        assert_eq!(valid("", "sin(x)^2 + cos(x)^2 == 1"), Validity::Holds);
        assert_eq!(valid("", "-1 <= sin(x) <= 1 && cos(x) <= 1"), Validity::Holds);
        assert_eq!(valid("", "0 <= x <= 0.1 => sin(x) >= 0 && cos(x) >= 0.99"), Validity::Holds);
        assert_eq!(valid("const yaw = 1.5708;", "cos(yaw) < 0.0001 && sin(yaw) > 0.9999"), Validity::Holds);
        // False, with a real counterexample near 0 (the enclosure is tight there).
        assert!(matches!(valid("", "0 <= x <= 0.1 => sin(x) >= 0.05"), Validity::Fails(_)));
        // True of the real functions but beyond the polynomial enclosure: never "fails".
        assert!(matches!(
            valid("", "sin(x) <= 0.999 || cos(x) <= 0.5 || cos(x) >= 0"),
            Validity::Holds | Validity::Unknown(_)
        ));
        assert!(!matches!(valid("", "cos(x) >= -0.5 || x^2 >= 4"), Validity::Fails(_)));
    }

    #[test]
    fn trig_of_a_constant_that_is_not_written_as_one_is_enclosed() {
        // The argument mentions `x` but simplifies to the rational 0.7853981633974483,
        // whose denominator (10^16) exceeds 2^53: before, only the Taylor bounds applied
        // (cos <= 0.70745) and this was not proved; now the numeral is read exactly.
        assert_eq!(valid("", "cos(x - x + 0.7853981633974483) <= 0.7072"), Validity::Holds);
        assert_eq!(valid("", "sin(x - x + 0.7853981633974483) >= 0.7071"), Validity::Holds);
        // The enclosure stays sound: cos(pi/4) is 0.70710678..., not below 0.70710678.
        assert!(matches!(
            valid("", "cos(x - x + 0.7853981633974483) < 0.70710678"),
            Validity::Fails(_) | Validity::Unknown(_)
        ));
    }

    #[test]
    fn points_and_vectors_are_triples() {
        assert_eq!(valid("", "norm2(vector(x, 0, 0)) == x^2"), Validity::Holds);
        assert_eq!(valid("", "dot(point(1, 2, 3), vector(x, x, x)) == 6 * x"), Validity::Holds);
        assert_eq!(valid("", "(point(x, 1, 2) - point(0, 1, 2)).x == x"), Validity::Holds);
    }

    /// [T-SESS] on two bots (radius 0.1, footprint the ball) placed `gap` apart.
    fn initially_apart(gap: &str) -> Decision {
        let src = format!(
            "robot Bot {{ state s: real; }}
             motion Bot.hold {{ interruptible: true; footprint(x, y, z): x^2 + y^2 + z^2 <= 0.01; }}
             system S {{ participant A: Bot {{ init: s == 0; }} participant B: Bot {{ init: s == 0; at: pose({gap}, 0, 0); }} }}
             choreography G = dt<A: hold> * dt<B: hold>;"
        );
        initial_states(&src)
    }

    /// Lowers `src` (which must be clean) and decides its [T-SESS] obligation: the first
    /// footprints of the participants, from their initial states, are disjoint.
    pub(crate) fn initial_states(src: &str) -> Decision {
        let (prog, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let hyps = prog.roles.iter().filter_map(|r| r.init.clone()).collect();
        let ob = Obligation {
            rule: crate::obligation::Rule::TSess,
            span: Default::default(),
            what: "initial states".into(),
            hyps,
            goal: Goal::InitiallyDisjoint { firsts: prog.first_motions() },
        };
        discharge(&prog, &[ob], &[], &SmtConfig::default()).remove(0).0
    }

    #[test]
    fn initially_apart_holds_for_distant_bots_and_fails_for_touching_ones() {
        assert!(matches!(initially_apart("0.5"), Decision::Holds(_)));
        let Decision::Fails(f) = initially_apart("0.15") else { panic!("the balls overlap") };
        let o = f.overlap.expect("a point");
        assert!(o.point[0] >= 0.05 - 1e-9 && o.point[0] <= 0.1 + 1e-9, "{o:?}");
    }

    #[test]
    fn an_input_is_its_source_state() {
        // `C.d` is an input connected to `E.d` (Sec 3.1): knowing one is knowing the other.
        let src = "robot Car { state x: real; input d: real; } robot Env { state d: real; }
             system S { participant C: Car; participant E: Env; }
             choreography G = C -> E : [d == 0] go. E -> C : [d == 0] back. end;";
        let (prog, d) = lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("expected a sequence")
        };
        let guard = |i: usize| match &items[i] {
            crate::hir::Global::Msg(m) => m.guard.clone().expect("guard"),
            _ => panic!("expected a message"),
        };
        let (car_d, env_d) = (guard(0), guard(1));
        assert_eq!(check_valid(&prog, std::slice::from_ref(&car_d), &env_d, &SmtConfig::default()), Validity::Holds);
        assert_eq!(check_valid(&prog, &[env_d], &car_d, &SmtConfig::default()), Validity::Holds);
    }

    /// The vacuity guard's witness point never calls an unsatisfiable context
    /// satisfiable, and finds the common satisfiable ones without Z3.
    #[test]
    fn witness_boxes_are_models() {
        let cases = [
            ("const dy = 0.65;", "x == dy * 3.0 && 0 <= x <= 10 && n == 2 && m >= n + 1", true),
            ("", "x == 0.1 + 0.2 && x > 0.29", true),
            ("", "x == 0 && x == 1", false),
            ("", "x >= 1 && x <= 0", false),
            ("", "x == 0.1 + 0.2 && x == 0.3", true), // exact rationals, not doubles
            ("", "x == 0.1 && x >= 0.1000000000000000001", false), // equal as doubles only
            ("", "x == 1.0 / 3 && 3 * x == 1 && (x < 0 => n >= 1)", true),
            ("", "x > 1 && x < 1.5 && n > 0 && n < 1", false),
            ("", "x * x == 2 && x > 0", false),
        ];
        for (consts, p, expected) in cases {
            let (prog, e) = pred(consts, p);
            let facts: Vec<Expr> = e.conjuncts().into_iter().cloned().collect();
            let shown = goals::witnessed(&prog, &facts);
            assert_eq!(shown, expected, "{p}");
            if shown {
                // A witness is a model: Z3 agrees the facts are satisfiable.
                let none = Expr::bool(false, crate::hir::Loc::default());
                assert!(matches!(check_valid(&prog, &facts, &none, &SmtConfig::default()), Validity::Fails(_)), "{p}");
            }
        }
    }

    /// The hard limit: a query during which Z3 ignores the watchdog (the test hook hangs
    /// the worker inside its armed query) is abandoned at its limit plus the grace, its
    /// obligation is unknown with a note saying so, and a replacement worker decides the
    /// rest. Once [`pool::MAX_ABANDONED`] workers are abandoned, the obligations not yet
    /// started are unknown without running. (Before the pool, `discharge` never returned.)
    #[test]
    fn a_query_that_ignores_the_interrupt_is_abandoned_at_the_limit() {
        use std::time::Instant;
        let (prog, e) = pred("", "x > 1 => x > 0");
        let ob = Obligation {
            rule: crate::obligation::Rule::TOut,
            span: Default::default(),
            what: "a guard".into(),
            hyps: Vec::new(),
            goal: Goal::Valid(e),
        };
        if let Ok(mut h) = pool::HANG.lock() {
            *h = Some("hang-me".into());
        }
        let limit = Duration::from_millis(300);
        let cfg = SmtConfig { timeout: limit, jobs: 1, ..SmtConfig::default() };
        let bound = limit + pool::grace(limit);
        // Slack for a loaded machine: the pool wakes at the bound, then reports.
        let slack = Duration::from_millis(1500);
        let abandoned = |d: &Decision| match d {
            Decision::Unknown { why: w @ Why::Abandoned(after), .. } => {
                assert!(*after >= bound && *after < bound + slack, "{after:?}");
                assert!(w.to_string().contains("did not stop when asked"), "{w}");
                true
            }
            _ => false,
        };
        // One hung query among good ones: abandoned; the others still decided.
        let labels: Vec<String> = ["hang-me-1", "fine-1", "fine-2"].map(String::from).to_vec();
        let t = Instant::now();
        let r = discharge(&prog, &[ob.clone(), ob.clone(), ob.clone()], &labels, &cfg);
        let took = t.elapsed();
        assert!(took >= bound && took < bound + slack, "{took:?}");
        assert!(abandoned(&r[0].0), "{:?}", r[0].0);
        assert!(matches!(r[1].0, Decision::Holds(_)) && matches!(r[2].0, Decision::Holds(_)), "{r:?}");
        // As many hung queries as the cap: the rest is not run.
        let mut labels: Vec<String> = (0..pool::MAX_ABANDONED).map(|i| format!("hang-me-{i}")).collect();
        labels.extend(["fine-1".to_string(), "fine-2".to_string()]);
        let obs = vec![ob; labels.len()];
        let t = Instant::now();
        let r = discharge(&prog, &obs, &labels, &cfg);
        let took = t.elapsed();
        pool::release_hung();
        assert!(took < (bound + slack) * pool::MAX_ABANDONED as u32, "{took:?}");
        for d in &r[..pool::MAX_ABANDONED] {
            assert!(abandoned(&d.0), "{d:?}");
        }
        for d in &r[pool::MAX_ABANDONED..] {
            assert!(matches!(&d.0, Decision::Unknown { why: Why::NotRun(s), .. } if s.contains("abandoned")), "{d:?}");
        }
    }

    /// The solver is chosen from the variables the encoder declared (an `Int`: the default
    /// solver; reals only: nlsat), and agrees with what the query's text declares.
    #[test]
    fn the_logic_is_the_encoders_decision() {
        for (p, ints) in [("x > 1 => x > 0", false), ("n > 1 => 2 * n >= 4", true), ("x > 0 || n >= 0 || b", true)] {
            let (prog, e) = pred("", p);
            let ob = Obligation {
                rule: crate::obligation::Rule::TOut,
                span: Default::default(),
                what: String::new(),
                hyps: Vec::new(),
                goal: Goal::Valid(e),
            };
            let q = goals::build(&prog, &ob, &Part::Valid).unwrap_or_else(|_| panic!("{p} encodes"));
            let logic = q.enc.logic();
            assert_eq!(logic == Logic::WithIntegers, ints, "{p}");
            let solver = solver_for(&q);
            for a in q.assertions.iter().chain(q.enc.side_conditions()) {
                solver.assert(a);
            }
            assert_eq!(solver.to_string().contains(" () Int)"), ints, "{p}");
        }
    }

    #[test]
    fn a_timeout_is_unknown() {
        // Fermat's last theorem for cubes: true, but beyond Z3's nonlinear integer
        // reasoning, and given 1 ms. Whatever Z3 says, it must not be "holds" or "fails".
        let (prog, e) = pred("", "n > 0 && m > 0 && k > 0 => n^3 + m^3 != k^3");
        let cfg = SmtConfig { timeout: Duration::from_millis(1), ..SmtConfig::default() };
        match check_valid(&prog, &[], &e, &cfg) {
            Validity::Unknown(_) => {}
            other => panic!("expected unknown, got {other:?}"),
        }
    }
}
