//! Golden files: every choreography under `choreographies/` is checked and its verdict,
//! checks, diagnostics and projections are compared with a snapshot in
//! `tests/snapshots/`. After an intended change, review with `cargo insta review` (or
//! run with `INSTA_UPDATE=always` and read the diff before committing).

use mochi::driver::{check_file, Config};
use mochi::render;
use mochi::source::SourceDb;
use std::fmt::Write;
use std::path::Path;

/// The stable part of a report: no timings, paths relative to the package root.
fn dump(path: &Path) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let rel = path.strip_prefix(root).unwrap_or(path);
    let mut db = SourceDb::new();
    let report = match check_file(&mut db, rel, &Config::default()) {
        Ok(r) => r,
        Err(e) => return format!("cannot read {}: {e}", rel.display()),
    };
    let mut out = String::new();
    let _ = writeln!(out, "==== VERDICT ====\n{:?}", report.verdict);
    out.push_str("==== CHECKS ====\n");
    for c in &report.checks {
        let _ = writeln!(out, "{:<20} {:?} {}", c.name, c.status, c.detail);
    }
    out.push_str("==== DIAGNOSTICS ====\n");
    for d in &report.diagnostics {
        out.push_str(&render::text(&db, d, false));
    }
    if !report.projections.is_empty() {
        out.push_str("==== PROJECTIONS ====\n");
        for (role, t) in &report.projections {
            let _ = writeln!(out, "{role} = {t}");
        }
    }
    out
}

#[test]
fn every_choreography_matches_its_golden_file() {
    insta::glob!("../choreographies", "**/*.chor", |path| {
        insta::assert_snapshot!(dump(path));
    });
}
