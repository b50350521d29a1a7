//! The run-time monitor (`mochi::monitor`) against the rest of mochi and the world:
//!
//! - static and run time agree: every protocol under `choreographies/mavlink/` that
//!   `mochi check` verifies is simulated (payloads are Z3 models, `mochi::simulate`), each
//!   run is encoded into MAVLink frames and fed to the monitor, which must take every
//!   message (never stuck, never a violation on a conforming trace); then one refined field
//!   of one message is changed so that its refinement (evaluated independently, with what
//!   the sender knew) is false, and the monitor must reject exactly that frame;
//! - the payload decoder agrees with the `mavlink` crate on random messages of the common
//!   dialect, field by field;
//! - the hot path does not allocate: a counting global allocator (the reason this is a
//!   test binary of its own) sees no allocation over a long conforming stream after
//!   warm-up.

use mochi::dialect::Dialect;
use mochi::driver::{Config, Verdict};
use mochi::exact::{self, Tri, Value};
use mochi::hir::{Program, RoleId};
use mochi::mavio::Frame;
use mochi::monitor::wire::{self, Layout, Scalar};
use mochi::monitor::{Automaton, Kind, Monitor, Outcome};
use mochi::simulate::{SimConfig, SimMessage};
use mochi::source::SourceDb;
use mochi_core::splitmix::SplitMix64;
use num_traits::ToPrimitive;
use std::alloc::{GlobalAlloc, Layout as AllocLayout, System};
use std::cell::Cell;
use std::path::Path;

// ---- a counting allocator (per thread: the test harness runs tests on several) ----------

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every call is forwarded to the system allocator unchanged; the counter is a
// thread-local `Cell` with a constant initialiser, which never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: AllocLayout) -> *mut u8 {
        count();
        System.alloc(l)
    }
    unsafe fn alloc_zeroed(&self, l: AllocLayout) -> *mut u8 {
        count();
        System.alloc_zeroed(l)
    }
    unsafe fn realloc(&self, p: *mut u8, l: AllocLayout, n: usize) -> *mut u8 {
        count();
        System.realloc(p, l, n)
    }
    unsafe fn dealloc(&self, p: *mut u8, l: AllocLayout) {
        System.dealloc(p, l)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

// ---- loading -------------------------------------------------------------------------

/// The lowered program of a file and whether `mochi check` verifies it.
fn load(path: &Path) -> (SourceDb, Program, Verdict) {
    let mut db = SourceDb::new();
    let verdict = mochi::fsload::check_file(&mut db, path, &Config::default()).expect("readable").verdict;
    let mut db = SourceDb::new();
    let root = mochi::fsload::load_root(&mut db, path).expect("readable");
    let mut read = |p: &Path| mochi::fsload::read_bytes(p);
    let prog = mochi::driver::prepare(&mut db, root, &mut read, mochi::driver::Stage::Names).expect("lowered");
    (db, prog, verdict)
}

fn protocols() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink");
    let mut out: Vec<_> = std::fs::read_dir(&dir)
        .expect("choreographies/mavlink")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "chor"))
        .collect();
    out.sort();
    out
}

// ---- frames from simulated messages -------------------------------------------------

/// A role's MAVLink end: the first role is a ground station (255/190), the others
/// vehicles (1/1, 2/1, ...).
fn end_of(r: RoleId) -> (u8, u8) {
    if r.0 == 0 {
        (255, 190)
    } else {
        (r.0 as u8, 1)
    }
}

/// The wire scalar of a simulated value for a field of this wire type.
fn scalar(prog: &Program, v: &Value, wire: mochi::dialect::Wire) -> Option<Scalar> {
    let Value::Num(n) = v else {
        return match v {
            Value::Bool(Tri::True) => Some(Scalar::Int(1)),
            Value::Bool(Tri::False) => Some(Scalar::Int(0)),
            _ => None,
        };
    };
    let r = n.value()?;
    let _ = prog;
    Some(match wire {
        mochi::dialect::Wire::F32 => Scalar::F32(r.to_f64()? as f32),
        mochi::dialect::Wire::F64 => Scalar::F64(r.to_f64()?),
        _ => Scalar::Int(r.to_integer().to_i128()?),
    })
}

/// A message's payload, its fields set to `values` (field name, value), its targets to the
/// receiver's end (unless listed), and the key a `[MAV_CMD_X]` or `["NAME"]` label fixes.
fn encode(prog: &Program, d: &Dialect, m: &SimMessage, values: &[(Option<String>, Value)]) -> (u32, Vec<u8>) {
    encode_label(prog, d, &m.label, m.to, values)
}

fn encode_label(
    prog: &Program,
    d: &Dialect,
    label: &str,
    to: RoleId,
    values: &[(Option<String>, Value)],
) -> (u32, Vec<u8>) {
    let (name, key) = mochi::dialect::split_label(label);
    let msg = d.message(name).expect("message of the dialect");
    let l = Layout::of(msg);
    let mut p = vec![0u8; l.size as usize];
    let (ts, tc) = end_of(to);
    if let Some(s) = l.slot(msg, "target_system") {
        wire::write(&mut p, s, 0, Scalar::Int(i128::from(ts)));
    }
    if let Some(s) = l.slot(msg, "target_component") {
        wire::write(&mut p, s, 0, Scalar::Int(i128::from(tc)));
    }
    match key {
        Some(mochi::dialect::LabelKey::Command(c)) => {
            let (_, e) = d.entry(c).expect("command entry");
            wire::write(&mut p, l.slot(msg, "command").expect("command field"), 0, Scalar::Int(i128::from(e.value)));
        }
        Some(mochi::dialect::LabelKey::Name(k)) => {
            let f = msg.key_field().expect("a key field");
            wire::write_str(&mut p, l.slot(msg, &f.name).expect("key field"), k.as_bytes());
        }
        None => {}
    }
    for (field, v) in values {
        let Some(field) = field else { continue };
        let slot = l.slot(msg, field).expect("field");
        let df = msg.field(field).expect("field");
        if df.is_string() {
            let bytes = match v {
                Value::Num(n) => {
                    let code = n.value().and_then(|r| r.to_integer().to_usize()).unwrap_or(usize::MAX);
                    match prog.strings.get(code) {
                        Some(s) => s.clone().into_bytes(),
                        None => format!("#{code}").into_bytes(),
                    }
                }
                _ => Vec::new(),
            };
            wire::write_str(&mut p, slot, &bytes);
        } else if let Some(s) = scalar(prog, v, df.wire) {
            wire::write(&mut p, slot, 0, s);
        }
    }
    let n = wire::truncate(&p).len();
    p.truncate(n);
    (msg.id, p)
}

fn frame(from: (u8, u8), (msgid, payload): &(u32, Vec<u8>)) -> Frame<'_> {
    Frame { time_us: None, version: 2, sysid: from.0, compid: from.1, msgid: *msgid, payload, signed: false, raw: &[] }
}

fn values_of(m: &SimMessage) -> Vec<(Option<String>, Value)> {
    m.fields.iter().map(|(_, f, _, v)| (f.clone(), v.clone())).collect()
}

/// Candidate wrong values for a field: around the sent value and at the ends of its range.
fn candidates(v: &Value, wire: mochi::dialect::Wire) -> Vec<Value> {
    let Value::Num(n) = v else { return vec![Value::Bool(Tri::True), Value::Bool(Tri::False)] };
    let Some(r) = n.value().cloned() else { return Vec::new() };
    let rat = |i: i128| exact::Rat::from_integer(num_bigint::BigInt::from(i));
    let mut out: Vec<exact::Rat> =
        [1, -1, 2, 7, 100, 1000, -1000].iter().map(|&d| r.clone() + rat(d)).chain([rat(0), rat(1)]).collect();
    match wire.int_range() {
        Some((lo, hi)) => {
            out.push(rat(lo));
            out.push(rat(hi));
            out.retain(|x| *x >= rat(lo) && *x <= rat(hi) && x.is_integer());
        }
        None => {
            out.push(rat(1_000_000));
            out.push(rat(-1_000_000));
            if wire == mochi::dialect::Wire::Char {
                out.clear();
                // A string no literal writes.
                out.push(rat(1_000_000));
            }
        }
    }
    out.retain(|x| *x != r);
    out.into_iter().map(Value::rat).collect()
}

/// The first wrong value of some refined field of `m` whose refinement, evaluated with
/// what the sender knew, is false: `(field index, value)`.
fn mutation(prog: &Program, d: &Dialect, m: &SimMessage) -> Option<(usize, Value)> {
    let name = m.label.split('[').next()?;
    let msg = d.message(name)?;
    for (k, (_, field, refinement, v)) in m.fields.iter().enumerate() {
        let (Some(field), Some(refinement)) = (field, refinement) else { continue };
        // The command a `[MAV_CMD_X]` label fixes, and the name a `["NAME"]` label fixes, is
        // the label: changing it makes another message, not a broken refinement.
        let keyed = match mochi::dialect::split_label(&m.label).1 {
            Some(mochi::dialect::LabelKey::Command(_)) => field == "command",
            Some(mochi::dialect::LabelKey::Name(_)) => msg.key_field().is_some_and(|f| &f.name == field),
            None => false,
        };
        if keyed {
            continue;
        }
        let df = msg.field(field)?;
        let wire = if df.is_string() { mochi::dialect::Wire::Char } else { df.wire };
        for c in candidates(v, wire) {
            let env = |var: &mochi::hir::Var| match var {
                mochi::hir::Var::Value(id, _) => {
                    if let Some(j) = m.fields.iter().position(|(fid, ..)| fid == id) {
                        return Some(if j == k { c.clone() } else { m.fields[j].3.clone() });
                    }
                    m.known.iter().find(|(kid, _)| kid == id).map(|(_, v)| v.clone())
                }
                _ => None,
            };
            if exact::holds(prog, refinement, &env) == Tri::False {
                return Some((k, c));
            }
        }
    }
    None
}

