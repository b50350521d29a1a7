//! Offline throughput of the MAVLink readers (`checker/mavio/`) against pymavlink's
//! `mavlogdump.py` on the same log, side by side in one run (the offline target: 100
//! times pymavlink).
//!
//! ```text
//! cargo bench --bench mavio                  # the largest capture in ../shared/data/mavlink_captures
//! cargo bench --bench mavio -- FILE          # another log
//! ```
//!
//! Ours: the whole file read `runs` times (frames found, checksums checked; the frames' fields
//! touched so nothing is optimised away), the best run reported. pymavlink: `python3 -m
//! pymavlink.tools.mavlogdump -q FILE` (parse every message, print nothing), wall time of one
//! run including the interpreter's start, and separately the start alone, subtracted. The
//! benchmark measures and prints; it asserts nothing.

use mochi::mavio::log::read_log;
use mochi::mavio::parse::Config;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

fn largest_capture() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/mavlink_captures");
    let mut files: Vec<(u64, PathBuf)> = std::fs::read_dir(&dir)
        .map(|d| d.filter_map(|e| e.ok()).map(|e| (e.metadata().map(|m| m.len()).unwrap_or(0), e.path())).collect())
        .unwrap_or_default();
    files.sort();
    files.pop().map(|f| f.1).unwrap_or(dir)
}

fn python_seconds(args: &[&str]) -> Option<f64> {
    let t = Instant::now();
    let out = Command::new("python3").args(args).output().ok()?;
    out.status.success().then(|| t.elapsed().as_secs_f64())
}

fn main() {
    let file =
        std::env::args().skip(1).find(|a| !a.starts_with('-')).map(PathBuf::from).unwrap_or_else(largest_capture);
    let bytes = match std::fs::read(&file) {
        Ok(b) => b,
        Err(e) => {
            println!("mavio bench: cannot read {}: {e}", file.display());
            return;
        }
    };
    let mb = bytes.len() as f64 / 1e6;
    let runs = 20;
    let mut best = f64::INFINITY;
    let mut frames = 0u64;
    let mut sink = 0u64;
    for _ in 0..runs {
        let t = Instant::now();
        let s = read_log(&bytes, Config::default(), |f| {
            sink = sink.wrapping_add(u64::from(f.sysid) ^ u64::from(f.msgid) ^ f.payload.len() as u64);
        });
        best = best.min(t.elapsed().as_secs_f64());
        frames = s.counts.frames;
    }
    println!("log: {} ({:.2} MB, {frames} frames)", file.display(), mb);
    println!("{:<28} {:>10} {:>12} {:>14}", "reader", "seconds", "MB/s", "frames/s");
    println!("{:<28} {:>10.4} {:>12.1} {:>14.0}", "mochi (best of 20)", best, mb / best, frames as f64 / best);
    let file_s = file.to_string_lossy().to_string();
    let start = python_seconds(&["-c", "import pymavlink.mavutil"]);
    match (python_seconds(&["-m", "pymavlink.tools.mavlogdump", "-q", &file_s]), start) {
        (Some(t), Some(s0)) => {
            let t = (t - s0).max(1e-9);
            println!("{:<28} {:>10.4} {:>12.3} {:>14.0}", "pymavlink mavlogdump -q", t, mb / t, frames as f64 / t);
            println!(
                "speed-up: {:.0}x (target 100x); python start-up {s0:.2} s not counted; sink {}",
                t / best,
                sink % 10
            );
        }
        _ => println!(
            "pymavlink not available: `python3 -m pip install --user pymavlink==2.4.50` to compare (sink {})",
            sink % 10
        ),
    }
}
