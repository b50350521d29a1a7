//! The driver: the only place where stages are wired together. Given a file in a
//! [`SourceDb`] and a loader for its imports (the IO stays at the edge, `fsload`), it runs
//! each stage whose inputs are free of errors, times it, and turns the result into a
//! [`Report`] with a [`Verdict`]. The report is data: `render` formats it.
//!
//! **Architecture invariant:** the verdict is `Verified` only when every check ran and
//! passed; any undecided obligation makes it `Unknown`, any error `Rejected`.

use crate::collision::PairClearance;
use crate::diag::{self, Code, Counterexample, Diagnostic};
use crate::hir::print;
use crate::obligation::{Goal, Obligation, Rule};
use crate::smt::{self, goals::Part, Decision, SmtConfig};
use crate::source::{FileId, SourceDb};
use crate::{library, lower, plan, project, space, subtype, syntax, typeck, wf};
use serde::Serialize;
use std::collections::{BTreeMap, HashSet};
use std::time::Instant;

mod explain;

use explain::*;

/// What the user asked for.
#[derive(Clone, Debug, Default)]
pub struct Config {
    /// How the SMT stage runs (timeout, threads, dump directory, progress bar).
    pub smt: SmtConfig,
    /// Stop after the structural checks (for `mochi project`): obligations are then
    /// reported as undecided.
    pub structural_only: bool,
    /// The per-query timeout (`smt.timeout`) was cut to the time left before the run's
    /// `--deadline`: a query that runs out then says so, rather than "raise --timeout".
    pub cut_by_deadline: bool,
    /// `--clearance`: after the verdict, the least distance between the bodies of each pair
    /// that moves together, certified to within this tolerance (m) ([`Report::clearances`]).
    pub clearance: Option<f64>,
}

impl Config {
    /// The default with a per-query limit of 60 s, for the golden and rejected-variants
    /// suites: they run debug builds (10 to 30 times slower than release) on a shared
    /// machine, where a geometric search that release finishes in a second may need twenty;
    /// with the default 10 s such a verdict would depend on the load. The searches are
    /// deterministic within their limits (node budgets, fixed probe sequences), so the
    /// verdicts and reports are then the same on every run.
    pub fn patient() -> Config {
        let mut c = Config::default();
        c.smt.timeout = std::time::Duration::from_secs(60);
        c
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Verified,
    Rejected,
    Unknown,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Pass,
    Fail,
    Unknown,
}

/// One check that ran, how it ended and how long it took.
#[derive(Clone, Debug, Serialize)]
pub struct CheckResult {
    pub name: &'static str,
    pub status: Status,
    pub millis: f64,
    /// What the check found, as counts; `render` words it ("3 obligation(s), 5 queries").
    #[serde(skip)]
    pub detail: Detail,
    /// SMT queries this check made (0 for the structural checks).
    pub queries: usize,
}

/// The counts behind a check's line in the table. Data only: `render` formats it (its
/// `Display` is the table's wording).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Detail {
    /// Nothing to add (a structural check that passed).
    #[default]
    None,
    /// A structural check that failed with this many errors.
    Errors(usize),
    /// A family of obligations decided by the SMT stage.
    Obligations {
        total: usize,
        queries: usize,
        /// Queries answered from the cache.
        cached: usize,
        /// Obligations settled without Z3 (bounds, folding).
        folded: usize,
        /// Collision questions the geometric procedure decided (branch and bound; Z3 only
        /// for witnesses), not counted in `queries`.
        geometric: usize,
        failed: usize,
        undecided: usize,
        /// Obligations that held only because their context is unsatisfiable.
        vacuous: usize,
    },
    /// Obligations not decided because only the structural checks ran (`mochi project`).
    NotDecided(usize),
    /// The vacuity guard: of `proved` obligations with hypotheses, `vacuous` held only
    /// because their context is unsatisfiable; `unsure` contexts were undecided.
    Vacuity { vacuous: usize, proved: usize, unsure: usize },
    /// The file was not started: the run's `--deadline` (in seconds) had passed.
    PastDeadline { seconds: f64 },
}

