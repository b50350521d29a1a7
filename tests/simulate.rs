//! The independent check: every choreography mochi verifies is simulated on concrete
//! trajectories (`mochi::simulate`), and the simulation must never find a collision, a
//! stuck state, a violated guard or refinement, or a model that does not replay. And
//! the simulator must be able to fail: it finds the collisions of rejected examples.

use mochi::driver::{Config, Verdict};
use mochi::fsload::{check_file, check_source};
use mochi::fsload::{read_bytes, simulate_file};
use mochi::simulate::{simulate_loaded, Kind, SimConfig, SimReport};
use mochi::source::SourceDb;
use std::path::Path;

// The parallel-lanes generator, shared with the example and the benchmark.
#[path = "../examples/common/lanes.rs"]
#[allow(dead_code)]
mod lanes;

fn cfg(runs: usize, steps: usize, seed: u64) -> SimConfig {
    SimConfig { runs, steps, seed, ..SimConfig::default() }
}

fn simulate_path(path: &str, c: &SimConfig) -> SimReport {
    let mut db = SourceDb::new();
    match simulate_file(&mut db, Path::new(path), c) {
        Ok(Ok(r)) => r,
        Ok(Err(d)) => panic!("{path} does not resolve: {d:?}"),
        Err(e) => panic!("cannot read {path}: {e}"),
    }
}

fn verdict(path: &str) -> Verdict {
    let mut db = SourceDb::new();
    check_file(&mut db, Path::new(path), &Config::default()).expect("readable").verdict
}

/// No collision, stuck state, violation or replay failure; and at least some steps ran
/// (a simulation that stops at once would pass vacuously).
fn assert_clean(what: &str, r: &SimReport) {
    let bad: Vec<String> = r
        .failures()
        .map(|f| format!("{:?} at step {}: {}\n  {}", f.kind, f.step, f.message, f.trace.join("\n  ")))
        .collect();
    assert!(bad.is_empty(), "{what}: the simulation of a verified choreography found:\n{}", bad.join("\n"));
    let undecided: Vec<&str> = r.findings.iter().map(|f| f.message.as_str()).collect();
    assert!(undecided.is_empty(), "{what}: runs stopped undecided: {undecided:?}");
    assert!(r.steps >= r.runs * 4, "{what}: too few steps simulated ({} in {} runs)", r.steps, r.runs);
}

/// A verified example (by the checker's verdict now) simulates without findings.
fn verified_example_is_clean(path: &str, seed: u64) {
    if verdict(path) != Verdict::Verified {
        // Not verified (any more): nothing to cross-check; the golden tests say why.
        return;
    }
    assert_clean(path, &simulate_path(path, &cfg(2, 12, seed)));
}

#[test]
fn cart_and_arms_never_collides_or_gets_stuck() {
    verified_example_is_clean("choreographies/cart-and-arms.chor", 1);
}

#[test]
fn sorting_never_collides_or_gets_stuck() {
    verified_example_is_clean("choreographies/sorting.chor", 2);
}

#[test]
fn example_4_2_4_never_collides_or_gets_stuck() {
    verified_example_is_clean("choreographies/example-4-2-4.chor", 3);
}

#[test]
fn pgcd_fetch_never_collides_or_gets_stuck() {
    verified_example_is_clean("choreographies/pgcd/fetch.chor", 4);
}

#[test]
fn pgcd_handover_never_collides_or_gets_stuck() {
    verified_example_is_clean("choreographies/pgcd/handover.chor", 5);
}

fn lanes(n: usize, spacing: &str) -> String {
    let src = lanes::parallel_lanes(n);
    let from = format!("const lane_dy: real = {:?};", lanes::LANE_SPACING);
    assert!(src.contains(&from), "the generator's spacing line changed");
    src.replace(&from, &format!("const lane_dy: real = {spacing};"))
}

