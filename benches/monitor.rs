//! The run-time monitor's work per message (target: under 100 ns).
//!
//! ```text
//! cargo bench --bench monitor                          # 200 passes (synthetic), 20 per capture
//! cargo bench --bench monitor -- --quick               # 20 and 3
//! valgrind --tool=callgrind --toggle-collect='*Monitor*on_frame*' \
//!     target/release/deps/monitor-HASH --callgrind ardusub  # instructions, one pass
//! ```
//!
//! Three figures, each the wall time of `Monitor::on_frame` per frame, a new monitor per pass
//! (so each pass starts the sessions again), the frames prepared beforehand:
//!
//! - a synthetic 500-item mission upload (`mission-upload-tolerant.chor`: MISSION_COUNT, 500
//!   times MISSION_REQUEST_INT and MISSION_ITEM_INT, MISSION_ACK, MISSION_CURRENT) with
//!   telemetry the protocols do not speak (ATTITUDE, GLOBAL_POSITION_INT, SYS_STATUS,
//!   VFR_HUD after every protocol message), monitored together with `arm-command.chor` and
//!   `param-set.chor`; every pass must end the upload conformant with no violation (asserted);
//! - every capture of `../shared/data/mavlink_captures` with the same three protocols;
//! - every capture with every protocol under `choreographies/mavlink/` that `mochi check`
//!   verifies, at once.
//!
//! Each figure twice, side by side: with the protocols compiled as the monitor compiles them
//! and compiled for the tree evaluator (`Automaton::compile_tree`: every guard and refinement
//! a tree of operators). `--tree` makes every figure, and `--callgrind`, use the latter.
//!
//! With `--callgrind WHICH` (`synthetic` or a part of a capture's name) it makes one pass
//! over that stream with the three protocols (with `--all`: every protocol under
//! `choreographies/mavlink/`) and no timing, for an instruction count of the monitor's work
//! that does not move with the machine's load.

use mochi::dialect::Dialect;
use mochi::mavio::log::read_log;
use mochi::mavio::parse::Config;
use mochi::mavio::Frame;
use mochi::monitor::wire::{self, Layout, Scalar};
use mochi::monitor::{Automaton, Monitor, Outcome, Stats};
use mochi::source::SourceDb;
use std::path::{Path, PathBuf};
use std::time::Instant;

const ITEMS: i128 = 500;
const TARGET_NS: f64 = 100.0;

/// Whether to compile the protocols for the tree evaluator (`--tree`): every guard and
/// refinement a tree of operators, as before comparisons were compiled
/// (`Automaton::compile_tree`), for the side-by-side figures.
fn tree() -> bool {
    std::env::args().any(|a| a == "--tree")
}

fn compile(path: &str) -> Automaton {
    compile_as(path, tree())
}

fn compile_as(path: &str, tree: bool) -> Automaton {
    let mut db = SourceDb::new();
    let root = mochi::fsload::load_root(&mut db, Path::new(path)).expect("read the protocol");
    let mut load = |p: &Path| mochi::fsload::read_bytes(p);
    let prog = mochi::driver::prepare(&mut db, root, &mut load, mochi::driver::Stage::Names).expect("lowered");
    if tree {
        Automaton::compile_tree(&prog).expect("compiles")
    } else {
        Automaton::compile(&prog).expect("compiles")
    }
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

/// A log's frames, copied out of the file once (the reader is not timed here: the figure
/// is the monitor's work).
struct Owned2 {
    meta: Vec<(Option<u64>, u8, u8, u8, u32, bool)>,
    payloads: Vec<Vec<u8>>,
    raws: Vec<Vec<u8>>,
}

impl Owned2 {
    fn read(bytes: &[u8]) -> Owned2 {
        let mut o = Owned2 { meta: Vec::new(), payloads: Vec::new(), raws: Vec::new() };
        read_log(bytes, Config::default(), |f| {
            o.meta.push((f.time_us, f.version, f.sysid, f.compid, f.msgid, f.signed));
            o.payloads.push(f.payload.to_vec());
            o.raws.push(f.raw.to_vec());
        });
        o
    }

    fn frames(&self) -> Vec<Frame<'_>> {
        self.meta
            .iter()
            .zip(self.payloads.iter().zip(&self.raws))
            .map(|(&(time_us, version, sysid, compid, msgid, signed), (p, r))| Frame {
                time_us,
                version,
                sysid,
                compid,
                msgid,
                payload: p,
                signed,
                raw: r,
            })
            .collect()
    }
}