/// Whether the protocol's choreography has a timeout branch (`after T ms by R`).
fn has_timeout(prog: &mochi::hir::Program) -> bool {
    prog.choreography.as_ref().is_some_and(|c| mochi::typeck::first_timeout(&c.body).is_some())
}

#[test]
fn static_and_run_time_agree_on_every_verified_protocol() {
    let mut checked = 0;
    let mut mutated = 0;
    for path in protocols() {
        let (_db, prog, verdict) = load(&path);
        if verdict != Verdict::Verified {
            continue;
        }
        let name = path.display().to_string();
        let automaton = Automaton::compile(&prog).unwrap_or_else(|e| panic!("{name}: {}", e.message));
        // The simulator does not take timeout branches (`mochi simulate` reports such a
        // program undecided): `timeouts_are_enforced_in_the_frames_time` draws their traces.
        if has_timeout(&prog) {
            continue;
        }
        // The simulator does not draw readings of streams (`mochi simulate` says so): a
        // protocol that reads observed state is checked by hand below
        // (`parachute_is_monitored_with_its_readings`).
        if !prog.streams.is_empty() {
            continue;
        }
        let d = prog.dialect.expect("a MAVLink protocol");
        let cfg = SimConfig { runs: 3, steps: 40, seed: 7, ..SimConfig::default() };
        let report = mochi::simulate::simulate(&prog, &cfg);
        let mut messages = 0;
        for run in &report.messages {
            // The conforming trace: every message is a step; the run's end is the session's.
            let mut m = Monitor::new(vec![automaton.clone()]);
            for (k, msg) in run.iter().enumerate() {
                let bytes = encode(&prog, d, msg, &values_of(msg));
                let o = m.on_frame(&frame(end_of(msg.from), &bytes));
                if let Outcome::Violation(v) = o {
                    panic!("{name}: a conforming message {k} ({}) rejected: {}", msg.label, m.describe(&_db, v));
                }
                messages += 1;
            }
            // The same trace with one refined field broken at the first message where
            // that is possible: rejected at exactly that frame, accepted before.
            if let Some((k, (field, wrong))) =
                run.iter().enumerate().find_map(|(k, msg)| mutation(&prog, d, msg).map(|x| (k, x)))
            {
                let mut m = Monitor::new(vec![automaton.clone()]);
                for (j, msg) in run.iter().enumerate().take(k + 1) {
                    let mut values = values_of(msg);
                    if j == k {
                        values[field].1 = wrong.clone();
                    }
                    let o = m.on_frame(&frame(end_of(msg.from), &encode(&prog, d, msg, &values)));
                    match (j == k, o) {
                        (false, Outcome::Violation(v)) => {
                            panic!("{name}: message {j} rejected: {}", m.describe(&_db, v))
                        }
                        (true, Outcome::Violation(v)) => {
                            let kind = m.violation(v).map(|v| v.kind);
                            assert!(
                                matches!(kind, Some(Kind::Refinement | Kind::Entry)),
                                "{name}: message {k} broken in field {field}: {kind:?}"
                            );
                        }
                        (true, o) => panic!(
                            "{name}: message {k} ({}) with field {} = {wrong} accepted: {o:?}",
                            msg.label,
                            msg.fields[field].1.as_deref().unwrap_or("?")
                        ),
                        _ => {}
                    }
                }
                mutated += 1;
            }
        }
        assert!(messages > 0, "{name}: the simulation sent nothing");
        checked += 1;
    }
    // Nine: param-set.chor reads streams now (its gains): tests/proxy.rs and
    // tests/mavproxy.rs run it between real peers, and `monitor::tests` a protocol of its
    // form; param-pass.chor's keyed labels are encoded here (`encode_label`).
    assert!(checked >= 9, "only {checked} verified protocols under choreographies/mavlink/");
    assert!(mutated >= checked, "only {mutated} mutated traces for {checked} protocols");
}

// ---- observed state: the parachute ---------------------------------------------------

/// A payload of `label` sent to `to`, the named fields set (integers).
fn payload(prog: &Program, label: &str, to: RoleId, fields: &[(&str, i128)]) -> (u32, Vec<u8>) {
    let d = prog.dialect.expect("a MAVLink protocol");
    let values: Vec<(Option<String>, Value)> = fields
        .iter()
        .map(|(f, v)| (Some(f.to_string()), Value::rat(exact::Rat::from_integer(num_bigint::BigInt::from(*v)))))
        .collect();
    encode_label(prog, d, label, to, &values)
}

/// A frame to send: its source end and its message.
type Sent<'a> = ((u8, u8), &'a (u32, Vec<u8>));

#[test]
fn parachute_is_monitored_with_its_readings() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink/parachute.chor");
    let (db, prog, verdict) = load(&path);
    assert_eq!(verdict, Verdict::Verified);
    let a = Automaton::compile(&prog).expect("a protocol with streams is monitored");
    let (gcs, uav) = (RoleId(0), RoleId(1));
    assert_eq!(prog.role_name(gcs), "GCS");
    // ArduCopter: MAV_TYPE_QUADROTOR 2, MAV_AUTOPILOT_ARDUPILOTMEGA 3; armed (128) in
    // stabilize (custom_mode 0); GCS heartbeat type 6; DO_PARACHUTE 208, release 2.
    let heartbeat = |armed: bool, mode: i128| {
        let base = if armed { 128 + 81 } else { 81 };
        payload(&prog, "HEARTBEAT", gcs, &[("type", 2), ("autopilot", 3), ("base_mode", base), ("custom_mode", mode)])
    };
    let position =
        |alt_mm: i128, vz: i128| payload(&prog, "GLOBAL_POSITION_INT", gcs, &[("relative_alt", alt_mm), ("vz", vz)]);
    let gcs_heartbeat = payload(&prog, "HEARTBEAT", uav, &[("type", 6), ("autopilot", 8)]);
    let release = payload(&prog, "COMMAND_LONG[MAV_CMD_DO_PARACHUTE]", uav, &[("param1", 2)]);
    let ack = |result: i128| payload(&prog, "COMMAND_ACK[MAV_CMD_DO_PARACHUTE]", gcs, &[("result", result)]);
    // The acknowledgement of another command (MAV_CMD_REQUEST_MESSAGE 512) is not the
    // protocol's: it passes, inside a session or outside.
    let other_ack = payload(&prog, "COMMAND_ACK[MAV_CMD_REQUEST_MESSAGE]", gcs, &[("result", 0)]);
    let (g, u) = (end_of(gcs), end_of(uav));
    let run = |frames: &[Sent<'_>]| {
        let mut m = Monitor::new(vec![a.clone()]);
        let out: Vec<Outcome> = frames.iter().map(|(from, p)| m.on_frame(&frame(*from, p))).collect();
        let kinds: Vec<Option<Kind>> = out
            .iter()
            .map(|o| match o {
                Outcome::Violation(v) => m.violation(*v).map(|v| v.kind),
                _ => None,
            })
            .collect();
        let described: Vec<String> = (0..m.violations().len()).map(|v| m.describe(&db, v)).collect();
        (out, kinds, described, m.stats)
    };
    let (safe_hb, safe_pos) = (heartbeat(true, 0), position(50_000, 10));
    let (low, climbing, disarmed) = (position(1_000, 10), position(50_000, -30), heartbeat(false, 0));

    // Conforming: readings at their own rates (any number, any order); the GCS sends nothing
    // while unsafe but its own 1 Hz HEARTBEAT, which is neither a step (the protocol has no
    // HEARTBEAT step) nor a reading of the vehicle's HEARTBEAT stream (a ground station is no
    // vehicle: its `type == MAV_TYPE_GCS` breaks the stream's invariant were it one), and
    // releases once safe; a heartbeat of the vehicle between the command and its ACK is a
    // reading, and another command's acknowledgement passes.
    let (out, kinds, d, stats) = run(&[
        (u, &disarmed),
        (u, &low),
        (u, &low),
        (g, &gcs_heartbeat),
        (u, &safe_hb),
        (g, &gcs_heartbeat),
        (u, &safe_pos),
        (u, &safe_hb),
        (g, &gcs_heartbeat),
        (g, &release),
        (u, &safe_hb),
        (u, &other_ack),
        (g, &gcs_heartbeat),
        (u, &safe_pos),
        (u, &ack(0)),
    ]);
    assert!(kinds.iter().all(Option::is_none), "{d:?}");
    assert!(matches!(out[14], Outcome::Ended { .. }), "{out:?}");
    assert!(matches!(out[3], Outcome::Passed) && matches!(out[11], Outcome::Passed), "{out:?}");
    assert_eq!(stats.readings, 8);
    // A refusal is always allowed; an ACCEPTED needs the vehicle's own latest reading safe.
    let (_, kinds, d, _) = run(&[(u, &safe_hb), (u, &safe_pos), (g, &release), (u, &climbing), (u, &ack(4))]);
    assert!(kinds.iter().all(Option::is_none), "{d:?}");
    let (_, kinds, _, _) = run(&[(u, &safe_hb), (u, &safe_pos), (g, &release), (u, &climbing), (u, &ack(0))]);
    assert_eq!(kinds[4], Some(Kind::Refinement));

    // Mutated: the release on an unsafe latest reading (the reading changed after an
    // earlier safe one) breaks the guard; on no reading at all, no reading.
    for unsafe_reading in [&low, &climbing, &disarmed, &heartbeat(true, 1)] {
        let (out, kinds, d, _) = run(&[(u, &safe_hb), (u, &safe_pos), (u, unsafe_reading), (g, &release)]);
        assert_eq!(kinds[3], Some(Kind::Guard), "{out:?} {d:?}");
    }
    let (_, kinds, d, _) = run(&[(u, &safe_hb), (g, &release)]);
    assert_eq!(kinds[1], Some(Kind::NoReading), "{d:?}");
    assert!(d[0].contains("no reading of the stream yet"), "{d:?}");
    // A stream message breaking the stream's invariant from an end no open session binds as
    // the vehicle (a fixed-wing's, a PX4 quadrotor's HEARTBEAT) is no reading and no
    // violation: it passes (a ground station must see every vehicle's and component's
    // HEARTBEAT), and it erases that end's earlier reading: a release on the safe reading
    // before it finds no reading.
    let plane =
        payload(&prog, "HEARTBEAT", gcs, &[("type", 1), ("autopilot", 3), ("base_mode", 81), ("custom_mode", 0)]);
    // MAV_AUTOPILOT_PX4 12, armed.
    let px4 =
        payload(&prog, "HEARTBEAT", gcs, &[("type", 2), ("autopilot", 12), ("base_mode", 209), ("custom_mode", 0)]);
    for other in [&plane, &px4] {
        let (out, kinds, d, stats) = run(&[(u, &safe_hb), (u, &safe_pos), (u, other), (g, &release)]);
        assert!(matches!(out[2], Outcome::Passed), "{out:?} {d:?}");
        assert_eq!(kinds[3], Some(Kind::NoReading), "{d:?}");
        assert_eq!(stats.readings, 2);
    }
    // Another component of the vehicle's system (a camera: MAV_TYPE_CAMERA 30,
    // MAV_AUTOPILOT_INVALID 8) passes, and the autopilot's readings still count.
    let camera = payload(&prog, "HEARTBEAT", gcs, &[("type", 30), ("autopilot", 8)]);
    let (out, kinds, d, _) = run(&[(u, &safe_hb), (u, &safe_pos), ((u.0, 100), &camera), (g, &release)]);
    assert!(matches!(out[2], Outcome::Passed) && kinds.iter().all(Option::is_none), "{out:?} {d:?}");
    // From the end an open session binds as the vehicle (the release sent, its ACK awaited),
    // it is a stream violation, and no reading: the last safe one still counts.
    let (out, kinds, d, stats) = run(&[(u, &safe_hb), (u, &safe_pos), (g, &release), (u, &plane), (u, &ack(0))]);
    assert_eq!(kinds[3], Some(Kind::Stream), "{d:?}");
    assert!(kinds[4].is_none() && matches!(out[4], Outcome::Ended { .. }), "{out:?} {d:?}");
    assert_eq!(stats.readings, 2);
}