/// A check's detail as the table shows it: `11 obligation(s), 18 queries (5 cached), 2
/// without Z3`, `1 error(s)`; empty for [`Detail::None`].
impl std::fmt::Display for Detail {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Detail::None => Ok(()),
            Detail::Errors(n) => write!(f, "{n} error(s)"),
            Detail::NotDecided(n) => write!(f, "{n} not decided (structural checks only)"),
            Detail::PastDeadline { seconds } => write!(f, "not checked: the --deadline of {seconds} s had passed"),
            Detail::Obligations { total, queries, cached, folded, geometric, failed, undecided, vacuous } => {
                write!(f, "{total} obligation(s), {queries} quer{}", if queries == 1 { "y" } else { "ies" })?;
                if cached > 0 {
                    write!(f, " ({cached} cached)")?;
                }
                if folded > 0 {
                    write!(f, ", {folded} without Z3")?;
                }
                if geometric > 0 {
                    write!(f, ", {geometric} by the geometric procedure")?;
                }
                if failed > 0 {
                    write!(f, ", {failed} failed")?;
                }
                if undecided > 0 {
                    write!(f, ", {undecided} undecided")?;
                }
                if vacuous > 0 {
                    write!(f, ", {vacuous} held vacuously")?;
                }
                Ok(())
            }
            Detail::Vacuity { vacuous, proved, unsure } => {
                write!(
                    f,
                    "{vacuous} of {proved} proved obligation(s) held only because their context is unsatisfiable"
                )?;
                if unsure > 0 {
                    write!(f, ", {unsure} context(s) undecided")?;
                }
                Ok(())
            }
        }
    }
}

/// Everything `mochi check` learns about one file.
#[derive(Debug)]
pub struct Report {
    pub verdict: Verdict,
    pub diagnostics: Vec<Diagnostic>,
    pub checks: Vec<CheckResult>,
    /// Role name → its local type printed in mochi's notation (when projection ran).
    pub projections: BTreeMap<String, String>,
    /// How each `*` was found separated (the inferred partitions), for `--verbose`.
    pub partitions: Vec<String>,
    /// The same, structured, for every `*` found separated (written partitions too), for
    /// `--format json`.
    pub separations: Vec<Separation>,
    /// Obligations that held only because their hypotheses are unsatisfiable (the
    /// vacuity guard's count; each such point is unreachable or reported).
    pub vacuous: usize,
    /// The program and the obligations the SMT stage was asked to decide (`None` when a
    /// structural check stopped the run first), for tests and tools that look behind a
    /// verdict (the golden test re-evaluates each counterexample against its goal).
    pub planned: Option<Planned>,
    /// With [`Config::clearance`], per pair of bodies that move together, their least
    /// distance (computed on the planned obligations, after the verdict).
    pub clearances: Vec<PairClearance>,
}

/// What the structural stages handed to the SMT stage.
#[derive(Debug)]
pub struct Planned {
    pub program: crate::hir::Program,
    pub obligations: Vec<Obligation>,
}

/// How one `*` was found separated.
#[derive(Clone, Debug, Serialize)]
pub struct Separation {
    /// Where the `*` is (1-based line and column; `None` outside the loaded files).
    pub file: Option<String>,
    pub line: Option<usize>,
    pub column: Option<usize>,
    /// `written` (the choreography's `partition` clause), `inferred` (disjoint boxes around
    /// the sides' footprints) or `queries` (footprints proved apart pair by pair).
    pub how: &'static str,
    /// The coordinate names a written partition's regions use.
    pub point: Option<[String; 3]>,
    pub sides: Vec<SeparationSide>,
}

/// One side of a `*`: its participants and its region.
#[derive(Clone, Debug, Serialize)]
pub struct SeparationSide {
    pub roles: Vec<String>,
    /// A written region, printed in mochi's notation.
    pub region: Option<String>,
    /// A box around the side's footprints, `[[x_lo, x_hi], [y_lo, y_hi], [z_lo, z_hi]]`
    /// in metres, where they can be bounded.
    #[serde(rename = "box")]
    pub bounds: Option<[[f64; 2]; 3]>,
}

/// The report of a root file that could be read but not taken as source (not UTF-8: its
/// E0107): rejected at the parse check, nothing else runs.
pub fn unreadable_root(d: Diagnostic) -> Report {
    let mut run = Pipeline::default();
    run.record("parse", vec![d]);
    run.finish()
}

