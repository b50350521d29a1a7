//! `mochi mission`'s output: each mission file's lists and the violations found in them, as
//! one JSON line per file.

use serde_json::{json, Value};

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