/// A frame from an end no session has bound, whose label is a stream's and a step's, and
/// which is both a valid reading and a valid first step, starts the session: taken as a
/// reading, the session's start is missed, and a later step that breaks the protocol is
/// checked as the start of another session, where it is allowed.
#[test]
fn a_heartbeat_that_could_start_a_session_starts_it() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/monitor-heartbeat-step-and-stream.chor");
    let (db, prog, verdict) = load(&path);
    assert_eq!(verdict, Verdict::Verified);
    let a = Automaton::compile(&prog).expect("a protocol with a stream is monitored");
    let (gcs, uav) = (RoleId(0), RoleId(1));
    assert_eq!(prog.role_name(gcs), "GCS");
    // MAV_TYPE_GCS 6, MAV_TYPE_QUADROTOR 2, MAV_STATE_ACTIVE 4; COMPONENT_ARM_DISARM 400.
    let announce = payload(&prog, "HEARTBEAT", uav, &[("type", 6), ("system_status", 4)]);
    let vehicle = payload(&prog, "HEARTBEAT", gcs, &[("type", 2), ("system_status", 4)]);
    let command = |arm: i128| payload(&prog, "COMMAND_LONG[MAV_CMD_COMPONENT_ARM_DISARM]", uav, &[("param1", arm)]);
    let ack = payload(&prog, "COMMAND_ACK", gcs, &[("command", 400)]);
    let (g, u) = (end_of(gcs), end_of(uav));
    let run = |frames: &[Sent<'_>]| {
        let mut m = Monitor::new(vec![a.clone()]);
        let out: Vec<Outcome> = frames.iter().map(|(from, p)| m.on_frame(&frame(*from, p))).collect();
        let kinds: Vec<Option<Kind>> = out
            .iter()
            .map(|o| match o {
                Outcome::Violation(v) => m.violation(*v).map(|v| v.kind),
                _ => None,
            })
            .collect();
        let described: Vec<String> = (0..m.violations().len()).map(|v| m.describe(&db, v)).collect();
        (out, kinds, described, m.stats)
    };
    // Conforming: the vehicle's heartbeat is a reading (as a step it breaks `type ==
    // MAV_TYPE_GCS`); the announcement starts the session, the arm follows.
    let (out, kinds, d, stats) = run(&[(u, &vehicle), (g, &announce), (u, &vehicle), (g, &command(1)), (u, &ack)]);
    assert!(kinds.iter().all(Option::is_none), "{d:?}");
    assert!(matches!(out[4], Outcome::Ended { .. }), "{out:?}");
    assert_eq!(stats.readings, 2);
    assert_eq!(stats.sessions_started, 1);
    // Conforming: a disarm without the announcement.
    let (out, kinds, d, _) = run(&[(u, &vehicle), (g, &command(0)), (u, &ack)]);
    assert!(kinds.iter().all(Option::is_none), "{d:?}");
    assert!(matches!(out[2], Outcome::Ended { .. }), "{out:?}");
    // Violating: after the announcement only an arm may follow. Taking the announcement for
    // a reading would start the session at the disarm, and pass it.
    let (out, kinds, d, _) = run(&[(u, &vehicle), (g, &announce), (g, &command(0)), (u, &ack)]);
    assert_eq!(kinds[2], Some(Kind::Refinement), "{out:?} {d:?}");
}

// ---- the decoder against the mavlink crate ---------------------------------------------

/// The crate's value of one field, from its serde form, as what this decoder reads.
fn crate_value(d: &Dialect, f: &mochi::dialect::Field, j: &serde_json::Value) -> Option<Vec<Scalar>> {
    let entry = |name: &str| d.entry(name).map(|(_, e)| e.value as i128);
    let one = |j: &serde_json::Value| -> Option<Scalar> {
        Some(match j {
            serde_json::Value::Null => Scalar::F64(f64::NAN),
            serde_json::Value::Number(n) if f.wire.is_float() => Scalar::F64(n.as_f64()?),
            serde_json::Value::Number(n) => Scalar::Int(n.as_i64().map(i128::from).or(n.as_u64().map(i128::from))?),
            serde_json::Value::Object(o) => Scalar::Int(entry(o.get("type")?.as_str()?)?),
            // A bitmask: flag names and hexadecimal rests joined by `|`.
            serde_json::Value::String(s) => {
                let mut v = 0i128;
                for part in s.split('|').map(str::trim).filter(|p| !p.is_empty()) {
                    v |= match part.strip_prefix("0x") {
                        Some(h) => i128::from_str_radix(h, 16).ok()?,
                        None => entry(part)?,
                    };
                }
                Scalar::Int(v)
            }
            _ => return None,
        })
    };
    match j {
        serde_json::Value::Array(xs) => xs.iter().map(one).collect(),
        _ => Some(vec![one(j)?]),
    }
}

fn same(mine: Scalar, theirs: Scalar) -> bool {
    match (mine, theirs) {
        (Scalar::Int(a), Scalar::Int(b)) => a == b,
        (Scalar::F32(a), Scalar::F64(b)) => {
            (a.is_nan() && b.is_nan()) || f64::from(a) == b || (!a.is_finite() && b.is_nan())
        }
        (Scalar::F64(a), Scalar::F64(b)) => (a.is_nan() && b.is_nan()) || a == b || (!a.is_finite() && b.is_nan()),
        _ => false,
    }
}

