//! What a log contains, in the terms of the protocols under `choreographies/mavlink/`: the
//! sessions that appear (mission uploads and downloads, parameter reads, sets and list
//! streams, command/ack pairs), heartbeats and telemetry rates, and the (system, component)
//! pairs seen. A description of the data for the people writing and checking protocols, not
//! a verdict: it decides nothing about conformance (that is the monitor's work), and its
//! session boundaries are the plain ones below.
//!
//! Sessions, keyed by the two ends (sysid/compid of the opener and of the target the opening
//! message names):
//!
//! - **mission transfer**: MISSION_COUNT from A to B opens it, unless B has a download from A
//!   open (then the COUNT is the download's): an upload from A, or a download whose
//!   MISSION_REQUEST_LIST the log does not have (after the COUNT the two are the same
//!   exchange). MISSION_REQUEST(_INT) from B and MISSION_ITEM(_INT) from A belong to it;
//!   MISSION_ACK from B to A closes it with its result (an ACK from A, a cancel, closes it
//!   too, marked "from the sender"). A new COUNT before the ACK abandons the open one.
//! - **mission download**: MISSION_REQUEST_LIST from A to B opens it; MISSION_COUNT,
//!   MISSION_ITEM(_INT) from B belong to it; MISSION_ACK from A closes it.
//! - **param list stream**: PARAM_REQUEST_LIST from A to B opens it; it has no closing message:
//!   it counts B's PARAM_VALUEs until the next PARAM_REQUEST_LIST between the same ends or the
//!   end of the log, and reports how many distinct indices of `param_count` arrived.
//! - **param read / param set**: PARAM_REQUEST_READ or PARAM_SET from A to B, answered by the
//!   next PARAM_VALUE from B with the same name (or, for a read by index, the same index).
//!   Reads, sets and commands may be pipelined: a new one abandons an open one only for the
//!   same parameter or command.
//! - **command**: COMMAND_LONG or COMMAND_INT from A to B with command c, answered by the next
//!   COMMAND_ACK from B to A for c (IN_PROGRESS acks counted, the final one closes it).
//!
//! A message of a session whose opener the log does not have (a log started mid-session) is
//! counted as an orphan of its kind.

use super::log::read_log;
use super::parse::Config;
use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::{MavlinkVersion, Message};
use std::collections::BTreeMap;
use std::fmt::Write;

/// A (system id, component id) pair.
pub type Ends = (u8, u8);

/// How a session ended.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum End {
    /// Closed by its final message, with the result it carried (MAV_MISSION_RESULT or
    /// MAV_RESULT name).
    Closed(String),
    /// Another session between the same ends began first.
    Abandoned,
    /// The log ended first.
    Open,
}

/// One session found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Session {
    /// "mission transfer", "mission download", "param list", "param read", "param set", "command".
    pub kind: &'static str,
    /// Who opened it.
    pub from: Ends,
    /// Whom it addressed.
    pub to: Ends,
    /// Details: mission type and count, parameter name, command.
    pub what: String,
    /// Messages that belonged to it (the opener included).
    pub messages: u32,
    /// How it ended.
    pub end: End,
}

/// Everything counted in one log.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Census {
    /// Frames read, and the log's format.
    pub frames: u64,
    /// The log's format name.
    pub format: &'static str,
    /// Framing counts.
    pub counts: super::parse::Counts,
    /// Messages per (sysid, compid).
    pub senders: BTreeMap<Ends, u64>,
    /// Per (sysid, compid): HEARTBEATs, first and last time (µs).
    pub heartbeats: BTreeMap<Ends, (u64, Option<u64>, Option<u64>)>,
    /// Per message name of the streamed telemetry the protocols meet (GLOBAL_POSITION_INT,
    /// MISSION_CURRENT, SYS_STATUS, ...): count, first and last time.
    pub telemetry: BTreeMap<&'static str, (u64, Option<u64>, Option<u64>)>,
    /// The sessions, in the order they opened.
    pub sessions: Vec<Session>,
    /// Messages of a session kind without an open session, per message name.
    pub orphans: BTreeMap<&'static str, u64>,
}

