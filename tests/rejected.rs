//! The rejected-variants corpus: each file under `choreographies/rejected/`,
//! `choreographies/rejected/geometry/` and `choreographies/mavlink/rejected/` (the MAVLink
//! case studies' defective variants, issue 10) breaks exactly one rule. Its first line says which,
//! as `// expect: E0301 at 5:3`: the check must reject the file, every error must carry
//! that code and a hint, and one of them must start at that line and column. A diagnostic
//! that points into another file (a URDF, whose errors point at its own lines) is expected
//! as `// expect: E0501 at robots/pybullet_data/husky/husky.urdf:97:18`, the path relative
//! to the repository root. The file name starts with the code. Every `.chor` file is one
//! (except the few of [`PENDING`]); a `.mochi` file (a library, checked on its own) is one
//! when its first line is an `// expect:` line (the others are imported by the `.chor`
//! files). The fixtures the geometry files name (URDFs, meshes) are in
//! `choreographies/rejected/geometry/fixtures/`.
//!
//! Every code in `diag.rs` is accounted for: produced by a file here (as its expected
//! code), listed in [`NOT_ALONE`] with the reason it cannot be the only error of a file,
//! or marked reserved in `diag.rs` (no check produces it).

use mochi::diag::{Code, Severity};
use mochi::driver::{Config, Verdict};
use mochi::fsload::check_file;
use mochi::source::SourceDb;
use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};

/// The folders of the corpus.
const DIRS: &[&str] =
    &["choreographies/rejected", "choreographies/rejected/geometry", "choreographies/mavlink/rejected"];

/// Rejected variants whose code the geometric procedure does not give in reasonable time
/// yet (they live in `choreographies/pending/` with the examples they vary, which the other
/// harnesses skip): their first line says in prose what they expect, and they join the
/// corpus when it is an `// expect: CODE at ...` line (the test below says when).
/// (None now: the mounted arm's variant joined the corpus as
/// `rejected/geometry/E0404-mounted-arm-orbit-too-small.chor`.)
const PENDING: &[&str] = &[];

fn corpus() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in DIRS {
        files.extend(
            std::fs::read_dir(dir)
                .unwrap_or_else(|e| panic!("{dir}: {e}"))
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.extension().is_some_and(|e| e == "chor")
                        || (p.extension().is_some_and(|e| e == "mochi")
                            && std::fs::read(p).is_ok_and(|t| t.starts_with(b"// expect: ")))
                })
                .filter(|p| !PENDING.iter().any(|q| Path::new(q) == p.as_path())),
        );
    }
    files.sort();
    // The geometry folder is read too (a walk that missed it would pass).
    assert!(
        files.iter().filter(|p| p.starts_with("choreographies/rejected/geometry")).count() >= 7,
        "the URDF and mesh files (choreographies/rejected/geometry/E050*.chor) are in the corpus"
    );
    // The MAVLink variants are read too (issue 10: each case study's defective variants).
    assert!(
        files.iter().filter(|p| p.starts_with("choreographies/mavlink/rejected")).count() >= 8,
        "the MAVLink variants (choreographies/mavlink/rejected/E*.chor) are in the corpus"
    );
    // The library files are read too (a filter that dropped them all would pass).
    assert!(
        files.iter().filter(|p| p.extension().is_some_and(|e| e == "mochi")).count() >= 2,
        "the rejected libraries (E0409-library-*.mochi, E0412-library-*.mochi) are in the corpus"
    );
    files
}

/// Where an expected diagnostic starts: a file (the rejected file itself unless the
/// expectation names another), a line and a column.
struct Expected {
    code: Code,
    file: PathBuf,
    line: usize,
    col: usize,
}

/// Parses `// expect: CODE at LINE:COL` or `// expect: CODE at PATH:LINE:COL` (PATH
/// relative to the repository root).
fn expectation(path: &Path) -> Expected {
    let text = std::fs::read_to_string(path).expect("readable");
    let first = text.lines().next().unwrap_or_default();
    let rest = first.strip_prefix("// expect: ").unwrap_or_else(|| panic!("{}: no `// expect:` line", path.display()));
    let (code, pos) = rest.split_once(" at ").unwrap_or_else(|| panic!("{}: malformed expect line", path.display()));
    let code: Code = code.parse().unwrap_or_else(|_| panic!("{}: unknown code {code}", path.display()));
    let mut parts = pos.trim().rsplitn(3, ':');
    let (c, l, file) = (parts.next(), parts.next(), parts.next());
    let num = |s: Option<&str>, what: &str| -> usize {
        s.and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("{}: `{pos}` is not [PATH:]LINE:COL ({what})", path.display()))
    };
    let file = match file {
        None => path.to_path_buf(),
        Some(f) => {
            assert!(Path::new(f).is_file(), "{}: the expected file `{f}` does not exist", path.display());
            PathBuf::from(f)
        }
    };
    Expected { code, file, line: num(l, "line"), col: num(c, "column") }
}