#[test]
fn the_payload_decoder_agrees_with_the_mavlink_crate() {
    use mavlink::{dialects::common::MavMessage, MavlinkVersion, Message};
    let d = mochi::dialect::builtin("common").expect("common");
    let mut rng = SplitMix64(21);
    let (mut decoded, mut fields, mut tried) = (0, 0, 0);
    for msg in &d.messages {
        let l = Layout::of(msg);
        for round in 0..8 {
            tried += 1;
            let mut p: Vec<u8> = (0..l.size).map(|_| rng.next_u64() as u8).collect();
            // Strings in ASCII (the crate's serde form of a string needs UTF-8), cut short
            // at a random place; small values in enum fields half of the time so that the
            // crate's typed enums parse.
            for (f, s) in msg.fields.iter().zip(&l.slots) {
                if f.is_string() {
                    let cut = (rng.next_u64() % (u64::from(s.len) + 1)) as usize;
                    for k in 0..s.len as usize {
                        p[s.offset as usize + k] = if k < cut { b'A' + (rng.next_u64() % 26) as u8 } else { 0 };
                    }
                } else if f.enum_name.is_some() && round % 2 == 0 {
                    let e = d.enum_(f.enum_name.as_deref().unwrap_or("")).expect("enum");
                    let v = e.entries[(rng.next_u64() as usize) % e.entries.len().max(1)].value;
                    for k in 0..s.len as usize {
                        wire::write(&mut p, *s, k, Scalar::Int(i128::from(v)));
                    }
                }
            }
            // MAVLink 2 truncation of trailing zeros, sometimes a shorter payload still.
            let n = wire::truncate(&p).len();
            p.truncate(n);
            let Ok(parsed) = MavMessage::parse(MavlinkVersion::V2, msg.id, &p) else { continue };
            assert_eq!(parsed.message_id(), msg.id);
            let Ok(serde_json::Value::Object(json)) = serde_json::to_value(&parsed) else { continue };
            decoded += 1;
            for (f, s) in msg.fields.iter().zip(&l.slots) {
                // The crate names the field `type` `mavtype` (a Rust keyword).
                // (`type` itself is the serde tag holding the message's name).
                let j = if f.name == "type" { json.get("mavtype") } else { json.get(&f.name) };
                let Some(j) = j else { panic!("{}.{}: not in the crate's form {json:?}", msg.name, f.name) };
                if f.is_string() {
                    let mine = String::from_utf8_lossy(wire::read_str(&p, *s)).to_string();
                    assert_eq!(Some(mine.as_str()), j.as_str(), "{}.{}", msg.name, f.name);
                } else {
                    let Some(theirs) = crate_value(d, f, j) else {
                        panic!("{}.{}: the crate's value {j} is not read", msg.name, f.name)
                    };
                    assert_eq!(theirs.len(), s.len as usize, "{}.{}", msg.name, f.name);
                    for (k, t) in theirs.into_iter().enumerate() {
                        let mut mine = wire::read(&p, *s, k);
                        // The crate reads an enum-typed field in its enum's primitive type
                        // (CAMERA_IMAGE_CAPTURED's `int8_t` MAV_BOOL as a `u8`): the same
                        // bytes, compared as such.
                        if let (Some(_), Scalar::Int(i), Scalar::Int(_)) = (&f.enum_name, mine, t) {
                            let bits = 8 * f.wire.bytes();
                            let unsigned = i.rem_euclid(1i128 << bits);
                            if Scalar::Int(unsigned) == t {
                                mine = t;
                            }
                        }
                        assert!(same(mine, t), "{}.{}[{k}]: mine {mine:?}, the crate's {t:?}", msg.name, f.name);
                    }
                }
                fields += 1;
            }
        }
    }
    // Random bytes break some typed enums; most messages must still be compared.
    assert!(decoded * 2 > tried, "only {decoded} of {tried} random messages parsed by the crate");
    assert!(fields > 1000, "only {fields} fields compared");
}

// ---- no allocation on the hot path ----------------------------------------------------

#[test]
fn the_hot_path_does_not_allocate() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink");
    let (_db, prog, _) = load(&dir.join("mission-upload-tolerant.chor"));
    let (_db2, param, _) = load(&dir.join("param-set.chor"));
    let d = prog.dialect.expect("dialect");
    let automata = vec![Automaton::compile(&prog).expect("compiles"), Automaton::compile(&param).expect("compiles")];
    let msg = |name: &str, fields: &[(&str, Scalar)], strs: &[(&str, &[u8])]| {
        let m = d.message(name).expect("message");
        let l = Layout::of(m);
        let mut p = vec![0u8; l.size as usize];
        for (f, v) in fields {
            wire::write(&mut p, l.slot(m, f).expect("field"), 0, *v);
        }
        for (f, s) in strs {
            wire::write_str(&mut p, l.slot(m, f).expect("field"), s);
        }
        (m.id, p)
    };
    let int = Scalar::Int;
    let (to_uav, to_gcs) = (
        [("target_system", int(1)), ("target_component", int(1))],
        [("target_system", int(255)), ("target_component", int(190))],
    );
    let with = |a: &[(&'static str, Scalar)], b: &[(&'static str, Scalar)]| [a, b].concat();
    let items = 300;
    let mut stream = vec![((255, 190), msg("MISSION_COUNT", &with(&to_uav, &[("count", int(items))]), &[]))];
    let telemetry = msg("ATTITUDE", &[("roll", Scalar::F32(0.25))], &[]);
    for i in 0..items {
        stream.push(((1, 1), msg("MISSION_REQUEST_INT", &with(&to_gcs, &[("seq", int(i))]), &[])));
        stream.push(((1, 1), telemetry.clone()));
        let item = [("seq", int(i)), ("command", int(16)), ("x", int(-353_632_621))];
        stream.push(((255, 190), msg("MISSION_ITEM_INT", &with(&to_uav, &item), &[])));
    }
    stream.push(((1, 1), msg("MISSION_ACK", &to_gcs, &[])));
    let last = ((1, 1), msg("MISSION_CURRENT", &[("total", int(items))], &[]));
    // Keyed labels on the way too: param-set.chor's streams are keyed by the parameter's
    // name (`PARAM_VALUE["MC_PITCH_P"]`) and its step is `PARAM_SET["MC_PITCHRATE_MAX"]`, so
    // each PARAM_VALUE and PARAM_SET is dispatched by comparing its `param_id` with the keys:
    // a reading of each gain in the warm-up, and measured: a reading, another parameter's
    // value and set (outside the alphabet by their key), and a read (outside by its id).
    let read = |id: &[u8]| {
        ((255, 190), msg("PARAM_REQUEST_READ", &with(&to_uav, &[("param_index", int(-1))]), &[("param_id", id)]))
    };
    let value = |id: &[u8], v: f32| {
        ((1, 1), msg("PARAM_VALUE", &[("param_value", Scalar::F32(v)), ("param_type", int(9))], &[("param_id", id)]))
    };
    let mut warm: Vec<_> = stream.clone();
    warm.extend([last, read(b"MC_PITCH_P"), value(b"MC_PITCH_P", 6.5), value(b"MC_PITCHRATE_FF", 0.0)]);
    // Measured: a second upload (its session reuses the first one's slot) without the
    // message that ends it (an end records the session's summary), and the second read.
    let mut measured = stream;
    // The upload's MISSION_ACK ends its session (MISSION_CURRENT is telemetry, not a step).
    let ack = measured.pop();
    assert!(matches!(&ack, Some((_, (47, _)))), "the upload's last message is MISSION_ACK");
    let set = |id: &[u8], v: f32| {
        let ints = with(&to_uav, &[("param_value", Scalar::F32(v)), ("param_type", int(9))]);
        ((255, 190), msg("PARAM_SET", &ints, &[("param_id", id)]))
    };
    measured.extend([
        read(b"MC_PITCHRATE_FF"),
        value(b"MC_PITCHRATE_FF", 0.25),
        value(b"MC_ROLL_P", 1e9),
        set(b"MC_ROLL_P", 1e9),
        set(b"MC_PITCHRATE_MA", 1e9),
    ]);
    let mut m = Monitor::new(automata);
    let mut outcomes = Vec::with_capacity(warm.len() + measured.len());
    for (from, x) in &warm {
        outcomes.push(m.on_frame(&frame(*from, x)));
    }
    assert_eq!(m.stats.violations, 0, "{:?}", m.violations().first().map(|v| v.kind));
    assert_eq!(m.stats.sessions_ended, 1);
    let frames: Vec<Frame> = measured.iter().map(|(from, x)| frame(*from, x)).collect();
    outcomes.clear();
    let fallbacks = m.stats.fallbacks;
    let mut allocating = Vec::with_capacity(frames.len());
    let before = allocations();
    for (k, f) in frames.iter().enumerate() {
        let at = allocations();
        outcomes.push(m.on_frame(f));
        if allocations() != at {
            allocating.push((k, f.msgid));
        }
    }
    let after = allocations();
    assert_eq!(m.stats.fallbacks, fallbacks, "fallbacks on the way");
    assert!(allocating.is_empty(), "frames that allocated (index, message id): {allocating:?}");
    assert_eq!(m.stats.violations, 0, "{:?}", m.violations().first().map(|v| v.kind));
    assert!(outcomes.iter().all(|o| matches!(o, Outcome::Step { .. } | Outcome::Passed)));
    assert_eq!(after - before, 0, "allocations over {} conforming messages", frames.len());
    // The counter counts: a violation is recorded with its values (off the hot path).
    let before = allocations();
    let stray = msg("MISSION_ACK", &to_gcs, &[]);
    let Outcome::Violation(v) = m.on_frame(&frame((9, 9), &stray)) else { panic!("a stray ACK accepted") };
    assert!(allocations() > before, "the counting allocator counts nothing");
    // The reports are taken without allocating, and the record is empty after.
    let before = allocations();
    let (mut violations, mut summaries) = (0, 0);
    {
        let r = m.take_reports();
        for x in r.violations {
            violations += usize::from(x.kind == Kind::OutsideSession);
        }
        summaries += r.summaries.count();
    }
    assert_eq!(allocations(), before, "take_reports allocated");
    assert_eq!((violations, summaries), (1, 1));
    assert!(m.violations().is_empty() && m.summaries().is_empty());
    assert!(m.violation(v).is_none(), "a taken violation is still found");
    // A later violation gets a fresh index (not one a caller may still hold).
    let Outcome::Violation(w) = m.on_frame(&frame((9, 9), &stray)) else { panic!("a stray ACK accepted") };
    assert!(w > v && m.violation(w).is_some_and(|x| x.kind == Kind::OutsideSession));
}

// ---- the real captures: the verdict table of docs/captures.md -----------------------

