//! Rendering: turns [`Diagnostic`]s and [`Report`]s into terminal text (through
//! codespan-reporting, rustc's layout) or into JSON for tools.
//!
//! **Architecture invariant:** this is the only module that knows about colours and
//! output formats. Stages produce plain data; `main.rs` decides where it is written.
//! Rendering never panics, whatever the spans say: a span past the end of its file is
//! clamped, one in an unknown file loses its location but not its message.

use crate::diag::{Diagnostic, Severity};
use crate::driver::{Report, Status, Verdict};
use crate::source::{SourceDb, Span};
use codespan_reporting::diagnostic::{self as cs, LabelStyle};
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term::termcolor::{Buffer, Color, ColorSpec, WriteColor};
use codespan_reporting::term::{self, Chars};
use serde_json::{json, Value};
use std::io::Write;
use std::ops::Range;

/// Renders one diagnostic as rustc does: `error[E0301]: message`, `--> file:line:col`,
/// the source lines with carets, then `= note: ...` and `= help: ...`.
pub fn text(db: &SourceDb, d: &Diagnostic, color: bool) -> String {
    let files = Files::new(db);
    let mut out = buffer(color);
    files.emit(&mut out, d);
    into_string(out)
}

/// Renders every diagnostic of `report`, then a summary: one line per check (status,
/// name, time, detail) and the verdict for `file_name`. `verbose` adds the files that
/// were read and the local type of each role, when projection ran.
pub fn report_text(db: &SourceDb, file_name: &str, report: &Report, color: bool, verbose: bool) -> String {
    let files = Files::new(db);
    let mut out = buffer(color);
    for d in &report.diagnostics {
        files.emit(&mut out, d);
    }
    // A `Buffer` is a `Vec<u8>` underneath: writing to it cannot fail.
    let _ = write_summary(&mut out, db, file_name, report, verbose);
    into_string(out)
}

/// The check table and the verdict line of [`report_text`].
fn write_summary(
    out: &mut Buffer,
    db: &SourceDb,
    file_name: &str,
    report: &Report,
    verbose: bool,
) -> std::io::Result<()> {
    for c in &report.checks {
        let (word, colour) = match c.status {
            Status::Pass => ("pass", Color::Green),
            Status::Fail => ("FAIL", Color::Red),
            Status::Unknown => ("unknown", Color::Yellow),
        };
        write!(out, "  ")?;
        paint(out, colour, &format!("{word:<7}"))?;
        write!(out, "  {:<16} {:>8.1} ms", c.name, c.millis)?;
        if !c.detail.is_empty() {
            write!(out, "  {}", c.detail)?;
        }
        writeln!(out)?;
    }
    if verbose {
        for p in &report.partitions {
            writeln!(out, "  separation {p}")?;
        }
        let names: Vec<&str> = db.files().map(|(_, f)| f.name.as_str()).collect();
        writeln!(out, "  files read: {}", names.join(", "))?;
        for (role, local) in &report.projections {
            writeln!(out, "  local type of {role}:")?;
            for line in local.lines() {
                writeln!(out, "    {line}")?;
            }
        }
    }
    let (word, colour) = match report.verdict {
        Verdict::Verified => ("verified", Color::Green),
        Verdict::Rejected => ("rejected", Color::Red),
        Verdict::Unknown => ("unknown", Color::Yellow),
    };
    write!(out, "verdict: ")?;
    paint(out, colour, word)?;
    writeln!(out, " ({file_name})")?;
    Ok(())
}

