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
//!
//! This file holds what every output shares: one diagnostic laid out as rustc does
//! ([`text`], through codespan-reporting, with the user's text escaped and spans clamped),
//! locations in JSON, and the colour decision. Each subcommand's output is a file of
//! `render/`: `report.rs` (`mochi check`), `project.rs`, `explain.rs`, `simulation.rs`,
//! `monitor.rs`, `mission.rs`; their functions are re-exported here
//! (`render::report_json`, `render::monitor_text`, ...). The proxy's event lines are not
//! here: the small enforcing executable writes them without this renderer
//! (`checker/monitor/src/proxy/lines.rs`).

use crate::diag::{Diagnostic, Severity};
use crate::source::{SourceDb, Span};
use codespan_reporting::diagnostic::{self as cs, LabelStyle};
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term::termcolor::{Buffer, Color, ColorSpec, WriteColor};
use codespan_reporting::term::{self, Chars};
use serde_json::Value;

/// A JSON value as this module builds it; `main.rs` only writes it ([`json_text`]).
pub use serde_json::Value as Json;
use std::borrow::Cow;
use std::io::Write;
use std::ops::Range;

mod explain;
mod mission;
mod monitor;
mod project;
mod report;
mod simulation;

pub use explain::{code_list_text, explain_text};
pub use mission::{mission_json, MissionFile, MissionList, MissionViolation};
pub use monitor::{monitor_json_text, monitor_text, MonitoredLog, MonitoredSession};
pub use project::{local_json, local_text, locals_json, locals_text};
pub use report::{
    clearance_json, clearance_text, diagnostic_json, diagnostics_text, no_report_json, report_json, report_text,
    run_summary_json, run_summary_text, summary_text, RunSummary, MAX_SHOWN, MAX_SHOWN_PER_CODE,
};
pub use simulation::{simulation_json_text, simulation_text};

/// Renders one diagnostic as rustc does: `error[E0301]: message`, `--> file:line:col`,
/// the source lines with carets, then `= note: ...` and `= help: ...`.
pub fn text(db: &SourceDb, d: &Diagnostic, color: bool) -> String {
    let files = Files::new(db);
    let mut out = buffer(color);
    files.emit(&mut out, d);
    into_string(out)
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

#[cfg(test)]
use explain::wrap;
#[cfg(test)]
mod tests;