/// Every row of the verdict table in docs/captures.md (protocol, capture, verdict,
/// violations, conformant and incomplete sessions) is what the monitor finds: the table
/// is kept true. Every capture of ../shared/data/mavlink_captures and every verified
/// protocol under choreographies/mavlink has its row.
#[test]
fn the_captures_table_is_what_the_monitor_finds() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/captures.md")).expect("docs/captures.md");
    let table = doc.split("## Verdicts").nth(1).expect("a `## Verdicts` section");
    let mut rows = Vec::new();
    for line in table.lines().skip_while(|l| !l.starts_with("| protocol")).skip(2) {
        if !line.starts_with('|') {
            break;
        }
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        assert!(cells.len() >= 6, "a row of six cells at least: {line}");
        let num = |s: &str| s.parse::<usize>().unwrap_or_else(|_| panic!("a number: {s} in {line}"));
        let protocol = cells[0].trim_matches('`').to_string();
        let capture = cells[1].trim_matches('`').to_string();
        rows.push((protocol, capture, cells[2].to_string(), num(cells[3]), num(cells[4]), num(cells[5])));
    }
    let captures_dir = root.join("../shared/data/mavlink_captures");
    let mut captures: Vec<String> = std::fs::read_dir(&captures_dir)
        .expect("../shared/data/mavlink_captures")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".md"))
        .collect();
    captures.sort();
    let mut automata = std::collections::HashMap::new();
    for path in protocols() {
        let name = path.file_name().expect("name").to_string_lossy().into_owned();
        let (_, prog, verdict) = load(&path);
        if verdict == Verdict::Verified {
            automata.insert(name, Automaton::compile(&prog).expect("compiled"));
        }
    }
    for p in automata.keys() {
        for c in &captures {
            assert!(rows.iter().any(|r| &r.0 == p && &r.1 == c), "docs/captures.md has no row for {p} x {c}");
        }
    }
    for (p, c, verdict, violations, conformant, incomplete) in &rows {
        let a = automata.get(p).unwrap_or_else(|| panic!("{p}: not a verified protocol"));
        let bytes = std::fs::read(captures_dir.join(c)).unwrap_or_else(|e| panic!("{c}: {e}"));
        let mut m = Monitor::new(vec![a.clone()]);
        mochi::mavio::log::read_log(&bytes, mochi::mavio::parse::Config::default(), |f| {
            m.on_frame(&f);
        });
        let found = m.violations().len();
        let summaries = m.finish();
        let conf = summaries.iter().filter(|s| s.conformant).count();
        let inc = summaries.len() - conf;
        assert_eq!((found, conf, inc), (*violations, *conformant, *incomplete), "{p} x {c}");
        let expected = if found > 0 {
            "violation"
        } else if inc > 0 {
            "incomplete"
        } else if conf > 0 {
            "conformant"
        } else {
            "not exercised"
        };
        assert_eq!(verdict, expected, "{p} x {c}");
    }
}

/// The vehicle-side vtol log holds a mission download (the vehicle's MISSION_COUNT to the
/// ground station, its items): the upload protocols must not take it as an upload with the
/// vehicle as their ground station. The vehicle (1/1) says what it is in its HEARTBEAT.
#[test]
fn a_download_is_not_bound_as_an_upload_with_the_roles_reversed() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let bytes =
        std::fs::read(root.join("../shared/data/mavlink_captures/uavlogviewer_vtol.tlog")).expect("the vtol log");
    for name in ["mission-upload.chor", "mission-upload-tolerant.chor", "fence-upload.chor", "rally-upload.chor"] {
        let (_, prog, verdict) = load(&root.join("choreographies/mavlink").join(name));
        assert_eq!(verdict, Verdict::Verified, "{name}");
        let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiled")]);
        mochi::mavio::log::read_log(&bytes, mochi::mavio::parse::Config::default(), |f| {
            m.on_frame(&f);
        });
        assert_eq!(m.end_kind(1, 1), mochi::monitor::EndKind::Vehicle, "{name}");
        assert_eq!(m.stats.sessions_started, 0, "{name}: the download was taken as an upload");
        // What is left is the vehicle's one MISSION_ACK, which no upload of the log asked for.
        assert_eq!(m.violations().len(), 1, "{name}");
        assert_eq!(m.violations()[0].kind, Kind::OutsideSession, "{name}");
    }
}

/// `mochi monitor` refuses a protocol `mochi check` did not verify with E0801, shown as
/// mochi's other diagnostics: the code, the file, line and column of the protocol's first
/// error, and what to do.
#[test]
fn a_protocol_not_verified_is_refused_with_a_code_and_a_position() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mochi"))
        .current_dir(root)
        .args([
            "monitor",
            "--color",
            "never",
            "-p",
            "choreographies/mavlink/rejected/E0419-param-pass-index-out-of-range.chor",
            "../shared/data/mavlink_captures/rust-mavlink_crate-0.21.0_log.tlog",
        ])
        .output()
        .expect("mochi runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("error[E0801]"), "{err}");
    assert!(err.contains("E0419-param-pass-index-out-of-range.chor:70:5"), "{err}");
    assert!(err.contains("help:") && err.contains("mochi check"), "{err}");
}

/// ardusub's list download ends by time (the ground station's 1 s and the vehicle's 3 s of
/// silence pass in the log's time) long before the vehicle's PARAM_VALUE with index 65535 (a
/// parameter changed): the session is closed when the first frame after its bounds arrives,
/// and that PARAM_VALUE is no flood item of it.
#[test]
fn a_session_ended_by_an_invisible_timeout_is_closed_while_the_log_goes_on() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let (_, prog, _) = load(&root.join("choreographies/mavlink/param-list.chor"));
    let bytes =
        std::fs::read(root.join("../shared/data/mavlink_captures/ardusub_log_tools_small.tlog")).expect("the log");
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiled")]);
    let mut ended_at = None;
    mochi::mavio::log::read_log(&bytes, mochi::mavio::parse::Config::default(), |f| {
        let before = m.stats.ended_by_time;
        m.on_frame(&f);
        if m.stats.ended_by_time > before && ended_at.is_none() {
            ended_at = Some(m.stats.frames - 1);
        }
    });
    let ended_at = ended_at.expect("the download ended by time while the log went on");
    assert_eq!(m.summaries().len(), 1, "closed before the end of the log");
    let s = &m.summaries()[0];
    assert!(s.conformant && s.last_frame < ended_at, "{s:?}");
    assert_eq!(m.violations().len(), 1);
    let v = &m.violations()[0];
    assert!(v.frame > ended_at && v.msgid == 22, "{v:?}");
    assert_eq!(v.kind, Kind::OutsideSession, "the PARAM_VALUE 65535 was taken in the ended session");
}

// ---- timeouts: the parameter list, in the frames' time -------------------------------

/// A frame at time `t_us`.
fn timed(from: (u8, u8), (msgid, payload): &(u32, Vec<u8>), t_us: u64) -> Frame<'_> {
    Frame {
        time_us: Some(t_us),
        version: 2,
        sysid: from.0,
        compid: from.1,
        msgid: *msgid,
        payload,
        signed: false,
        raw: &[],
    }
}

/// One way to break a conforming parameter-list trace, and what the monitor must say.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Break {
    None,
    /// The first re-request sent before 1000 ms of silence passed.
    EarlyRequest,
    /// An answer to a re-request with another index: not a break. It may be a late answer to
    /// an earlier request (mavlink/mavlink#950), so the ground station accepts any
    /// PARAM_VALUE after a re-request, and the monitor must pass it (E0326 made the
    /// protocol say so).
    OtherIndex,
    /// A re-request beyond the three the protocol allows.
    FourthRequest,
    /// A flood value whose index is not below the count.
    IndexOverCount,
}

/// A parameter-list download drawn from `rng` (the ground station 255/190, the vehicle 1/1),
/// as (source, message, time) in order, broken as `brk` says; the index of the broken
/// frame, if any; and the time after which the session has ended by time.
#[allow(clippy::type_complexity)]
fn param_list_trace(
    prog: &Program,
    rng: &mut SplitMix64,
    brk: Break,
) -> (Vec<((u8, u8), (u32, Vec<u8>), u64)>, Option<usize>, u64) {
    let (gcs, uav) = (RoleId(0), RoleId(1));
    let mut t: u64 = 1_700_000_000_000_000;
    let mut out = Vec::new();
    let mut broken = None;
    out.push((end_of(gcs), payload(prog, "PARAM_REQUEST_LIST", uav, &[]), t));
    let count = (rng.next_u64() % 40 + 1) as i128;
    for k in 0..rng.next_u64() % 30 {
        // The flood may pause for more than the timeout: the ground station has not acted.
        t += rng.next_u64() % 1_500_000;
        let mut idx = (rng.next_u64() % count as u64) as i128;
        if brk == Break::IndexOverCount && k == 0 {
            idx = count + (rng.next_u64() % 3) as i128;
            broken = Some(out.len());
        }
        out.push((end_of(uav), payload(prog, "PARAM_VALUE", gcs, &[("param_count", count), ("param_index", idx)]), t));
    }
    if brk == Break::IndexOverCount && broken.is_none() {
        t += 1000;
        broken = Some(out.len());
        out.push((
            end_of(uav),
            payload(prog, "PARAM_VALUE", gcs, &[("param_count", count), ("param_index", count)]),
            t,
        ));
    }
    let requests = match brk {
        Break::None => rng.next_u64() % 4,
        Break::FourthRequest => 4,
        _ => 1 + rng.next_u64() % 3,
    };
    for r in 0..requests {
        // At least the bound after the last message (flood or answer), or after the last
        // request (unanswered: the inner timeout).
        let early = brk == Break::EarlyRequest && r == 0;
        t += if early { rng.next_u64() % 1_000_000 } else { 1_000_000 + rng.next_u64() % 1_500_000 };
        let want = (rng.next_u64() % count as u64) as i128;
        if early || (brk == Break::FourthRequest && r == 3) {
            broken = Some(out.len());
        }
        out.push((end_of(gcs), payload(prog, "PARAM_REQUEST_READ", uav, &[("param_index", want)]), t));
        let other = brk == Break::OtherIndex && r == 0;
        if other || !rng.next_u64().is_multiple_of(3) {
            t += rng.next_u64() % 900_000;
            let got = if other { want + 1 + (rng.next_u64() % 5) as i128 } else { want };
            out.push((
                end_of(uav),
                payload(prog, "PARAM_VALUE", gcs, &[("param_count", count), ("param_index", got)]),
                t,
            ));
        }
    }
    // Silence: the ground station's timeout (1 s) and the vehicle's (3 s) both pass.
    (out, broken, t + 4_000_001)
}

