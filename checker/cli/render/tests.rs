//! Unit tests of the renderers: layout, escaping, clamping, caps and the JSON schema.

use super::*;
use crate::diag::Code;
use crate::driver::{CheckResult, Detail, Report, Status, Verdict};
use crate::source::FileId;
use serde_json::json;
use std::collections::BTreeMap;

fn db_with(text: &str) -> (SourceDb, FileId) {
    let mut db = SourceDb::new();
    let f = db.add("a.chor", text);
    (db, f)
}

fn report(diagnostics: Vec<Diagnostic>) -> Report {
    Report {
        verdict: Verdict::Rejected,
        diagnostics,
        checks: vec![CheckResult {
            name: "parse",
            status: Status::Fail,
            millis: 0.25,
            detail: Detail::Errors(1),
            queries: 0,
        }],
        projections: BTreeMap::new(),
        partitions: Vec::new(),
        separations: Vec::new(),
        vacuous: 0,
        planned: None,
        clearances: Vec::new(),
    }
}

#[test]
fn wrap_keeps_lines_short_and_words_whole() {
    let text = Code::NotTotallySynchronised.explain();
    let wrapped = wrap(text, 90);
    assert!(wrapped.lines().all(|l| l.chars().count() <= 90), "{wrapped}");
    assert_eq!(wrapped.split_whitespace().collect::<Vec<_>>(), text.split_whitespace().collect::<Vec<_>>());
    assert_eq!(wrap("a-very-long-word b", 4), "a-very-long-word\nb");
}

#[test]
fn colour_is_decided_from_the_choice_the_terminal_and_no_color() {
    use std::ffi::OsStr;
    assert!(use_color(ColorChoice::Always, false, Some(OsStr::new("1"))));
    assert!(!use_color(ColorChoice::Never, true, None));
    assert!(use_color(ColorChoice::Auto, true, None));
    assert!(use_color(ColorChoice::Auto, true, Some(OsStr::new(""))), "an empty NO_COLOR does not count");
    assert!(!use_color(ColorChoice::Auto, true, Some(OsStr::new("1"))));
    assert!(!use_color(ColorChoice::Auto, false, None));
}

#[test]
fn the_run_summary_counts_every_input() {
    let s = RunSummary { verified: 3, rejected: 1, unknown: 0, unreadable: 2, seconds: 0.8123 };
    assert_eq!(run_summary_text(&s), "\n3 verified, 1 rejected, 0 unknown, 2 unreadable in 0.8 s\n");
    assert_eq!(run_summary_text(&RunSummary { unreadable: 0, ..s }), "\n3 verified, 1 rejected, 0 unknown in 0.8 s\n");
    assert_eq!(
        run_summary_json(&s),
        json!({ "summary": { "files": 6, "verified": 3, "rejected": 1, "unknown": 0, "unreadable": 2, "seconds": 0.812 } })
    );
}

#[test]
fn details_read_as_the_table_shows_them() {
    let ob = Detail::Obligations {
        total: 11,
        queries: 18,
        cached: 5,
        folded: 2,
        geometric: 0,
        failed: 0,
        undecided: 0,
        vacuous: 0,
    };
    assert_eq!(ob.to_string(), "11 obligation(s), 18 queries (5 cached), 2 without Z3");
    let ob = Detail::Obligations {
        total: 1,
        queries: 1,
        cached: 0,
        folded: 0,
        geometric: 0,
        failed: 1,
        undecided: 2,
        vacuous: 3,
    };
    assert_eq!(ob.to_string(), "1 obligation(s), 1 query, 1 failed, 2 undecided, 3 held vacuously");
    assert_eq!(Detail::None.to_string(), "");
    assert_eq!(Detail::Errors(2).to_string(), "2 error(s)");
    assert_eq!(
        Detail::Vacuity { vacuous: 0, proved: 4, unsure: 1 }.to_string(),
        "0 of 4 proved obligation(s) held only because their context is unsatisfiable, 1 context(s) undecided"
    );
    assert_eq!(Detail::PastDeadline { seconds: 0.5 }.to_string(), "not checked: the --deadline of 0.5 s had passed");
}