fn check_and_simulate(src: &str, c: &SimConfig) -> (Verdict, SimReport) {
    let mut db = SourceDb::new();
    let v = check_source(&mut db, "lanes.chor", src, &Config::default()).verdict;
    let mut db = SourceDb::new();
    let root = db.add("lanes.chor", src);
    let r = simulate_loaded(&mut db, root, c, &mut read_bytes).unwrap_or_else(|d| panic!("does not resolve: {d:?}"));
    (v, r)
}

/// Generated choreographies: parallel lanes with a random number of carts and a random
/// lane spacing. Whatever mochi verifies must simulate cleanly; where the lanes are too
/// close for the carts (0.61 m wide with their tracking error), mochi must reject and the
/// simulator must find the collision.
#[test]
fn generated_lanes_agree_with_the_verdict() {
    let mut state = 0x5EED_u64;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 33) as usize
    };
    let mut verified = 0;
    for case in 0..4 {
        let n = 2 + next() % 2;
        let spacing = ["0.5", "0.65", "0.9", "0.4"][case];
        let (v, r) = check_and_simulate(&lanes(n, spacing), &cfg(1, 6 * n, next() as u64));
        let what = format!("{n} lanes {spacing} m apart");
        match v {
            Verdict::Verified => {
                verified += 1;
                assert_clean(&what, &r);
            }
            Verdict::Rejected => {
                assert!(
                    r.findings.iter().any(|f| f.kind == Kind::Collision),
                    "{what}: rejected, but no collision found: {r:?}"
                );
            }
            Verdict::Unknown => {}
        }
    }
    assert!(verified >= 2, "the generator's spacings 0.65 and 0.9 must verify");
}

/// Generated from the library primitives: the cart-and-arms layout with the arms at a
/// random distance along and beside the lane. Verified layouts simulate cleanly; layouts
/// rejected for overlapping footprints (E0404, E0406) show a collision or get stuck first.
#[test]
fn generated_cart_and_arm_layouts_agree_with_the_verdict() {
    let base = std::fs::read_to_string("choreographies/cart-and-arms.chor").expect("the example");
    let (gx, off) = ("const g_x: real = 1.6;", "const arm_track_offset: real = 0.45;");
    assert!(base.contains(gx) && base.contains(off), "the example's layout lines changed");
    let mut seen = (0, 0);
    for (case, (x, y)) in [("2.0", "0.6"), ("1.0", "0.2")].into_iter().enumerate() {
        let src = base
            .replace(gx, &format!("const g_x: real = {x};"))
            .replace(off, &format!("const arm_track_offset: real = {y};"));
        let mut db = SourceDb::new();
        let report = check_source(&mut db, "choreographies/generated.chor", &src, &Config::default());
        let mut db = SourceDb::new();
        let root = db.add("choreographies/generated.chor", src);
        let r = simulate_loaded(&mut db, root, &cfg(1, 12, case as u64), &mut read_bytes).expect("resolves");
        let what = format!("arms at x = {x}, {y} m beside the lane");
        let overlap = report.diagnostics.iter().any(|d| matches!(d.code.as_str(), "E0404" | "E0406"));
        match report.verdict {
            Verdict::Verified => {
                seen.0 += 1;
                assert_clean(&what, &r);
            }
            Verdict::Rejected if overlap => {
                seen.1 += 1;
                // A collision, or a stuck state before it (no safe payload exists).
                assert!(r.failures().next().is_some(), "{what}: nothing found: {r:?}");
            }
            _ => {}
        }
    }
    assert!(seen.0 >= 1 && seen.1 >= 1, "the layouts must cover both verdicts: {seen:?}");
}

