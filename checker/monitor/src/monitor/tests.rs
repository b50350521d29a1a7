//! Unit tests of the monitor: frames built by hand against small protocols.

use super::wire::{self, Layout, Scalar};
use super::*;
use crate::dialect::Dialect;
use crate::source::SourceDb;

/// A lowered program from source text (no imports).
pub(crate) fn program(db: &mut SourceDb, src: &str) -> crate::hir::Program {
    let file = db.add("t.chor", src);
    let mut no_imports = |_: &std::path::Path| Err(std::io::Error::other("no imports"));
    match mochi_verify::driver::prepare(db, file, &mut no_imports, mochi_verify::driver::Stage::Names) {
        Ok(p) => p,
        Err(d) => panic!("{:?}", d.iter().map(|d| d.message.clone()).collect::<Vec<_>>()),
    }
}

/// A frame of message `name` with these fields (the rest zero), as owned bytes.
pub(crate) fn payload(d: &Dialect, name: &str, ints: &[(&str, Scalar)], strs: &[(&str, &[u8])]) -> (u32, Vec<u8>) {
    let m = d.message(name).expect("message");
    let l = Layout::of(m);
    let mut p = vec![0u8; l.size as usize];
    for (f, v) in ints {
        wire::write(&mut p, l.slot(m, f).expect("field"), 0, *v);
    }
    for (f, s) in strs {
        wire::write_str(&mut p, l.slot(m, f).expect("field"), s);
    }
    let n = wire::truncate(&p).len();
    p.truncate(n);
    (m.id, p)
}

fn frame(sysid: u8, compid: u8, (msgid, payload): &(u32, Vec<u8>)) -> Frame<'_> {
    Frame { time_us: Some(1000), version: 2, sysid, compid, msgid: *msgid, payload, signed: false, raw: &[] }
}

fn int(i: i128) -> Scalar {
    Scalar::Int(i)
}

const UPLOAD: &str = "dialect common;
system S { participant GCS; participant UAV; }
choreography Upload =
  GCS -> UAV: MISSION_COUNT(count {1 <= count && count < 500},
                            mission_type {mission_type == MAV_MISSION_TYPE_MISSION}).
  mu t(i: int {0 <= i && i <= count} = 0) decreases count - i.
    ( UAV -> GCS: [i < count] MISSION_REQUEST_INT(seq as x {x == i},
                                                  mission_type {mission_type == MAV_MISSION_TYPE_MISSION}).
      GCS -> UAV: MISSION_ITEM_INT(seq as y {y == x},
                                   mission_type {mission_type == MAV_MISSION_TYPE_MISSION}).
      t(i + 1)
    + UAV -> GCS: MISSION_ACK(type {(type == MAV_MISSION_ACCEPTED && i == count)
                                     || (MAV_MISSION_ERROR <= type && type <= MAV_MISSION_OPERATION_CANCELLED)},
                              mission_type {mission_type == MAV_MISSION_TYPE_MISSION}).
      end );";

fn upload_monitor(db: &mut SourceDb) -> (Monitor, &'static Dialect) {
    let prog = program(db, UPLOAD);
    let d = prog.dialect.expect("dialect");
    (Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]), d)
}

fn to_uav(d: &Dialect, name: &str, fields: &[(&str, Scalar)]) -> (u32, Vec<u8>) {
    let mut f = vec![("target_system", int(1)), ("target_component", int(1))];
    f.extend_from_slice(fields);
    payload(d, name, &f, &[])
}

fn to_gcs(d: &Dialect, name: &str, fields: &[(&str, Scalar)]) -> (u32, Vec<u8>) {
    let mut f = vec![("target_system", int(255)), ("target_component", int(190))];
    f.extend_from_slice(fields);
    payload(d, name, &f, &[])
}

#[test]
fn a_conforming_upload_steps_to_its_end_and_telemetry_passes() {
    let mut db = SourceDb::new();
    let (mut m, d) = upload_monitor(&mut db);
    let count = to_uav(d, "MISSION_COUNT", &[("count", int(2))]);
    assert!(matches!(m.on_frame(&frame(255, 190, &count)), Outcome::Step { .. }));
    let hb = payload(d, "HEARTBEAT", &[], &[]);
    assert_eq!(m.on_frame(&frame(1, 1, &hb)), Outcome::Passed);
    for i in 0..2 {
        let req = to_gcs(d, "MISSION_REQUEST_INT", &[("seq", int(i))]);
        assert!(matches!(m.on_frame(&frame(1, 1, &req)), Outcome::Step { .. }), "request {i}");
        let item = to_uav(d, "MISSION_ITEM_INT", &[("seq", int(i))]);
        assert!(matches!(m.on_frame(&frame(255, 190, &item)), Outcome::Step { .. }), "item {i}");
    }
    let ack = to_gcs(d, "MISSION_ACK", &[]);
    assert!(matches!(m.on_frame(&frame(1, 1, &ack)), Outcome::Ended { .. }));
    let s = m.finish();
    assert_eq!(s.len(), 1);
    assert!(s[0].conformant);
    assert_eq!(s[0].taken.iter().filter(|&&n| n > 0).count(), 4);
    assert_eq!(m.stats.violations, 0);
}

