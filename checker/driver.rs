//! The driver: the only place where stages are wired together. It reads a file and
//! its imports, runs each stage whose inputs are free of errors, times it, and turns
//! the result into a [`Report`] with a [`Verdict`].
//!
//! **Architecture invariant:** the verdict is `Verified` only when every check ran and
//! passed; any undecided obligation makes it `Unknown`, any error `Rejected`.

use crate::diag::{self, Code, Diagnostic};
use crate::hir::print;
use crate::obligation::Obligation;
use crate::source::{FileId, SourceDb};
use crate::{lower, project, syntax, typeck, wf};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// What the user asked for. Grows with later parts (SMT timeout, dump directory).
#[derive(Clone, Debug, Default)]
pub struct Config {}

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
    /// A short human summary ("3 obligations undecided").
    #[serde(skip)]
    pub detail: String,
}

/// Everything `mochi check` learns about one file.
#[derive(Debug)]
pub struct Report {
    pub verdict: Verdict,
    pub diagnostics: Vec<Diagnostic>,
    pub checks: Vec<CheckResult>,
    /// Role name → its local type printed in mochi's notation (when projection ran).
    pub projections: BTreeMap<String, String>,
}

/// Checks the file at `path` (and its imports, read from disk).
pub fn check_file(db: &mut SourceDb, path: &Path, cfg: &Config) -> std::io::Result<Report> {
    let root = syntax::load_root(db, path)?;
    Ok(check_loaded(db, root, cfg))
}

/// Checks source text given in memory under the display name `name`. Imports are read
/// from disk relative to `name`.
pub fn check_source(db: &mut SourceDb, name: &str, text: &str, cfg: &Config) -> Report {
    let root = db.add(name, text);
    check_loaded(db, root, cfg)
}

/// Runs the pipeline on a file already in `db`.
pub fn check_loaded(db: &mut SourceDb, root: FileId, _cfg: &Config) -> Report {
    let mut run = Run::default();
    let mut read = |p: &Path| std::fs::read_to_string(p);
    let (parsed, diags) = run.stage(|| syntax::parse_with_imports(db, root, &mut read));
    if !run.record("parse", diags) {
        return run.finish();
    }
    let (prog, diags) = run.stage(|| lower::lower(&parsed));
    if !run.record("names", diags) {
        return run.finish();
    }
    let Some(chor) = &prog.choreography else { return run.finish() };
    // The three well-formedness checks, each timed on its own; synchronisability relies
    // on the other two (see `wf::check`).
    let diags = run.stage(|| wf::side::check(&prog, &chor.body));
    let side_ok = run.record("side-conditions", diags);
    let (diags, mut obligations) = run.stage(|| wf::scope::check(&prog, &chor.body));
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
    if projected && !prog.locals.is_empty() {
        let diags = run.stage(|| project::check_declared(&prog, &locals));
        run.record("declared-locals", diags);
    }
    if projected {
        let (diags, obs) = run.stage(|| typeck::check_processes(&prog, &locals));
        if run.record("typing", diags) {
            obligations.extend(obs);
        }
    }
    if !run.checks.iter().any(|c| c.status == Status::Fail) {
        run.obligations(&obligations);
    }
    run.finish()
}

/// Accumulates diagnostics and check results while the stages run.
#[derive(Default)]
struct Run {
    diagnostics: Vec<Diagnostic>,
    checks: Vec<CheckResult>,
    projections: BTreeMap<String, String>,
    last_millis: f64,
}

impl Run {
    /// Times `f`; the time is attached by the next [`Run::record`].
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
            detail: if ok { String::new() } else { format!("{n} error(s)") },
        });
        self.diagnostics.extend(diags);
        ok
    }

    /// Settles what needs no solver and reports the rest as undecided, one check per
    /// rule family (total choice, compatibility, separation, typing obligations).
    fn obligations(&mut self, obligations: &[Obligation]) {
        let t = Instant::now();
        let mut groups: BTreeMap<&'static str, (usize, Vec<&Obligation>)> = BTreeMap::new();
        for ob in obligations.iter() {
            let g = groups.entry(ob.rule.check()).or_default();
            g.0 += 1;
            if !ob.trivially_holds() {
                g.1.push(ob);
            }
        }
        let millis = t.elapsed().as_secs_f64() * 1000.0 / groups.len().max(1) as f64;
        for (name, (total, open)) in groups {
            if open.is_empty() {
                self.checks.push(CheckResult {
                    name,
                    status: Status::Pass,
                    millis,
                    detail: format!("{total} trivial"),
                });
                continue;
            }
            let n = open.len();
            self.checks.push(CheckResult {
                name,
                status: Status::Unknown,
                millis,
                detail: format!("{n} of {total} obligation(s) undecided"),
            });
            let mut rules: Vec<&str> = open.iter().map(|o| o.rule.name()).collect();
            rules.sort_unstable();
            rules.dedup();
            let mut d = Diagnostic::note_at(
                Code::Undecided,
                open[0].span,
                format!("{n} proof obligation(s) of {} left undecided", rules.join(", ")),
            )
            .with_help("this version decides no predicates; the SMT stage (Z3) will, so the verdict is `unknown`, not `verified`");
            d = d.with_note(format!("first: {}", open[0].what));
            let mut shown = vec![open[0].span];
            for ob in open.iter().skip(1) {
                if shown.len() == 5 {
                    break;
                }
                if !shown.contains(&ob.span) {
                    shown.push(ob.span);
                    d = d.with_label(ob.span, ob.what.clone());
                }
            }
            if n > 5 {
                d = d.with_note(format!("and {} more", n - 5));
            }
            self.diagnostics.push(d);
        }
    }

    fn finish(mut self) -> Report {
        diag::sort(&mut self.diagnostics);
        let verdict = if self.checks.iter().any(|c| c.status == Status::Fail)
            || self.diagnostics.iter().any(Diagnostic::is_error)
        {
            Verdict::Rejected
        } else if self.checks.iter().any(|c| c.status == Status::Unknown) {
            Verdict::Unknown
        } else {
            Verdict::Verified
        };
        Report { verdict, diagnostics: self.diagnostics, checks: self.checks, projections: self.projections }
    }
}