#[test]
fn text_looks_like_rustc() {
    let (db, f) = db_with("system {\n  a -> a : go;\n}\n");
    let d = Diagnostic::error(Code::SelfMessage, Span::new(f, 16, 17), "`a` sends a message to itself")
        .with_label(Span::new(f, 11, 12), "sender")
        .with_note("Def 4.1")
        .with_help("send to another participant");
    let out = text(&db, &d, false);
    assert!(out.starts_with("error[E0301]: `a` sends a message to itself\n"), "{out}");
    assert!(out.contains("--> a.chor:2:8"), "{out}");
    assert!(out.contains("2 |   a -> a : go;"), "{out}");
    assert!(out.contains("|   -    ^\n"), "carets under both spans: {out}");
    assert!(out.contains("sender"), "{out}");
    assert!(out.contains("= note: Def 4.1"), "{out}");
    assert!(out.contains("= help: send to another participant"), "{out}");
    assert!(!out.contains('\x1b'), "no colour asked: {out}");
    assert!(text(&db, &d, true).contains('\x1b'), "colour asked");
}

#[test]
fn a_span_spanning_lines_shows_every_line() {
    let (db, f) = db_with("one\ntwo\nthree\nfour\n");
    let d = Diagnostic::error(Code::UnexpectedToken, Span::new(f, 4, 13), "bad block");
    let out = text(&db, &d, false);
    assert!(out.contains("--> a.chor:2:1"), "{out}");
    for line in ["2 |", "two", "3 |", "three"] {
        assert!(out.contains(line), "missing {line:?}: {out}");
    }
    assert!(!out.contains("four"), "{out}");
}

#[test]
fn spans_at_or_past_the_end_of_the_file_are_clamped() {
    let (db, f) = db_with("const a = 1");
    for (start, end) in [(11, 11), (11, 40), (50, 60), (u32::MAX, u32::MAX)] {
        let d = Diagnostic::error(Code::UnexpectedToken, Span { file: f, start, end }, "expected `;`");
        let out = text(&db, &d, false);
        assert!(out.contains("--> a.chor:1:12"), "{start}..{end}: {out}");
    }
}

#[test]
fn no_span_makes_rendering_panic() {
    // Multi-byte characters, CRLF, a blank last line: every start/end pair, in either order.
    let (db, f) = db_with("é\r\n\tx ü\n\n");
    let n = db.file(f).text.len() as u32 + 2;
    for start in 0..n {
        for end in 0..n {
            let d = Diagnostic::error(Code::UnexpectedChar, Span { file: f, start, end }, "m")
                .with_label(Span { file: f, start: end, end: start }, "l");
            assert!(text(&db, &d, false).starts_with("error[E0101]: m"));
            assert_eq!(diagnostic_json(&db, &d)["code"], "E0101");
        }
    }
}

#[test]
fn a_span_in_an_unknown_file_keeps_its_message() {
    let (db, _) = db_with("x");
    let d = Diagnostic::error(Code::UnexpectedChar, Span::new(FileId(7), 0, 1), "lost");
    assert!(text(&db, &d, false).starts_with("error[E0101]: lost"));
    let v = diagnostic_json(&db, &d);
    assert!(v["file"].is_null() && v["line"].is_null() && v["column"].is_null(), "{v}");
}

#[test]
fn report_text_ends_with_checks_and_verdict() {
    let (db, f) = db_with("const a = ;\n");
    let r = report(vec![Diagnostic::error(Code::UnexpectedToken, Span::new(f, 10, 11), "expected an expression")]);
    let out = report_text(&db, "a.chor", &r, false, false);
    let diag_at = out.find("error[E0103]").expect("diagnostic rendered");
    let check_at = out.find("  FAIL     parse                 0.2 ms  1 error(s)\n").expect(&out);
    assert!(diag_at < check_at, "{out}");
    assert!(out.ends_with("verdict: rejected (a.chor)\n"), "{out}");
    assert!(!out.contains("files read"), "{out}");
    assert!(report_text(&db, "a.chor", &r, false, true).contains("files read: a.chor"));
}

#[test]
fn many_diagnostics_are_capped_per_code_and_in_all() {
    let (db, f) = db_with(&"~ ".repeat(3000));
    let many = |code| (0..3000).map(move |i| Diagnostic::error(code, Span::new(f, 2 * i, 2 * i + 1), "bad"));
    let r = report(many(Code::UnexpectedChar).chain(many(Code::UnexpectedToken).take(5)).collect());
    let out = diagnostics_text(&db, &r, false);
    assert_eq!(out.matches("error[E0101]").count(), MAX_SHOWN_PER_CODE, "{out}");
    assert_eq!(out.matches("error[E0103]").count(), 5);
    assert!(out.contains("note: 2990 more diagnostic(s) not shown (2990 E0101)"), "{out}");
    assert!(out.len() < 20_000, "{} bytes", out.len());
}