#[test]
fn an_early_accept_is_the_refinement_that_fails_with_its_values() {
    let mut db = SourceDb::new();
    let (mut m, d) = upload_monitor(&mut db);
    m.on_frame(&frame(255, 190, &to_uav(d, "MISSION_COUNT", &[("count", int(3))])));
    m.on_frame(&frame(1, 1, &to_gcs(d, "MISSION_REQUEST_INT", &[("seq", int(0))])));
    m.on_frame(&frame(255, 190, &to_uav(d, "MISSION_ITEM_INT", &[("seq", int(0))])));
    // The seed's stale buffer: ACCEPTED after one item of three.
    let Outcome::Violation(v) = m.on_frame(&frame(1, 1, &to_gcs(d, "MISSION_ACK", &[]))) else { panic!("accepted") };
    let viol = m.violation(v).expect("recorded").clone();
    assert_eq!(viol.kind, Kind::Refinement);
    assert_eq!(viol.field.as_deref(), Some("type"));
    let text = m.describe(&db, v);
    assert!(text.contains("t.chor:"), "{text}");
    assert!(text.contains("i = 1"), "{text}");
    assert!(text.contains("count = 3"), "{text}");
    assert!(text.contains("role UAV (1/1)"), "{text}");
    // Not delivered: the session still takes the next request.
    let req = to_gcs(d, "MISSION_REQUEST_INT", &[("seq", int(1))]);
    assert!(matches!(m.on_frame(&frame(1, 1, &req)), Outcome::Step { .. }));
    // A request out of order breaks `x == i`.
    m.on_frame(&frame(255, 190, &to_uav(d, "MISSION_ITEM_INT", &[("seq", int(1))])));
    let bad = to_gcs(d, "MISSION_REQUEST_INT", &[("seq", int(0))]);
    let Outcome::Violation(v) = m.on_frame(&frame(1, 1, &bad)) else { panic!("accepted") };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Refinement));
}

#[test]
fn sessions_are_keyed_by_both_ends_and_strangers_are_reported() {
    let mut db = SourceDb::new();
    let (mut m, d) = upload_monitor(&mut db);
    // Two ground stations upload to two vehicles at once.
    m.on_frame(&frame(255, 190, &to_uav(d, "MISSION_COUNT", &[("count", int(1))])));
    let count2 =
        payload(d, "MISSION_COUNT", &[("target_system", int(2)), ("target_component", int(1)), ("count", int(1))], &[]);
    m.on_frame(&frame(255, 230, &count2));
    let req2 = payload(d, "MISSION_REQUEST_INT", &[("target_system", int(255)), ("target_component", int(230))], &[]);
    assert!(matches!(m.on_frame(&frame(2, 1, &req2)), Outcome::Step { session: 1, .. }));
    let req1 = to_gcs(d, "MISSION_REQUEST_INT", &[]);
    assert!(matches!(m.on_frame(&frame(1, 1, &req1)), Outcome::Step { session: 0, .. }));
    // A request from a third vehicle, to nobody's upload: outside any session.
    let stray = payload(d, "MISSION_REQUEST_INT", &[("target_system", int(255)), ("target_component", int(1))], &[]);
    let Outcome::Violation(v) = m.on_frame(&frame(3, 1, &stray)) else { panic!("passed") };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::OutsideSession));
    // The first upload is left incomplete at the end of the stream.
    let s = m.finish();
    assert_eq!(s.iter().filter(|s| !s.conformant).count(), 2);
}

#[test]
fn floats_are_exact_and_nan_is_rejected() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography P =
  GCS -> UAV: PARAM_SET(param_id {param_id == \"RATE\"}, param_value as v {v <= 0.1}).
  UAV -> GCS: PARAM_VALUE(param_id {param_id == \"RATE\"}, param_value as w {w == v}).
  end;",
    );
    let d = prog.dialect.expect("dialect");
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]);
    let set = |x: f32, id: &[u8]| {
        payload(
            d,
            "PARAM_SET",
            &[("target_system", int(1)), ("target_component", int(1)), ("param_value", Scalar::F32(x))],
            &[("param_id", id)],
        )
    };
    // 0.1f32 is 0.100000001490116..., above 1/10: a violation.
    let Outcome::Violation(v) = m.on_frame(&frame(255, 190, &set(0.1, b"RATE"))) else { panic!("accepted 0.1f32") };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Refinement));
    let Outcome::Violation(v) = m.on_frame(&frame(255, 190, &set(f32::NAN, b"RATE"))) else { panic!("accepted NaN") };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::NonFinite));
    let Outcome::Violation(v) = m.on_frame(&frame(255, 190, &set(f32::NEG_INFINITY, b"RATE"))) else {
        panic!("accepted -inf")
    };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::NonFinite));
    let Outcome::Violation(_) = m.on_frame(&frame(255, 190, &set(0.05, b"RATEX"))) else { panic!("accepted RATEX") };
    assert!(matches!(m.on_frame(&frame(255, 190, &set(0.05, b"RATE"))), Outcome::Step { .. }));
    let value = |x: f32| payload(d, "PARAM_VALUE", &[("param_value", Scalar::F32(x))], &[("param_id", b"RATE")]);
    let Outcome::Violation(_) = m.on_frame(&frame(1, 1, &value(0.05000001))) else { panic!("accepted another value") };
    assert!(matches!(m.on_frame(&frame(1, 1, &value(0.05))), Outcome::Ended { .. }));
}

