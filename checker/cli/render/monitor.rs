//! `mochi monitor`'s output: each log's sessions (conformant or not, coverage) and
//! violations, as text or JSON.

use serde_json::{json, Value};
use std::fmt::Write as _;

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
