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

/// The `.chor` files under `dir`, recursively, leaving out `rejected/` folders when
/// `rejected` is false and keeping only them when it is true.
fn chor_files(dir: &Path, rejected: bool, out: &mut Vec<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).expect("a folder").map(|e| e.expect("entry").path()).collect();
    entries.sort();
    for p in entries {
        let in_rejected = p.components().any(|c| c.as_os_str() == "rejected");
        if p.is_dir() {
            if rejected || p.file_name().is_some_and(|n| n != "rejected") {
                chor_files(&p, rejected, out);
            }
        } else if p.extension().is_some_and(|e| e == "chor") && in_rejected == rejected {
            out.push(p.display().to_string());
        }
    }
}

/// The verdict the golden snapshot of `path` records. The corpus harness (tests/corpus.rs)
/// checks every file of `choreographies/` once, with the golden suite's patience (60 s a
/// query), and fails unless its report, verdict first, is the snapshot's: so the snapshot's
/// verdict is the file's, and this test reads it rather than checking each file again.
fn golden_verdict(path: &str) -> Verdict {
    let below = Path::new(path).strip_prefix("choreographies").expect("a file of the corpus");
    let below = below.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("__");
    let snap = format!("tests/snapshots/golden__every_choreography_matches_its_golden_file@{below}.snap");
    let text = std::fs::read_to_string(&snap)
        .unwrap_or_else(|e| panic!("{path}: no golden snapshot {snap} ({e}); run `cargo test --test corpus`"));
    let v = text.split("==== VERDICT ====\n").nth(1).and_then(|r| r.lines().next());
    match v.map(str::trim) {
        Some("Verified") => Verdict::Verified,
        Some("Rejected") => Verdict::Rejected,
        Some("Unknown") => Verdict::Unknown,
        other => panic!("{snap}: no verdict line ({other:?})"),
    }
}

/// `files` ordered largest first (by size in bytes, then as they were): a file's size stands
/// for the cost of its simulation (sorting-case-study, the largest, was the slowest), and
/// the slowest started last keeps one thread busy alone at the end of [`par_map`].
fn largest_first<T>(files: &mut [T], path: impl Fn(&T) -> &str) {
    files.sort_by_cached_key(|f| std::cmp::Reverse(std::fs::metadata(path(f)).map_or(0, |m| m.len())));
}

/// Runs `f` on every item on two threads (the simulations are independent), results in the
/// items' order.
fn par_map<T: Sync, R: Send>(items: &[T], f: impl Fn(usize, &T) -> R + Sync) -> Vec<R> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let out: Vec<std::sync::Mutex<Option<R>>> = items.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                let r = f(i, item);
                *out[i].lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
            });
        }
    });
    out.into_iter().map(|m| m.into_inner().unwrap_or_else(|e| e.into_inner()).expect("every item ran")).collect()
}

/// The examples the simulator must run clean, whatever else changes: the flagship case
/// study (URDF robots, meshes), the mounted arm (a URDF arm on a turning base, `pi / 2`
/// arguments) and every MAVLink protocol.
const MUST_VERIFY: &[&str] = &[
    "choreographies/sorting-case-study.chor",
    "choreographies/mounted-arm.chor",
    "choreographies/bridge.chor",
    "choreographies/turn-together.chor",
    "choreographies/diagonal.chor",
    "choreographies/mavlink/arm-command.chor",
    "choreographies/mavlink/mission-download.chor",
    "choreographies/mavlink/mission-upload.chor",
    "choreographies/mavlink/mission-upload-tolerant.chor",
    "choreographies/mavlink/parachute.chor",
    "choreographies/mavlink/param-set.chor",
];

/// Verified files whose simulation may stop at a witness that does not replay exactly (a
/// `Replay` finding, never a collision or a stuck state), with the reason. Only that kind of
/// finding is let through for them.
const REPLAY_UNDECIDED: &[(&str, &str)] = &[(
    "choreographies/diagonal.chor",
    "the carts turn by pi / 4 and 3 * pi / 4: Z3's witness of the motion has cos/sin values inside the encoder's enclosure (a few ulps of f64 wide), outside the 1e-40-wide enclosure the exact replay uses since counterexamples are replayed against their goals; the simulator cannot draw an exact witness there (the check's verdict does not rest on witnesses)",
)];

