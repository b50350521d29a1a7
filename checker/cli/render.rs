//! Rendering: turns [`Diagnostic`]s and [`Report`]s into terminal text (through
//! codespan-reporting, rustc's layout) or into JSON for tools.
//!
//! **Architecture invariant:** this is the only module that knows about colours and
//! output formats (`tests/tidy.rs` checks that no other names `serde_json`, `termcolor`,
//! `codespan` or `NO_COLOR`). Stages produce plain data; `main.rs` gathers the facts
//! (is the stream a terminal, is `NO_COLOR` set), asks [`use_color`], and writes what
//! this module returns where it belongs.
//! Rendering never panics, whatever the spans say: a span past the end of its file is
//! clamped, one in an unknown file loses its location but not its message.

use crate::diag::{Code, Diagnostic, Severity};
use crate::driver::{Detail, Report, Status, Verdict};
use crate::source::{SourceDb, Span};
use codespan_reporting::diagnostic::{self as cs, LabelStyle};
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term::termcolor::{Buffer, Color, ColorSpec, WriteColor};
use codespan_reporting::term::{self, Chars};
use serde_json::{json, Value};

/// A JSON value as this module builds it; `main.rs` only writes it ([`json_text`]).
pub use serde_json::Value as Json;
use std::borrow::Cow;
use std::fmt::Write as _;
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

/// Renders every diagnostic of `report` ([`diagnostics_text`]), then a summary
/// ([`summary_text`]).
pub fn report_text(db: &SourceDb, file_name: &str, report: &Report, color: bool, verbose: bool) -> String {
    diagnostics_text(db, report, color) + &summary_text(db, file_name, report, color, verbose)
}

/// At most this many diagnostics of one report are rendered as text...
pub const MAX_SHOWN: usize = 50;
/// ...and at most this many of one code; the rest are counted in a last note
/// (`--format json` lists them all).
pub const MAX_SHOWN_PER_CODE: usize = 10;

/// The diagnostics of `report` as rustc shows them, capped like rustc's own limits: the
/// first [`MAX_SHOWN_PER_CODE`] of each code and [`MAX_SHOWN`] in all, then one line that
/// counts the others by code. 5 KB of garbage gives a screenful, not 38 MB.
pub fn diagnostics_text(db: &SourceDb, report: &Report, color: bool) -> String {
    let files = Files::new(db);
    let mut out = buffer(color);
    let mut shown = 0;
    let mut per_code: std::collections::BTreeMap<&str, (usize, usize)> = Default::default();
    for d in &report.diagnostics {
        let (seen, hidden) = per_code.entry(d.code.as_str()).or_default();
        if shown >= MAX_SHOWN || *seen >= MAX_SHOWN_PER_CODE {
            *hidden += 1;
            continue;
        }
        *seen += 1;
        shown += 1;
        files.emit(&mut out, d);
    }
    let hidden: Vec<String> =
        per_code.iter().filter(|(_, (_, h))| *h > 0).map(|(code, (_, h))| format!("{h} {code}")).collect();
    if !hidden.is_empty() {
        let total: usize = per_code.values().map(|(_, h)| h).sum();
        let _ = writeln!(
            out,
            "note: {total} more diagnostic(s) not shown ({}); `--format json` lists them all\n",
            hidden.join(", ")
        );
    }
    into_string(out)
}