/// The best and the mean time per frame of `passes` runs of a fresh monitor of `protos`
/// over `frames`, and the last run's statistics.
fn time_passes(protos: &[Automaton], frames: &[Frame], passes: usize) -> (f64, f64, Stats) {
    let mut best = f64::INFINITY;
    let mut total = 0.0;
    let mut stats = Stats::default();
    for _ in 0..passes {
        let mut m = Monitor::new(protos.to_vec());
        let t = Instant::now();
        for f in frames {
            std::hint::black_box(m.on_frame(std::hint::black_box(f)));
        }
        let ns = t.elapsed().as_nanos() as f64 / frames.len().max(1) as f64;
        stats = m.stats;
        best = best.min(ns);
        total += ns;
    }
    (best, total / passes as f64, stats)
}

/// The protocols under `choreographies/mavlink/` that `mochi check` verifies (the monitor
/// enforces only those), compiled.
fn verified_protocols() -> Vec<(String, PathBuf)> {
    let dir = Path::new("choreographies/mavlink");
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "chor")).collect()
        })
        .unwrap_or_default();
    paths.sort();
    let mut out = Vec::new();
    for p in paths {
        let mut db = SourceDb::new();
        let verified = mochi::fsload::check_file(&mut db, &p, &mochi::driver::Config::default())
            .is_ok_and(|r| r.verdict == mochi::driver::Verdict::Verified);
        if verified {
            let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            out.push((name, p));
        }
    }
    out
}

fn captures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/mavlink_captures");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|d| {
            d.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e != "md")).collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// Under callgrind only the work of `Monitor::on_frame` is of interest
/// (`--toggle-collect='*Monitor*on_frame*'`): one pass over one stream with the three
/// protocols, no timing, no verification (Z3 under valgrind would take minutes). `which` is
/// `synthetic` or a part of a capture's file name.
fn callgrind(protos: &[Automaton], synthetic: &[Frame], which: &str) {
    if which == "synthetic" {
        let mut m = Monitor::new(protos.to_vec());
        for f in synthetic {
            std::hint::black_box(m.on_frame(std::hint::black_box(f)));
        }
        println!("callgrind: synthetic upload, {} frames, {} protocols", synthetic.len(), protos.len());
        return;
    }
    for path in captures().into_iter().filter(|p| p.to_string_lossy().contains(which)) {
        let Ok(bytes) = std::fs::read(&path) else { continue };
        let log = Owned2::read(&bytes);
        let frames = log.frames();
        let mut m = Monitor::new(protos.to_vec());
        for f in &frames {
            std::hint::black_box(m.on_frame(std::hint::black_box(f)));
        }
        println!("callgrind: {}, {} frames, {} protocols", path.display(), frames.len(), protos.len());
    }
}