/// Every file under `choreographies/` (not `rejected/`) that `mochi check` verifies
/// simulates with no finding and no undecided run. The verdict is the golden snapshot's
/// ([`golden_verdict`]); the files are simulated two at a time.
fn verified_files_are_clean(filter: &dyn Fn(&str) -> bool) {
    let mut files = Vec::new();
    chor_files(Path::new("choreographies"), false, &mut files);
    // Each file's seed is 100 plus its index among the files of the filter.
    let files: Vec<(usize, String)> = files.into_iter().filter(|p| filter(p)).enumerate().collect();
    let verified: Vec<(usize, String)> = files
        .into_iter()
        .filter(|(_, path)| {
            let v = golden_verdict(path);
            if MUST_VERIFY.contains(&path.as_str()) {
                assert_eq!(v, Verdict::Verified, "{path} is one the simulator must run, and it is verified");
            }
            v == Verdict::Verified
        })
        .collect();
    assert!(!verified.is_empty(), "no verified file was simulated");
    let mut verified = verified;
    largest_first(&mut verified, |(_, p)| p);
    let bad: Vec<String> = par_map(&verified, |_, (k, path)| {
        let started = std::time::Instant::now();
        let r = simulate_path(path, &cfg(2, 12, 100 + *k as u64));
        eprintln!("  {:>8.2} s  {path}", started.elapsed().as_secs_f64());
        // A timeout branch is refused as undecided (not simulated yet), never a clean run.
        let with_timeouts = [
            "choreographies/mavlink/compass-calibration.chor",
            "choreographies/mavlink/parachute.chor",
            "choreographies/mavlink/param-list.chor",
        ];
        if with_timeouts.contains(&path.as_str()) {
            if r.failures().next().is_none()
                && r.undecided().count() == 1
                && r.undecided().all(|f| f.message.starts_with("not supported yet"))
            {
                return Vec::new();
            }
            return vec![format!(
                "{path}: a program with a timeout branch is reported not supported: {:?}",
                r.findings
            )];
        }
        let mut bad: Vec<String> = r
            .findings
            .iter()
            .filter(|f| {
                !(REPLAY_UNDECIDED.iter().any(|(p, _)| path.ends_with(p)) && f.kind == mochi::simulate::Kind::Replay)
            })
            .map(|f| format!("{path}: {:?} at step {}: {}\n  {}", f.kind, f.step, f.message, f.trace.join("\n  ")))
            .collect();
        // Every run made a step (a run that stops at once would pass vacuously).
        if r.steps < r.runs {
            bad.push(format!("{path}: too few steps simulated ({} in {} runs)", r.steps, r.runs));
        }
        bad
    })
    .into_iter()
    .flatten()
    .collect();
    assert!(bad.is_empty(), "the simulation of verified files found:\n{}", bad.join("\n"));
}

#[test]
fn every_verified_motion_choreography_simulates_clean() {
    verified_files_are_clean(&|p| !p.contains("/mavlink/"));
}

#[test]
fn every_verified_mavlink_protocol_simulates_clean() {
    verified_files_are_clean(&|p| p.contains("/mavlink/"));
}