/// Static and run time agree on timeouts: every conforming trace of `param-list.chor` (a
/// random flood, pauses, up to three re-requests after a silence, answered or not, then
/// silence) is accepted and the session ends by time, conformant, an answer with another
/// index than asked for included; a re-request before the silence, a fourth re-request and
/// an index over the count are each
/// rejected at exactly the frame that breaks the protocol, with the rule it breaks.
/// (`mochi simulate` does not take timeout branches, so the trace generator is this one.)
#[test]
fn timeouts_are_enforced_in_the_frames_time() {
    let protocols_with_timeouts: Vec<_> = protocols()
        .into_iter()
        .filter(|p| {
            let (_, prog, verdict) = load(p);
            verdict == Verdict::Verified && has_timeout(&prog)
        })
        .map(|p| p.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    // A new verified protocol with a timeout needs a trace generator: param-list.chor's is
    // here, compass-calibration.chor's and parachute.chor's in
    // `calibration_and_parachute_end_by_time_as_verified`.
    assert_eq!(protocols_with_timeouts, ["compass-calibration.chor", "parachute.chor", "param-list.chor"]);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink/param-list.chor");
    let (db, prog, _) = load(&path);
    let a = Automaton::compile(&prog).unwrap_or_else(|e| panic!("param-list.chor: {}", e.message));
    let heartbeat = (0u32, vec![0u8; 9]);
    let mut rng = SplitMix64(21);
    let breaks = [Break::None, Break::EarlyRequest, Break::OtherIndex, Break::FourthRequest, Break::IndexOverCount];
    let mut timeouts = 0;
    for round in 0..200 {
        let brk = breaks[round % breaks.len()];
        let (trace, broken, quiet) = param_list_trace(&prog, &mut rng, brk);
        let mut m = Monitor::new(vec![a.clone()]);
        for (k, (from, msg, t)) in trace.iter().enumerate() {
            let o = m.on_frame(&timed(*from, msg, *t));
            match (Some(k) == broken, o) {
                (false, Outcome::Violation(v)) => {
                    panic!("{brk:?}: conforming frame {k} rejected: {}", m.describe(&db, v))
                }
                (true, Outcome::Violation(v)) => {
                    let kind = m.violation(v).map(|v| v.kind);
                    let expected = match brk {
                        Break::EarlyRequest => Kind::Early,
                        Break::FourthRequest => Kind::Guard,
                        _ => Kind::Refinement,
                    };
                    assert_eq!(kind, Some(expected), "{brk:?}: {}", m.describe(&db, v));
                    break;
                }
                (true, o) => panic!("{brk:?}: frame {k} accepted: {o:?}"),
                _ => {}
            }
        }
        if matches!(brk, Break::None | Break::OtherIndex) {
            // Telemetry after the silence moves the clock: the session ended by time.
            assert_eq!(m.on_frame(&timed((1, 1), &heartbeat, quiet)), Outcome::Passed);
            timeouts += m.stats.timeouts;
            let s = m.finish();
            assert_eq!(s.len(), 1);
            assert!(s[0].conformant, "a conforming download not conformant: {s:?}");
        }
    }
    assert!(timeouts > 0, "no timeout branch was taken");
    // Without the silence the session is incomplete: the vehicle's timeout (3 s, the
    // shortest way to `end` from any state) has not passed.
    let (trace, _, quiet) = param_list_trace(&prog, &mut SplitMix64(5), Break::None);
    let mut m = Monitor::new(vec![a.clone()]);
    for (from, msg, t) in &trace {
        assert!(!matches!(m.on_frame(&timed(*from, msg, *t)), Outcome::Violation(_)));
    }
    assert_eq!(m.on_frame(&timed((1, 1), &heartbeat, quiet - 4_000_001 + 2_999_999)), Outcome::Passed);
    assert!(!m.finish()[0].conformant);
    // A log without time cannot say whether a re-request waited: undecided, never passed.
    let mut m = Monitor::new(vec![a]);
    let list = payload(&prog, "PARAM_REQUEST_LIST", RoleId(1), &[]);
    let read = payload(&prog, "PARAM_REQUEST_READ", RoleId(1), &[("param_index", 0)]);
    assert!(matches!(m.on_frame(&frame((255, 190), &list)), Outcome::Step { .. }));
    let Outcome::Violation(v) = m.on_frame(&frame((255, 190), &read)) else {
        panic!("a re-request without time accepted")
    };
    assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Undecided));
}

// ---- the compiled evaluator against the tree evaluator ---------------------------------

/// A protocol lowered (no verification: the comparison below is of two evaluators of the
/// same program, whatever its verdict).
fn lowered(path: &Path) -> Program {
    let mut db = SourceDb::new();
    let root = mochi::fsload::load_root(&mut db, path).expect("readable");
    let mut read = |p: &Path| mochi::fsload::read_bytes(p);
    mochi::driver::prepare(&mut db, root, &mut read, mochi::driver::Stage::Names).expect("lowered")
}

/// What a monitor found over a stream, report by report: each frame's outcome, each
/// violation (where, what, the values read), each session's summary, the counters (all but
/// the fallbacks, which the two evaluators take at different places with the same answer).
fn run_all(protos: Vec<Automaton>, bytes: &[u8]) -> Vec<String> {
    let mut m = Monitor::new(protos);
    let mut out = Vec::new();
    mochi::mavio::log::read_log(bytes, mochi::mavio::parse::Config::default(), |f| {
        out.push(format!("{:?}", m.on_frame(&f)));
    });
    for v in m.violations() {
        out.push(format!(
            "{} {:?} {:?} {:?} {:?} {} {:?} {:?} {:?} {:?} {:?}",
            v.frame, v.time_us, v.kind, v.protocol, v.session, v.state, v.edge, v.pred, v.field, v.why, v.regs
        ));
    }
    let mut stats = m.stats;
    stats.fallbacks = 0;
    for s in m.finish() {
        out.push(format!(
            "{} {} {} {} {} {} {} {:?} {:?} {:?}",
            s.session,
            s.protocol,
            s.conformant,
            s.state,
            s.first_frame,
            s.last_frame,
            s.violations,
            s.roles,
            s.taken,
            s.evaluated
        ));
    }
    out.push(format!("{stats:?}"));
    out
}

/// Every protocol under choreographies/mavlink, compiled for the monitor's evaluator
/// (comparisons compiled, enum disjunctions one lookup) and for the tree evaluator, finds
/// the same on every real capture: alone, and all of them at once (frame-id dispatch over
/// fifteen protocols).
#[test]
fn the_compiled_evaluator_finds_what_the_tree_evaluator_finds_on_every_capture() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let progs: Vec<Program> = protocols().iter().map(|p| lowered(p)).collect();
    let flat: Vec<Automaton> = progs.iter().map(|p| Automaton::compile(p).expect("compiles")).collect();
    let tree: Vec<Automaton> = progs.iter().map(|p| Automaton::compile_tree(p).expect("compiles")).collect();
    let dir = root.join("../shared/data/mavlink_captures");
    let mut captures: Vec<_> = std::fs::read_dir(&dir)
        .expect("../shared/data/mavlink_captures")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e != "md"))
        .collect();
    captures.sort();
    assert!(captures.len() >= 4, "the captures are missing");
    let mut steps = 0;
    for c in &captures {
        let bytes = std::fs::read(c).expect("capture");
        let (a, b) = (run_all(flat.clone(), &bytes), run_all(tree.clone(), &bytes));
        assert_eq!(a.len(), b.len(), "{}", c.display());
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            assert_eq!(x, y, "{}, all protocols at once, report {k}", c.display());
        }
        steps += a.iter().filter(|o| o.starts_with("Step") || o.starts_with("Ended")).count();
        for (i, (f, t)) in flat.iter().zip(&tree).enumerate() {
            let (a, b) = (run_all(vec![f.clone()], &bytes), run_all(vec![t.clone()], &bytes));
            assert_eq!(a, b, "{} with {}", c.display(), protocols()[i].display());
        }
    }
    assert!(steps > 100, "the captures exercised the protocols {steps} times only");
}

/// A frame to send at a time: its source end, its message and its time (µs).
type TimedFrame = ((u8, u8), (u32, Vec<u8>), u64);