/// The check table, the optional `--verbose` listings and the verdict line.
pub fn summary_text(db: &SourceDb, file_name: &str, report: &Report, color: bool, verbose: bool) -> String {
    let mut out = buffer(color);
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
        if c.detail != Detail::None {
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
    write!(out, " ({file_name})")?;
    // A protocol with no process (E0242; MAVLink, or a robot cell before its programs
    // exist): the verdict is the global type's only.
    if report.diagnostics.iter().any(|d| d.code == crate::diag::Code::ProtocolOnly) {
        write!(out, " -- protocol only: no process typed")?;
    }
    writeln!(out)?;
    Ok(())
}

/// The report as one JSON object. The schema is part of mochi's interface:
///
/// ```text
/// { "file", "verdict": "verified" | "rejected" | "unknown",
///   "diagnostics": [{ "code", "severity", "message", "file", "line", "column",
///                     "help", "notes", "labels": [{ "message", "file", "line", "column" }],
///                     "counterexample": null | { "values": [{ "name", "value" }],
///                                                "overlap": null | { "point": [x, y, z], "times": [t] },
///                                                "trace"?: [step] } }],   (a global type's path to the point)
///   "checks": [{ "name", "status": "pass" | "fail" | "unknown", "millis", "queries" }],
///   "partitions": [{ "file", "line", "column", "how": "written" | "inferred" | "queries",
///                    "point": null | [x, y, z],
///                    "sides": [{ "roles": [..], "region": null | "predicate",
///                                "box": null | [[x_lo, x_hi], [y_lo, y_hi], [z_lo, z_hi]] }] }],
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
        "partitions": report.separations,
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

/// `--clearance`: one line per pair, the certified least distance and where it is attained.
pub fn clearance_text(db: &SourceDb, pairs: &[crate::collision::PairClearance]) -> String {
    let mut out = String::from("clearance (least distance between bodies, m):\n");
    if pairs.is_empty() {
        out.push_str("  no pair of participants with bodies moves together\n");
    }
    let m = |v: f64| if v.is_finite() { format!("{v:.4}") } else { "?".to_string() };
    for p in pairs {
        let at = if contains(db, p.span) {
            let (f, l, c) = db.location(p.span);
            format!("{f}:{l}:{c}")
        } else {
            String::new()
        };
        let mut line = format!("  {} - {}: at least {}", p.a, p.b, m(p.lower));
        if p.upper.is_finite() {
            line.push_str(&format!(", {} attained", m(p.upper)));
            if let Some(t) = p.time {
                line.push_str(&format!(" at time {} s", m(t)));
            }
            if let Some([a, b]) = p.points {
                line.push_str(&format!(
                    " between ({}, {}, {}) and ({}, {}, {})",
                    m(a[0]),
                    m(a[1]),
                    m(a[2]),
                    m(b[0]),
                    m(b[1]),
                    m(b[2])
                ));
            }
        }
        if !at.is_empty() {
            line.push_str(&format!(" (joint motion at {at})"));
        }
        if let Some(n) = &p.note {
            line.push_str(&format!("; {n}"));
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

/// `--clearance` in `--format json`.
pub fn clearance_json(db: &SourceDb, pairs: &[crate::collision::PairClearance]) -> Value {
    let num = |v: f64| if v.is_finite() { serde_json::json!(v) } else { Value::Null };
    Value::Array(
        pairs
            .iter()
            .map(|p| {
                let (file, line, column) = location_json(db, p.span);
                serde_json::json!({
                    "a": p.a, "b": p.b, "lower": num(p.lower), "upper": num(p.upper),
                    "time": p.time, "points": p.points, "note": p.note,
                    "file": file, "line": line, "column": column,
                })
            })
            .collect(),
    )
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
    files: SimpleFiles<&'a str, Cow<'a, str>>,
    config: term::Config,
}

impl<'a> Files<'a> {
    fn new(db: &'a SourceDb) -> Files<'a> {
        let mut files = SimpleFiles::new();
        for (_, f) in db.files() {
            files.add(f.name.as_str(), displayable(&f.text));
        }
        // ASCII art (`-->`, `|`, `^`) as rustc prints it, and safe in any terminal.
        let config = term::Config { chars: Chars::ascii(), ..term::Config::default() };
        Files { db, files, config }
    }

    /// Writes `d` to `out`, or a plain one-line form if codespan refuses it. A diagnostic
    /// on a very long line (minified or generated input) shows a window of that line.
    fn emit(&self, out: &mut Buffer, d: &Diagnostic) {
        if self.on_long_line(d) {
            let d = &escaped(d);
            let _ = self.emit_long(out, d);
            return;
        }
        let mut rich = if out.supports_color() { Buffer::ansi() } else { Buffer::no_color() };
        match term::emit(&mut rich, &self.config, &self.files, &self.to_codespan(d)) {
            Ok(()) => {
                let _ = out.write_all(rich.as_slice());
            }
            // Only a span codespan cannot place gets here; the clamping should prevent it.
            Err(_) => {
                let _ = self.emit_plain(out, &escaped(d));
            }
        }
    }

    /// Whether a label of `d` touches a line longer than [`MAX_LINE`] characters.
    fn on_long_line(&self, d: &Diagnostic) -> bool {
        std::iter::once(d.span).chain(d.labels.iter().map(|l| l.span)).filter(|s| contains(self.db, *s)).any(|s| {
            let file = self.db.file(s.file);
            let (l1, _) = file.line_col(s.start as usize);
            let (l2, _) = file.line_col(s.end as usize);
            (l1..=l2.min(l1 + 2)).any(|l| file.line_text(l).len() > MAX_LINE)
        })
    }

    /// rustc's layout with the primary line cut to a window around the span, and the
    /// secondary labels as notes with their locations.
    fn emit_long(&self, out: &mut Buffer, d: &Diagnostic) -> std::io::Result<()> {
        let severity = severity_word(d.severity);
        writeln!(out, "{severity}[{}]: {}", d.code, d.message)?;
        if contains(self.db, d.span) {
            let (file, line, col) = self.db.location(d.span);
            writeln!(out, "  --> {file}:{line}:{col}")?;
            let text: Vec<char> = self.db.file(d.span.file).line_text(line).chars().collect();
            let width = (d.span.end.saturating_sub(d.span.start) as usize).max(1);
            let from = (col - 1).saturating_sub(WINDOW / 4);
            let to = (from + WINDOW).min(text.len());
            let shown: String = text[from.min(to)..to].iter().collect();
            let pad = line.to_string().len();
            let (pre, post) = (if from > 0 { "..." } else { "" }, if to < text.len() { "..." } else { "" });
            writeln!(out, "{:pad$} |", "")?;
            writeln!(out, "{line} | {pre}{}{post}", displayable(&shown))?;
            let caret_at = pre.len() + (col - 1 - from);
            let carets = width.min(to.saturating_sub(col - 1)).max(1);
            writeln!(out, "{:pad$} | {:caret_at$}{}", "", "", "^".repeat(carets))?;
            writeln!(
                out,
                "{:pad$} = note: line {line} has {} characters; columns {}-{to} are shown",
                "",
                text.len(),
                from + 1
            )?;
        }
        for l in &d.labels {
            if contains(self.db, l.span) {
                let (file, line, col) = self.db.location(l.span);
                writeln!(out, "  = note: {file}:{line}:{col}: {}", l.message)?;
            }
        }
        for note in &d.notes {
            writeln!(out, "  = note: {note}")?;
        }
        if let Some(help) = &d.help {
            writeln!(out, "  = help: {help}")?;
        }
        writeln!(out)
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
        let notes = notes.iter().map(|n| escape_controls(n).into_owned()).collect();
        cs::Diagnostic::new(severity)
            .with_code(d.code.as_str())
            .with_message(escape_controls(&d.message))
            .with_labels(primary.into_iter().chain(secondary).collect())
            .with_notes(notes)
    }

    fn label(&self, style: LabelStyle, span: Span, message: &str) -> Option<cs::Label<usize>> {
        if !contains(self.db, span) {
            return None;
        }
        let text = &self.db.file(span.file).text;
        Some(cs::Label::new(style, span.file.0 as usize, clamp(text, span)).with_message(escape_controls(message)))
    }
}

/// `s` with control characters other than line ends and tabs escaped (`\0`, `\u{1b}`):
/// messages quote the user's text (an import path, a string), which must not reach a
/// terminal raw.
fn escape_controls(s: &str) -> Cow<'_, str> {
    if !s.chars().any(|c| c.is_control() && c != '\n' && c != '\t') {
        return Cow::Borrowed(s);
    }
    Cow::Owned(
        s.chars()
            .map(
                |c| if c.is_control() && c != '\n' && c != '\t' { c.escape_debug().to_string() } else { c.to_string() },
            )
            .collect(),
    )
}

/// `d` with every text field passed through [`escape_controls`].
fn escaped(d: &Diagnostic) -> Diagnostic {
    let mut d = d.clone();
    d.message = escape_controls(&d.message).into_owned();
    d.notes = d.notes.iter().map(|n| escape_controls(n).into_owned()).collect();
    d.help = d.help.as_deref().map(|h| escape_controls(h).into_owned());
    for l in &mut d.labels {
        l.message = escape_controls(&l.message).into_owned();
    }
    d
}

/// Lines longer than this many bytes are shown as a window of [`WINDOW`] characters.
const MAX_LINE: usize = 240;
const WINDOW: usize = 120;

/// `text` as it may be written to a terminal: control characters other than tab and line
/// ends become `?` (one byte for one byte, so spans still fit), and a lone `\r` becomes
/// `\n` so codespan numbers lines as [`SourceDb`] does. A NUL or an escape sequence in
/// the input never reaches the terminal raw.
fn displayable(text: &str) -> Cow<'_, str> {
    let b = text.as_bytes();
    let bad = |i: usize| {
        let c = b[i];
        (c < 0x20 && c != b'\t' && c != b'\n' && c != b'\r')
            || c == 0x7f
            || (c == b'\r' && b.get(i + 1) != Some(&b'\n'))
    };
    if !(0..b.len()).any(bad) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    for (i, ch) in text.char_indices() {
        out.push(match ch {
            '\r' if b.get(i + 1) != Some(&b'\n') => '\n',
            '\t' | '\n' | '\r' => ch,
            c if c.is_ascii_control() => '?',
            c => c,
        });
    }
    Cow::Owned(out)
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

/// The report of `mochi simulate` as text: a summary line, then each finding with the
/// trace of its run.
pub fn simulation_text(file_name: &str, r: &crate::simulate::SimReport) -> String {
    use crate::simulate::Kind;
    let mut out = String::new();
    let failures = r.failures().count();
    let undecided = r.findings.len() - failures;
    let _ = writeln!(
        out,
        "{file_name}: {} runs, {} steps, {} queries: {}",
        r.runs,
        r.steps,
        r.queries,
        match (failures, undecided) {
            (0, 0) => "no collision, no stuck state".to_string(),
            (0, u) => format!("no collision, no stuck state; {u} run(s) stopped undecided"),
            (f, _) => format!("{f} finding(s)"),
        }
    );
    for f in &r.findings {
        let kind = match f.kind {
            Kind::Collision => "collision",
            Kind::Stuck => "stuck",
            Kind::Violation => "violation",
            Kind::Replay => "bug (a model did not replay)",
            Kind::Undecided => "undecided",
        };
        let _ = writeln!(out, "\n{kind} in run {}, step {}, at time {}: {}", f.run, f.step, f.time, f.message);
        for line in &f.trace {
            let _ = writeln!(out, "  {line}");
        }
    }
    out
}

/// `--color`: when to colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorChoice {
    /// Colour a terminal unless `NO_COLOR` is set to a non-empty value (no-color.org).
    Auto,
    Always,
    Never,
}

/// The environment variable that turns colour off under [`ColorChoice::Auto`].
pub const COLOR_OFF_VAR: &str = "NO_COLOR";

/// Whether to colour a stream: `is_terminal` says whether it is one, `no_color` is the
/// value of [`COLOR_OFF_VAR`] (the caller reads the environment).
pub fn use_color(choice: ColorChoice, is_terminal: bool, no_color: Option<&std::ffi::OsStr>) -> bool {
    match choice {
        ColorChoice::Always => true,
        ColorChoice::Never => false,
        ColorChoice::Auto => is_terminal && no_color.is_none_or(|v| v.is_empty()),
    }
}

/// `value` as text: one line (several inputs: JSON Lines) or pretty, with a final newline.
pub fn json_text(value: &Json, one_line: bool) -> Result<String, String> {
    let res = if one_line { serde_json::to_string(value) } else { serde_json::to_string_pretty(value) };
    res.map(|s| s + "\n").map_err(|e| e.to_string())
}

/// The JSON object of an input that yielded no report: `verdict` is `unreadable` (with
/// the reason) or `crashed`; the other fields of [`report_json`] are there, empty, so that
/// every input has the same shape.
pub fn no_report_json(file_name: &str, verdict: &str, error: &str) -> Json {
    json!({
        "file": file_name, "verdict": verdict, "error": error,
        "diagnostics": [], "checks": [], "partitions": []
    })
}

/// How many inputs of a `mochi check` run ended how, and how long the run took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunSummary {
    pub verified: usize,
    pub rejected: usize,
    pub unknown: usize,
    /// Inputs with no report: unreadable, or mochi crashed on them.
    pub unreadable: usize,
    pub seconds: f64,
}

/// The last line of a `mochi check` of several inputs, after a blank line:
/// `3 verified, 1 rejected, 0 unknown in 0.8 s`.
pub fn run_summary_text(s: &RunSummary) -> String {
    let unreadable = if s.unreadable > 0 { format!(", {} unreadable", s.unreadable) } else { String::new() };
    format!(
        "\n{} verified, {} rejected, {} unknown{unreadable} in {:.1} s\n",
        s.verified, s.rejected, s.unknown, s.seconds
    )
}

/// The last object of a `mochi check --format json` of several inputs (after one object
/// per input): `{"summary": {"files", "verified", "rejected", "unknown", "unreadable",
/// "seconds"}}`. It is the only object with a `summary` key (per-input objects have
/// `file`).
pub fn run_summary_json(s: &RunSummary) -> Json {
    let files = s.verified + s.rejected + s.unknown + s.unreadable;
    let seconds = (s.seconds * 1000.0).round() / 1000.0;
    json!({ "summary": {
        "files": files, "verified": s.verified, "rejected": s.rejected, "unknown": s.unknown,
        "unreadable": s.unreadable, "seconds": seconds,
    } })
}

/// `mochi project --role R`: R's local type on its own line.
pub fn local_text(local: &str) -> String {
    format!("{}\n", local.trim_end_matches('\n'))
}

/// `mochi project`: every local type as a `local R = T;` line.
pub fn locals_text(locals: &[(&String, &String)]) -> String {
    locals.iter().map(|(role, local)| format!("local {role} = {};\n", local.trim_end())).collect()
}

/// `mochi project --role R --format json`: `{"file", "role", "local"}`.
pub fn local_json(file_name: &str, role: &str, local: &str) -> Json {
    json!({ "file": file_name, "role": role, "local": local })
}

/// `mochi project --format json`: `{"file", "locals": [{"role", "local"}]}`.
pub fn locals_json(file_name: &str, locals: &[(&String, &String)]) -> Json {
    let locals: Vec<Value> = locals.iter().map(|(role, local)| json!({ "role": role, "local": local })).collect();
    json!({ "file": file_name, "locals": locals })
}

/// `mochi simulate --format json`: the report, pretty, its fields named and ordered as in
/// Rust (text, not a [`Json`] value, which would sort the keys).
pub fn simulation_json_text(r: &crate::simulate::SimReport) -> Result<String, String> {
    serde_json::to_string_pretty(r).map(|s| s + "\n").map_err(|e| e.to_string())
}

/// `mochi explain CODE`: the title, a blank line, and the paragraph wrapped at 90 columns.
pub fn explain_text(code: Code) -> String {
    format!("{code}: {}\n\n{}\n", code.title(), wrap(code.explain(), 90))
}

/// `mochi explain --list`: every code and its title, sorted by code.
pub fn code_list_text() -> String {
    let mut codes = Code::ALL.to_vec();
    codes.sort_by_key(|c| c.as_str());
    codes.iter().map(|c| format!("{c}  {}\n", c.title())).collect()
}

/// Greedy word wrap at `width` characters; a longer word gets a line of its own.
fn wrap(text: &str, width: usize) -> String {
    let mut out = String::new();
    let mut line_len = 0;
    for word in text.split_whitespace() {
        let n = word.chars().count();
        if line_len > 0 && line_len + 1 + n > width {
            out.push('\n');
            line_len = 0;
        } else if line_len > 0 {
            out.push(' ');
            line_len += 1;
        }
        out.push_str(word);
        line_len += n;
    }
    out
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
        assert_eq!(
            run_summary_text(&RunSummary { unreadable: 0, ..s }),
            "\n3 verified, 1 rejected, 0 unknown in 0.8 s\n"
        );
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
        assert_eq!(
            Detail::PastDeadline { seconds: 0.5 }.to_string(),
            "not checked: the --deadline of 0.5 s had passed"
        );
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
        let d = Diagnostic::error(Code::UnexpectedChar, Span::new(f, 5000, 5001), "unexpected character `\\0`")
            .with_help("h");
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
            overlap: Some(Overlap { point: [1.0, 0.25, 0.0], times: vec![2.5], not_before: None }),
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
        let d =
            Diagnostic::error(Code::MeasureNotDecreasing, Span::new(f, 0, 6), "no progress").with_counterexample(cx);
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
}

/// One session of a monitored log, for [`monitor_text`] and [`monitor_json_text`].
#[derive(Clone, Debug)]
pub struct MonitoredSession {
    pub protocol: String,
    pub session: u64,
    /// Ended in `end`; otherwise incomplete (the log ended, or the session was abandoned).
    pub conformant: bool,
    /// The state it ended in (its number in the automaton).
    pub state: u32,
    pub first_frame: u64,
    pub last_frame: u64,
    /// Each role and the end it was bound to (`GCS = 255/190`).
    pub roles: Vec<String>,
    pub violations: u32,
    /// Coverage: states visited and edges taken, of the automaton's.
    pub states: (usize, usize),
    pub edges: (usize, usize),
}

/// What `mochi monitor` found in one log.
#[derive(Clone, Debug, Default)]
pub struct MonitoredLog {
    pub file: String,
    /// The format read (`tlog`, `raw`, `pcapng`, ...).
    pub format: String,
    /// The reader's counts (frames, bad CRC, truncated, unknown ids, garbage bytes).
    pub counts: crate::mavio::parse::Counts,
    /// Messages passed through (outside every protocol's alphabet), steps taken, violations.
    pub stats: crate::monitor::Stats,
    pub sessions: Vec<MonitoredSession>,
    /// Each violation in words ([`crate::monitor::Monitor::describe`]).
    pub violations: Vec<String>,
    /// Why the log could not be read, if it could not.
    pub error: Option<String>,
}

/// How many violations of one log the text report shows in full.
const MONITOR_VIOLATIONS_SHOWN: usize = 10;

/// `mochi monitor`'s report as text: per log, what was read, each session's verdict and
/// coverage, each violation.
pub fn monitor_text(logs: &[MonitoredLog]) -> String {
    let mut out = String::new();
    for l in logs {
        if let Some(e) = &l.error {
            let _ = writeln!(out, "{}: cannot be read: {e}", l.file);
            continue;
        }
        let c = &l.counts;
        let _ = writeln!(
            out,
            "{} ({}): {} frames ({} MAVLink 1, {} signed); {} bad CRC, {} truncated, {} unknown ids, {} garbage bytes",
            l.file, l.format, c.frames, c.v1, c.signed, c.bad_crc, c.truncated, c.unknown_id, c.garbage_bytes
        );
        let s = &l.stats;
        let _ = writeln!(
            out,
            "  {} passed through (outside every protocol), {} protocol steps, {} sessions, {} violations",
            s.passed,
            s.steps,
            l.sessions.len(),
            s.violations
        );
        for x in &l.sessions {
            let _ = writeln!(
                out,
                "  session {} of `{}` ({}), frames {}-{}: {}{}; coverage: {}/{} states, {}/{} edges",
                x.session,
                x.protocol,
                x.roles.join(", "),
                x.first_frame,
                x.last_frame,
                if x.conformant { "conformant".to_string() } else { format!("incomplete (in state {})", x.state) },
                if x.violations > 0 { format!(", {} violation(s)", x.violations) } else { String::new() },
                x.states.0,
                x.states.1,
                x.edges.0,
                x.edges.1
            );
        }
        // The first violations in full; all of them are in `--format json`.
        for v in l.violations.iter().take(MONITOR_VIOLATIONS_SHOWN) {
            let _ = writeln!(out, "  violation: {}", v.replace('\n', "\n    "));
        }
        if l.violations.len() > MONITOR_VIOLATIONS_SHOWN {
            let _ = writeln!(
                out,
                "  ... and {} more violation(s) (`--format json` lists them all)",
                l.violations.len() - MONITOR_VIOLATIONS_SHOWN
            );
        }
    }
    let violations: u64 = logs.iter().map(|l| l.stats.violations).sum();
    let unread = logs.iter().filter(|l| l.error.is_some()).count();
    let _ = writeln!(
        out,
        "monitor: {} log(s), {} violation(s){}",
        logs.len(),
        violations,
        if unread > 0 { format!(", {unread} not readable") } else { String::new() }
    );
    out
}

/// `mochi monitor`'s report as one JSON document.
pub fn monitor_json_text(logs: &[MonitoredLog]) -> Result<String, String> {
    let logs: Vec<Value> = logs
        .iter()
        .map(|l| {
            let c = &l.counts;
            let s = &l.stats;
            json!({
                "file": l.file,
                "format": l.format,
                "error": l.error,
                "frames": {"total": c.frames, "v1": c.v1, "signed": c.signed, "bad_crc": c.bad_crc,
                           "bad_signature": c.bad_signature, "bad_flags": c.bad_flags,
                           "unknown_id": c.unknown_id, "truncated": c.truncated, "garbage_bytes": c.garbage_bytes},
                "passed": s.passed,
                "steps": s.steps,
                "violations": l.violations,
                "sessions": l.sessions.iter().map(|x| json!({
                    "protocol": x.protocol, "session": x.session, "conformant": x.conformant,
                    "state": x.state, "first_frame": x.first_frame, "last_frame": x.last_frame,
                    "roles": x.roles, "violations": x.violations,
                    "coverage": {"states": [x.states.0, x.states.1], "edges": [x.edges.0, x.edges.1]},
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    serde_json::to_string_pretty(&json!({ "logs": logs })).map_err(|e| e.to_string())
}

/// `mochi proxy`'s first line: the ends it opened and what it enforces (docs/proxy.md).
pub fn proxy_start_json(
    gcs: &str,
    gcs_local: Option<String>,
    vehicle: &str,
    vehicle_local: Option<String>,
    protocols: &[String],
    alert_only: bool,
) -> String {
    json!({
        "event": "start",
        "gcs": gcs,
        "gcs_local": gcs_local,
        "vehicle": vehicle,
        "vehicle_local": vehicle_local,
        "protocols": protocols,
        "mode": if alert_only { "alert-only" } else { "enforce" },
    })
    .to_string()
}

/// One event of `mochi proxy` as one JSON line (no newline); `protocols` are the names of
/// the protocols enforced, which the events index (docs/proxy.md, "Output").
pub fn proxy_event_json(e: &crate::proxy::Event, protocols: &[String]) -> String {
    use crate::proxy::{At, Event};
    let name = |p: Option<usize>| p.and_then(|p| protocols.get(p)).cloned();
    let head = |event: &str, at: &At| {
        json!({
            "event": event,
            "time_us": at.time_us,
            "dir": at.dir.as_str(),
            "msgid": at.msgid,
            "from": format!("{}/{}", at.from.0, at.from.1),
            "signed": at.signed,
        })
    };
    let mut v = match e {
        Event::Step { at, session, state } => {
            let mut v = head("step", at);
            v["session"] = json!(session);
            v["state"] = json!(state);
            v["action"] = json!("forward");
            v
        }
        Event::End { at, session, protocol, conformant } => {
            let mut v = head("end", at);
            v["session"] = json!(session);
            v["protocol"] = json!(name(*protocol));
            v["conformant"] = json!(conformant);
            v["action"] = json!("forward");
            v
        }
        Event::Violation { at, kind, protocol, session, state, field, detail, forwarded } => {
            let mut v = head("violation", at);
            v["kind"] = json!(kind.as_str());
            if protocol.is_some() {
                v["protocol"] = json!(name(*protocol));
            }
            if let Some(s) = session {
                v["session"] = json!(s);
            }
            v["state"] = json!(state);
            if let Some(f) = field {
                v["field"] = json!(f);
            }
            if let Some(d) = detail {
                v["detail"] = json!(d);
            }
            v["action"] = json!(if *forwarded { "alert" } else { "drop" });
            v
        }
        Event::Input { time_us, dir, counts: c } => json!({
            "event": "input",
            "time_us": time_us,
            "dir": dir.as_str(),
            "frames": c.frames,
            "signed": c.signed,
            "bad_crc": c.bad_crc,
            "bad_signature": c.bad_signature,
            "bad_flags": c.bad_flags,
            "unknown_id": c.unknown_id,
            "truncated": c.truncated,
            "garbage_bytes": c.garbage_bytes,
        }),
        Event::Reset { time_us, reason, open_sessions_lost, resets } => json!({
            "event": "reset",
            "time_us": time_us,
            "reason": reason,
            "open_sessions_lost": open_sessions_lost,
            "resets": resets,
        }),
        Event::Error { dir, error } => json!({ "event": "error", "dir": dir.as_str(), "error": error }),
    };
    v.take().to_string()
}

/// One mission file as `mochi mission` found it (`checker/cli/mission_cmd.rs`), to render.
pub struct MissionFile {
    pub file: String,
    /// The file's format, or `None` when it could not be read.
    pub format: Option<String>,
    /// `accepted`, `rejected` or `unreadable`.
    pub verdict: &'static str,
    pub error: Option<String>,
    pub lists: Vec<MissionList>,
}

/// One list of a mission file (mission, fence, rally) against one protocol.
pub struct MissionList {
    pub mission_type: &'static str,
    pub items: usize,
    pub protocol: String,
    /// `conformant`, `incomplete` or `violation`.
    pub verdict: &'static str,
    pub violations: Vec<MissionViolation>,
}

/// A violation of the upload trace, at the frame and (where it is an item's) the file's line.
pub struct MissionViolation {
    pub frame: u64,
    pub message: String,
    pub item: Option<usize>,
    pub line: Option<u32>,
    pub kind: &'static str,
    pub field: Option<String>,
    pub detail: String,
}

/// `mochi mission --format json`: one object per file.
pub fn mission_json(m: &MissionFile) -> String {
    let v = match &m.format {
        None => json!({"file": m.file, "verdict": m.verdict, "error": m.error}),
        Some(format) => {
            let lists: Vec<Value> = m
                .lists
                .iter()
                .map(|l| {
                    let violations: Vec<Value> = l
                        .violations
                        .iter()
                        .map(|v| {
                            json!({
                                "frame": v.frame, "message": v.message, "item": v.item, "line": v.line,
                                "kind": v.kind, "field": v.field, "detail": v.detail,
                            })
                        })
                        .collect();
                    json!({
                        "mission_type": l.mission_type,
                        "items": l.items,
                        "protocol": l.protocol,
                        "verdict": l.verdict,
                        "violations": violations,
                    })
                })
                .collect();
            json!({"file": m.file, "format": format, "verdict": m.verdict, "lists": lists})
        }
    };
    v.to_string()
}