/// Rejected files the simulator runs (a program exists) but does not find, each with why
/// (checked with 2 runs of 16 steps, seed 1, as the test runs the others). Files rejected
/// before a program exists (syntax, names, sorts, dialects, geometry files) are not listed:
/// there is nothing to run.
const NOT_FOUND: &[(&str, &str)] = &[
    ("mavlink/rejected/E0316-fence-bad-item-before-the-last.chor", "stuck only after a bad fence item that is not the last (a polygon vertex count below 3, a circle radius not above 0, a second return point); the runs' payloads, Z3 models nudged a little, did not draw one"),
    ("mavlink/rejected/E0316-rally-count-beyond-storage.chor", "stuck only for a count beyond the vehicle's storage (the counterexample is count = RALLY_LIMIT + 1); the runs' payloads did not draw one"),
    ("mavlink/rejected/E0415-compass-progress-past-100.chor", "the invariant breaks only for a reported percentage above 100 (the counterexample is c = 101); the runs' payloads did not draw one"),
    ("rejected/geometry/E0510-turning-cart-corner-hits-the-post.chor", "the footprint's corner passes through the post only at headings near 1.38 rad (about 9.2 s into the 10 s turn); the two runs' samples of the turn did not land there (seed 0 finds it in runs 8 and 9 of 10)"),
    ("rejected/E0317-loader-still-restacking.chor", "a run starts a joint motion for all its participants at one time (the global type's step), so the early release E0317 finds does not happen in it"),
    ("rejected/E0317-stacker-outlasts-the-press.chor", "a run starts a joint motion for all its participants at one time (the global type's step), so the early release E0317 finds does not happen in it"),
    ("rejected/E0318-tray-turns-by-timing-alone.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0408-joint-faster-than-its-urdf-velocity.chor", "the URDF's velocity limits are not part of the simulator's trajectories (it draws them from the contracts), so the swing it draws ends in time; the limit is only in mochi's can-end question"),
    ("mavlink/rejected/E0316-command-range-skips-conditions.chor", "no branch covers the entries between the ranges; a run shows it only when it draws such a command (the counterexample is cmd = 159), which the runs' payloads did not"),
    ("mavlink/rejected/E0419-clock-past-the-wire-range.chor", "the payload is stuck only when the received clock is at the top of the uint64 range (the counterexample is last = 2^64 - 1 before the step), far beyond the values the runs draw"),
    ("mavlink/rejected/E0419-set-current-number-not-an-item.chor", "stuck only for a received number that is no whole item index (the counterexample is s = 1.75); the runs did not draw one"),
    ("mavlink/rejected/E0316-ack-branch-never-taken.chor", "a branch no state can take: a run shows what happens, never that a branch is dead"),
    ("mavlink/rejected/E0415-in-progress-for-ever.chor", "the loop breaks its invariant only after MAX_IN_PROGRESS answers IN_PROGRESS in a row, a path the random choices do not take in 2 runs of 16 steps"),
    ("mavlink/rejected/E0417-counter-never-incremented.chor", "a termination measure: a defect of infinitely many steps, beyond a bounded run"),
    ("mavlink/rejected/E0417-download-re-request-for-free.chor", "a termination measure: a defect of infinitely many steps, beyond a bounded run"),
    ("mavlink/rejected/E0417-retries-never-spent.chor", "a termination measure: a defect of infinitely many steps, beyond a bounded run"),
    ("mavlink/rejected/E0417-tolerant-duplicate-spends-no-retry.chor", "a termination measure: a defect of infinitely many steps, beyond a bounded run"),
    ("mavlink/rejected/E0419-param-pass-index-out-of-range.chor", "stuck only at the 14th choice's second answer, 27 messages in, beyond the 16 steps of a run"),
    ("mavlink/rejected/E0419-float-window-holds-no-float32.chor", "a refinement with real solutions and no float32 one: the simulator draws real payloads and rounds them, so it reports the run undecided, not stuck"),
    ("mavlink/rejected/E0602-declared-ground-station-never-gives-up.chor", "a written local type that is no subtype of the projection (Fig 5): the run follows the choreography, never the written type; the program has a timeout branch, which the simulator does not run yet"),
    ("mavlink/rejected/E0410-only-the-timeout-can-be-taken.chor", "a choice with a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0326-late-answer-read-as-the-next-answer.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run; the crossing needs messages in flight, which a run of the global type does not have"),
    ("mavlink/rejected/E0326-param-value-crosses-the-timeout.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run; the crossing needs messages in flight, which a run of the global type does not have"),
    ("mavlink/rejected/E0326-vehicle-ended-before-the-re-request.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run; the crossing needs messages in flight, which a run of the global type does not have"),
    ("mavlink/rejected/E0326-reboot-restarts-the-round-count.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run; the crossing needs messages in flight, which a run of the global type does not have"),
    ("mavlink/rejected/E0410-only-a-real-answer-before-the-timeout.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0410-stream-invariant-holds-no-float32.chor", "the stream's invariant admits no float32; the simulator draws real readings and rounds them to the wire's float, which it reports undecided, never a clean run"),
    ("mavlink/rejected/E0320-timeout-bound-zero.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0321-timeout-after-a-step.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0322-two-timeouts-in-one-choice.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0323-the-sender-times-out.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0324-vehicle-not-told-of-the-timeout.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0324-vehicle-times-out-before-it-is-told.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run; the early timeout needs clocks that disagree, which a run of the global type does not have"),
    ("mavlink/rejected/E0325-process-typed-against-a-timeout.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("mavlink/rejected/E0417-re-request-timeout-spends-no-retry.chor", "a choice has a timeout branch, which the simulator does not run yet: it reports the program undecided (\"not supported yet\"), never a clean run"),
    ("rejected/E0301-self-message.chor", "a message to oneself runs like any other: the rule is about the type's form (Def 4.1), not an event of a run"),
    ("rejected/E0302-command-with-and-without-its-command.chor", "two branches with one label are ambiguous to the receiver's projection, which a motion choreography's run (the global type) does not consult"),
    ("rejected/E0302-duplicate-label.chor", "two branches with one label are ambiguous to the receiver's projection, which a motion choreography's run (the global type) does not consult"),
    ("mavlink/rejected/E0236-status-text-echoed-as-a-param-id.chor", "the simulator draws a string as a code without a length, as the checks read it: the width of a char[N] field is a front-end rule (E0236), which no run of codes can break"),
    ("mavlink/rejected/E0236-process-echoes-a-status-text-as-a-param-id.chor", "the simulator draws a string as a code without a length, as the checks read it: the width of a char[N] field is a front-end rule (E0236), which no run of codes can break"),
    ("mavlink/rejected/E0236-process-sends-a-status-text-as-a-param-id.chor", "the simulator draws a string as a code without a length, as the checks read it: the width of a char[N] field is a typing rule (E0236), which no run of codes can break"),
    ("mavlink/rejected/E0236-loop-carries-a-status-text-into-a-param-id.chor", "the simulator draws a string as a code without a length, as the checks read it: the width of a char[N] field is a front-end rule (E0236), which no run of codes can break"),
    ("mavlink/rejected/E0302-same-key-written-twice.chor", "two branches with one label (the second key ends at its NUL: the same name on the wire) are ambiguous to the receiver's projection, which a run of the global type does not consult"),
    ("rejected/E0303-branch-starts-with-motion.chor", "a choice not decided by one message runs as a random pick: the defect is a participant not told, which needs projections"),
    ("rejected/E0303-fig2-literal-choice.chor", "a choice not decided by one message runs as a random pick: the defect is a participant not told, which needs projections"),
    ("rejected/E0308-recursion-into-separation.chor", "a scope rule about the type's text (Def 4.4): the run unrolls the loop into the `*` without an event to show"),
    ("rejected/E0309-motion-misses-participant.chor", "a participant left without a primitive (Def 4.4 (3)) is not placed: no collision or stuck state follows at the sampled times"),
    ("rejected/E0310-two-minimal-messages.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0311-joint-end-sent-by-interruptible.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0311-merge-before-stroke-ends.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0311-sender-still-moving.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0312-interruptible-lone-chain.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0312-motion-after-motion.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0313-participant-unused.chor", "a participant that takes no part runs nothing: nothing happens to show"),
    ("rejected/E0314-after-end.chor", "what follows `end` is never reached"),
    ("rejected/E0315-input-across-separation.chor", "a coupling through inputs across `*`: each side's witness fixes the other side's inputs, so the coupling shows as no collision or stuck state"),
    ("rejected/E0316-guards-miss-a-gap.chor", "stuck only in the gap between the guards, a state Z3's models do not pick in 2 runs"),
    ("rejected/E0317-released-from-different-sides.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0317-relay-third-still-moving.chor", "a run starts a joint motion for all its participants at one time (the global type's step), so the early release E0317 finds does not happen in it"),
    ("rejected/E0317-twist-and-turn-arm-still-gripping.chor", "a run starts a joint motion for all its participants at one time (the global type's step), so the early release E0317 finds does not happen in it"),
    ("rejected/E0318-second-star-starts-early.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0319-interrupted-after-its-duration.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0319-never-interrupted-before-end.chor", "a rule of synchronisation (Def 4.10): it is about an order in which participants disagree on what happens, and a run of the global type shows every participant every step"),
    ("rejected/E0401-joint-end-not-a-singleton.chor", "the durations disagree only when q's s > 0 and the witness ends p's exact 1 s at the same time as q's brake, which the witness may choose"),
    ("rejected/E0406-pose-offset-sum-rounds-to-zero.chor", "an overlap 1e-400 m deep near the end of the motion: the sampled times and the doubles of placement do not reach it"),
    ("rejected/E0406-tiny-pose-offset.chor", "an overlap 1e-400 m deep near the end of the motion: the sampled times and the doubles of placement do not reach it"),
    ("rejected/E0410-inits-contradict-through-input.chor", "initial states are drawn one participant at a time, so a contradiction only through an input connection is not joined (a gap of the simulator)"),
    ("rejected/E0415-countdown-below-zero.chor", "the jump from n = 0 needs the run to count down to 0 and then choose `more`, a path the random choices do not take in 2 runs of 16 steps"),
    ("rejected/E0416-measure-below-zero.chor", "a termination measure: a defect of infinitely many steps, beyond a bounded run"),
    ("rejected/E0417-counter-never-incremented.chor", "a termination measure: a defect of infinitely many steps, beyond a bounded run"),
    ("rejected/E0419-no-payload-fits.chor", "stuck only after a count c >= 2, a payload Z3's models do not pick in 2 runs"),
    ("rejected/E0601-different-motions.chor", "merging projections: a motion choreography runs as the global type, not as projections"),
    ("rejected/E0601-merged-command-with-and-without-its-command.chor", "the projections cannot be merged (the defect itself): the run stops undecided and says so"),
    ("rejected/E0601-same-text-different-values.chor", "merging projections: a motion choreography runs as the global type, not as projections"),
    ("rejected/E0601-told-by-different-senders.chor", "merging projections: a motion choreography runs as the global type, not as projections"),
    ("rejected/E0318-parked-cart-run-over.chor", "a participant standing still after its primitive ended is not placed by the simulator (it has no footprint then), so the cart that runs on meets nothing"),
    ("rejected/E0316-guards-about-shadowed-value.chor", "the choreography's gap needs a payload v in [0, 0.5], but q's process sends 0.75 and the runs follow the processes, so no run reaches it"),
    ("rejected/E0407-abstract-precondition-read-with-concrete-arguments.chor", "the refinement fails only from a start the abstract precondition allows and the run does not reach (s in [0.1, 0.3)); the runs start where the choreography puts the participant"),
    ("rejected/E0407-careful-pick-needs-more.chor", "the concrete precondition is stronger only in a band of states the runs do not reach (the arm is higher when the pick starts)"),
    ("rejected/E0407-careful-pick-promises-less.chor", "the concrete guarantee allows a lower gripper, but Z3's witnesses of it stay within the type's guarantee in 2 runs"),
    ("rejected/E0407-no-footprint-refines-a-mesh.chor", "a footprint larger than the type's is not compared point by point: the process's footprint (all space) meets nothing in the run"),
    ("rejected/E0407-turned-footprint-refines.chor", "a footprint larger than the type's is not compared point by point: the process's 1 cm longer footprint meets nothing in the run"),
    ("rejected/E0602-forgotten-loop.chor", "a declared local type that stops after one round: declared local types are not run, and the processes, run in lockstep with the global type, loop as it does"),
    ("rejected/E0701-missing-process.chor", "a participant without a process runs its part of the global type: nothing wrong happens in a run"),
    ("rejected/E0709-loop-parameter-without-the-types-refinement.chor", "the process's guard may fail only for a parameter below zero, which its loop never reaches (it counts down from a positive value and stops at 0)"),
    ("rejected/E0711-declared-receive-assumes-more.chor", "a declared local type weaker than the projection: declared local types are not run, and the processes, run in lockstep with the global type, do what the projection says"),
    ("rejected/E0711-declared-send-promises-less.chor", "a declared local type weaker than the projection: declared local types are not run, and the processes, run in lockstep with the global type, do what the projection says"),
    ("rejected/geometry/E0404-mounted-arm-orbit-too-small.chor", "the contact needs the Rover at one azimuth of its annulus with the Base turned to match, a state Z3's witnesses (which favour boundary values) do not pick at the 3 sampled times of 2 runs (nor in 8 runs)"),
    ("rejected/geometry/E0406-sorting-panda-reaches-into-cart-path.chor", "the Panda is low only while the carrier passes a few centimetres of its path, a time and state the sampled witnesses of the two sides of `*` do not pick together"),
    ("rejected/E0402-pendulum-round-ends-too-far-from-zero.chor", "the next round's precondition fails only when a round ends in the band 0.05 < |swing| <= 0.1, states Z3's witnesses (which favour boundary values such as 0) do not pick in 2 runs of 6 steps"),
    ("rejected/E0402-low-pick-below-the-next-pick.chor", "the next pick's precondition fails only when the low pick ends in the 5 mm band between hover_z and cart_h + grip_gap and `work` keeps it there, states Z3's witnesses (which favour boundary values) do not pick in 2 runs"),
];

/// Every rejected file with a program is found by the simulator (a collision, stuck state,
/// violation or replay failure), or is in [`NOT_FOUND`] with the reason. Listed files are
/// not simulated (what the table says is the reason; simulating them would only cost time).
fn rejected_files_are_found_or_explained(filter: &dyn Fn(&str) -> bool, runs: usize) {
    for (p, why) in NOT_FOUND {
        assert!(Path::new("choreographies").join(p).is_file() && !why.is_empty(), "NOT_FOUND names no file: {p}");
    }
    let mut files = Vec::new();
    chor_files(Path::new("choreographies"), true, &mut files);
    let mut files: Vec<String> =
        files.into_iter().filter(|p| filter(p) && !NOT_FOUND.iter().any(|(n, _)| p.ends_with(n))).collect();
    largest_first(&mut files, |p| p);
    // Per file: `Ok(true)` found, `Ok(false)` no program to run, `Err` missed.
    let results = par_map(&files, |_, path| {
        let mut db = SourceDb::new();
        let r = match simulate_file(&mut db, Path::new(path), &cfg(runs, 16, 1)) {
            Ok(Ok(r)) => r,
            // Rejected before a program exists: nothing to run.
            Ok(Err(d)) => {
                assert!(d.iter().any(|d| d.is_error()), "{path}: no program, and no error either");
                return Ok(false);
            }
            Err(e) => panic!("cannot read {path}: {e}"),
        };
        if r.failures().next().is_some() {
            Ok(true)
        } else {
            let what: Vec<String> = r.findings.iter().map(|f| format!("{:?}: {}", f.kind, f.message)).collect();
            Err(format!("{path} ({} steps): {what:?}", r.steps))
        }
    });
    let found = results.iter().filter(|r| matches!(r, Ok(true))).count();
    let missed: Vec<String> = results.into_iter().filter_map(Result::err).collect();
    assert!(
        missed.is_empty(),
        "rejected files the simulator does not find and NOT_FOUND does not explain:\n{}",
        missed.join("\n")
    );
    assert!(found > 0, "the simulator found nothing in the rejected corpus");
}

#[test]
fn the_simulator_finds_the_defects_of_rejected_motion_choreographies() {
    rejected_files_are_found_or_explained(&|p| !p.contains("/mavlink/"), 2);
}

#[test]
fn the_simulator_finds_the_defects_of_rejected_mavlink_protocols() {
    // Six runs: a stale reading shows only when a run reaches the choice that trusts it and
    // draws the adversarial reading there (protocols without motion simulate in seconds).
    rejected_files_are_found_or_explained(&|p| p.contains("/mavlink/"), 6);
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

/// The simulator reads a concave mesh footprint as the region its triangles bound: a box
/// whose top stands in the slot of a cradle (tests/findings/body-in-the-hollow-of-a-mesh-footprint.chor,
/// inside the cradle's hull) leaves its footprint, and a pin standing in the slot is inside
/// the box. Reading the footprint as its hull found nothing.
#[test]
fn the_simulator_finds_a_body_in_the_hollow_of_a_mesh_footprint() {
    let path = "tests/findings/body-in-the-hollow-of-a-mesh-footprint.chor";
    let r = simulate_path(path, &cfg(2, 10, 7));
    let v = r.findings.iter().find(|f| f.kind == Kind::Violation);
    let v = v.unwrap_or_else(|| panic!("{path}: no body outside its footprint found: {r:?}"));
    assert!(v.message.contains("the body of `P` (Sled, solid `box`) leaves the footprint of `hold`"), "{}", v.message);
}

/// Bodies, not only footprints: a sled that has ended its motion and waits stands where its
/// motion left it, and the other sled's box backs into it, while the footprints of the two
/// motions, at their own times, never meet. The simulator places both real bodies at each
/// sampled time and finds the contact. (B's motion leaves A out of the `dt`, which the
/// checks reject, E0309: this is a test of the simulator's eyes, not of a verdict.)
#[test]
fn the_simulator_finds_a_moving_body_that_meets_a_waiting_one() {
    let src = "robot Sled {
  state x: real;
  geometry: box(0.5, 0.4, 0.1) at pose(x, 0, 0);
  invariant: -10 <= x <= 10;
}
motion Sled.slide(xf: real) {
  interruptible: false;
  pre: x < xf;
  guarantee: old(x) <= x <= xf;
  post: x == xf;
  footprint(px, py, pz): old(x) - 0.25 <= px <= xf + 0.25 && -0.2 <= py <= 0.2 && 0 <= pz <= 0.1;
  duration: [1, 1];
}
motion Sled.back(xf: real) {
  interruptible: false;
  pre: xf < x;
  guarantee: xf <= x <= old(x);
  post: x == xf;
  footprint(px, py, pz): xf - 0.25 <= px <= old(x) + 0.25 && -0.2 <= py <= 0.2 && 0 <= pz <= 0.1;
  duration: [1, 1];
}
system S {
  participant A: Sled { init: x == 0; at: pose(0, 0, 0); }
  participant B: Sled { init: x == 0; at: pose(2, 0, 0); }
}
choreography G = dt<A: slide(1)>. A -> B: done. dt<B: back(-0.7)>. end;
process A = dt<slide(1)>.B!done.end;
process B = A?done.dt<back(-0.7)>.end;
";
    let (_, r) = check_and_simulate(src, &cfg(2, 10, 3));
    let c = r.findings.iter().find(|f| f.kind == Kind::Collision);
    let c = c.unwrap_or_else(|| panic!("no collision of the bodies found: {r:?}"));
    assert!(c.message.contains("the bodies of `B` and `A`, waiting, meet"), "{}", c.message);
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

// ---------------------------------------------------------------------------------------
// The differential relation between process typing and the simulator: a process that
// `mochi check` verifies runs in lockstep with its type without a finding. Processes are
// mutated (a constant nudged, a comparison flipped, an action dropped or swapped, a binder
// shadowed: the operators of tests/mutation/ops.rs whose edits lie in `process` items; and a
// motion replaced by another of the file's process motions); a mutant check verifies and the
// simulator finds wrong is a false `verified` of process typing.

use crate::ops;

/// A stable hash (FNV-1a) of a mutant's id, for a sample that is the same every run.
fn fnv(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

/// The byte ranges of the `process` items of `text` (each up to the next item or the end).
fn process_regions(text: &str) -> Vec<(usize, usize)> {
    const ITEMS: &[&str] =
        &["import ", "const ", "robot ", "motion ", "system ", "choreography ", "process ", "local "];
    let mut starts: Vec<(usize, bool)> = Vec::new();
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        if ITEMS.iter().any(|k| line.starts_with(k)) {
            starts.push((at, line.starts_with("process ")));
        }
        at += line.len();
    }
    let mut out = Vec::new();
    for (k, (s, is_process)) in starts.iter().enumerate() {
        if *is_process {
            out.push((*s, starts.get(k + 1).map_or(text.len(), |n| n.0)));
        }
    }
    out
}

/// `dt<...>` of a process replaced by another motion written in the file's processes:
/// (id, description, mutated text).
fn motion_swaps(text: &str) -> Vec<(String, String, String)> {
    let mut motions: Vec<(usize, usize)> = Vec::new();
    for (s, e) in process_regions(text) {
        let mut i = s;
        while let Some(k) = text[i..e].find("dt<") {
            let from = i + k + 3;
            let Some(len) = text[from..e].find('>') else { break };
            motions.push((from, from + len));
            i = from + len;
        }
    }
    let mut distinct: Vec<&str> = motions.iter().map(|(a, b)| &text[*a..*b]).collect();
    distinct.sort();
    distinct.dedup();
    let mut out = Vec::new();
    for (a, b) in &motions {
        let here = &text[*a..*b];
        // The next distinct motion in sorted order (a deterministic other one).
        let Some(k) = distinct.iter().position(|d| *d == here) else { continue };
        let other = distinct[(k + 1) % distinct.len()];
        if other == here {
            continue;
        }
        let mut t = text.to_string();
        t.replace_range(*a..*b, other);
        out.push((format!("@{a}:motion-swap"), format!("dt<{here}> -> dt<{other}>"), t));
    }
    out
}

/// Every process mutant of `text`: (id, description, mutated text).
fn process_mutants(text: &str) -> Vec<(String, String, String)> {
    let regions = process_regions(text);
    let inside = |s: usize, e: usize| regions.iter().any(|(a, b)| *a <= s && e <= *b);
    let (consts, states) = ops::declared_names(text);
    let mut out: Vec<(String, String, String)> = ops::mutants(text, &states, &consts, None)
        .into_iter()
        .filter(|m| !m.edits.is_empty() && m.edits.iter().all(|(s, e, _)| inside(*s, *e)))
        .map(|m| (m.id.clone(), m.desc.clone(), m.apply(text)))
        .collect();
    out.extend(motion_swaps(text));
    out
}

/// How many process mutants the relation checks: `MOCHI_SIM_MUTANTS` (the long mode; `all`
/// for every one), else 16.
fn sim_mutant_budget() -> usize {
    match std::env::var("MOCHI_SIM_MUTANTS").ok().as_deref() {
        Some("all") => usize::MAX,
        Some(n) => n.parse().unwrap_or(16),
        None => 16,
    }
}

/// `mochi check` verifies ⇒ `mochi simulate` finds nothing, over mutants of the processes
/// of every verified motion choreography that has processes (a fixed sample: the ids of
/// least hash). A mutant that is verified and found wrong is a false `verified`, printed
/// with its text.
#[test]
fn process_mutants_that_check_verifies_simulate_clean() {
    let mut files = Vec::new();
    chor_files(Path::new("choreographies"), false, &mut files);
    let mut all: Vec<(u64, String, String, String, String)> = Vec::new();
    for path in files.iter().filter(|p| !p.contains("/mavlink/")) {
        let text = std::fs::read_to_string(path).expect("readable");
        if process_regions(&text).is_empty() || golden_verdict(path) != Verdict::Verified {
            continue;
        }
        for (id, desc, mutated) in process_mutants(&text) {
            let id = format!("{path}:{id}");
            all.push((fnv(&id), id, desc, path.clone(), mutated));
        }
    }
    assert!(all.len() >= 50, "too few process mutants were generated: {}", all.len());
    all.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)));
    all.truncate(sim_mutant_budget());
    let rows = par_map(&all, |k, (_, id, desc, path, text)| {
        let mut db = SourceDb::new();
        let v = check_source(&mut db, path, text, &Config::default()).verdict;
        if v != Verdict::Verified {
            return (v, None);
        }
        let mut db = SourceDb::new();
        let root = db.add(path, text.clone());
        let r = match simulate_loaded(&mut db, root, &cfg(2, 12, 500 + k as u64), &mut read_bytes) {
            Ok(r) => r,
            Err(d) => return (v, Some(format!("{id} ({desc}): verified, but it does not resolve: {d:?}"))),
        };
        let found: Vec<String> = r
            .failures()
            .filter(|f| f.kind != Kind::Replay)
            .map(|f| format!("{:?}: {}\n    {}", f.kind, f.message, f.trace.join("\n    ")))
            .collect();
        if found.is_empty() {
            return (v, None);
        }
        let procs: Vec<&str> = process_regions(text).into_iter().map(|(s, e)| text[s..e].trim()).collect();
        (
            v,
            Some(format!(
                "{id} ({desc}): verified, and the simulator finds:\n  {}\n  the processes:\n{}",
                found.join("\n  "),
                procs.join("\n")
            )),
        )
    });
    let false_verified: Vec<&String> = rows.iter().filter_map(|(_, f)| f.as_ref()).collect();
    let rejected = rows.iter().filter(|(v, _)| *v == Verdict::Rejected).count();
    let verified = rows.iter().filter(|(v, _)| *v == Verdict::Verified).count();
    eprintln!("process mutants: {} checked, {verified} verified, {rejected} rejected", rows.len());
    assert!(
        false_verified.is_empty(),
        "false `verified` of process typing (the mutant is verified, the simulator finds it wrong):\n{}",
        false_verified.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("\n")
    );
    assert!(rejected > 0, "no sampled mutant was rejected: the relation tested nothing");
}
