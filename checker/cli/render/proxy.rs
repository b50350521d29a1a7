//! `mochi proxy`'s output: its first line and one JSON line per event (docs/proxy.md).

use serde_json::json;

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
        Event::Late { at, session, forwarded } => {
            let mut v = head("late", at);
            v["session"] = json!(session);
            v["action"] = json!(if *forwarded { "forward" } else { "drop" });
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