/// The report as one JSON object. The schema is part of mochi's interface:
///
/// ```text
/// { "file", "verdict": "verified" | "rejected" | "unknown",
///   "diagnostics": [{ "code", "severity", "message", "file", "line", "column",
///                     "help", "notes", "labels": [{ "message", "file", "line", "column" }],
///                     "counterexample": null | { "values": [{ "name", "value" }],
///                                                "overlap": null | { "point": [x, y, z], "times": [t] } } }],
///   "checks": [{ "name", "status": "pass" | "fail" | "unknown", "millis", "queries" }],
///   "partitions": ["file:line:col: partition inferred: ..."],
///   "vacuous": number of obligations that held only because their context is unsatisfiable }
/// ```
///
/// Lines and columns are 1-based (columns count characters). A location in a file the
/// database does not hold is `null`.
pub fn report_json(db: &SourceDb, file_name: &str, report: &Report) -> Value {
    let verdict = match report.verdict {
        Verdict::Verified => "verified",
        Verdict::Rejected => "rejected",
        Verdict::Unknown => "unknown",
    };
    let checks: Vec<Value> = report
        .checks
        .iter()
        .map(|c| {
            let status = match c.status {
                Status::Pass => "pass",
                Status::Fail => "fail",
                Status::Unknown => "unknown",
            };
            // Microseconds are the last meaningful digit; more is noise in the output.
            let millis = (c.millis * 1000.0).round() / 1000.0;
            json!({ "name": c.name, "status": status, "millis": millis, "queries": c.queries })
        })
        .collect();
    json!({
        "file": file_name,
        "verdict": verdict,
        "diagnostics": report.diagnostics.iter().map(|d| diagnostic_json(db, d)).collect::<Vec<_>>(),
        "checks": checks,
        "partitions": report.partitions,
        "vacuous": report.vacuous,
    })
}

/// One diagnostic as a JSON object (an element of `report_json`'s `diagnostics`).
pub fn diagnostic_json(db: &SourceDb, d: &Diagnostic) -> Value {
    let severity = match d.severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Note => "note",
    };
    let (file, line, column) = location_json(db, d.span);
    let labels: Vec<Value> = d
        .labels
        .iter()
        .map(|l| {
            let (file, line, column) = location_json(db, l.span);
            json!({ "message": l.message, "file": file, "line": line, "column": column })
        })
        .collect();
    json!({
        "code": d.code.as_str(),
        "severity": severity,
        "message": d.message,
        "file": file,
        "line": line,
        "column": column,
        "help": d.help,
        "notes": d.notes,
        "labels": labels,
        "counterexample": d.counterexample.as_ref().map(|c| serde_json::to_value(c).unwrap_or(Value::Null)),
    })
}

fn location_json(db: &SourceDb, span: Span) -> (Value, Value, Value) {
    if !contains(db, span) {
        return (Value::Null, Value::Null, Value::Null);
    }
    let (file, line, column) = db.location(span);
    (file.into(), line.into(), column.into())
}

/// Whether `span` names a file of `db` (accessing any other panics in `SourceDb`).
fn contains(db: &SourceDb, span: Span) -> bool {
    db.files().nth(span.file.0 as usize).is_some()
}

/// The files of a `SourceDb` in codespan's form; codespan ids are `FileId` indices.
struct Files<'a> {
    db: &'a SourceDb,
    files: SimpleFiles<&'a str, &'a str>,
    config: term::Config,
}