/// Runs the pipeline on a file already in `db`; its imports, URDFs and meshes come from
/// `load` (the file system's loader is [`crate::fsload::read_bytes`]; source files are
/// decoded as UTF-8 by [`syntax::decode`]). The pipeline does no IO of its own.
pub fn check_loaded(db: &mut SourceDb, root: FileId, cfg: &Config, load: &mut syntax::ByteLoader<'_>) -> Report {
    let mut report = checks(db, root, cfg, load);
    if let (Some(tolerance), Some(p)) = (cfg.clearance, &report.planned) {
        report.clearances = crate::collision::clearances(&p.program, &p.obligations, tolerance, cfg.smt.timeout);
    }
    report
}

/// The stages every command shares, in order: [`prepare`] runs them up to the one asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Parsed with its imports and lowered: names resolved, sorts checked (`parse`, `names`).
    Names,
    /// Then the geometry stage: footprints as predicates where Z3 can decide them, every
    /// body as solids (`geometry`).
    Geometry,
}

/// The front of every pipeline, recorded in `run`: parse, names and, from [`Stage::Geometry`],
/// the geometry stage. `Some((program, library))` when none of them has an error; `library`
/// says the root is a `.mochi` library on its own (its missing system and choreography are
/// then no error, E0210) when `libraries` accepts one.
fn front(
    run: &mut Pipeline,
    db: &mut SourceDb,
    root: FileId,
    load: &mut syntax::ByteLoader<'_>,
    upto: Stage,
    libraries: bool,
) -> Option<(crate::hir::Program, bool)> {
    let mut text = |p: &std::path::Path| {
        load(p).and_then(|b| syntax::decode(b).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e)))
    };
    let (parsed, diags) = run.stage(|| syntax::parse_with_imports(db, root, &mut text));
    if !run.record("parse", diags) {
        return None;
    }
    let (mut prog, mut diags) = run.stage(|| lower::lower(&parsed));
    // A `.mochi` library on its own: no E0210, its kinds and primitives are checked.
    let library = libraries && library::is_library(db, root, &prog);
    if library {
        diags.retain(|d| d.code != Code::MissingItem);
    }
    if !run.record("names", diags) {
        return None;
    }
    if upto >= Stage::Geometry {
        // Bodies: sizes, and geometric footprints as predicates where Z3 can decide them;
        // then every body as solids (URDFs and meshes read here) for the geometric procedure.
        let diags = run.stage(|| geometry(&mut prog, db, load));
        if !run.record("geometry", diags) {
            return None;
        }
    }
    Some((prog, library))
}

/// Every check of `mochi check` on the file `root`, up to the verdict.
fn checks(db: &mut SourceDb, root: FileId, cfg: &Config, load: &mut syntax::ByteLoader<'_>) -> Report {
    let mut run = Pipeline::default();
    let Some((mut prog, library)) = front(&mut run, db, root, load, Stage::Geometry, true) else { return run.finish() };
    if library {
        library::synthetic_participants(&mut prog);
        let (obligations, notes) = run.stage(|| library::plan(&prog, root));
        run.record("library", notes);
        run.decide(db, prog, obligations, cfg);
        return run.finish();
    }
    let Some(chor) = &prog.choreography else { return run.finish() };
    // The three well-formedness checks, each timed on its own; synchronisability relies
    // on the other two.
    let diags = run.stage(|| wf::side::check(&prog, &chor.body));
    let side_ok = run.record("side-conditions", diags);
    let (mut obligations, diags) =
        run.stage(|| (plan::obligations(&prog, &chor.body), wf::scope::check(&prog, &chor.body)));
    let scope_ok = run.record("well-scoped", diags);
    if !(side_ok && scope_ok) {
        return run.finish();
    }
    // Asynchrony: the timeout crossing (E0326) with synchronisability on happens-before.
    let diags = run.stage(|| {
        let mut d = wf::sync::check(&prog, &chor.body);
        d.extend(plan::crossing::check(&prog, &chor.body));
        d
    });
    if !run.record("synchronisable", diags) {
        return run.finish();
    }
    let (locals, diags) = run.stage(|| project::project_all(&prog));
    for (role, t) in &locals {
        run.projections.insert(prog.role_name(*role).to_string(), print::local(&prog, t));
    }
    let projected = run.record("projection", diags);
    // [T-SUB]: a written `local R = T;` is a subtype of the projection, and R's process
    // is typed against T (`subtype::check_declared`).
    let mut types = locals.clone();
    if projected && !prog.locals.is_empty() {
        let (obs, declared, diags) = run.stage(|| subtype::check_declared(&prog, &locals));
        if run.record("declared-locals", diags) {
            obligations.extend(obs);
        }
        types = declared;
    }
    if projected {
        let (obs, diags, hints) = run.stage(|| typeck::check_processes_hinted(&prog, &types));
        run.hints = hints;
        if run.record("typing", diags) {
            obligations.extend(obs);
        }
    }
    if !cfg.structural_only {
        // The contract (E0409) of every primitive the protocol runs, decided last in the same worker pool
        // as the rest (a second pool would cost a Z3 context per worker, ~15 ms): a contract
        // that some use has already shown able to end needs no question of its own.
        let used = used_primitives(&obligations);
        obligations.extend(library::contracts(&prog, &used));
    }
    run.decide(db, prog, obligations, cfg);
    run.finish()
}