/// `a/b/../c` as `a/c`: the loader names a URDF by the path the source wrote, joined to
/// the source's folder, so a diagnostic's file name may hold `..`.
fn lexical(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::ParentDir if out.file_name().is_some() => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

#[test]
fn each_rejected_file_fails_with_exactly_its_code_at_its_position() {
    let files = corpus();
    assert!(files.len() >= 25, "the corpus has {} files, at least 25 expected", files.len());
    let mut failures = Vec::new();
    for path in &files {
        let Expected { code, file, line, col } = expectation(path);
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        if !name.starts_with(code.as_str()) {
            failures.push(format!("{name}: file name does not start with {code}"));
        }
        let mut db = SourceDb::new();
        let report = check_file(&mut db, path, &Config::patient()).expect("readable");
        let errors: Vec<_> = report.diagnostics.iter().filter(|d| d.severity == Severity::Error).collect();
        let summary: Vec<String> = errors
            .iter()
            .map(|d| {
                let (f, l, c) = db.location(d.span);
                format!("{} at {f}:{l}:{c}: {}", d.code, d.message)
            })
            .collect();
        for d in &errors {
            if d.help.is_none() {
                failures.push(format!("{name}: {} has no hint: {}", d.code, d.message));
            }
        }
        if report.verdict != Verdict::Rejected {
            failures.push(format!("{name}: verdict {:?}, expected Rejected", report.verdict));
            continue;
        }
        if errors.iter().any(|d| d.code != code) {
            failures.push(format!("{name}: expected only {code}, got {summary:#?}"));
            continue;
        }
        let at = errors.iter().any(|d| {
            let (f, l, c) = db.location(d.span);
            l == line && c == col && lexical(Path::new(&f)) == lexical(&file)
        });
        if !at {
            failures.push(format!("{name}: no {code} at {}:{line}:{col}; got {summary:#?}", file.display()));
        }
    }
    assert!(failures.is_empty(), "{} of {} files fail:\n{}", failures.len(), files.len(), failures.join("\n"));
}

/// Codes that cannot be the only error of a file, and why. Each is still tested where it
/// can fire (see the named test).
const NOT_ALONE: &[(&str, &str)] = &[
    (
        "E0430",
        "a warning about the environment, not the source: an SMT dump that cannot be written \
         (`--dump-smt`). Tested in tests/cli.rs::a_dump_that_cannot_be_written_is_a_warning_not_a_lost_error",
    ),
    (
        "E0710",
        "[T-SESS] compares first footprints at time 0; every participant moves in the first motion \
         of its scope (total motion), so a collision there is also an [AGCOMP] (E0404) or separation \
         (E0406) failure at time 0. Tested in smt::tests::initially_apart_holds_for_distant_bots_and_fails_for_touching_ones",
    ),
    (
        "E0244",
        "a warning, not an error: a deprecated MAVLink message is checked as written (autopilots \
         still send some). Shown by choreographies/mavlink/mission-download.chor and \
         mission-upload-tolerant.chor (MISSION_REQUEST, MISSION_ITEM; golden snapshots) and \
         tested in lower::mav_tests::deprecated_messages_are_warned_about_once_naming_the_replacement",
    ),
    (
        "E0242",
        "a note, not an error: a program with a dialect and no process is a protocol, verified \
         without typing processes, and says so. Tested in tests/cli.rs::\
         a_mavlink_protocol_without_processes_is_verified_and_says_no_process_was_typed",
    ),
    (
        "E0420",
        "a note, not an error: a library with no robot kind and no motion primitive is verified \
         (names and sorts checked) and says so. Tested in library::tests::\
         a_library_of_constants_verifies_with_a_note_and_chor_files_still_need_a_system",
    ),
    (
        "U0001",
        "a note, not an error: an undecided obligation makes the verdict `unknown`, never \
         `rejected`. Tested in tests/cli.rs a_forced_timeout_gives_unknown_and_exit_3",
    ),
];

/// Each pending file exists and still says in prose what it expects: once its first line
/// is an `// expect: CODE at ...` line, its entry in [`PENDING`] must go.
#[test]
fn pending_geometry_files_are_still_pending() {
    for p in PENDING {
        let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{p}: {e}: drop it from PENDING"));
        let first = text.lines().next().unwrap_or_default();
        let code = first.strip_prefix("// expect: ").and_then(|r| r.split_once(" at ")).map(|(c, _)| c.parse::<Code>());
        assert!(
            !matches!(code, Some(Ok(_))),
            "{p} has an `// expect: CODE at` line now: drop it from PENDING so that the corpus checks it"
        );
    }
}

#[test]
fn every_code_is_produced_by_a_rejected_example_or_explained() {
    let covered: BTreeSet<Code> = corpus().iter().map(|p| expectation(p).code).collect();
    let missing: Vec<&str> = Code::ALL
        .iter()
        .filter(|c| !covered.contains(c) && !c.is_reserved())
        .map(|c| c.as_str())
        .filter(|c| !NOT_ALONE.iter().any(|(n, _)| n == c))
        .collect();
    assert!(
        missing.is_empty(),
        "codes without a file in choreographies/rejected/, an entry in NOT_ALONE or a reserved mark in diag.rs: {missing:?}"
    );
    for (code, why) in NOT_ALONE {
        let c: Code = code.parse().unwrap_or_else(|_| panic!("NOT_ALONE names {code}, which is no code"));
        assert!(!covered.contains(&c), "{code} has a file now: drop it from NOT_ALONE");
        assert!(!c.is_reserved(), "{code} is reserved: drop it from NOT_ALONE");
        assert!(why.len() > 40, "{code}: say why it cannot be alone, and where it is tested");
    }
    // A reserved code is produced by no check, so no file can expect it.
    for c in &covered {
        assert!(!c.is_reserved(), "{c} is marked reserved in diag.rs but a rejected file expects it");
    }
}