/// The simulator can fail: rejected examples whose collision is real.
#[test]
fn the_simulator_finds_the_collisions_of_rejected_examples() {
    for path in
        ["choreographies/rejected/E0406-two-carts-one-lane.chor", "choreographies/rejected/E0404-target-too-close.chor"]
    {
        assert_eq!(verdict(path), Verdict::Rejected, "{path}");
        let r = simulate_path(path, &cfg(2, 10, 7));
        let c = r.findings.iter().find(|f| f.kind == Kind::Collision);
        let c = c.unwrap_or_else(|| panic!("{path}: no collision found: {r:?}"));
        // In the user's terms: a time, the participants' states and a point.
        assert!(c.message.contains("share the point ("), "{}", c.message);
        assert!(!c.trace.is_empty());
    }
}

/// The simulator finds what the other rejected [AGCOMP] examples get wrong: an
/// environment allowed to break the cart's assumption (E0403), a non-interruptible pick
/// outlasting the brake the cart waits on (E0405), a motion that cannot end (E0408).
#[test]
fn the_simulator_finds_broken_assumptions_durations_and_endless_motions() {
    for (path, kind, text) in [
        ("choreographies/rejected/E0403-gusty-environment.chor", Kind::Violation, "break the assumption"),
        ("choreographies/rejected/E0405-brake-releases-during-pick.chor", Kind::Stuck, "outside the duration"),
        ("choreographies/rejected/E0408-beyond-the-lane.chor", Kind::Stuck, "no trajectory"),
    ] {
        assert_eq!(verdict(path), Verdict::Rejected, "{path}");
        let r = simulate_path(path, &cfg(4, 24, 9));
        assert!(
            r.findings.iter().any(|f| f.kind == kind && f.message.contains(text)),
            "{path}: expected a {kind:?} finding about `{text}`: {:?}",
            r.findings
        );
    }
}

/// Runs are reproducible from the seed.
#[test]
fn a_seed_fixes_the_run() {
    let a = simulate_path("choreographies/pgcd/fetch.chor", &cfg(1, 8, 42));
    let b = simulate_path("choreographies/pgcd/fetch.chor", &cfg(1, 8, 42));
    assert_eq!(format!("{:?}", a.findings), format!("{:?}", b.findings));
    assert_eq!(a.steps, b.steps);
}

/// Every counterexample mochi shows replays in exact arithmetic: none of the rejected
/// corpus's SMT-decided failures is turned into "did not replay".
#[test]
fn counterexamples_of_the_corpus_replay() {
    let mut n = 0;
    for entry in std::fs::read_dir("choreographies/rejected").expect("the corpus") {
        let path = entry.expect("entry").path();
        let name = path.file_name().and_then(|s| s.to_str()).unwrap_or_default().to_string();
        if !(name.starts_with("E04") || name.starts_with("E070") || name.starts_with("E0316")) {
            continue;
        }
        let mut db = SourceDb::new();
        let report = check_file(&mut db, &path, &Config::default()).expect("readable");
        for d in &report.diagnostics {
            let text = format!("{d:?}");
            assert!(!text.contains("did not replay"), "{name}: {text}");
        }
        n += 1;
    }
    assert!(n >= 5, "the corpus has SMT-decided examples");
}

/// `mochi simulate`: exit 0 when nothing is found, 1 on a collision, with the trace.
#[test]
fn the_command_line_reports_findings_and_exit_codes() {
    let run = |path: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_mochi"))
            .args(["simulate", path, "--runs", "1", "--steps", "8", "--seed", "3"])
            .output()
            .expect("mochi runs")
    };
    let ok = run("choreographies/pgcd/fetch.chor");
    assert_eq!(ok.status.code(), Some(0), "{}", String::from_utf8_lossy(&ok.stdout));
    assert!(String::from_utf8_lossy(&ok.stdout).contains("no collision, no stuck state"));
    let bad = run("choreographies/rejected/E0406-two-carts-one-lane.chor");
    let out = String::from_utf8_lossy(&bad.stdout);
    assert_eq!(bad.status.code(), Some(1), "{out}");
    assert!(out.contains("collision in run 0") && out.contains("t = 0: start"), "{out}");
}
