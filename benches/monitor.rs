//! The run-time monitor's work per message (target: under 100 ns).
//!
//! ```text
//! cargo bench --bench monitor             # 200 passes over the stream
//! cargo bench --bench monitor -- --quick  # 20 passes
//! ```
//!
//! The stream: a 500-item mission upload (`choreographies/mavlink/mission-upload-tolerant.chor`:
//! MISSION_COUNT, 500 times MISSION_REQUEST_INT and MISSION_ITEM_INT, MISSION_ACK,
//! MISSION_CURRENT) interleaved with telemetry the protocols do not speak (ATTITUDE,
//! GLOBAL_POSITION_INT, SYS_STATUS, VFR_HUD after every protocol message), monitored
//! together with `arm-command.chor` and `param-set.chor` (three protocols at once). The
//! frames are built once (payloads encoded by the dialect's wire layout); the timed loop
//! is `Monitor::on_frame` over the whole stream, a new monitor per pass (so each pass starts
//! the session again), and the figure is the wall time per frame. The benchmark prints and
//! asserts only that every pass ends the upload conformant with no violation.

use mochi::dialect::Dialect;
use mochi::mavio::Frame;
use mochi::monitor::wire::{self, Layout, Scalar};
use mochi::monitor::{Automaton, Monitor, Outcome};
use mochi::source::SourceDb;
use std::path::Path;
use std::time::Instant;

const ITEMS: i128 = 500;
const TARGET_NS: f64 = 100.0;

fn compile(path: &str) -> Automaton {
    let mut db = SourceDb::new();
    let root = mochi::fsload::load_root(&mut db, Path::new(path)).expect("read the protocol");
    let mut load = |p: &Path| mochi::fsload::read_bytes(p);
    let prog = mochi::driver::prepare(&mut db, root, &mut load, mochi::driver::Stage::Names).expect("lowered");
    Automaton::compile(&prog).expect("compiles")
}

/// `(sysid, compid, msgid, payload)`.
type Owned = (u8, u8, u32, Vec<u8>);

fn msg(d: &Dialect, from: (u8, u8), name: &str, fields: &[(&str, Scalar)]) -> Owned {
    let m = d.message(name).expect("message");
    let l = Layout::of(m);
    let mut p = vec![0u8; l.size as usize];
    for (f, v) in fields {
        wire::write(&mut p, l.slot(m, f).expect("field"), 0, *v);
    }
    let n = wire::truncate(&p).len();
    p.truncate(n);
    (from.0, from.1, m.id, p)
}

fn stream(d: &Dialect) -> Vec<Owned> {
    let (gcs, uav) = ((255, 190), (1, 1));
    let int = Scalar::Int;
    let to_uav = [("target_system", int(1)), ("target_component", int(1))];
    let to_gcs = [("target_system", int(255)), ("target_component", int(190))];
    let with = |base: &[(&'static str, Scalar)], more: &[(&'static str, Scalar)]| {
        let mut v = base.to_vec();
        v.extend_from_slice(more);
        v
    };
    let telemetry = [
        msg(d, uav, "ATTITUDE", &[("roll", Scalar::F32(0.01)), ("yaw", Scalar::F32(1.5))]),
        msg(d, uav, "GLOBAL_POSITION_INT", &[("lat", int(-353_632_621)), ("relative_alt", int(20_000))]),
        msg(d, uav, "SYS_STATUS", &[("voltage_battery", int(12_600))]),
        msg(d, uav, "VFR_HUD", &[("groundspeed", Scalar::F32(3.25))]),
    ];
    let mut out = Vec::new();
    let push = |m: Owned, out: &mut Vec<Owned>| {
        out.push(m);
        out.extend(telemetry.iter().cloned());
    };
    push(msg(d, gcs, "MISSION_COUNT", &with(&to_uav, &[("count", int(ITEMS))])), &mut out);
    for i in 0..ITEMS {
        push(msg(d, uav, "MISSION_REQUEST_INT", &with(&to_gcs, &[("seq", int(i))])), &mut out);
        let item = [("seq", int(i)), ("command", int(16)), ("x", int(-353_632_621 + i)), ("z", Scalar::F32(20.0))];
        push(msg(d, gcs, "MISSION_ITEM_INT", &with(&to_uav, &item)), &mut out);
    }
    push(msg(d, uav, "MISSION_ACK", &with(&to_gcs, &[])), &mut out);
    push(msg(d, uav, "MISSION_CURRENT", &[("seq", int(0)), ("total", int(ITEMS))]), &mut out);
    out
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let passes = if quick { 20 } else { 200 };
    let protos = vec![
        compile("choreographies/mavlink/mission-upload-tolerant.chor"),
        compile("choreographies/mavlink/arm-command.chor"),
        compile("choreographies/mavlink/param-set.chor"),
    ];
    let d = protos[0].prog.dialect.expect("dialect");
    let owned = stream(d);
    let frames: Vec<Frame> = owned
        .iter()
        .map(|(s, c, id, p)| Frame {
            time_us: Some(0),
            version: 2,
            sysid: *s,
            compid: *c,
            msgid: *id,
            payload: p,
            signed: false,
            raw: p,
        })
        .collect();
    let mut best = f64::INFINITY;
    let mut total = 0.0;
    for _ in 0..passes {
        let mut m = Monitor::new(protos.clone());
        let t = Instant::now();
        let mut ended = 0;
        for f in &frames {
            if let Outcome::Ended { .. } = std::hint::black_box(m.on_frame(std::hint::black_box(f))) {
                ended += 1;
            }
        }
        let ns = t.elapsed().as_nanos() as f64 / frames.len() as f64;
        assert_eq!((ended, m.stats.violations), (1, 0), "the upload must end conformant");
        best = best.min(ns);
        total += ns;
    }
    let mean = total / passes as f64;
    let protocol = frames.len() / (1 + 4);
    println!(
        "monitor: {} frames per pass ({} protocol messages, {} telemetry), 3 protocols, {passes} passes",
        frames.len(),
        protocol,
        frames.len() - protocol
    );
    println!(
        "monitor: {mean:.1} ns/message mean, {best:.1} ns/message best (target {TARGET_NS} ns): {}",
        if mean < TARGET_NS { "met" } else { "NOT met" }
    );
}
