//! Offline throughput of the MAVLink readers (`checker/monitor/src/mavio/`) and of `mochi
//! monitor`'s work on a log, against pymavlink's `mavlogdump.py` on the same log, side by
//! side in one run (the offline target: 100 times pymavlink).
//!
//! ```text
//! cargo bench --bench mavio                  # every .tlog in ../shared/data/mavlink_captures
//! cargo bench --bench mavio -- --quick       # the largest one only
//! cargo bench --bench mavio -- FILE...       # other logs
//! ```
//!
//! Per log, four rows:
//!
//! - `mochi read`: the whole file read (frames found, checksums checked; the frames' fields
//!   touched so nothing is optimised away), best of 20 runs;
//! - `mochi read + monitor`: what `mochi monitor` does with a log once its protocols are
//!   compiled: read, every frame through `Monitor::on_frame` with `mission-upload-tolerant`,
//!   `arm-command` and `param-set` at once, `Monitor::finish`; best of 20 runs;
//! - `pymavlink mavlogdump -q`: `python3 -m pymavlink.tools.mavlogdump -q FILE` (every message
//!   parsed and decoded, nothing printed), one run, minus the interpreter's start with
//!   pymavlink imported (measured once, `python3 -c "import pymavlink.mavutil"`).
//!
//! The speed-ups divide pymavlink's time by each of mochi's: throughput, start-up excluded on
//! both sides. Then, end to end, the wall time of the `mochi monitor` executable on the log
//! with the same three protocols (best of 3; start-up, the verification of the three
//! protocols by Z3 in the process, compilation, the report written to a pipe) against
//! mavlogdump's whole run (start-up included). The verification takes about a second and
//! dominates the executable's time on these logs; its time on an empty log is printed
//! first. The benchmark measures and prints; it asserts nothing.

use mochi::mavio::log::read_log;
use mochi::mavio::parse::Config;
use mochi::monitor::{Automaton, Monitor};
use mochi::source::SourceDb;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

const PROTOCOLS: [&str; 3] = [
    "choreographies/mavlink/mission-upload-tolerant.chor",
    "choreographies/mavlink/arm-command.chor",
    "choreographies/mavlink/param-set.chor",
];