impl<'a> Files<'a> {
    fn new(db: &'a SourceDb) -> Files<'a> {
        let mut files = SimpleFiles::new();
        for (_, f) in db.files() {
            files.add(f.name.as_str(), f.text.as_str());
        }
        // ASCII art (`-->`, `|`, `^`) as rustc prints it, and safe in any terminal.
        let config = term::Config { chars: Chars::ascii(), ..term::Config::default() };
        Files { db, files, config }
    }

    /// Writes `d` to `out`, or a plain one-line form if codespan refuses it.
    fn emit(&self, out: &mut Buffer, d: &Diagnostic) {
        let mut rich = if out.supports_color() { Buffer::ansi() } else { Buffer::no_color() };
        match term::emit(&mut rich, &self.config, &self.files, &self.to_codespan(d)) {
            Ok(()) => {
                let _ = out.write_all(rich.as_slice());
            }
            // Only a span codespan cannot place gets here; the clamping should prevent it.
            Err(_) => {
                let _ = self.emit_plain(out, d);
            }
        }
    }

    fn emit_plain(&self, out: &mut Buffer, d: &Diagnostic) -> std::io::Result<()> {
        let severity = severity_word(d.severity);
        writeln!(out, "{severity}[{}]: {}", d.code, d.message)?;
        if contains(self.db, d.span) {
            let (file, line, col) = self.db.location(d.span);
            writeln!(out, "  --> {file}:{line}:{col}")?;
        }
        for note in &d.notes {
            writeln!(out, "  = note: {note}")?;
        }
        if let Some(help) = &d.help {
            writeln!(out, "  = help: {help}")?;
        }
        writeln!(out)
    }

    fn to_codespan(&self, d: &Diagnostic) -> cs::Diagnostic<usize> {
        let severity = match d.severity {
            Severity::Error => cs::Severity::Error,
            Severity::Warning => cs::Severity::Warning,
            Severity::Note => cs::Severity::Note,
        };
        let primary = self.label(LabelStyle::Primary, d.span, "");
        let secondary = d.labels.iter().filter_map(|l| self.label(LabelStyle::Secondary, l.span, &l.message));
        let mut notes: Vec<String> = d.notes.iter().map(|n| format!("note: {n}")).collect();
        notes.extend(d.help.iter().map(|h| format!("help: {h}")));
        cs::Diagnostic::new(severity)
            .with_code(d.code.as_str())
            .with_message(&d.message)
            .with_labels(primary.into_iter().chain(secondary).collect())
            .with_notes(notes)
    }

    fn label(&self, style: LabelStyle, span: Span, message: &str) -> Option<cs::Label<usize>> {
        if !contains(self.db, span) {
            return None;
        }
        let text = &self.db.file(span.file).text;
        Some(cs::Label::new(style, span.file.0 as usize, clamp(text, span)).with_message(message))
    }
}

/// The byte range of `span` inside `text`: ends past the text are pulled back, and both
/// ends move outwards to character boundaries, so codespan can slice it safely.
fn clamp(text: &str, span: Span) -> Range<usize> {
    let mut start = (span.start as usize).min(text.len());
    while !text.is_char_boundary(start) {
        start -= 1;
    }
    let mut end = (span.end as usize).clamp(start, text.len());
    while !text.is_char_boundary(end) {
        end += 1;
    }
    start..end
}

fn severity_word(s: Severity) -> &'static str {
    match s {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Note => "note",
    }
}

fn buffer(color: bool) -> Buffer {
    if color {
        Buffer::ansi()
    } else {
        Buffer::no_color()
    }
}

fn paint(out: &mut Buffer, colour: Color, text: &str) -> std::io::Result<()> {
    out.set_color(ColorSpec::new().set_fg(Some(colour)).set_bold(true))?;
    write!(out, "{text}")?;
    out.reset()
}

fn into_string(out: Buffer) -> String {
    String::from_utf8_lossy(out.as_slice()).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::Code;
    use crate::driver::CheckResult;
    use crate::source::FileId;
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
                detail: "1 error(s)".into(),
                queries: 0,
            }],
            projections: BTreeMap::new(),
            partitions: Vec::new(),
            vacuous: 0,
        }
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
    fn a_counterexample_is_in_the_json() {
        use crate::diag::{Assignment, Counterexample, Overlap};
        let (db, f) = db_with("system {}\n");
        let cx = Counterexample {
            values: vec![Assignment { name: "Cart.x".into(), value: "0.5".into() }],
            overlap: Some(Overlap { point: [1.0, 0.25, 0.0], times: vec![2.5] }),
        };
        let d = Diagnostic::error(Code::FootprintsOverlap, Span::new(f, 0, 6), "overlap").with_counterexample(cx);
        let v = diagnostic_json(&db, &d);
        assert_eq!(
            v["counterexample"],
            json!({ "values": [{ "name": "Cart.x", "value": "0.5" }], "overlap": { "point": [1.0, 0.25, 0.0], "times": [2.5] } })
        );
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
}