#[test]
fn enum_fields_must_hold_an_entry_and_commands_are_fixed_by_the_label() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography A =
  GCS -> UAV: COMMAND_LONG[MAV_CMD_COMPONENT_ARM_DISARM](arm).
  UAV -> GCS: COMMAND_ACK(command {command == MAV_CMD_COMPONENT_ARM_DISARM}, result).
  end;",
    );
    let d = prog.dialect.expect("dialect");
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]);
    let cmd = |c: i128, arm: f32| to_uav(d, "COMMAND_LONG", &[("command", int(c)), ("param1", Scalar::F32(arm))]);
    // Another command is not this protocol's message: outside its alphabet, it passes.
    assert_eq!(m.on_frame(&frame(255, 190, &cmd(176, 1.0))), Outcome::Passed);
    // MAV_BOOL has 0 and 1: 0.5 is no entry.
    let Outcome::Violation(v) = m.on_frame(&frame(255, 190, &cmd(400, 0.5))) else { panic!("accepted 0.5") };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Entry));
    assert!(matches!(m.on_frame(&frame(255, 190, &cmd(400, 1.0))), Outcome::Step { .. }));
    // MAV_RESULT has no 200.
    let ack = |r: i128| to_gcs(d, "COMMAND_ACK", &[("command", int(400)), ("result", int(r))]);
    let Outcome::Violation(v) = m.on_frame(&frame(1, 1, &ack(200))) else { panic!("accepted 200") };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Entry));
    assert!(matches!(m.on_frame(&frame(1, 1, &ack(0))), Outcome::Ended { .. }));
}

#[test]
fn a_division_by_zero_is_a_violation() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography P =
  GCS -> UAV: MISSION_COUNT(count as n).
  UAV -> GCS: MISSION_REQUEST_INT(seq as q {q <= 100 / n}).
  end;",
    );
    let d = prog.dialect.expect("dialect");
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]);
    m.on_frame(&frame(255, 190, &to_uav(d, "MISSION_COUNT", &[("count", int(0))])));
    let Outcome::Violation(v) = m.on_frame(&frame(1, 1, &to_gcs(d, "MISSION_REQUEST_INT", &[]))) else { panic!() };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Undefined));
}

#[test]
fn big_values_take_the_exact_fallback() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography P =
  GCS -> UAV: PARAM_SET(param_value as v {v * v * v * v * v > 0}).
  end;",
    );
    let d = prog.dialect.expect("dialect");
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]);
    let set = |x: f32| to_uav(d, "PARAM_SET", &[("param_value", Scalar::F32(x))]);
    // (2^100)^5 leaves 128 bits: decided over big rationals, and counted.
    assert!(matches!(m.on_frame(&frame(255, 190, &set(2f32.powi(100)))), Outcome::Ended { .. }));
    assert!(m.stats.fallbacks >= 1);
    let Outcome::Violation(_) = m.on_frame(&frame(255, 190, &set(-(2f32.powi(100))))) else { panic!() };
    // f32::MAX does not fit a register's rational either: decided the same way.
    assert!(matches!(m.on_frame(&frame(255, 190, &set(f32::MAX))), Outcome::Ended { .. }));
}

/// A HEARTBEAT of `type` and `autopilot`.
fn heartbeat(d: &Dialect, ty: i128, autopilot: i128) -> (u32, Vec<u8>) {
    payload(d, "HEARTBEAT", &[("type", int(ty)), ("autopilot", int(autopilot))], &[])
}

#[test]
fn a_vehicles_mission_count_does_not_start_an_upload() {
    // MAV_TYPE_FIXED_WING 1, MAV_AUTOPILOT_ARDUPILOTMEGA 3; MAV_TYPE_GCS 6, MAV_AUTOPILOT_INVALID 8.
    let mut db = SourceDb::new();
    let (mut m, d) = upload_monitor(&mut db);
    assert_eq!(m.on_frame(&frame(1, 1, &heartbeat(d, 1, 3))), Outcome::Passed);
    assert_eq!(m.end_kind(1, 1), EndKind::Vehicle);
    // The vehicle answers a download (the MISSION_REQUEST_LIST is not this protocol's):
    // its MISSION_COUNT to the ground station is no upload's, whose GCS sends it.
    let count = to_gcs(d, "MISSION_COUNT", &[("count", int(2))]);
    assert_eq!(m.on_frame(&frame(1, 1, &count)), Outcome::Passed);
    assert_eq!(m.stats.sessions_started, 0);
    // The same count from a ground station does start one.
    assert_eq!(m.on_frame(&frame(255, 190, &heartbeat(d, 6, 8))), Outcome::Passed);
    assert_eq!(m.end_kind(255, 190), EndKind::GroundStation);
    let count = to_uav(d, "MISSION_COUNT", &[("count", int(2))]);
    assert!(matches!(m.on_frame(&frame(255, 190, &count)), Outcome::Step { .. }));
    // A ground station's count addressed to another ground station (by its HEARTBEAT) is
    // no upload either: the receiver must be a vehicle.
    assert_eq!(m.on_frame(&frame(255, 230, &heartbeat(d, 6, 8))), Outcome::Passed);
    let sideways = payload(
        d,
        "MISSION_COUNT",
        &[("target_system", int(255)), ("target_component", int(230)), ("count", int(2))],
        &[],
    );
    assert_eq!(m.on_frame(&frame(255, 190, &sideways)), Outcome::Passed);
    assert_eq!(m.stats.sessions_started, 1);
    // Ends with no HEARTBEAT play any role, as before.
    let unknown =
        payload(d, "MISSION_COUNT", &[("target_system", int(7)), ("target_component", int(1)), ("count", int(2))], &[]);
    assert!(matches!(m.on_frame(&frame(9, 9, &unknown)), Outcome::Step { .. }));
    // A default HEARTBEAT (all zeros) claims nothing; a pinned kind is not changed by one.
    assert_eq!(m.on_frame(&frame(4, 4, &heartbeat(d, 0, 0))), Outcome::Passed);
    assert_eq!(m.end_kind(4, 4), EndKind::Unknown);
    m.pin_end_kind(255, 190, EndKind::GroundStation);
    assert_eq!(m.on_frame(&frame(255, 190, &heartbeat(d, 2, 3))), Outcome::Passed);
    assert_eq!(m.end_kind(255, 190), EndKind::GroundStation);
    // Role names declare the kinds.
    assert_eq!(EndKind::of_role("GCS"), EndKind::GroundStation);
    assert_eq!(EndKind::of_role("Vehicle"), EndKind::Vehicle);
    assert_eq!(EndKind::of_role("Sender"), EndKind::Unknown);
}

