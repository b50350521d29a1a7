//! `mochi simulate`'s output: the simulation report as text (each finding with the trace of
//! its run) or JSON.

use std::fmt::Write as _;

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

/// `mochi simulate --format json`: the report, pretty, its fields named and ordered as in
/// Rust (text, not a [`Json`] value, which would sort the keys).
pub fn simulation_json_text(r: &crate::simulate::SimReport) -> Result<String, String> {
    serde_json::to_string_pretty(r).map(|s| s + "\n").map_err(|e| e.to_string())
}