/// The geometry stage: bodies' sizes, geometric footprints as predicates where Z3 can
/// decide them ([`space::prepare`]); then every body as solids (URDFs and meshes read
/// through `load`) in `prog.world`.
fn geometry(prog: &mut crate::hir::Program, db: &mut SourceDb, load: &mut syntax::ByteLoader<'_>) -> Vec<Diagnostic> {
    let mut diags = space::prepare(prog);
    if !diags.iter().any(Diagnostic::is_error) {
        let (world, more) = space::world::build(prog, db, load);
        prog.world = Some(std::sync::Arc::new(world));
        if !more.iter().any(Diagnostic::is_error) {
            space::world::add_joint_limits(prog);
        }
        diags.extend(more);
    }
    diags
}

/// The program of the file `root` as the checks see it, prepared up to `upto` with no check
/// run (for `mochi simulate`, which asks for [`Stage::Geometry`]: footprint predicates and
/// solids, as the checks have them). `Err` holds the diagnostics when one of these stages
/// has an error (the warnings of a good run are dropped: `mochi check` reports them).
pub fn prepare(
    db: &mut SourceDb,
    root: FileId,
    load: &mut syntax::ByteLoader<'_>,
    upto: Stage,
) -> Result<crate::hir::Program, Vec<Diagnostic>> {
    let mut run = Pipeline::default();
    match front(&mut run, db, root, load, upto, false) {
        Some((prog, _)) => Ok(prog),
        None => Err(run.diagnostics),
    }
}

/// Accumulates diagnostics and check results while the stages run.
#[derive(Default)]
struct Pipeline {
    diagnostics: Vec<Diagnostic>,
    checks: Vec<CheckResult>,
    projections: BTreeMap<String, String>,
    partitions: Vec<String>,
    separations: Vec<Separation>,
    last_millis: f64,
    vacuous: usize,
    planned: Option<Planned>,
    /// Advice more precise than a code's help for some obligations (`typeck::Hints`).
    hints: typeck::Hints,
}

impl Pipeline {
    /// Times `f`; the time is attached by the next [`Pipeline::record`].
    fn stage<T>(&mut self, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let r = f();
        self.last_millis = t.elapsed().as_secs_f64() * 1000.0;
        r
    }

    /// Records a check's diagnostics; it passes when none is an error.
    fn record(&mut self, name: &'static str, diags: Vec<Diagnostic>) -> bool {
        let ok = !diags.iter().any(Diagnostic::is_error);
        let n = diags.iter().filter(|d| d.is_error()).count();
        self.checks.push(CheckResult {
            name,
            status: if ok { Status::Pass } else { Status::Fail },
            millis: self.last_millis,
            detail: if ok { Detail::None } else { Detail::Errors(n) },
            queries: 0,
        });
        self.diagnostics.extend(diags);
        ok
    }