#[test]
fn a_construct_the_monitor_cannot_run_is_refused_with_e0802_at_it() {
    let mut db = SourceDb::new();
    let src = "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  mu t. ( GCS -> UAV: MISSION_CLEAR_ALL(mission_type). end
        + GCS -> UAV: MISSION_SET_CURRENT(seq). t );";
    let prog = program(&mut db, src);
    assert!(Automaton::compile(&prog).is_ok());
    let file = db.find("t.chor").expect("the file");
    // A program with no dialect has no wire format: refused, at the choreography.
    let mut no_dialect = prog.clone();
    no_dialect.dialect = None;
    let e = Automaton::compile(&no_dialect).expect_err("no dialect");
    let d = e.diagnostic(crate::source::Span::new(file, 0, 0));
    assert_eq!(d.code, crate::diag::Code::MonitorUnsupported);
    assert!(d.message.contains("dialect"), "{}", d.message);
    assert_eq!(db.location(d.span).1, 3, "at the choreography");
    assert!(d.help.as_deref().is_some_and(|h| h.contains("mochi check")));
}

/// A flood whose receiver gave up: the ground station took the timeout (it sent
/// PARAM_SET after a second of silence), and a PARAM_VALUE of the flood that was on the wire
/// arrives after. The static checks (E0326) accept the protocol because the ground station
/// ignores such a message; the monitor says so (`Late`, not a step, not a violation), and a
/// proxy that enforces drops it.
#[test]
fn a_message_of_an_abandoned_branch_is_late() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  GCS -> UAV: PARAM_REQUEST_LIST.
  mu flood.
    ( UAV -> GCS: PARAM_VALUE(param_index as idx {0 <= idx && idx < 10}). flood
    + after 1000 ms by GCS.
        GCS -> UAV: PARAM_SET(param_value as v {v <= 10}).
        UAV -> GCS: STATUSTEXT. end );",
    );
    let d = prog.dialect.expect("dialect");
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]);
    let mut at = |us: u64, sysid: u8, compid: u8, msg: &(u32, Vec<u8>)| -> Outcome {
        let (msgid, payload) = msg;
        m.on_frame(&Frame {
            time_us: Some(us),
            version: 2,
            sysid,
            compid,
            msgid: *msgid,
            payload,
            signed: false,
            raw: &[],
        })
    };
    let list = payload(d, "PARAM_REQUEST_LIST", &[("target_system", int(1)), ("target_component", int(1))], &[]);
    let value = payload(d, "PARAM_VALUE", &[("param_index", int(3)), ("param_count", int(10))], &[]);
    let set = payload(
        d,
        "PARAM_SET",
        &[("target_system", int(1)), ("target_component", int(1)), ("param_value", Scalar::F32(2.0))],
        &[],
    );
    assert!(matches!(at(1_000_000, 255, 190, &list), Outcome::Step { .. }));
    assert!(matches!(at(1_100_000, 1, 1, &value), Outcome::Step { .. }));
    // 1.1 s of silence: the ground station gives up and sets.
    assert!(matches!(at(2_200_000, 255, 190, &set), Outcome::Step { .. }));
    // The flood's value that crossed the timeout.
    assert!(matches!(at(2_200_100, 1, 1, &value), Outcome::Late { .. }), "a late value is not Late");
    assert_eq!(m.stats.late, 1);
}

// ---- the late window: bounded in time, never restarting a timeout ---------------------

/// A flood the ground station gives up on after a second, then sets a parameter and waits
/// for a reply; the vehicle ends by its own silence after the set.
const FLOOD: &str = "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  GCS -> UAV: PARAM_REQUEST_LIST.
  mu flood.
    ( UAV -> GCS: PARAM_VALUE(param_index as idx {0 <= idx && idx < 10}). flood
    + after 1000 ms by GCS.
        GCS -> UAV: PARAM_SET(param_value as v {v <= 10}).
        UAV -> GCS: STATUSTEXT. end );";