/// Telemetry whose rate the protocols care about.
const TELEMETRY: &[&str] =
    &["GLOBAL_POSITION_INT", "MISSION_CURRENT", "SYS_STATUS", "ATTITUDE", "GPS_RAW_INT", "VFR_HUD", "STATUSTEXT"];

fn param_name(id: &[u8; 16]) -> String {
    id.iter().take_while(|&&b| b != 0).map(|&b| b as char).collect()
}

fn bump(m: &mut BTreeMap<&'static str, u64>, k: &'static str) {
    *m.entry(k).or_default() += 1;
}

/// The census of the log in `bytes`.
pub fn census(bytes: &[u8], config: Config) -> Census {
    let mut c = Census::default();
    let mut open: Vec<usize> = Vec::new();
    let mut sessions: Vec<Session> = Vec::new();
    // Per param list session: distinct indices seen and the count announced.
    let mut lists: BTreeMap<usize, (std::collections::BTreeSet<u16>, u16)> = BTreeMap::new();
    let summary = read_log(bytes, config, |f| {
        c.frames += 1;
        let me = (f.sysid, f.compid);
        *c.senders.entry(me).or_default() += 1;
        let v = if f.version == 1 { MavlinkVersion::V1 } else { MavlinkVersion::V2 };
        let Ok(m) = MavMessage::parse(v, f.msgid, f.payload) else { return };
        let name = m.message_name();
        if let Some(t) = TELEMETRY.iter().find(|t| **t == name) {
            let e = c.telemetry.entry(t).or_insert((0, None, None));
            e.0 += 1;
            e.1 = e.1.or(f.time_us);
            e.2 = f.time_us.or(e.2);
        }
        let target = (m.target_system_id().unwrap_or(0), m.target_component_id().unwrap_or(0));
        // The open session of `kind` between `a` (opener) and `b`: the target's component 0
        // stands for any component of its system (MAV_COMP_ID_ALL).
        let find = |sessions: &[Session], open: &[usize], kind: &str, a: Ends, b: Ends| -> Option<usize> {
            open.iter().rev().copied().find(|&i| {
                let s = &sessions[i];
                s.kind == kind && s.from == a && (s.to == b || (s.to.0 == b.0 && (s.to.1 == 0 || b.1 == 0)))
            })
        };
        let start = |sessions: &mut Vec<Session>, open: &mut Vec<usize>, kind: &'static str, what: String| {
            // Reads, sets and commands are pipelined: only one for the same name or command
            // abandons the open one.
            let keyed = matches!(kind, "param read" | "param set" | "command");
            if let Some(i) = find(sessions, open, kind, me, target).filter(|&i| !keyed || sessions[i].what == what) {
                sessions[i].end = End::Abandoned;
                open.retain(|&j| j != i);
            }
            sessions.push(Session { kind, from: me, to: target, what, messages: 1, end: End::Open });
            open.push(sessions.len() - 1);
            sessions.len() - 1
        };
        let close = |sessions: &mut Vec<Session>, open: &mut Vec<usize>, i: usize, result: String| {
            sessions[i].messages += 1;
            sessions[i].end = End::Closed(result);
            open.retain(|&j| j != i);
        };
        // MISSION_REQUEST and MISSION_ITEM are deprecated in the dialect, but real peers still
        // send them (ArduPilot answers either), so they are sessions' messages too.
        #[allow(deprecated)]
        match &m {
            MavMessage::MISSION_COUNT(d) => {
                // The vehicle's answer to a download the target opened?
                if let Some(i) = find(&sessions, &open, "mission download", target, me) {
                    sessions[i].messages += 1;
                    sessions[i].what =
                        format!("{:?} count {}", d.mission_type, d.count).replace("MAV_MISSION_TYPE_", "");
                } else {
                    let what = format!("{:?} count {}", d.mission_type, d.count).replace("MAV_MISSION_TYPE_", "");
                    start(&mut sessions, &mut open, "mission transfer", what);
                }
            }
            MavMessage::MISSION_REQUEST_LIST(d) => {
                let what = format!("{:?}", d.mission_type).replace("MAV_MISSION_TYPE_", "");
                start(&mut sessions, &mut open, "mission download", what);
            }
            MavMessage::MISSION_REQUEST(_) | MavMessage::MISSION_REQUEST_INT(_) => {
                match find(&sessions, &open, "mission transfer", target, me) {
                    Some(i) => sessions[i].messages += 1,
                    None => bump(&mut c.orphans, name),
                }
            }
            MavMessage::MISSION_ITEM(_) | MavMessage::MISSION_ITEM_INT(_) => {
                let up = find(&sessions, &open, "mission transfer", me, target);
                let down = find(&sessions, &open, "mission download", target, me);
                match up.or(down) {
                    Some(i) => sessions[i].messages += 1,
                    None => bump(&mut c.orphans, name),
                }
            }
            MavMessage::MISSION_ACK(d) => {
                let result = format!("{:?}", d.mavtype).replace("MAV_MISSION_", "");
                let up = find(&sessions, &open, "mission transfer", target, me);
                let down = find(&sessions, &open, "mission download", me, target);
                // The sender of the list may end it too (MAVLink: a cancel is an ACK from it).
                let by_sender = find(&sessions, &open, "mission transfer", me, target)
                    .or_else(|| find(&sessions, &open, "mission download", target, me));
                match (up.or(down), by_sender) {
                    (Some(i), _) => close(&mut sessions, &mut open, i, result),
                    (None, Some(i)) => close(&mut sessions, &mut open, i, format!("{result} from the sender")),
                    (None, None) => bump(&mut c.orphans, name),
                }
            }
            MavMessage::PARAM_REQUEST_LIST(_) => {
                let i = start(&mut sessions, &mut open, "param list", String::new());
                lists.insert(i, (Default::default(), 0));
            }
            MavMessage::PARAM_REQUEST_READ(d) => {
                let what = if d.param_index >= 0 { format!("#{}", d.param_index) } else { param_name(&d.param_id) };
                start(&mut sessions, &mut open, "param read", what);
            }
            MavMessage::PARAM_SET(d) => {
                start(&mut sessions, &mut open, "param set", param_name(&d.param_id));
            }
            MavMessage::PARAM_VALUE(d) => {
                let pname = param_name(&d.param_id);
                let index = format!("#{}", d.param_index);
                // A read or set this answers (by name, or a read by index).
                let answered = open.iter().rev().copied().find(|&i| {
                    let s = &sessions[i];
                    (s.kind == "param read" || s.kind == "param set")
                        && s.to.0 == me.0
                        && (s.what == pname || s.what == index)
                });
                if let Some(i) = answered {
                    close(&mut sessions, &mut open, i, "PARAM_VALUE".into());
                } else if let Some(&i) =
                    open.iter().rev().find(|&&i| sessions[i].kind == "param list" && sessions[i].to.0 == me.0)
                {
                    sessions[i].messages += 1;
                    if let Some((seen, count)) = lists.get_mut(&i) {
                        // Index 65535 is a value outside the list (sent after a set).
                        if d.param_index != u16::MAX {
                            seen.insert(d.param_index);
                        }
                        *count = d.param_count;
                    }
                } else {
                    bump(&mut c.orphans, name);
                }
            }
            MavMessage::COMMAND_LONG(d) => {
                start(&mut sessions, &mut open, "command", format!("{:?}", d.command));
            }
            MavMessage::COMMAND_INT(d) => {
                start(&mut sessions, &mut open, "command", format!("{:?}", d.command));
            }
            MavMessage::COMMAND_ACK(d) => {
                let cmd = format!("{:?}", d.command);
                let i = open.iter().rev().copied().find(|&i| {
                    let s = &sessions[i];
                    s.kind == "command" && s.what == cmd && s.from.0 == target.0 && s.to.0 == me.0
                });
                let result = format!("{:?}", d.result).replace("MAV_RESULT_", "");
                match i {
                    Some(i) if result == "IN_PROGRESS" => sessions[i].messages += 1,
                    Some(i) => close(&mut sessions, &mut open, i, result),
                    None => bump(&mut c.orphans, name),
                }
            }
            MavMessage::HEARTBEAT(_) => {
                let e = c.heartbeats.entry(me).or_insert((0, None, None));
                e.0 += 1;
                e.1 = e.1.or(f.time_us);
                e.2 = f.time_us.or(e.2);
            }
            _ => {}
        }
    });
    for (i, (seen, count)) in lists {
        sessions[i].what = format!("{} of {} indices", seen.len(), count);
        if count > 0 && seen.len() == usize::from(count) {
            sessions[i].end = End::Closed("all indices".into());
        }
    }
    c.sessions = sessions;
    c.format = summary.format.name();
    c.counts = summary.counts;
    c
}