    /// The end of every pipeline: unless a check failed, the obligations go to the SMT
    /// stage (and are handed out in the report, [`Report::planned`]), or, with
    /// `structural_only` (`mochi project`), are counted as not decided.
    fn decide(&mut self, db: &SourceDb, prog: crate::hir::Program, obligations: Vec<Obligation>, cfg: &Config) {
        if self.checks.iter().any(|c| c.status == Status::Fail) {
            return;
        }
        if cfg.structural_only {
            if !obligations.is_empty() {
                self.checks.push(CheckResult {
                    name: "obligations",
                    status: Status::Unknown,
                    millis: 0.0,
                    detail: Detail::NotDecided(obligations.len()),
                    queries: 0,
                });
            }
            return;
        }
        self.obligations(db, &prog, &obligations, cfg);
        self.planned = Some(Planned { program: prog, obligations });
    }

    /// Decides the obligations with the SMT stage, one check per rule family (total
    /// choice, compatibility, separation, typing obligations), each timed on its own.
    fn obligations(&mut self, db: &SourceDb, prog: &crate::hir::Program, obligations: &[Obligation], config: &Config) {
        let cfg = &config.smt;
        // One pool of workers for everything; the time of each check is the time its
        // obligations took on the workers.
        let labels: Vec<String> = obligations.iter().map(|o| label(db, o)).collect();
        let results = smt::discharge(prog, obligations, &labels, cfg);
        // A primitive that can never end (E0409), or whose footprint holds no point (E0412),
        // makes every motion using it unable to end too; that is said once, at its declaration.
        let never_ends: Vec<crate::hir::PrimId> = obligations
            .iter()
            .zip(&results)
            .filter_map(|(ob, (d, _))| match (&ob.goal, d) {
                (Goal::CanEnd { prim } | Goal::Occupies { prim }, Decision::Fails(_)) => Some(*prim),
                _ => None,
            })
            .collect();
        // A footprint that holds no point (E0412) contains no body either: said once.
        let empty: Vec<crate::hir::PrimId> = obligations
            .iter()
            .zip(&results)
            .filter_map(|(ob, (d, _))| match (&ob.goal, d) {
                (Goal::Occupies { prim }, Decision::Fails(_)) => Some(*prim),
                _ => None,
            })
            .collect();
        // A process's send that no value fits fails [T-OUT] (E0709), with the sender's
        // knowledge: typing implies progress, so the protocol's own progress failure
        // (E0419) is the same defect seen from the global type, said once, at the send.
        // Without processes (or with every send typed) E0419 stands.
        let send_fails = obligations
            .iter()
            .zip(&results)
            .any(|(ob, (d, _))| ob.rule == Rule::TOut && matches!(d, Decision::Fails(_)));
        // A refinement that leaves an enum-typed field no entry (E0243) leaves its message
        // no payload: the progress failure (E0419) is the same defect, said once, naming
        // the enum.
        let entry_fails = obligations
            .iter()
            .zip(&results)
            .any(|(ob, (d, _))| ob.rule == Rule::EnumEntry && matches!(d, Decision::Fails(_)));
        let explained = |ob: &Obligation, f: &smt::Failure| match (&ob.goal, &f.which) {
            (Goal::Progress { .. }, _) => send_fails || entry_fails,
            (Goal::Contains { prim }, _) => empty.contains(prim),
            (Goal::Compatible { parts }, Some(Part::CanEnd)) => parts.iter().any(|(_, a)| never_ends.contains(&a.prim)),
            (Goal::Refines { concrete, .. }, Some(Part::Refine(smt::goals::RefineItem::Realisable))) => {
                never_ends.contains(&concrete.prim)
            }
            _ => false,
        };
        let mut groups: BTreeMap<&'static str, Vec<(&Obligation, Decision, smt::Stats)>> = BTreeMap::new();
        let mut vacuous: Vec<&Obligation> = Vec::new();
        let (mut proved, mut unsure) = (0, 0);
        for (ob, (d, st)) in obligations.iter().zip(results) {
            if matches!(d, Decision::Holds(_)) && !ob.hyps.is_empty() {
                proved += 1;
            }
            if st.vacuous > 0 {
                vacuous.push(ob);
            }
            unsure += st.unsure;
            groups.entry(ob.rule.check()).or_default().push((ob, d, st));
        }
        for (name, obs) in groups {
            let total = obs.len();
            let mut stats = smt::Stats::default();
            let (mut failed, mut unknown) = (0, 0);
            let mut undecided = Vec::new();
            for (ob, d, st) in obs {
                if let Some(e) = &st.dump_error {
                    self.diagnostics.push(dump_failed(ob, e));
                }
                stats.add(&st);
                match d {
                    Decision::Holds(note) => {
                        self.separations.extend(separation(db, prog, ob, note.is_some()));
                        self.partitions.extend(note.map(|n| format!("{}: {n}", obligation_site(db, ob))));
                    }
                    // A guard that cannot hold where it is offered: a dead branch, a
                    // warning (its checks hold vacuously and prove nothing).
                    Decision::Fails(f) if matches!(ob.goal, Goal::Reachable { dead_branch: true, .. }) => {
                        self.diagnostics.push(dead_branch(prog, ob, f));
                    }
                    Decision::Fails(f) => {
                        failed += 1;
                        if !explained(ob, &f) {
                            self.diagnostics.push(failure(prog, ob, f, self.hints.get(&(ob.rule, ob.span))));
                        }
                    }
                    Decision::Unknown { part, why } => {
                        unknown += 1;
                        undecided.push((ob, part, why));
                    }
                }
            }
            let millis = stats.millis;
            const SHOWN: usize = 20;
            for (ob, part, why) in undecided.iter().take(SHOWN) {
                let why_text = match why {
                    // The limit was the time left before the run's deadline, not --timeout.
                    smt::Why::Timeout(d, _) if config.cut_by_deadline => format!(
                        "Z3 ran out of time after {} ms: the run's --deadline was reached (the query had only {:.1} s left)",
                        d.as_millis(),
                        d.as_secs_f64()
                    ),
                    _ => why.to_string(),
                };
                let mut d = Diagnostic::note_at(Code::Undecided, ob.span, format!("could not decide {}", ob.what))
                    .with_note(format!("{}: {why_text}", if part.is_empty() { ob.rule.name() } else { part }))
                    .with_help(undecided_help(why, config.cut_by_deadline));
                if ob.rule == Rule::AgComp || ob.rule == Rule::FullSeparation {
                    d = d.with_note(format!("rule: {}", ob.rule.name()));
                }
                self.diagnostics.push(d);
            }
            if undecided.len() > SHOWN {
                let first = undecided[SHOWN].0;
                self.diagnostics.push(
                    Diagnostic::note_at(
                        Code::Undecided,
                        first.span,
                        format!("and {} more undecided obligation(s)", undecided.len() - SHOWN),
                    )
                    .with_help("fix the ones above first; `--format json` lists every diagnostic"),
                );
            }
            let status = if failed > 0 {
                Status::Fail
            } else if unknown > 0 {
                Status::Unknown
            } else {
                Status::Pass
            };
            let detail = Detail::Obligations {
                total,
                queries: stats.queries,
                cached: stats.cached,
                folded: stats.folded,
                geometric: stats.geometric,
                failed,
                undecided: unknown,
                vacuous: stats.vacuous,
            };
            self.checks.push(CheckResult { name, status, millis, detail, queries: stats.queries });
        }
        self.vacuity(db, vacuous, proved, unsure);
    }

