//! `mochi check`'s output: a report's diagnostics (capped as rustc caps its own), its check
//! table and verdict line, the report and each diagnostic as JSON (the schema is part of
//! mochi's interface), `--clearance`, and the summary of a run of several inputs.

use super::Json;
use super::{buffer, contains, into_string, location_json, paint, Files};
use crate::diag::{Diagnostic, Severity};
use crate::driver::{Detail, Report, Status, Verdict};
use crate::source::SourceDb;
use codespan_reporting::term::termcolor::{Buffer, Color};
use serde_json::{json, Value};
use std::io::Write;

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