/// The frames of the flood protocols: the list, a value, a set (ground station 255/190,
/// vehicle 1/1).
fn flood_frames(d: &'static Dialect) -> [(u32, Vec<u8>); 3] {
    let list = payload(d, "PARAM_REQUEST_LIST", &[("target_system", int(1)), ("target_component", int(1))], &[]);
    let value = payload(d, "PARAM_VALUE", &[("param_index", int(3)), ("param_count", int(10))], &[]);
    let set = payload(
        d,
        "PARAM_SET",
        &[("target_system", int(1)), ("target_component", int(1)), ("param_value", Scalar::F32(2.0))],
        &[],
    );
    [list, value, set]
}

/// A frame to run: its time (µs), its source end, its message.
type Timed<'a> = (u64, (u8, u8), &'a (u32, Vec<u8>));

/// Runs `frames` through a fresh monitor of `a`.
fn run_timed(a: &Automaton, frames: &[Timed]) -> (Monitor, Vec<Outcome>) {
    let mut m = Monitor::new(vec![a.clone()]);
    let out = frames
        .iter()
        .map(|(us, (sysid, compid), (msgid, payload))| {
            m.on_frame(&Frame {
                time_us: Some(*us),
                version: 2,
                sysid: *sysid,
                compid: *compid,
                msgid: *msgid,
                payload,
                signed: false,
                raw: &[],
            })
        })
        .collect();
    (m, out)
}

fn violation_kind(m: &Monitor, o: &Outcome) -> Option<Kind> {
    match o {
        Outcome::Violation(v) => m.violation(*v).map(|v| v.kind),
        _ => None,
    }
}

/// A ground station's log of a flood it gave up on: its timeout could fire 1 s after the
/// value at 1.1 s; a value of the flood that was on the wire is logged at 2.2 s, and the
/// ground station sets 1 ms later. That is a conformant run (it gave up before the value
/// came and ignored it, then acted), so the set is no violation: the late value does not
/// restart the timeout. A set 1 ms after a value that came before the bound passed, and a
/// set 100 ms after the late value (beyond the reaction bound: the ground station took the
/// value and waited only 100 ms), are each "before its timeout".
#[test]
fn a_late_flood_item_does_not_restart_the_timeout() {
    let mut db = SourceDb::new();
    let prog = program(&mut db, FLOOD);
    let a = Automaton::compile(&prog).expect("compiles");
    let [list, value, set] = flood_frames(prog.dialect.expect("dialect"));
    let (gcs, uav) = ((255, 190), (1, 1));
    let (m, out) = run_timed(
        &a,
        &[(1_000_000, gcs, &list), (1_100_000, uav, &value), (2_200_000, uav, &value), (2_201_000, gcs, &set)],
    );
    assert!(matches!(out[2], Outcome::Step { .. }), "{out:?}: the value may have been a step; it is passed");
    assert!(matches!(out[3], Outcome::Step { .. }), "{out:?}: {:?}", violation_kind(&m, &out[3]));
    assert_eq!(m.stats.timeouts, 1);
    // Several late values: the ground station gave up before the first, and acts within
    // the reaction bound (20 ms) of it; 25 ms after it, it had taken them.
    let late = |set_at: u64| {
        run_timed(
            &a,
            &[
                (1_000_000, gcs, &list),
                (1_100_000, uav, &value),
                (2_150_000, uav, &value),
                (2_155_000, uav, &value),
                (2_160_000, uav, &value),
                (set_at, gcs, &set),
            ],
        )
    };
    let (_, out) = late(2_165_000);
    assert!(matches!(out[5], Outcome::Step { .. }), "{out:?}");
    let (m, out) = late(2_175_000);
    assert_eq!(violation_kind(&m, &out[5]), Some(Kind::Early), "{out:?}");
    let (m, out) = run_timed(
        &a,
        &[(1_000_000, gcs, &list), (1_100_000, uav, &value), (2_050_000, uav, &value), (2_051_000, gcs, &set)],
    );
    assert_eq!(violation_kind(&m, &out[3]), Some(Kind::Early), "{out:?}");
    let (m, out) = run_timed(
        &a,
        &[(1_000_000, gcs, &list), (1_100_000, uav, &value), (2_200_000, uav, &value), (2_300_000, gcs, &set)],
    );
    assert_eq!(violation_kind(&m, &out[3]), Some(Kind::Early), "{out:?}");
}

/// A late message is late only within the timeout's bound after the act: the value that
/// crossed the timeout, logged 100 µs after the set, is `Late`; one logged 1.5 s after it
/// (the protocol's 1 s timeout exceeds the link's round trip) is no late message: the
/// ground station, waiting for STATUSTEXT, does not expect it.
#[test]
fn the_late_window_closes_after_the_timeouts_bound() {
    let mut db = SourceDb::new();
    let prog = program(&mut db, FLOOD);
    let a = Automaton::compile(&prog).expect("compiles");
    let [list, value, set] = flood_frames(prog.dialect.expect("dialect"));
    let (gcs, uav) = ((255, 190), (1, 1));
    let base = [(1_000_000, gcs, &list), (1_100_000, uav, &value), (2_200_000, gcs, &set)];
    let (m, out) = run_timed(&a, &[base[0], base[1], base[2], (2_200_100, uav, &value)]);
    assert!(matches!(out[3], Outcome::Late { .. }), "{out:?}");
    assert_eq!(m.stats.late, 1);
    let (m, out) = run_timed(&a, &[base[0], base[1], base[2], (3_700_000, uav, &value)]);
    assert_eq!(violation_kind(&m, &out[3]), Some(Kind::Unexpected), "{out:?}");
}

