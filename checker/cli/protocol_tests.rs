//! A robot cell without processes is a protocol ([`crate::typeck`], E0242): the whole
//! pipeline and the report's wording, in text and JSON ([`crate::render`]).

use crate::diag::Code;

/// `text` with every `process` item blanked (each of its lines left empty, so the other
/// items keep their lines and columns): the choreography as its designer writes it before
/// the robots' programs exist.
fn without_processes(text: &str) -> String {
    let mut out = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        inside |= line.starts_with("process ");
        out.push(if inside { "" } else { line });
        if inside && line.trim_end().ends_with(';') {
            inside = false;
        }
    }
    assert!(!inside, "a process item runs to the end of the file");
    out.join("\n") + "\n"
}

/// Checks the corpus file `path` (relative to the repository root) with its processes
/// removed; the report and the database its spans point into.
fn check_without_processes(path: &str) -> (crate::source::SourceDb, crate::driver::Report) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let stripped = without_processes(&text);
    assert_ne!(stripped.trim_end(), text.trim_end(), "{path} has processes to remove");
    let mut db = crate::source::SourceDb::new();
    let report = crate::fsload::check_source(&mut db, path, &stripped, &crate::driver::Config::patient());
    (db, report)
}

/// A robot cell without processes is a protocol: every check but process typing runs, so
/// each rejected file of the corpus whose defect lies in the choreography (a collision, a
/// separation, a compatibility, a duration, an unreachable end state) is still rejected
/// with its own code at its own place once its processes are removed; no participant is
/// asked for a process (E0701) and the report says no process was typed (E0242, and the
/// verdict line).
#[test]
fn a_cell_without_processes_is_checked_as_a_protocol_and_its_defects_are_still_found() {
    for (path, code, line, col) in [
        ("choreographies/rejected/E0404-target-too-close.chor", Code::FootprintsOverlap, 21, 3),
        ("choreographies/rejected/E0406-two-carts-one-lane.chor", Code::SidesOverlap, 0, 0),
        ("choreographies/rejected/E0401-two-non-interruptible.chor", Code::TwoNonInterruptible, 0, 0),
        ("choreographies/rejected/E0405-brake-releases-during-pick.chor", Code::DurationsIncompatible, 0, 0),
        ("choreographies/rejected/E0408-beyond-the-lane.chor", Code::MotionCannotEnd, 0, 0),
    ] {
        let (db, report) = check_without_processes(path);
        let found: Vec<(Code, usize, usize)> = report
            .diagnostics
            .iter()
            .map(|d| {
                let (_, l, c) = db.location(d.span);
                (d.code, l, c)
            })
            .collect();
        assert_eq!(report.verdict, crate::driver::Verdict::Rejected, "{path}: {found:?}");
        assert!(found.iter().any(|&(c, _, _)| c == Code::ProtocolOnly), "{path}: {found:?}");
        assert!(!found.iter().any(|&(c, _, _)| c == Code::MissingProcess), "{path}: {found:?}");
        let errors: Vec<_> = report.diagnostics.iter().filter(|d| d.is_error()).collect();
        assert!(!errors.is_empty() && errors.iter().all(|d| d.code == code), "{path}: {found:?}");
        let expect = std::fs::read_to_string(path).expect("read").lines().next().unwrap_or_default().to_string();
        let (l, c) = if line > 0 {
            (line, col)
        } else {
            let at = expect.rsplit(' ').next().unwrap_or_default();
            let (l, c) = at.split_once(':').expect("L:C");
            (l.parse().expect("line"), c.parse().expect("column"))
        };
        assert!(found.contains(&(code, l, c)), "{path}: no {code:?} at {l}:{c}: {found:?}");
        let text = crate::render::summary_text(&db, path, &report, false, false);
        assert!(text.ends_with(&format!("verdict: rejected ({path}) -- protocol only: no process typed\n")), "{text}");
    }
}

/// A correct cell without processes verifies as a protocol and says so, in text and JSON
/// (with some but not all processes, each missing one is still E0701: typeck's tests).
#[test]
fn a_correct_cell_without_processes_verifies() {
    let path = "choreographies/sorting.chor";
    let (db, report) = check_without_processes(path);
    assert_eq!(report.verdict, crate::driver::Verdict::Verified, "{:#?}", report.diagnostics);
    let text = crate::render::summary_text(&db, path, &report, false, false);
    assert!(text.ends_with(&format!("verdict: verified ({path}) -- protocol only: no process typed\n")), "{text}");
    let json = crate::render::report_json(&db, path, &report);
    assert_eq!(json["verdict"], "verified", "{json}");
    assert!(
        json["diagnostics"].as_array().is_some_and(|d| {
            d.iter().any(|d| {
                d["code"] == "E0242" && d["message"].as_str().is_some_and(|m| m.contains("no process was typed"))
            })
        }),
        "{json}"
    );
}
