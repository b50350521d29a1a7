//! The hand-written lines against serde_json's: the same object, byte for byte, for every
//! kind of event and for strings with every character class serde_json escapes.

use super::*;
use crate::mavio::parse::Counts;
use crate::monitor::Kind;
use crate::proxy::{Dir, Sink};
use proptest::prelude::*;
use serde_json::json;

/// The reference: the event as a serde_json object (the format docs/proxy.md gives).
fn reference(e: &Event, protocols: &[String]) -> String {
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
    let v = match e {
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
    v.to_string()
}

fn mine(e: &Event, protocols: &[String]) -> String {
    let mut out = Vec::new();
    event_line(&mut out, e, protocols);
    String::from_utf8(out).expect("UTF-8")
}

const KINDS: [Kind; 12] = [
    Kind::Guard,
    Kind::Refinement,
    Kind::Entry,
    Kind::NonFinite,
    Kind::Undefined,
    Kind::Undecided,
    Kind::Invariant,
    Kind::Unexpected,
    Kind::OutsideSession,
    Kind::Stream,
    Kind::NoReading,
    Kind::Early,
];

/// Every kind of event, with each optional field present and absent, and a protocol index
/// out of range (a `null` name).
fn every_event(text: &str) -> Vec<Event> {
    let at = |dir, signed| At { time_us: u64::MAX, dir, msgid: 16_777_215, from: (255, 0), signed };
    let mut out = vec![
        Event::Step { at: at(Dir::GcsToVehicle, false), session: 0, state: u32::MAX },
        Event::End { at: at(Dir::VehicleToGcs, true), session: 7, protocol: Some(1), conformant: true },
        Event::End { at: at(Dir::VehicleToGcs, false), session: 7, protocol: Some(9), conformant: false },
        Event::End { at: at(Dir::VehicleToGcs, false), session: 7, protocol: None, conformant: false },
        Event::Late { at: at(Dir::GcsToVehicle, false), session: 3, forwarded: false },
        Event::Late { at: at(Dir::GcsToVehicle, true), session: 3, forwarded: true },
        Event::Input {
            time_us: 1,
            dir: Dir::VehicleToGcs,
            counts: Counts {
                frames: 1,
                signed: 2,
                v1: 3,
                bad_crc: 4,
                bad_signature: 5,
                bad_flags: 6,
                unknown_id: 7,
                truncated: 8,
                garbage_bytes: 9,
            },
        },
        Event::Reset { time_us: 10, reason: "too many open sessions", open_sessions_lost: 1024, resets: 2 },
        Event::Error { dir: Dir::GcsToVehicle, error: text.to_string() },
    ];
    for (i, kind) in KINDS.into_iter().enumerate() {
        let some = i % 2 == 0;
        out.push(Event::Violation {
            at: at(if some { Dir::GcsToVehicle } else { Dir::VehicleToGcs }, some),
            kind,
            protocol: [Some(0), None, Some(5)][i % 3],
            session: some.then_some(i as u64),
            state: i as u32,
            field: some.then(|| text.to_string()),
            detail: (i % 3 != 1).then(|| format!("{text} at x.chor:1:2")),
            forwarded: i % 4 == 0,
        });
    }
    out
}

fn protocols() -> Vec<String> {
    vec!["UploadTolerant".into(), "Param\"Set\\\n".into()]
}

#[test]
fn every_event_is_what_serde_json_writes() {
    let all: String = (0u8..=0x7f).map(char::from).chain("é€😀\u{2028}".chars()).collect();
    for text in ["", "param_value", all.as_str()] {
        for e in every_event(text) {
            assert_eq!(mine(&e, &protocols()), reference(&e, &protocols()), "{e:?}");
        }
    }
}

#[test]
fn the_start_line_is_what_serde_json_writes() {
    for (local, protos) in [(Some("127.0.0.1:14550"), protocols()), (None, Vec::new())] {
        let mut out = Vec::new();
        start_line(&mut out, "udpin:0.0.0.0:14550", local, "udpout:\"x\":1", None, &protos, local.is_some());
        let reference = json!({
            "event": "start",
            "gcs": "udpin:0.0.0.0:14550",
            "gcs_local": local,
            "vehicle": "udpout:\"x\":1",
            "vehicle_local": None::<String>,
            "protocols": protos,
            "mode": if local.is_some() { "alert-only" } else { "enforce" },
        })
        .to_string();
        assert_eq!(String::from_utf8(out).unwrap(), reference);
    }
}

#[test]
fn a_batch_is_one_line_per_event_and_the_buffer_is_reused() {
    let lines = Lines::new(Vec::new(), protocols());
    let events = every_event("x");
    lines.events(&events);
    let cap = lines.state.lock().unwrap().0.capacity();
    lines.events(&events[..1]);
    let g = lines.state.lock().unwrap();
    assert_eq!(g.0.capacity(), cap, "the buffer kept its capacity");
    let text = String::from_utf8(g.1.clone()).unwrap();
    assert_eq!(text.lines().count(), events.len() + 1);
    for (line, e) in text.lines().zip(events.iter().chain(&events[..1])) {
        assert_eq!(line, reference(e, &protocols()));
    }
}

proptest! {
    #[test]
    fn any_text_is_escaped_as_serde_json_escapes_it(text in any::<String>(), n in any::<u64>()) {
        let e = Event::Violation {
            at: At { time_us: n, dir: Dir::GcsToVehicle, msgid: (n >> 40) as u32, from: (n as u8, (n >> 8) as u8), signed: n % 2 == 0 },
            kind: Kind::Refinement,
            protocol: Some((n % 3) as usize),
            session: Some(n),
            state: n as u32,
            field: Some(text.clone()),
            detail: Some(text.clone()),
            forwarded: false,
        };
        prop_assert_eq!(mine(&e, std::slice::from_ref(&text)), reference(&e, &[text]));
    }
}