/// A late message of a session that its timeout ended is `Late` within the abandoned
/// choice's window, not "outside any session": the ground station gives up the flood and
/// the session ends by time; a value of the flood logged 0.5 s after that end is late, one
/// logged 5 s after is outside any session.
#[test]
fn a_late_message_of_a_session_ended_by_its_timeout_is_late_within_its_window() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  GCS -> UAV: PARAM_REQUEST_LIST.
  mu flood.
    ( UAV -> GCS: PARAM_VALUE(param_index as idx {0 <= idx && idx < 10}). flood
    + after 1000 ms by GCS. end );",
    );
    let a = Automaton::compile(&prog).expect("compiles");
    let [list, value, _] = flood_frames(prog.dialect.expect("dialect"));
    let (gcs, uav) = ((255, 190), (1, 1));
    let base = [(1_000_000, gcs, &list), (1_100_000, uav, &value)];
    let (m, out) = run_timed(&a, &[base[0], base[1], (2_600_000, uav, &value)]);
    assert!(matches!(out[2], Outcome::Late { .. }), "{out:?}");
    assert_eq!((m.stats.ended_by_time, m.stats.late), (1, 1));
    let (m, out) = run_timed(&a, &[base[0], base[1], (7_100_000, uav, &value)]);
    assert_eq!(violation_kind(&m, &out[2]), Some(Kind::OutsideSession), "{out:?}");
    // Ended by the ground station's act after its timeout: the value that crossed it.
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  GCS -> UAV: PARAM_REQUEST_LIST.
  mu flood.
    ( UAV -> GCS: PARAM_VALUE(param_index as idx {0 <= idx && idx < 10}). flood
    + after 1000 ms by GCS. GCS -> UAV: PARAM_SET(param_value as v {v <= 10}). end );",
    );
    let a = Automaton::compile(&prog).expect("compiles");
    let [list, value, set] = flood_frames(prog.dialect.expect("dialect"));
    let base = [(1_000_000, gcs, &list), (1_100_000, uav, &value), (2_200_000, gcs, &set)];
    let (m, out) = run_timed(&a, &[base[0], base[1], base[2], (2_200_500, uav, &value)]);
    assert!(matches!(out[2], Outcome::Ended { .. }), "{out:?}");
    assert!(matches!(out[3], Outcome::Late { .. }), "{out:?}: {:?}", violation_kind(&m, &out[3]));
    let (m, out) = run_timed(&a, &[base[0], base[1], base[2], (4_000_000, uav, &value)]);
    assert_eq!(violation_kind(&m, &out[3]), Some(Kind::OutsideSession), "{out:?}");
}

/// The monitor reads a session's messages in the protocol's order: a third role that may
/// send before the message its step follows (nothing orders the two on the link), and a
/// protocol whose first act is a role's after a timeout (no frame shows when its waiting
/// began), are refused at compile time, at the message and at the timeout.
#[test]
fn protocols_the_monitor_would_misread_are_refused_with_a_position() {
    let refused = |src: &str| {
        let mut db = SourceDb::new();
        let prog = program(&mut db, src);
        let Err(e) = Automaton::compile(&prog) else { panic!("accepted: {src}") };
        let span = e.span.expect("a position");
        (e.message, db.location(span).1)
    };
    let (msg, line) = refused(
        "dialect common;
system S { participant GCS; participant UAV; participant CAM; }
choreography C =
  GCS -> UAV: PARAM_REQUEST_LIST.
  CAM -> UAV: PARAM_REQUEST_READ(param_index as i {0 <= i}).
  end;",
    );
    assert_eq!(line, 5, "{msg}");
    assert!(msg.contains("`CAM`") && msg.contains("order"), "{msg}");
    let (msg, line) = refused(
        "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  ( UAV -> GCS: PARAM_VALUE(param_index as i {0 <= i}). end
  + after 1000 ms by GCS. GCS -> UAV: PARAM_REQUEST_LIST. end );",
    );
    assert_eq!(line, 5, "{msg}");
    assert!(msg.contains("starts by waiting"), "{msg}");
    let (msg, line) = refused(
        "dialect common;
system S { participant GCS; participant UAV; participant CAM; }
choreography C =
  GCS -> CAM: STATUSTEXT.
  ( GCS -> UAV: PARAM_REQUEST_LIST. end
  + after 500 ms by UAV. UAV -> GCS: STATUSTEXT. end );",
    );
    assert_eq!(line, 6, "{msg}");
    assert!(msg.contains("cannot know when this wait began"), "{msg}");
    // A third role that hears of the session first, and a first choice whose timeout
    // branch ends at once, are read.
    for ok in [
        "dialect common;
system S { participant GCS; participant UAV; participant CAM; }
choreography C =
  GCS -> UAV: PARAM_REQUEST_LIST.
  UAV -> CAM: PARAM_REQUEST_LIST.
  CAM -> GCS: PARAM_VALUE(param_index as i {0 <= i}).
  end;",
        "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  ( UAV -> GCS: PARAM_VALUE(param_index as i {0 <= i}). end
  + after 1000 ms by GCS. end );",
    ] {
        let mut db = SourceDb::new();
        let prog = program(&mut db, ok);
        if let Err(e) = Automaton::compile(&prog) {
            panic!("{}\n{ok}", e.message);
        }
    }
}

