//! The driver: the only place where stages are wired together. Given a file in a
//! [`SourceDb`] and a loader for its imports (the IO stays at the edge, `fsload`), it runs
//! each stage whose inputs are free of errors, times it, and turns the result into a
//! [`Report`] with a [`Verdict`]. The report is data: `render` formats it.
//!
//! **Architecture invariant:** the verdict is `Verified` only when every check ran and
//! passed; any undecided obligation makes it `Unknown`, any error `Rejected`.

use crate::diag::{self, Code, Counterexample, Diagnostic};
use crate::geometry::search::checks::PairClearance;
use crate::hir::print;
use crate::obligation::{Goal, Obligation, Rule};
use crate::smt::{self, goals::Part, Decision, SmtConfig};
use crate::source::{FileId, SourceDb};
use crate::{library, lower, project, space, subtype, syntax, typeck, wf};
use serde::Serialize;
use std::collections::{BTreeMap, HashSet};
use std::time::Instant;

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
        report.clearances =
            crate::geometry::search::checks::clearances(&p.program, &p.obligations, tolerance, cfg.smt.timeout);
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
    let (mut obligations, diags) = run.stage(|| wf::scope::check(&prog, &chor.body));
    let scope_ok = run.record("well-scoped", diags);
    if !(side_ok && scope_ok) {
        return run.finish();
    }
    let diags = run.stage(|| wf::sync::check(&prog, &chor.body));
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
        // A primitive that can never end (E0409) makes every motion using it unable to
        // end too; that is said once, at its declaration.
        let never_ends: Vec<crate::hir::PrimId> = obligations
            .iter()
            .zip(&results)
            .filter_map(|(ob, (d, _))| match (&ob.goal, d) {
                (Goal::CanEnd { prim }, Decision::Fails(_)) => Some(*prim),
                _ => None,
            })
            .collect();
        // A footprint that holds no point (E0412) contains no body either: said once.
        let empty: Vec<crate::hir::PrimId> = obligations
            .iter()
            .zip(&results)
            .filter_map(|(ob, (d, _))| match (&ob.goal, d) {
                (Goal::CanEnd { prim }, Decision::Fails(_)) if ob.rule == Rule::Occupies => Some(*prim),
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

/// `file:line:col` of an obligation.
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

/// The error for a failed obligation: the code of the rule and part that failed, what
/// was required, and the counterexample in the user's terms.
/// The path through the global type to `ob`'s point, with the counterexample's values
/// (`wf::trace`), as lines; empty when the point is not in the global type.
fn trace(prog: &crate::hir::Program, ob: &Obligation, f: &smt::Failure) -> Vec<String> {
    let Some(chor) = &prog.choreography else { return Vec::new() };
    match crate::wf::trace::path_to(&chor.body, ob.span) {
        Some(steps) => crate::wf::trace::lines(prog, &steps, &f.values, &f.bound),
        None => Vec::new(),
    }
}

/// The trace as a note: "trace to this point: ..." one step a line.
fn trace_note(lines: &[String], values: bool) -> Option<String> {
    let how = if values { "one path; values from the counterexample" } else { "one path" };
    (!lines.is_empty()).then(|| format!("trace to this point ({how}):\n  {}", lines.join("\n  ")))
}

fn failure(prog: &crate::hir::Program, ob: &Obligation, f: smt::Failure, hint: Option<&String>) -> Diagnostic {
    let steps = trace(prog, ob, &f);
    let code = match (ob.rule, &f.which) {
        (Rule::TotalChoice, _) => Code::ChoiceNotTotal,
        (Rule::AgComp, Some(Part::Pre(_))) => Code::PreconditionAtMotion,
        (Rule::AgComp, Some(Part::CanEnd)) => Code::MotionCannotEnd,
        (Rule::AgComp, Some(Part::Assume(_))) => Code::AssumptionNotDischarged,
        (Rule::AgComp, Some(Part::Within(..) | Part::Meet)) => Code::DurationsIncompatible,
        (Rule::AgComp, Some(Part::ClearOf { .. })) => Code::ObstacleHit,
        (Rule::AgComp, Some(Part::CommonEnd(..))) => Code::TwoNonInterruptible,
        (Rule::AgComp, _) => Code::FootprintsOverlap,
        (Rule::FullSeparation, _) => Code::SidesOverlap,
        (Rule::Refinement, _) => Code::RefinementFails,
        (Rule::TMotion, _) => Code::MotionPrecondition,
        (Rule::TOut, _) => Code::SendPredicate,
        (Rule::TSess, _) => Code::InitialCollision,
        (Rule::Subtype, _) => Code::SubtypePredicate,
        (Rule::RecInit, _) => Code::RecInitRefinement,
        (Rule::RecJump, _) => Code::RecJumpRefinement,
        (Rule::MeasureBound, _) => Code::MeasureNegative,
        (Rule::MeasureDecrease, _) => Code::MeasureNotDecreasing,
        (Rule::Progress, _) => Code::Stuck,
        (Rule::EnumEntry, _) => Code::NotAnEntry,
        (Rule::TRecInit, _) => Code::ProcessRecInit,
        (Rule::TRecJump, _) => Code::ProcessRecJump,
        (Rule::TRecArgs, _) => Code::ProcessRecArgs,
        (Rule::Contract, _) => Code::VacuousContract,
        (Rule::Occupies, _) => Code::EmptyFootprint,
        (Rule::Reachable, _) => Code::StuckContext,
        (Rule::InitInvariant, Some(Part::Before(_))) => Code::StuckContext,
        (Rule::InitInvariant, _) => Code::InitOutsideInvariant,
        (Rule::Contains, _) => Code::FootprintMissesBody,
    };
    let help = match code {
        Code::ChoiceNotTotal => "add a branch whose guard covers the counterexample's state, or weaken a guard",
        Code::PreconditionAtMotion => "establish the precondition before the motion (an earlier motion's postcondition, a message's refinement), or weaken it",
        Code::AssumptionNotDischarged => "strengthen the partners' guarantees so that they imply the assumption, or weaken the assumption",
        Code::FootprintsOverlap => "keep the participants apart: change a pose or a motion's target, shrink a footprint, or strengthen a guarantee so the footprints stay clear of each other",
        Code::FootprintMissesBody => "widen the footprint to cover the robot's body wherever the guarantee lets it be, or write it as `footprint: geometry;`",
        Code::ObstacleHit => "keep the motion clear of the obstacle: change its target or the participant's pose, or tighten its footprint",
        Code::MotionCannotEnd => "change the motion's arguments so that it ends inside the robot's invariant, or fix its postcondition",
        Code::DurationsIncompatible => "make the non-interruptible primitive's duration fit within its partners' (or let it be interrupted)",
        Code::TwoNonInterruptible => "give the non-interruptible primitives the same single duration `[d, d]` (equal under what is known at the motion), or make all but one of them interruptible",
        Code::SidesOverlap => "keep the sides of `*` in disjoint regions, or merge the motions that meet into one joint motion",
        Code::RefinementFails => "use a primitive whose contract refines the one the choreography names (Def 3.4, corrected direction)",
        Code::MotionPrecondition => "establish the precondition before the motion in the process, or choose another primitive",
        Code::SendPredicate => "send values that satisfy the refinement, or establish the guard before sending",
        Code::InitialCollision => "move the participants apart (`at: pose(...)` or `init:`)",
        Code::RecInitRefinement | Code::ProcessRecInit => "start the parameter at a value that satisfies its refinement, or weaken the refinement",
        Code::RecJumpRefinement | Code::ProcessRecJump => "guard the branch that jumps back (e.g. `[n > 0]` before `t(n - 1)`), or pass arguments that satisfy the refinement",
        Code::MeasureNegative => "guard the branch that jumps back so that the measure is still non-negative there (e.g. `[i < count]`), or choose another measure",
        Code::MeasureNotDecreasing => "pass arguments that make the measure smaller (e.g. `t(i + 1)` for `decreases count - i`), or drop `decreases` if the loop may run forever",
        Code::NotAnEntry => "make the refinement admit an entry named above: compare with the entries' names (`{x == ENTRY}`; flags summed, or tested with `has_flag`), not with numbers that are none",
        Code::Stuck => "weaken the refinement or guard that no value satisfies in the counterexample's state, or add a branch for that state",
        Code::ProcessRecArgs => "pass the loop the same values as the local type's recursion (its initial values and the arguments of its jump), computed from what the process sent and received",
        Code::EmptyFootprint => "write a footprint that contains the robot at every state its guarantee allows (a footprint no point satisfies, such as `false`, hides every collision)",
        Code::VacuousContract => "fix the duration's bounds (lo <= hi, hi >= 0), or make the guarantee and the postcondition agree at the end of the motion (with every `sqrt` taken of a value >= 0 and every divisor non-zero: an undefined value satisfies nothing)",
        Code::StuckContext => "fix the step named above (an `init` no state satisfies, a refinement or guard that contradicts what holds there): no execution gets past it",
        Code::InitOutsideInvariant => "make `init` and the robot kind's invariant agree on at least one state (fix `init`, or widen the invariant)",
        Code::SubtypePredicate => "in the declared local type, strengthen the send's guard or refinement (weaken the reception's) until it implies the projection's, or drop the `local` item",
        _ => "make the process's predicate imply the type's",
    };
    // A fix more precise than the code's, found where the obligation was made
    // (`typeck::Hints`): e.g. the type's refinement a process loop parameter lacks.
    let help = hint.cloned().unwrap_or_else(|| help.to_string());
    let mut d = Diagnostic::error(code, ob.span, format!("{} ({})", code.title(), ob.what))
        .with_note(format!("required: {}", f.part))
        .with_note(format!("rule: {}", ob.rule.name()));
    // Two values of one name are two variables (`v`, `v#2`): say where each is bound.
    for (symbol, name, span) in &f.bound {
        d = d.with_label(*span, format!("`{symbol}` in the counterexample is the `{name}` bound here"));
    }
    if let Some(text) = trace_note(&steps, !f.values.is_empty()) {
        d = d.with_note(text);
    }
    let cx = Counterexample { values: f.values, overlap: f.overlap, trace: steps };
    let since = matches!(code, Code::FootprintsOverlap | Code::ObstacleHit).then(|| since_start(prog, ob));
    if let Some(text) = counterexample_text(&cx, code, since.as_ref()) {
        d = d.with_note(text);
    }
    d.with_help(help).with_counterexample(cx)
}

/// The help of an undecided obligation (U0001): what to change, matched to why it was
/// not decided: the hard construct the query holds (`smt::hard`), the engine that
/// stopped and how, or the limit that was reached.
fn undecided_help(why: &smt::Why, cut_by_deadline: bool) -> String {
    const STAYS: &str = "the verdict stays `unknown`, never `verified`";
    match why {
        smt::Why::Timeout(..) if cut_by_deadline => format!(
            "give the run a later `--deadline` (or none), or check this file on its own; {STAYS}"
        ),
        smt::Why::Timeout(_, hard) => match hard.advice() {
            Some(a) => format!("{a}; or raise the per-query limit with `--timeout SECONDS`; {STAYS}"),
            None => format!(
                "raise the per-query limit with `--timeout SECONDS`, or simplify the predicates (keep them polynomial and local); {STAYS}"
            ),
        },
        smt::Why::Unsupported(_) => {
            format!("rewrite the predicate with the supported constructs (LANGUAGE.md, \"Expressions\"); {STAYS}")
        }
        smt::Why::Abandoned(_) | smt::Why::NotRun(_) => format!(
            "simplify the predicates (keep them polynomial and local; Z3 ignored the interrupt on this one, so a higher `--timeout` may not help); {STAYS}"
        ),
        smt::Why::Incomplete(_, hard) => match hard.advice() {
            Some(a) => format!("{a}; {STAYS}"),
            None => format!(
                "simplify the predicate (nonlinear and trigonometric facts are decided only partially); {STAYS}"
            ),
        },
        // The geometric search: what to change depends on how it stopped.
        smt::Why::Search(s) if s.contains("time limit") || s.contains("boxes searched") => format!(
            "give the geometric search more time with `--timeout SECONDS`, or narrow what it must cover (tighter bounds on the motion's variables in its precondition or guarantee); {STAYS}"
        ),
        smt::Why::Search(s) if s.contains("resolution") => format!(
            "leave more clearance between the parts (the search cannot separate surfaces closer than its resolution), or tighten the motion's bounds near the contact shown; {STAYS}"
        ),
        smt::Why::Search(_) => format!(
            "simplify the motion's geometry or bounds (primitive shapes instead of meshes, tighter bounds on its variables), or write a footprint predicate for Z3 to decide; {STAYS}"
        ),
    }
}

/// The SMT stage's dump sink failed on a query of `ob` (E0430): a warning, the verdict
/// stands; nothing more is dumped.
fn dump_failed(ob: &Obligation, e: &str) -> Diagnostic {
    Diagnostic {
        severity: diag::Severity::Warning,
        ..Diagnostic::error(Code::SmtDumpFailed, ob.span, format!("could not dump a query of {}", ob.what))
    }
    .with_note(e.to_string())
    .with_note("no further query was dumped; the checks are not affected")
    .with_help("make the `--dump-smt` directory writable (and free space), or run without `--dump-smt`")
}

/// A branch whose guard cannot hold where the choice is made: a warning (the branch is
/// unreachable; its obligations hold vacuously).
fn dead_branch(prog: &crate::hir::Program, ob: &Obligation, f: smt::Failure) -> Diagnostic {
    let steps = trace(prog, ob, &f);
    let mut d = Diagnostic {
        severity: diag::Severity::Warning,
        ..Diagnostic::error(Code::StuckContext, ob.span, format!("dead branch: {} can never hold", ob.what))
    }
    .with_note("the context at the choice contradicts this branch's guard, or leaves no value its payload's refinements admit, so no execution takes it; its checks hold vacuously");
    if let Some(text) = trace_note(&steps, false) {
        d = d.with_note(text);
    }
    d.with_help("remove the branch, or fix its guard or its payload's refinements")
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

/// `counterexample: at time 2.1 s, the point (1.02, 0.2, 0.05) is in both footprints;
/// Cart.x = 0, tr = 2`.
/// How the time of a contact in a joint motion relates to the choreography's start,
/// read off the path to the motion (`wf::trace`): messages take no time (README, "model
/// of time"), so with no motion, choice or loop before it on the path the motion starts
/// when the choreography does; otherwise the counterexample does not fix the time.
enum Since {
    /// The motion starts when the choreography does.
    Start,
    /// Not determined by the counterexample: why.
    Open(String),
}

fn since_start(prog: &crate::hir::Program, ob: &Obligation) -> Since {
    use crate::wf::trace::Step;
    let Some(chor) = &prog.choreography else { return Since::Open("the motion is not in the choreography".into()) };
    let Some(steps) = crate::wf::trace::path_to(&chor.body, ob.span) else {
        return Since::Open("the path to the motion is not known".into());
    };
    let motions = steps.iter().filter(|s| matches!(s, Step::Motion(_))).count();
    let choices = steps.iter().filter(|s| matches!(s, Step::Choice)).count();
    let looped = steps.iter().any(|s| matches!(s, Step::Loop { .. }));
    if motions == 0 && choices == 0 && !looped {
        return Since::Start;
    }
    let mut why = Vec::new();
    if motions > 0 {
        why.push(format!(
            "{motions} joint motion(s) precede it on this path, whose durations the counterexample does not fix"
        ));
    }
    if choices > 0 {
        why.push(format!("{choices} choice(s) before it may run motions"));
    }
    if looped {
        why.push("it is in a loop, and the counterexample does not say which iteration".to_string());
    }
    Since::Open(why.join("; "))
}

/// The participants' states in a collision's counterexample, one participant at a time:
/// `Cart: x = 0.8, v = 0.5` from the values `Cart.x(t)`, `Cart.v(t)` (at the contact)
/// or `Cart.x`, `Cart.v` (at the motion's start, `at_start`).
fn states(values: &[crate::diag::Assignment], at_start: bool) -> Vec<String> {
    let mut by_role: Vec<(String, Vec<String>)> = Vec::new();
    for a in values {
        let name = if at_start {
            if a.name.ends_with("(t)") || a.name.contains('(') {
                continue;
            }
            a.name.as_str()
        } else {
            match a.name.strip_suffix("(t)") {
                Some(n) if !n.contains('(') => n,
                _ => continue,
            }
        };
        let Some((role, var)) = name.split_once('.') else { continue };
        if role == "point" {
            continue;
        }
        let entry = format!("{var} = {}", a.value);
        match by_role.iter_mut().find(|(r, _)| r == role) {
            Some((_, vs)) => vs.push(entry),
            None => by_role.push((role.to_string(), vec![entry])),
        }
    }
    by_role.into_iter().map(|(r, vs)| format!("{r}: {}", vs.join(", "))).collect()
}

fn counterexample_text(cx: &Counterexample, code: Code, since: Option<&Since>) -> Option<String> {
    let mut parts = Vec::new();
    // A collision: the contact's time within the motion and since the choreography's
    // start, and every participant's state there. A contact is not claimed the earliest:
    // the solver's model is one contact, not the first.
    let collision = since.is_some() && cx.overlap.as_ref().is_some_and(|o| o.times.len() == 1);
    if let Some(o) = &cx.overlap {
        let p = o.point.map(short);
        let at = match (o.times.as_slice(), since) {
            ([], _) => String::new(),
            ([t], Some(since)) if o.not_before.is_some() || *t == 0.0 => {
                let meet = if code == Code::ObstacleHit { "the footprint meets the obstacle" } else { "the footprints meet" };
                let when = match o.not_before {
                    Some(lo) => format!(
                        "{meet} at {} s into this joint motion, and no meeting is possible at or before {} s (proved), so the first is between {} and {} s",
                        short(*t), short(lo), short(lo), short(*t)
                    ),
                    None => format!("{meet} at 0 s, the joint motion's start (the earliest)"),
                };
                match since {
                    Since::Start => format!("{when}; the joint motion starts when the choreography does (no motion precedes it on this path, and messages take no time): "),
                    Since::Open(why) => format!("{when} (the time since the choreography started is not determined: {why}): "),
                }
            }
            ([t], Some(Since::Start)) => format!(
                "the footprints meet at {} s into this joint motion, which is {} s after the choreography starts (no motion precedes it on this path, and messages take no time): ",
                short(*t),
                short(*t)
            ),
            ([t], Some(Since::Open(why))) => format!(
                "the footprints meet at {} s into this joint motion (the time since the choreography started is not determined: {why}): ",
                short(*t)
            ),
            ([t], None) => format!("at time {} s, ", short(*t)),
            (ts, _) => format!("at times {} s, ", ts.iter().map(|t| short(*t)).collect::<Vec<_>>().join(" and ")),
        };
        let (frame, where_) = match code {
            Code::FootprintMissesBody => ("in the robot's own frame ", "is a point of the body outside the footprint"),
            Code::ObstacleHit => ("", "is in the footprint and in the obstacle"),
            Code::RefinementFails => ("", "is in the concrete footprint and outside the abstract one"),
            _ => ("", "is in both footprints"),
        };
        parts.push(format!("{at}the point (x, y, z) = ({}, {}, {}) m {frame}{where_}", p[0], p[1], p[2]));
    }
    if collision {
        let now = states(&cx.values, false);
        let start = states(&cx.values, true);
        if now.is_empty() {
            parts.push("the participants' states at that time are not part of this counterexample".to_string());
        } else {
            parts.push(format!("the participants' states at that time: {}", now.join("; ")));
        }
        if !start.is_empty() {
            parts.push(format!("at the start of the joint motion: {}", start.join("; ")));
        }
        // The rest (payload values, inputs): what the states above do not show.
        let shown = |n: &str| {
            n.starts_with("point.") || n.starts_with("time") || n.split_once('.').is_some_and(|(r, _)| r != "point")
        };
        let rest: Vec<String> = cx
            .values
            .iter()
            .filter(|a| !shown(&a.name))
            .take(16)
            .map(|a| format!("{} = {}", a.name, a.value))
            .collect();
        if !rest.is_empty() {
            parts.push(format!("with {}", rest.join(", ")));
        }
        return Some(format!("counterexample: {}", parts.join("; ")));
    }
    // The point and the time are shown above when there is an overlap.
    let hidden = |n: &str| cx.overlap.is_some() && (n.starts_with("point.") || n.starts_with("time"));
    let values: Vec<String> =
        cx.values.iter().filter(|a| !hidden(&a.name)).take(16).map(|a| format!("{} = {}", a.name, a.value)).collect();
    if !values.is_empty() {
        parts.push(values.join(", "));
    }
    (!parts.is_empty()).then(|| format!("counterexample: {}", parts.join("; ")))
}

fn short(v: f64) -> String {
    let r = (v * 1e4).round() / 1e4;
    if r == 0.0 && v != 0.0 {
        format!("{v:.2e}")
    } else {
        format!("{r}")
    }
}