/// How a compass calibration trace breaks the protocol, if it does.
#[derive(Clone, Copy, Debug, PartialEq)]
enum CalBreak {
    None,
    /// A progress report with a lower percentage than the one before (the loop invariant).
    ProgressBack,
    /// A progress report after the vehicle refused the calibration (the guard).
    ProgressAfterRefusal,
    /// A success reported not saved, though autosave was asked (the report's refinement).
    SuccessNotSaved,
    /// A progress report after the ground station's silence and the late window after it
    /// passed (a report within the window is late: `late_messages_of_ended_sessions_...`):
    /// the session is over.
    AfterTheSilence,
}

/// A compass calibration in the frames' time: the command, then (or not) the
/// acknowledgement, accepted or refused, then progress reports that never go back and a
/// result, or a silence of more than 5 s; each gap before a message of the vehicle under 5 s
/// (the protocol's SILENCE_MS), so no timeout passes before it. Returns the frames, the
/// index of the one that breaks the protocol, and the time at which the session is over by
/// time (`None`: it ends with the report).
fn calibration_trace(
    prog: &Program,
    rng: &mut SplitMix64,
    brk: CalBreak,
) -> (Vec<TimedFrame>, Option<usize>, Option<u64>) {
    let (gcs, uav) = (RoleId(0), RoleId(1));
    let (g, u) = (end_of(gcs), end_of(uav));
    // MAV_CMD_DO_START_MAG_CAL: param1 magnetometers 0, param2 retry 0, param3 autosave 1.
    let start =
        payload(prog, "COMMAND_LONG[MAV_CMD_DO_START_MAG_CAL]", uav, &[("param1", 0), ("param2", 0), ("param3", 1)]);
    let ack = |result: i128| payload(prog, "COMMAND_ACK[MAV_CMD_DO_START_MAG_CAL]", gcs, &[("result", result)]);
    // MAG_CAL_RUNNING_STEP_ONE 2, MAG_CAL_SUCCESS 4, MAG_CAL_FAILED 5.
    let progress = |pct: i128| payload(prog, "MAG_CAL_PROGRESS", gcs, &[("cal_status", 2), ("completion_pct", pct)]);
    let report = |status: i128, saved: i128| {
        payload(prog, "MAG_CAL_REPORT", gcs, &[("cal_status", status), ("autosaved", saved)])
    };
    let mut t = 1_000_000_000u64;
    let gap = |rng: &mut SplitMix64| 1 + rng.next_u64() % 4_900_000;
    let mut out = vec![(g, start, t)];
    let mut broken = None;
    let refused = brk == CalBreak::ProgressAfterRefusal || (brk == CalBreak::None && rng.next_u64().is_multiple_of(4));
    let no_ack = brk == CalBreak::None && !refused && rng.next_u64().is_multiple_of(5);
    if no_ack {
        return (out, None, Some(t + 5_000_000));
    }
    t += gap(rng);
    out.push((u, ack(if refused { 4 } else { 0 }), t));
    if refused {
        if brk == CalBreak::ProgressAfterRefusal {
            t += gap(rng);
            broken = Some(out.len());
            out.push((u, progress(10), t));
        }
        return (out, broken, Some(t + 5_000_000));
    }
    // At least two reports: the second is the loop's, whose refinement reads the first.
    let n = 2 + rng.next_u64() % 7;
    let mut pct = 0i128;
    for k in 0..n {
        t += gap(rng);
        if brk == CalBreak::ProgressBack && k == n - 1 {
            broken = Some(out.len());
            out.push((u, progress(pct - 1), t));
            return (out, broken, None);
        }
        pct = (pct + 1 + (rng.next_u64() % 30) as i128).min(100);
        out.push((u, progress(pct), t));
    }
    match brk {
        CalBreak::AfterTheSilence => {
            t += 10_000_001;
            broken = Some(out.len());
            out.push((u, progress(pct), t));
            (out, broken, None)
        }
        CalBreak::SuccessNotSaved => {
            t += gap(rng);
            broken = Some(out.len());
            out.push((u, report(4, 0), t));
            (out, broken, None)
        }
        _ if rng.next_u64().is_multiple_of(3) => (out, None, Some(t + 5_000_000)),
        _ => {
            t += gap(rng);
            let failed = rng.next_u64().is_multiple_of(2);
            out.push((u, if failed { report(5, 0) } else { report(4, 1) }, t));
            (out, None, None)
        }
    }
}

/// Static and run time agree on the timeouts of `compass-calibration.chor` and
/// `parachute.chor`: every conforming trace (a calibration acknowledged or not, accepted or
/// refused, reporting progress and a result or falling silent; a release acknowledged in
/// time or not) is accepted and its session ends conformant, by its last message or by time;
/// each broken trace is rejected at exactly the frame that breaks it, with the rule it breaks.
#[test]
fn calibration_and_parachute_end_by_time_as_verified() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink");
    let (db, prog, verdict) = load(&dir.join("compass-calibration.chor"));
    assert_eq!(verdict, Verdict::Verified);
    let a = Automaton::compile(&prog).unwrap_or_else(|e| panic!("compass-calibration.chor: {}", e.message));
    let heartbeat = (0u32, vec![0u8; 9]);
    let breaks = [
        CalBreak::None,
        CalBreak::ProgressBack,
        CalBreak::ProgressAfterRefusal,
        CalBreak::SuccessNotSaved,
        CalBreak::AfterTheSilence,
    ];
    let mut rng = SplitMix64(11);
    let (mut by_time, mut by_report) = (0, 0);
    for round in 0..200 {
        let brk = breaks[round % breaks.len()];
        let (trace, broken, quiet) = calibration_trace(&prog, &mut rng, brk);
        assert_eq!(broken.is_some(), brk != CalBreak::None, "{brk:?}");
        let mut m = Monitor::new(vec![a.clone()]);
        for (k, (from, msg, t)) in trace.iter().enumerate() {
            match (Some(k) == broken, m.on_frame(&timed(*from, msg, *t))) {
                (false, Outcome::Violation(v)) => {
                    panic!("{brk:?}: conforming frame {k} rejected: {}", m.describe(&db, v))
                }
                (true, Outcome::Violation(v)) => {
                    let expected = match brk {
                        CalBreak::ProgressAfterRefusal => Kind::Guard,
                        CalBreak::AfterTheSilence => Kind::OutsideSession,
                        _ => Kind::Refinement,
                    };
                    assert_eq!(m.violation(v).map(|v| v.kind), Some(expected), "{brk:?}: {}", m.describe(&db, v));
                }
                (true, o) => panic!("{brk:?}: frame {k} accepted: {o:?}"),
                _ => {}
            }
        }
        if brk != CalBreak::None {
            continue;
        }
        if let Some(q) = quiet {
            // One microsecond before the silence passed the session is still open; telemetry
            // after it moves the clock, and the session ended by time.
            assert_eq!(m.on_frame(&timed((1, 1), &heartbeat, q - 1)), Outcome::Passed);
            assert_eq!(m.stats.ended_by_time, 0, "ended before its silence");
            assert_eq!(m.on_frame(&timed((1, 1), &heartbeat, q)), Outcome::Passed);
            assert_eq!(m.stats.ended_by_time, 1);
            by_time += 1;
        } else {
            by_report += 1;
        }
        let s = m.finish();
        assert_eq!(s.len(), 1);
        assert!(s[0].conformant, "a conforming calibration not conformant: {s:?}");
    }
    assert!(by_time > 0 && by_report > 0, "{by_time} ended by time, {by_report} by their report");

    // The parachute: a release acknowledged within the ground station's 3 s ends with the
    // acknowledgement; one never acknowledged ends by time, and an acknowledgement after that
    // is in no session: late within the 3 s after the timeout (it crossed it), outside any
    // session after.
    let (db, prog, verdict) = load(&dir.join("parachute.chor"));
    assert_eq!(verdict, Verdict::Verified);
    let a = Automaton::compile(&prog).expect("parachute.chor compiles");
    let (gcs, uav) = (RoleId(0), RoleId(1));
    let (g, u) = (end_of(gcs), end_of(uav));
    let safe_hb =
        payload(&prog, "HEARTBEAT", gcs, &[("type", 2), ("autopilot", 3), ("base_mode", 209), ("custom_mode", 0)]);
    let safe_pos = payload(&prog, "GLOBAL_POSITION_INT", gcs, &[("relative_alt", 50_000), ("vz", 10)]);
    let release = payload(&prog, "COMMAND_LONG[MAV_CMD_DO_PARACHUTE]", uav, &[("param1", 2)]);
    let ack = payload(&prog, "COMMAND_ACK[MAV_CMD_DO_PARACHUTE]", gcs, &[("result", 0)]);
    let t0 = 1_000_000_000u64;
    for (ack_after, in_time) in [(2_999_999u64, true), (3_000_000, false), (6_000_001, false)] {
        let mut m = Monitor::new(vec![a.clone()]);
        for (from, msg, t) in [(u, &safe_hb, t0), (u, &safe_pos, t0 + 1), (g, &release, t0 + 2)] {
            assert!(!matches!(m.on_frame(&timed(from, msg, t)), Outcome::Violation(_)));
        }
        let o = m.on_frame(&timed(u, &ack, t0 + 2 + ack_after));
        if in_time {
            assert!(matches!(o, Outcome::Ended { .. }), "{o:?}");
        } else if ack_after <= 6_000_000 {
            assert!(matches!(o, Outcome::Late { .. }), "an acknowledgement that crossed the timeout: {o:?}");
            assert_eq!((m.stats.ended_by_time, m.stats.late), (1, 1));
        } else {
            let Outcome::Violation(v) = o else { panic!("an acknowledgement after the timeout accepted: {o:?}") };
            assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::OutsideSession), "{}", m.describe(&db, v));
            assert_eq!(m.stats.ended_by_time, 1);
        }
        assert!(m.finish().iter().all(|s| s.conformant));
    }
}