/// Late messages of a session that ended by its timeouts, found by the explorer of
/// asynchronous runs (tests/asyncruns.rs): the vehicle floods, the ground station gives up
/// twice in a row and its session ends by time. A value that crossed the timeout opens a
/// session of its own (it is a first message of the protocol), and the vehicle's next
/// message, which goes on past the value in the ended session, is late there, not a
/// violation of the new session.
#[test]
fn a_late_first_message_opens_a_session_and_what_follows_it_is_late() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  ( UAV -> GCS: PARAM_VALUE.
      ( UAV -> GCS: PARAM_VALUE.
          ( UAV -> GCS: MISSION_COUNT. end + after 500 ms by GCS. end )
      + after 500 ms by GCS. end )
  + after 500 ms by GCS. end );",
    );
    let d = prog.dialect.expect("dialect");
    let a = Automaton::compile(&prog).expect("compiles");
    let value = payload(d, "PARAM_VALUE", &[("param_index", int(0)), ("param_count", int(1))], &[]);
    let count = payload(d, "MISSION_COUNT", &[("target_system", int(255)), ("target_component", int(190))], &[]);
    let uav = (1, 1);
    let (m, out) = run_timed(&a, &[(1_004_000, uav, &value), (1_507_000, uav, &value), (1_508_000, uav, &count)]);
    assert!(matches!(out[1], Outcome::Step { .. }), "{out:?}");
    assert!(matches!(out[2], Outcome::Late { .. }), "{out:?}: {:?}", violation_kind(&m, &out[2]));
    assert_eq!(m.stats.ended_by_time, 1);
}

/// Each choice a session's waiting role abandoned keeps its own late window: the vehicle
/// gives up on the ground station's request after 1 s and on its list after 0.5 s more, and
/// the session ends; the request that crossed the first timeout, logged after the second,
/// is late (within 1 s of the first act), as is the list that crossed the second.
#[test]
fn every_abandoned_choice_keeps_its_late_window() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S { participant GCS; participant UAV; }
choreography C =
  UAV -> GCS: PARAM_VALUE(param_index as i {0 <= i}).
  ( GCS -> UAV: PARAM_REQUEST_READ. UAV -> GCS: PARAM_VALUE(param_index as j {0 <= j}).
      ( GCS -> UAV: PARAM_REQUEST_LIST. UAV -> GCS: MISSION_COUNT. end
      + after 500 ms by UAV. UAV -> GCS: MISSION_COUNT. end )
  + after 1000 ms by UAV. UAV -> GCS: PARAM_VALUE(param_index as j {0 <= j}).
      ( GCS -> UAV: PARAM_REQUEST_LIST. UAV -> GCS: MISSION_COUNT. end
      + after 500 ms by UAV. UAV -> GCS: MISSION_COUNT. end ) );",
    );
    let d = prog.dialect.expect("dialect");
    let a = Automaton::compile(&prog).expect("compiles");
    let value = payload(d, "PARAM_VALUE", &[("param_index", int(0)), ("param_count", int(1))], &[]);
    let count = payload(d, "MISSION_COUNT", &[("target_system", int(255)), ("target_component", int(190))], &[]);
    let to_uav = [("target_system", int(1)), ("target_component", int(1))];
    let read = payload(d, "PARAM_REQUEST_READ", &to_uav, &[]);
    let list = payload(d, "PARAM_REQUEST_LIST", &to_uav, &[]);
    let (gcs, uav) = ((255, 190), (1, 1));
    let (m, out) = run_timed(
        &a,
        &[
            (1_000_000, uav, &value),
            (2_000_000, uav, &value),
            (2_500_000, uav, &count),
            (2_700_000, gcs, &read),
            (2_800_000, gcs, &list),
        ],
    );
    assert!(matches!(out[2], Outcome::Ended { .. }), "{out:?}");
    assert!(matches!(out[3], Outcome::Late { .. }), "{out:?}: {:?}", violation_kind(&m, &out[3]));
    assert!(matches!(out[4], Outcome::Late { .. }), "{out:?}: {:?}", violation_kind(&m, &out[4]));
}

