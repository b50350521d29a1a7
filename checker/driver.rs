//! The driver: the only place where stages are wired together. It reads a file and
//! its imports, runs each stage whose inputs are free of errors, times it, and turns
//! the result into a [`Report`] with a [`Verdict`].
//!
//! **Architecture invariant:** the verdict is `Verified` only when every check ran and
//! passed; any undecided obligation makes it `Unknown`, any error `Rejected`.

use crate::diag::{self, Diagnostic};
use crate::source::{FileId, SourceDb};
use crate::syntax;
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
    let (_parsed, diags) = run.stage("parse", || syntax::parse_with_imports(db, root, &mut read));
    run.record("parse", diags);
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
    fn stage<T>(&mut self, _name: &'static str, f: impl FnOnce() -> T) -> T {
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

    fn finish(mut self) -> Report {
        diag::sort(&mut self.diagnostics);
        let verdict = if self.checks.iter().any(|c| c.status == Status::Fail) || self.diagnostics.iter().any(Diagnostic::is_error) {
            Verdict::Rejected
        } else if self.checks.iter().any(|c| c.status == Status::Unknown) {
            Verdict::Unknown
        } else {
            Verdict::Verified
        };
        Report { verdict, diagnostics: self.diagnostics, checks: self.checks, projections: self.projections }
    }
}
