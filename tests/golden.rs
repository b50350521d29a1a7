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
        // How many SMT queries a check asked depends on which worker thread answered which
        // question first (the cache, and the vacuity guard's shared context answers): not
        // golden. The obligation and error counts are.
        let detail = c.detail.to_string();
        let detail = detail
            .split(", ")
            .filter(|part| !part.contains(" quer") && !part.contains("without Z3"))
            .collect::<Vec<_>>()
            .join(", ");
        let _ = writeln!(out, "{:<20} {:?} {}", c.name, c.status, detail);
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

/// `mochi project` prints local types that parse back to the same type: for every
/// bundled choreography that projects, print each local type, parse it, lower it for
/// its role and compare it with the projection.
#[test]
fn printed_projections_parse_back_to_the_same_type() {
    use mochi::hir::print;
    use mochi::syntax::{parse_with_imports, parser::parse_local};
    let mut checked = 0;
    for entry in std::fs::read_dir("choreographies").expect("choreographies/") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "chor") {
            continue;
        }
        let mut db = SourceDb::new();
        let root = mochi::syntax::load_root(&mut db, &path).expect("readable");
        let (parsed, d) = parse_with_imports(&mut db, root, &mut |p| std::fs::read_to_string(p));
        assert!(d.is_empty(), "{}: {d:?}", path.display());
        let (prog, d) = mochi::lower::lower(&parsed);
        if !d.is_empty() {
            continue;
        }
        let (locals, d) = mochi::project::project_all(&prog);
        if !d.is_empty() {
            continue;
        }
        for (role, t) in &locals {
            let text = print::local(&prog, t);
            let file = db.add("printed", text.clone());
            let (ast, d) = parse_local(file, &text);
            assert!(
                d.is_empty(),
                "{}: printed type of {} does not parse: {d:?}\n{text}",
                path.display(),
                prog.role_name(*role)
            );
            let (back, d) = mochi::lower::lower_local(&prog, *role, &ast.expect("parsed"));
            assert!(
                d.is_empty(),
                "{}: printed type of {} does not lower: {d:?}\n{text}",
                path.display(),
                prog.role_name(*role)
            );
            assert!(
                mochi::project::equal(&back, t),
                "{}: the printed type of {} reads back differently\n{text}",
                path.display(),
                prog.role_name(*role)
            );
            checked += 1;
        }
    }
    assert!(checked >= 8, "only {checked} projections were round-tripped");
}