/// The table of the real captures monitored with `protos`; the mean time per message over
/// all their frames.
fn real(title: &str, protos: &[Automaton], passes: usize) -> f64 {
    println!("monitor: real captures, {title}");
    println!(
        "  {:<52} {:>8} {:>7} {:>6} {:>6} {:>10} {:>10}",
        "capture", "frames", "passed", "steps", "viol.", "mean ns", "best ns"
    );
    let (mut frames_all, mut ns_all) = (0usize, 0.0f64);
    for path in captures() {
        let Ok(bytes) = std::fs::read(&path) else { continue };
        let log = Owned2::read(&bytes);
        let fs = log.frames();
        if fs.is_empty() {
            continue;
        }
        let (best, mean, st) = time_passes(protos, &fs, passes);
        frames_all += fs.len();
        ns_all += mean * fs.len() as f64;
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        println!(
            "  {:<52} {:>8} {:>7} {:>6} {:>6} {:>10.1} {:>10.1}",
            name,
            fs.len(),
            st.passed,
            st.steps,
            st.violations,
            mean,
            best
        );
    }
    let mean_all = ns_all / frames_all.max(1) as f64;
    println!(
        "  all {frames_all} frames: {mean_all:.1} ns/message mean (target {TARGET_NS} ns): {}",
        if mean_all < TARGET_NS { "met" } else { "NOT met" }
    );
    mean_all
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let passes = if quick { 20 } else { 200 };
    let three = [
        "choreographies/mavlink/mission-upload-tolerant.chor",
        "choreographies/mavlink/arm-command.chor",
        "choreographies/mavlink/param-set.chor",
    ];
    let protos: Vec<Automaton> = three.iter().map(|p| compile(p)).collect();
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
    let args: Vec<String> = std::env::args().collect();
    if let Some(k) = args.iter().position(|a| a == "--callgrind") {
        let which = args.get(k + 1).map_or("synthetic", |s| s.as_str());
        if args.iter().any(|a| a == "--all") {
            // Every protocol under choreographies/mavlink/, compiled without verification
            // (all of them verify: the timed run checks it).
            let mut paths: Vec<PathBuf> = std::fs::read_dir("choreographies/mavlink")
                .map(|d| {
                    d.filter_map(|e| e.ok())
                        .map(|e| e.path())
                        .filter(|p| p.extension().is_some_and(|e| e == "chor"))
                        .collect()
                })
                .unwrap_or_default();
            paths.sort();
            let all: Vec<Automaton> = paths.iter().map(|p| compile(&p.to_string_lossy())).collect();
            callgrind(&all, &frames, which);
        } else {
            callgrind(&protos, &frames, which);
        }
        return;
    }
    // Side by side in one run: each figure with the protocols compiled for the evaluator
    // of compiled comparisons (the monitor's) and for the tree evaluator (`--tree`'s).
    let tree_protos: Vec<Automaton> = three.iter().map(|p| compile_as(p, true)).collect();
    for (which, protos) in [("compiled", &protos), ("tree", &tree_protos)] {
        let (best, mean) = synthetic(protos, &frames, passes);
        let protocol = frames.len() / (1 + 4);
        println!(
            "monitor ({which} evaluator): synthetic upload, {} frames per pass ({} protocol messages, {} telemetry), 3 protocols, {passes} passes",
            frames.len(),
            protocol,
            frames.len() - protocol
        );
        println!(
            "monitor ({which} evaluator): {mean:.1} ns/message mean, {best:.1} ns/message best (target {TARGET_NS} ns): {}",
            if mean < TARGET_NS { "met" } else { "NOT met" }
        );
    }

    // The real captures: with the same three protocols, and with every verified protocol
    // at once (the heaviest configuration: each frame is looked up in the protocols that
    // speak its message, and the protocols that overlap, such as the two mission uploads,
    // find violations of each other's sessions, which are recorded).
    let real_passes = if quick { 3 } else { 20 };
    let verified = verified_protocols();
    let names: Vec<&str> = verified.iter().map(|(n, _)| n.as_str()).collect();
    for (which, tree) in [("compiled", false), ("tree", true)] {
        let three_protos: Vec<Automaton> = three.iter().map(|p| compile_as(p, tree)).collect();
        real(
            &format!("{which} evaluator, mission-upload-tolerant, arm-command, param-set"),
            &three_protos,
            real_passes,
        );
        let all: Vec<Automaton> = verified.iter().map(|(_, p)| compile_as(&p.to_string_lossy(), tree)).collect();
        real(
            &format!("{which} evaluator, {} verified protocols at once: {}", all.len(), names.join(", ")),
            &all,
            real_passes,
        );
    }
}

/// The best and the mean time per frame of `passes` runs over the synthetic upload, each
/// asserted to end the upload conformant.
fn synthetic(protos: &[Automaton], frames: &[Frame], passes: usize) -> (f64, f64) {
    let mut best = f64::INFINITY;
    let mut total = 0.0;
    for _ in 0..passes {
        let mut m = Monitor::new(protos.to_vec());
        let t = Instant::now();
        let mut ended = 0;
        for f in frames {
            if let Outcome::Ended { .. } = std::hint::black_box(m.on_frame(std::hint::black_box(f))) {
                ended += 1;
            }
        }
        let ns = t.elapsed().as_nanos() as f64 / frames.len() as f64;
        assert_eq!((ended, m.stats.violations), (1, 0), "the upload must end conformant");
        best = best.min(ns);
        total += ns;
    }
    (best, total / passes as f64)
}