/// A keyed label's alphabet is (message id, key): another parameter's PARAM_VALUE,
/// PARAM_SET and PARAM_REQUEST_READ pass untouched, a name that only starts or ends like the
/// key is another name, the keyed stream's messages are readings, and a PARAM_SET of the
/// keyed parameter always opens the protocol (a set from a cached list is checked).
#[test]
fn keyed_labels_dispatch_by_the_name_as_the_wire_carries_it() {
    let mut db = SourceDb::new();
    let prog = program(
        &mut db,
        "dialect common;
system S {
  participant GCS;
  participant UAV;
  stream UAV -> GCS: PARAM_VALUE[\"MC_PITCH_P\"](param_value as p {0 <= p && p <= 12});
}
choreography P =
  GCS -> UAV: PARAM_SET[\"MC_PITCHRATE_MAX\"](param_value as r {0 <= r && r * (1 + p) <= 540},
                                            param_type {param_type == MAV_PARAM_TYPE_REAL32}).
  end;",
    );
    let d = prog.dialect.expect("dialect");
    let a = Automaton::compile(&prog).expect("compiles");
    assert!(matches!(a.edges[0].key, Some(automaton::Key::Name(_, ref k)) if &k[..] == b"MC_PITCHRATE_MAX"));
    let mut m = Monitor::new(vec![a]);
    let value = |id: &[u8], v: f32| {
        payload(d, "PARAM_VALUE", &[("param_value", Scalar::F32(v)), ("param_type", int(9))], &[("param_id", id)])
    };
    let set = |id: &[u8], v: f32| {
        let ints = [
            ("target_system", int(1)),
            ("target_component", int(1)),
            ("param_value", Scalar::F32(v)),
            ("param_type", int(9)),
        ];
        payload(d, "PARAM_SET", &ints, &[("param_id", id)])
    };
    let read = |id: &[u8]| {
        let ints = [("target_system", int(1)), ("target_component", int(1)), ("param_index", int(-1))];
        payload(d, "PARAM_REQUEST_READ", &ints, &[("param_id", id)])
    };
    // Before any reading of the gain, a set of the keyed parameter is checked: no reading.
    let Outcome::Violation(v) = m.on_frame(&frame(255, 190, &set(b"MC_PITCHRATE_MAX", 100.0))) else {
        panic!("a set without the gain accepted")
    };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::NoReading));
    // Every other parameter's messages are outside the alphabet, whatever their values.
    for f in [
        value(b"MC_ROLL_P", 1e9),
        set(b"MC_ROLL_P", 1e9),
        read(b"MC_PITCHRATE_MAX"),
        value(b"MC_PITCH", 100.0),
        value(b"MC_PITCH_PX", 100.0),
        set(b"MC_PITCHRATE_MA", 1e9),
        set(b"", 1e9),
        value(b"MC_PITCHRATE_MAX", 1e9),
    ] {
        assert_eq!(m.on_frame(&frame(1, 1, &f)), Outcome::Passed);
    }
    // The keyed stream: a gain beyond its invariant, from an end no session binds, is no
    // reading (docs/monitor.md, "Streams and observed state": not this protocol's vehicle):
    // it passes, and a set after it still finds no reading. One within it is a reading.
    assert_eq!(m.on_frame(&frame(1, 1, &value(b"MC_PITCH_P", 13.0))), Outcome::Passed);
    let Outcome::Violation(v) = m.on_frame(&frame(255, 190, &set(b"MC_PITCHRATE_MAX", 10.0))) else {
        panic!("a set after a value that is no reading accepted")
    };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::NoReading));
    assert_eq!(m.on_frame(&frame(1, 1, &value(b"MC_PITCH_P", 6.5))), Outcome::Passed);
    // The bound with P 6.5 is 540 / 7.5 = 72: 70 passes (a one-step session), 80 does not.
    assert!(matches!(m.on_frame(&frame(255, 190, &set(b"MC_PITCHRATE_MAX", 70.0))), Outcome::Ended { .. }));
    let Outcome::Violation(v) = m.on_frame(&frame(255, 190, &set(b"MC_PITCHRATE_MAX", 80.0))) else {
        panic!("80 accepted")
    };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Refinement));
}

/// A name key is compared as the wire carries a `char[N]`: up to the first NUL, or all N
/// bytes when none; a MAVLink 2 payload truncated of its trailing zeros reads as zero.
#[test]
fn a_name_key_fits_the_field_up_to_its_first_nul_or_all_of_it() {
    let d = crate::dialect::builtin("common").expect("common");
    let m = d.message("PARAM_SET").expect("PARAM_SET");
    let slot = Layout::of(m).slot(m, "param_id").expect("param_id");
    let key = |k: &[u8]| automaton::Key::Name(slot, k.into());
    let with = |id: &[u8]| payload(d, "PARAM_SET", &[("param_value", Scalar::F32(1.0))], &[("param_id", id)]).1;
    assert!(key(b"ABCDEFGHIJKLMNOP").fits(&with(b"ABCDEFGHIJKLMNOP")));
    assert!(!key(b"ABCDEFGHIJKLMNO").fits(&with(b"ABCDEFGHIJKLMNOP")));
    assert!(!key(b"ABCDEFGHIJKLMNOP").fits(&with(b"ABCDEFGHIJKLMNO")));
    // Bytes after the NUL are not the name's.
    assert!(key(b"MC_X").fits(&with(b"MC_X\0Y")));
    // param_type (0) is truncated away: the payload ends inside param_id's padding.
    let short = with(b"AB");
    assert!(short.len() < Layout::of(m).size as usize);
    assert!(key(b"AB").fits(&short) && !key(b"ABC").fits(&short) && !key(b"").fits(&short));
    assert!(key(b"").fits(&with(b"")));
}