/// The proxy's event lines allocate nothing per message once their buffer has grown: a step,
/// an end and a late message (the events of conforming traffic) are written from integers
/// and `&'static str`s into the reused buffer (checker/monitor/src/proxy/lines.rs).
#[test]
fn the_proxy_lines_of_steps_allocate_nothing() {
    use mochi::proxy::lines::Lines;
    use mochi::proxy::{At, Dir, Event, Sink};
    let at = At { time_us: 1_764_306_000_123_456, dir: Dir::GcsToVehicle, msgid: 73, from: (255, 190), signed: false };
    let batch = [
        Event::Step { at, session: 12, state: 4 },
        Event::End { at, session: 12, protocol: Some(0), conformant: true },
        Event::Late { at, session: 12, forwarded: false },
    ];
    let lines = Lines::new(std::io::sink(), vec!["UploadTolerant".to_string()]);
    lines.events(&batch);
    let before = allocations();
    for _ in 0..1000 {
        lines.events(&batch);
    }
    assert_eq!(allocations() - before, 0, "allocations while writing 3,000 lines");
}

// ---- the late window (bounded in time; it never restarts a timeout) --------------------

/// `param-list.chor` in a ground station's log: the flood's last value came at `t`; the
/// ground station's timeout could fire at `t + 1 s`; a value that was on the wire when it
/// gave up is logged 1 ms after that, and its re-request 1 ms after the value. The log is a
/// run of the protocol (the late value was ignored), so nothing is a violation, and the
/// session ends by time, conformant. With the re-request 50 ms after the value (beyond the
/// reaction bound) the ground station took the value: `before its timeout`.
#[test]
fn a_late_flood_item_leaves_the_ground_stations_re_request_in_time() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink/param-list.chor");
    let (db, prog, _) = load(&path);
    let a = Automaton::compile(&prog).expect("compiled");
    let (gcs, uav) = (RoleId(0), RoleId(1));
    let (g, u) = (end_of(gcs), end_of(uav));
    let list = payload(&prog, "PARAM_REQUEST_LIST", uav, &[]);
    let value = |i: i128| payload(&prog, "PARAM_VALUE", gcs, &[("param_count", 5), ("param_index", i)]);
    let read = payload(&prog, "PARAM_REQUEST_READ", uav, &[("param_index", 4)]);
    let t = 1_700_000_000_000_000u64;
    let heartbeat = (0u32, vec![0u8; 9]);
    for (reaction, in_time) in [(1_000u64, true), (50_000, false)] {
        let mut frames = vec![(g, list.clone(), t)];
        frames.extend((0..4).map(|i| (u, value(i), t + 10_000 * (i as u64 + 1))));
        let last = t + 40_000;
        frames.push((u, value(4), last + 1_001_000));
        frames.push((g, read.clone(), last + 1_001_000 + reaction));
        let mut m = Monitor::new(vec![a.clone()]);
        let outs: Vec<Outcome> = frames.iter().map(|(from, msg, t)| m.on_frame(&timed(*from, msg, *t))).collect();
        let (flood, act) = (outs[5], outs[6]);
        assert!(matches!(flood, Outcome::Step { .. }), "the value that may have crossed: {flood:?}");
        if in_time {
            if let Outcome::Violation(v) = act {
                panic!("the re-request after a late value: {}", m.describe(&db, v));
            }
            assert_eq!(m.stats.timeouts, 1);
            m.on_frame(&timed((1, 1), &heartbeat, last + 10_000_000));
            assert!(m.finish().iter().all(|s| s.conformant), "{:?}", m.summaries());
        } else {
            let Outcome::Violation(v) = act else { panic!("a re-request 50 ms after a value accepted: {act:?}") };
            assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::Early), "{}", m.describe(&db, v));
        }
    }
}

/// Late messages of sessions that ended by a timeout: `param-list.chor`'s vehicle gives up
/// 3 s after the ground station's 1 s (the session ends by time); a re-request that crossed
/// the vehicle's timeout is late within its 3 s after it, outside any session after; and
/// `compass-calibration.chor`'s progress report that crossed the ground station's 5 s
/// silence is late, not outside any session.
#[test]
fn late_messages_of_ended_sessions_are_late_within_their_window() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies/mavlink");
    let (db, prog, _) = load(&dir.join("param-list.chor"));
    let a = Automaton::compile(&prog).expect("compiled");
    let (gcs, uav) = (RoleId(0), RoleId(1));
    let (g, u) = (end_of(gcs), end_of(uav));
    let list = payload(&prog, "PARAM_REQUEST_LIST", uav, &[]);
    let value = payload(&prog, "PARAM_VALUE", gcs, &[("param_count", 5), ("param_index", 0)]);
    let read = payload(&prog, "PARAM_REQUEST_READ", uav, &[("param_index", 4)]);
    let t = 1_700_000_000_000_000u64;
    for (after, late) in [(4_500_000u64, true), (7_000_000, true), (7_000_001, false)] {
        let mut m = Monitor::new(vec![a.clone()]);
        m.on_frame(&timed(g, &list, t));
        m.on_frame(&timed(u, &value, t + 10_000));
        let o = m.on_frame(&timed(g, &read, t + 10_000 + after));
        assert_eq!(m.stats.ended_by_time, 1);
        match (late, o) {
            (true, Outcome::Late { .. }) => assert_eq!(m.stats.late, 1),
            (false, Outcome::Violation(v)) => {
                assert_eq!(m.violation(v).map(|v| v.kind), Some(Kind::OutsideSession), "{}", m.describe(&db, v))
            }
            (_, o) => panic!("a re-request {after} µs after the value: {o:?}"),
        }
    }
    let (_, prog, _) = load(&dir.join("compass-calibration.chor"));
    let a = Automaton::compile(&prog).expect("compiled");
    let start =
        payload(&prog, "COMMAND_LONG[MAV_CMD_DO_START_MAG_CAL]", uav, &[("param1", 0), ("param2", 0), ("param3", 1)]);
    let ack = payload(&prog, "COMMAND_ACK[MAV_CMD_DO_START_MAG_CAL]", gcs, &[("result", 0)]);
    let progress = |pct: i128| payload(&prog, "MAG_CAL_PROGRESS", gcs, &[("cal_status", 2), ("completion_pct", pct)]);
    let mut m = Monitor::new(vec![a]);
    for (from, msg, at) in
        [(g, &start, t), (u, &ack, t + 1_000), (u, &progress(10), t + 2_000), (u, &progress(20), t + 3_000)]
    {
        assert!(!matches!(m.on_frame(&timed(from, msg, at)), Outcome::Violation(_)));
    }
    let o = m.on_frame(&timed(u, &progress(30), t + 3_000 + 5_000_001));
    assert!(matches!(o, Outcome::Late { .. }), "{o:?}");
    assert_eq!((m.stats.ended_by_time, m.stats.late), (1, 1));
}

/// Every protocol of the corpus is one the monitor reads in its order: none is refused for
/// a message that may race the one before it, or for starting by waiting.
#[test]
fn no_corpus_protocol_is_refused_for_its_order_or_for_starting_by_waiting() {
    for p in protocols() {
        let (_, prog, verdict) = load(&p);
        if verdict != Verdict::Verified {
            continue;
        }
        if let Err(e) = Automaton::compile(&prog) {
            assert!(
                !e.message.contains("starts by waiting") && !e.message.contains("may reach the link before"),
                "{}: {}",
                p.display(),
                e.message
            );
        }
    }
}

/// Keyed streams over a real list download: the two keyed parameters' PARAM_VALUEs of the
/// ardusub capture are readings (MOT_THST_HOVER twice, SERVO16_FUNCTION's 16 characters
/// with no NUL once), each of the other 885 names passes outside the alphabet, and with
/// invariants the captured values break, none of the three is a reading (outside any
/// session they pass: not this protocol's vehicle).
#[test]
fn keyed_streams_read_their_parameters_in_a_real_list_download() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("tests/data/mavlink/keyed-ardusub-parameters.chor");
    let (_, prog, verdict) = load(&path);
    assert_eq!(verdict, Verdict::Verified);
    let bytes = std::fs::read(root.join("../shared/data/mavlink_captures/ardusub_log_tools_small.tlog")).expect("log");
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]);
    mochi::mavio::log::read_log(&bytes, mochi::mavio::parse::Config::default(), |f| {
        m.on_frame(&f);
    });
    assert_eq!((m.violations().len(), m.stats.readings, m.stats.sessions_started), (0, 3, 0));
    // The same protocol with invariants the captured values break.
    let text = std::fs::read_to_string(&path).expect("source");
    let broken = text.replace("hover <= 0.6875}", "hover <= 0.25}").replace("servo16 == 7", "servo16 == 6");
    let dir = std::env::temp_dir().join(format!("mochi-keyed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let broken_path = dir.join("broken.chor");
    std::fs::write(&broken_path, broken).expect("write");
    let prog = lowered(&broken_path);
    let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiles")]);
    mochi::mavio::log::read_log(&bytes, mochi::mavio::parse::Config::default(), |f| {
        m.on_frame(&f);
    });
    let _ = std::fs::remove_dir_all(&dir);
    // Outside any session, a value the invariant refuses is no reading of this protocol's
    // vehicle (docs/monitor.md, "Streams and observed state"): it passes, and is not read.
    let kinds: Vec<Kind> = m.violations().iter().map(|v| v.kind).collect();
    assert_eq!(kinds, []);
    assert_eq!(m.stats.readings, 0);
}