/// A row of the sessions table: kind, from, to, what, end.
type GroupKey = (&'static str, String, String, String, String);

fn rate(n: u64, first: Option<u64>, last: Option<u64>) -> String {
    match (first, last) {
        (Some(a), Some(b)) if b > a && n > 1 => format!("{:.2} Hz", (n - 1) as f64 / ((b - a) as f64 / 1e6)),
        _ => "-".into(),
    }
}

fn ends(e: Ends) -> String {
    format!("{}/{}", e.0, e.1)
}

/// The census as Markdown: a heading for the capture, then tables.
pub fn render_table(name: &str, c: &Census) -> String {
    let mut s = String::new();
    let k = &c.counts;
    let _ = writeln!(s, "### `{name}`\n");
    let _ = writeln!(
        s,
        "{} frames ({}; {} MAVLink 1, {} signed); bad CRC {}, unknown id {}, truncated {}, garbage bytes {}.\n",
        c.frames, c.format, k.v1, k.signed, k.bad_crc, k.unknown_id, k.truncated, k.garbage_bytes
    );
    let _ = writeln!(s, "| sender sysid/compid | messages | HEARTBEATs | heartbeat rate |\n|---|---|---|---|");
    for (e, n) in &c.senders {
        let (h, a, b) = c.heartbeats.get(e).copied().unwrap_or((0, None, None));
        let _ = writeln!(s, "| {} | {n} | {h} | {} |", ends(*e), rate(h, a, b));
    }
    if !c.telemetry.is_empty() {
        let _ = writeln!(s, "\n| telemetry | count | rate |\n|---|---|---|");
        for (t, (n, a, b)) in &c.telemetry {
            let _ = writeln!(s, "| {t} | {n} | {} |", rate(*n, *a, *b));
        }
    }
    // Sessions grouped: kind, ends, what, end → count and messages.
    let mut groups: BTreeMap<GroupKey, (u32, u32)> = BTreeMap::new();
    for ss in &c.sessions {
        let end = match &ss.end {
            End::Closed(r) => format!("closed: {r}"),
            End::Abandoned => "abandoned".into(),
            End::Open => "open at end of log".into(),
        };
        let what = if ss.kind == "param read" || ss.kind == "param set" { String::new() } else { ss.what.clone() };
        let g = groups.entry((ss.kind, ends(ss.from), ends(ss.to), what, end)).or_default();
        g.0 += 1;
        g.1 += ss.messages;
    }
    if groups.is_empty() {
        let _ = writeln!(s, "\nNo sessions.");
    } else {
        let _ =
            writeln!(s, "\n| session | from | to | what | end | sessions | messages |\n|---|---|---|---|---|---|---|");
        for ((kind, f, t, what, end), (n, m)) in &groups {
            let _ = writeln!(s, "| {kind} | {f} | {t} | {what} | {end} | {n} | {m} |");
        }
    }
    if !c.orphans.is_empty() {
        let list: Vec<String> = c.orphans.iter().map(|(k, v)| format!("{k} {v}")).collect();
        let _ = writeln!(s, "\nOutside any session the log shows opening: {}.", list.join(", "));
    }
    s
}
