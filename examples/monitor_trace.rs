//! The run-time monitor on a short trace: `choreographies/mavlink/mission-upload.chor`
//! compiled once, then a conforming upload of three items and the seed's attack (a vehicle
//! that accepts after one item of three) fed to it, message by message, as frames the
//! `mavlink` crate encoded.
//!
//! ```text
//! cargo run --example monitor_trace
//! ```

use mavlink::dialects::common::{
    MavMessage, MavMissionResult, MavMissionType, ATTITUDE_DATA, MISSION_ACK_DATA, MISSION_COUNT_DATA,
    MISSION_ITEM_INT_DATA, MISSION_REQUEST_INT_DATA,
};
use mavlink::{MavlinkVersion, Message};
use mochi::mavio::Frame;
use mochi::monitor::{Automaton, Monitor, Outcome};
use mochi::source::SourceDb;
use std::path::Path;

const GCS: (u8, u8) = (255, 190);
const UAV: (u8, u8) = (1, 1);

fn count(n: u16) -> MavMessage {
    MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        target_system: UAV.0,
        target_component: UAV.1,
        count: n,
        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
        ..Default::default()
    })
}

fn request(seq: u16) -> MavMessage {
    MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
        target_system: GCS.0,
        target_component: GCS.1,
        seq,
        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
    })
}

fn item(seq: u16) -> MavMessage {
    MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
        target_system: UAV.0,
        target_component: UAV.1,
        seq,
        x: -353_632_621,
        y: 1_491_652_374,
        z: 20.0,
        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
        ..Default::default()
    })
}

fn ack() -> MavMessage {
    MavMessage::MISSION_ACK(MISSION_ACK_DATA {
        target_system: GCS.0,
        target_component: GCS.1,
        mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
        mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
        ..Default::default()
    })
}

fn attitude() -> MavMessage {
    MavMessage::ATTITUDE(ATTITUDE_DATA { roll: 0.02, pitch: -0.01, yaw: 1.57, ..Default::default() })
}

/// Feeds `msgs` to the monitor, printing each outcome.
fn feed(m: &mut Monitor, db: &SourceDb, what: &str, msgs: &[((u8, u8), MavMessage)]) {
    println!("{what}:");
    for (from, msg) in msgs {
        let mut payload = [0u8; 255];
        let n = msg.ser(MavlinkVersion::V2, &mut payload);
        let frame = Frame {
            time_us: None,
            version: 2,
            sysid: from.0,
            compid: from.1,
            msgid: msg.message_id(),
            payload: &payload[..n],
            signed: false,
            raw: &payload[..n],
        };
        let o = m.on_frame(&frame);
        let shown = match o {
            Outcome::Passed => "passed through (not a protocol message)".to_string(),
            Outcome::Step { session, state } => format!("session {session}: now in state {state}"),
            Outcome::Ended { session } => format!("session {session}: ended, conformant"),
            Outcome::Late { session } => {
                format!("session {session}: late, ignored (its branch was abandoned by a timeout)")
            }
            Outcome::Violation(v) => format!("VIOLATION\n    {}", m.describe(db, v).replace('\n', "\n    ")),
        };
        println!("  {:>2}/{:<3} {:<20} {shown}", from.0, from.1, msg.message_name());
    }
}

fn main() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink/mission-upload.chor");
    let mut db = SourceDb::new();
    let report = mochi::fsload::check_file(&mut db, &path, &mochi::driver::Config::default()).expect("readable");
    println!("{}: {:?}", path.display(), report.verdict);
    let mut db = SourceDb::new();
    let root = mochi::fsload::load_root(&mut db, &path).expect("readable");
    let mut read = |p: &Path| mochi::fsload::read_bytes(p);
    let prog = mochi::driver::prepare(&mut db, root, &mut read, mochi::driver::Stage::Names).expect("lowered");
    let automaton = Automaton::compile(&prog).expect("a MAVLink protocol");
    println!(
        "compiled `{}`: {} states, {} edges, messages {:?}\n",
        automaton.name,
        automaton.states.len(),
        automaton.edges.len(),
        automaton.alphabet
    );
    let mut m = Monitor::new(vec![automaton]);
    let conforming = [
        (GCS, count(3)),
        (UAV, attitude()),
        (UAV, request(0)),
        (GCS, item(0)),
        (UAV, request(1)),
        (GCS, item(1)),
        (UAV, attitude()),
        (UAV, request(2)),
        (GCS, item(2)),
        (UAV, ack()),
    ];
    feed(&mut m, &db, "a conforming upload", &conforming);
    let attack = [(GCS, count(3)), (UAV, request(0)), (GCS, item(0)), (UAV, ack())];
    feed(&mut m, &db, "\nan upload the vehicle accepts after one item of three", &attack);
    println!();
    for s in m.finish() {
        let visited = s.visited.iter().filter(|&&v| v).count();
        let taken = s.taken.iter().filter(|&&n| n > 0).count();
        println!(
            "session {}: {} ({} violation(s)); coverage: {visited} states, {taken} edges, {} predicates evaluated",
            s.session,
            if s.conformant { "conformant" } else { "incomplete" },
            s.violations,
            s.evaluated.iter().filter(|&&n| n > 0).count()
        );
    }
}