    /// The vacuity guard's line: how many obligations held only because their context
    /// is unsatisfiable. Each such context is unreachable: the step that made it so is
    /// an error (E0410, a stuck protocol) or a dead branch (E0410 as a warning). An
    /// obligation held vacuously with neither reported (a process's own dead code, say)
    /// gets a warning of its own, so that no vacuous proof goes unmentioned.
    fn vacuity(&mut self, db: &SourceDb, vacuous: Vec<&Obligation>, proved: usize, unsure: usize) {
        self.vacuous = vacuous.len();
        // Any error explains them (the verdict is `rejected` anyway).
        let explained = self.diagnostics.iter().any(|d| d.code == Code::StuckContext || d.is_error());
        if let (false, Some(first)) = (explained, vacuous.first()) {
            self.diagnostics.push(
                Diagnostic {
                    severity: diag::Severity::Warning,
                    ..Diagnostic::error(
                        Code::StuckContext,
                        first.span,
                        format!(
                            "{} obligation(s) held only because their context is unsatisfiable, first {} ({})",
                            vacuous.len(),
                            first.what,
                            obligation_site(db, first)
                        ),
                    )
                }
                .with_note("no execution reaches these points, so their checks prove nothing")
                .with_help("remove the unreachable code, or fix the condition that makes its context false"),
            );
        }
        let detail = Detail::Vacuity { vacuous: vacuous.len(), proved, unsure };
        self.checks.push(CheckResult { name: "vacuity", status: Status::Pass, millis: 0.0, detail, queries: 0 });
    }