fn captures() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/mavlink_captures");
    let mut files: Vec<(u64, PathBuf)> = std::fs::read_dir(&dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| (e.metadata().map(|m| m.len()).unwrap_or(0), e.path()))
                .filter(|(_, p)| p.extension().is_some_and(|e| e == "tlog"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files.into_iter().rev().map(|f| f.1).collect()
}

fn compile(db: &mut SourceDb, path: &str) -> Automaton {
    let root = mochi::fsload::load_root(db, Path::new(path)).expect("read the protocol");
    let mut load = |p: &Path| mochi::fsload::read_bytes(p);
    let prog = mochi::driver::prepare(db, root, &mut load, mochi::driver::Stage::Names).expect("lowered");
    Automaton::compile(&prog).expect("compiles")
}

fn python_seconds(args: &[&str]) -> Option<f64> {
    let t = Instant::now();
    let out = Command::new("python3").args(args).output().ok()?;
    out.status.success().then(|| t.elapsed().as_secs_f64())
}

/// Wall time of `mochi monitor` with the three protocols on `log` (best of `runs`).
fn binary_seconds(log: &Path, runs: usize) -> Option<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..runs {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_mochi"));
        cmd.arg("monitor");
        for p in PROTOCOLS {
            cmd.args(["--protocol", p]);
        }
        let t = Instant::now();
        let out = cmd.arg(log).stdin(Stdio::null()).stderr(Stdio::null()).output().ok()?;
        // 0: no violation; 1: a violation in the log (a verdict, not a failure).
        if !matches!(out.status.code(), Some(0 | 1)) {
            return None;
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    Some(best)
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let named: Vec<PathBuf> = std::env::args().skip(1).filter(|a| !a.starts_with('-')).map(PathBuf::from).collect();
    let files = if !named.is_empty() {
        named
    } else if quick {
        captures().into_iter().take(1).collect()
    } else {
        captures()
    };
    let mut db = SourceDb::new();
    let protocols: Vec<Automaton> = PROTOCOLS.iter().map(|p| compile(&mut db, p)).collect();
    let start = python_seconds(&["-c", "import pymavlink.mavutil"]);
    let empty = std::env::temp_dir().join(format!("mochi-bench-empty-{}.tlog", std::process::id()));
    let empty_s = std::fs::write(&empty, b"").ok().and_then(|_| binary_seconds(&empty, 3));
    // Not subtracted: on an empty log the executable's time is its start-up and the
    // verification of the protocols.
    let _ = std::fs::remove_file(&empty);
    match (start, empty_s) {
        (Some(s), Some(e)) => println!(
            "start-up: python3 with pymavlink imported {s:.3} s (subtracted below); `mochi monitor` with 3 protocols on an empty log {e:.3} s"
        ),
        _ => println!("start-up: python3 with pymavlink {start:?} s, `mochi monitor` on an empty log {empty_s:?} s"),
    }
    let mut sink = 0u64;
    for file in files {
        let bytes = match std::fs::read(&file) {
            Ok(b) => b,
            Err(e) => {
                println!("mavio bench: cannot read {}: {e}", file.display());
                continue;
            }
        };
        let mb = bytes.len() as f64 / 1e6;
        let runs = 20;
        let mut read_best = f64::INFINITY;
        let mut frames = 0u64;
        for _ in 0..runs {
            let t = Instant::now();
            let s = read_log(&bytes, Config::default(), |f| {
                sink = sink.wrapping_add(u64::from(f.sysid) ^ u64::from(f.msgid) ^ f.payload.len() as u64);
            });
            read_best = read_best.min(t.elapsed().as_secs_f64());
            frames = s.counts.frames;
        }
        let mut mon_best = f64::INFINITY;
        let mut violations = 0;
        for _ in 0..runs {
            let t = Instant::now();
            let mut m = Monitor::new(protocols.clone());
            read_log(&bytes, Config::default(), |f| {
                std::hint::black_box(m.on_frame(&f));
            });
            let sessions = m.finish().len();
            mon_best = mon_best.min(t.elapsed().as_secs_f64());
            violations = m.stats.violations;
            sink = sink.wrapping_add(sessions as u64);
        }
        let bin = binary_seconds(&file, 3);
        println!();
        println!("log: {} ({:.2} MB, {frames} frames; {violations} violations of the 3 protocols)", file.display(), mb);
        println!("  {:<36} {:>10} {:>10} {:>12} {:>10}", "reader", "seconds", "MB/s", "frames/s", "speed-up");
        let file_s = file.to_string_lossy().to_string();
        let py_whole = python_seconds(&["-m", "pymavlink.tools.mavlogdump", "-q", &file_s]);
        let py = match (py_whole, start) {
            (Some(t), Some(s0)) => Some((t - s0).max(1e-9)),
            _ => None,
        };
        let row = |name: &str, t: f64| {
            let up = py.map_or("-".to_string(), |p| format!("{:.0}x", p / t));
            println!("  {name:<36} {t:>10.4} {:>10.1} {:>12.0} {up:>10}", mb / t, frames as f64 / t);
        };
        row("mochi read (best of 20)", read_best);
        row("mochi read + monitor (best of 20)", mon_best);
        match py {
            Some(t) => row("pymavlink mavlogdump -q (- start)", t),
            None => println!(
                "  pymavlink not available: `python3 -m pip install --user pymavlink==2.4.50` to compare (sink {})",
                sink % 10
            ),
        }
        match (bin, py_whole) {
            (Some(b), Some(p)) => println!(
                "  end to end: `mochi monitor` {b:.3} s (verification included), mavlogdump {p:.3} s: {:.1}x",
                p / b
            ),
            _ => println!("  end to end: `mochi monitor` {bin:?} s, mavlogdump {py_whole:?} s"),
        }
    }
    println!("(target: mochi monitor 100x pymavlink's mavlogdump.py; sink {})", sink % 10);
}
