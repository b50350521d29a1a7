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
mod describe;
mod encode;
pub mod goals;
mod guess;
pub mod hard;
mod key;
pub mod pool;
pub mod replay;
mod worker;

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
pub(crate) use worker::solver_for;
use worker::{work, Caches};

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
    /// and bound, [`crate::collision`]) stopped without deciding: why.
    Search(String),
    /// An interval search stopped without deciding: why. Body containment against
    /// stand-ins (`space::enclose`: a URDF or mesh part under a predicate footprint, or a
    /// footprint with a URDF or mesh part as the container), for which no SMT query is
    /// posed (the encoding has no predicate for a URDF or a mesh); or a footprint predicate
    /// turned by the state against an obstacle (`collision::predicate`), whose questions
    /// Z3's nonlinear arithmetic does not decide.
    Interval(String),
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
            Why::Interval(s) => write!(f, "the interval search stopped without deciding: {s}"),
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

/// The requirement of `part` of `ob` in words, as the note "required: ..." of a failed
/// part shows it (before any note on the engine that found the counterexample).
pub fn describe_part(prog: &Program, ob: &Obligation, part: &Part) -> String {
    describe::describe(prog, ob, part)
}

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

#[cfg(test)]
pub(crate) mod tests;