    fn finish(mut self) -> Report {
        diag::sort(&mut self.diagnostics);
        diag::dedupe(&mut self.diagnostics);
        let verdict = if self.checks.iter().any(|c| c.status == Status::Fail)
            || self.diagnostics.iter().any(Diagnostic::is_error)
        {
            Verdict::Rejected
        } else if self.checks.iter().any(|c| c.status == Status::Unknown) {
            Verdict::Unknown
        } else {
            Verdict::Verified
        };
        Report {
            verdict,
            diagnostics: self.diagnostics,
            checks: self.checks,
            projections: self.projections,
            partitions: self.partitions,
            separations: self.separations,
            vacuous: self.vacuous,
            planned: self.planned,
            clearances: Vec::new(),
        }
    }
}

/// The structured account of a separation obligation that holds (`None` for others).
/// `by_boxes`: the SMT stage decided it from disjoint boxes, without queries.
fn separation(db: &SourceDb, prog: &crate::hir::Program, ob: &Obligation, by_boxes: bool) -> Option<Separation> {
    let crate::obligation::Goal::Separated { sides } = &ob.goal else { return None };
    let (file, line, column) = if db.files().nth(ob.span.file.0 as usize).is_some() {
        let (f, l, c) = db.location(ob.span);
        (Some(f), Some(l), Some(c))
    } else {
        (None, None, None)
    };
    let written = prog.partition(ob.span);
    let boxes = smt::goals::side_boxes(prog, sides);
    let sides = sides
        .iter()
        .enumerate()
        .map(|(i, s)| SeparationSide {
            roles: s.roles.iter().map(|r| prog.role_name(*r).to_string()).collect(),
            region: written.and_then(|p| p.regions.get(i)).map(|e| print::expr(prog, None, e)),
            bounds: boxes.get(i).copied().flatten().map(|b| b.map(|iv| [iv.lo, iv.hi])),
        })
        .collect();
    let how = if written.is_some() {
        "written"
    } else if by_boxes {
        "inferred"
    } else {
        "queries"
    };
    Some(Separation { file, line, column, how, point: written.map(|p| p.point.clone()), sides })
}

/// `file:line:col` of an obligation (`?` when its file is not in the database).
fn obligation_site(db: &SourceDb, ob: &Obligation) -> String {
    if db.files().nth(ob.span.file.0 as usize).is_none() {
        return "?".into();
    }
    let (file, line, col) = db.location(ob.span);
    format!("{file}:{line}:{col}")
}

/// A file-name-safe label for dumped queries: `agcomp-cart-and-arms-37-9`.
fn label(db: &SourceDb, ob: &Obligation) -> String {
    let rule = ob.rule.slug();
    let at = obligation_site(db, ob);
    let file = at.rsplit('/').next().unwrap_or(&at);
    let clean: String = file.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '-' }).collect();
    format!("{rule}-{clean}")
}

/// The primitives the protocol runs: every part of a `dt` and both sides of every
/// refinement. A primitive nothing runs cannot make a run of this protocol deadlock.
fn used_primitives(obligations: &[Obligation]) -> HashSet<crate::hir::PrimId> {
    let mut used = HashSet::new();
    for ob in obligations {
        match &ob.goal {
            Goal::Compatible { parts } => used.extend(parts.iter().map(|(_, a)| a.prim)),
            Goal::Refines { concrete, abstract_, .. } => {
                used.insert(concrete.prim);
                used.extend(abstract_.iter().map(|a| a.prim));
            }
            _ => {}
        }
    }
    used
}