#[test]
fn a_long_line_is_shown_as_a_window_and_control_characters_are_escaped() {
    let (db, f) = db_with(&format!("{}\0{}\n", "x".repeat(5000), "y".repeat(5000)));
    let d =
        Diagnostic::error(Code::UnexpectedChar, Span::new(f, 5000, 5001), "unexpected character `\\0`").with_help("h");
    let out = text(&db, &d, false);
    assert!(out.len() < 1000, "{out}");
    assert!(out.contains("--> a.chor:1:5001"), "{out}");
    assert!(out.contains("1 | ...xxxxx") && out.contains("xxxxx?yyyyy"), "{out}");
    assert!(!out.contains('\0'), "{out}");
    assert!(out.contains("line 1 has 10001 characters"), "{out}");
    let (db, f) = db_with("a\x1b[31mb\rc\0");
    let d = Diagnostic::error(Code::UnexpectedChar, Span::new(f, 8, 9), "m");
    let out = text(&db, &d, false);
    assert!(!out.contains('\x1b') && !out.contains('\0'), "{out:?}");
    assert!(out.contains("--> a.chor:2:1"), "{out}");
}

#[test]
fn control_characters_in_messages_are_escaped() {
    let (db, f) = db_with("import \"x\";\n");
    let d = Diagnostic::error(Code::NotSourceFile, Span::new(f, 0, 6), "`a\0b\x1b[2J` is not a mochi file")
        .with_label(Span::new(f, 7, 10), "\x07")
        .with_help("h\0");
    let out = text(&db, &d, false);
    assert!(!out.bytes().any(|b| b < 0x20 && b != b'\n'), "{out:?}");
    assert!(out.contains("`a\\0b\\u{1b}[2J`"), "{out}");
}

#[test]
fn a_counterexample_is_in_the_json() {
    use crate::diag::{Assignment, Counterexample, Overlap};
    let (db, f) = db_with("system {}\n");
    let cx = Counterexample {
        values: vec![Assignment { name: "Cart.x".into(), value: "0.5".into() }],
        overlap: Some(Overlap::at([1.0, 0.25, 0.0], vec![2.5])),
        trace: Vec::new(),
    };
    let d = Diagnostic::error(Code::FootprintsOverlap, Span::new(f, 0, 6), "overlap").with_counterexample(cx);
    let v = diagnostic_json(&db, &d);
    assert_eq!(
        v["counterexample"],
        json!({ "values": [{ "name": "Cart.x", "value": "0.5" }], "overlap": { "point": [1.0, 0.25, 0.0], "times": [2.5] } })
    );
}

/// A counterexample's trace (the path through the global type) is in the JSON as a
/// list of lines, after the values.
#[test]
fn a_counterexample_trace_is_in_the_json() {
    use crate::diag::{Assignment, Counterexample};
    let (db, f) = db_with("system {}\n");
    let cx = Counterexample {
        values: vec![Assignment { name: "i".into(), value: "0".into() }],
        overlap: None,
        trace: vec!["GCS -> UAV: count(c = 1)".into(), "mu t: i = 0".into()],
    };
    let d = Diagnostic::error(Code::MeasureNotDecreasing, Span::new(f, 0, 6), "no progress").with_counterexample(cx);
    let v = diagnostic_json(&db, &d);
    assert_eq!(v["counterexample"]["trace"], json!(["GCS -> UAV: count(c = 1)", "mu t: i = 0"]));
}

#[test]
fn report_json_has_every_field() {
    let (db, f) = db_with("// header\nconst a = ;\n");
    let d = Diagnostic::error(Code::UnexpectedToken, Span::new(f, 20, 21), "expected an expression")
        .with_label(Span::new(f, 0, 2), "here")
        .with_note("n");
    let v = report_json(&db, "a.chor", &report(vec![d]));
    assert_eq!(v["file"], "a.chor");
    assert_eq!(v["verdict"], "rejected");
    let d = &v["diagnostics"][0];
    assert_eq!(d["code"], "E0103");
    assert_eq!(d["severity"], "error");
    assert_eq!(d["message"], "expected an expression");
    assert_eq!((d["file"].as_str(), d["line"].as_u64(), d["column"].as_u64()), (Some("a.chor"), Some(2), Some(11)));
    assert!(d["help"].is_null(), "help is present even when absent: {d}");
    assert_eq!(d["notes"], json!(["n"]));
    assert_eq!(d["labels"], json!([{ "message": "here", "file": "a.chor", "line": 1, "column": 1 }]));
    assert!(d["counterexample"].is_null(), "a parse error has no counterexample: {d}");
    assert_eq!(v["checks"], json!([{ "name": "parse", "status": "fail", "millis": 0.25, "queries": 0 }]));
    let mut keys: Vec<&String> = v.as_object().map(|o| o.keys().collect()).unwrap_or_default();
    keys.sort();
    assert_eq!(keys, ["checks", "diagnostics", "file", "partitions", "vacuous", "verdict"]);
}
