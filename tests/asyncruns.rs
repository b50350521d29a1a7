//! An independent oracle for timeouts on asynchronous links (E0326, the timeout crossing).
//!
//! `explore.rs` runs a protocol's projections over FIFO queues, one per ordered pair of
//! roles, with every interleaving and every moment a timeout may fire, up to a bound, and
//! says where a role misreads: it receives a label its state does not expect (and the message
//! is not late), a value its refinement does not admit, a late message as a step of its
//! protocol (unless the reception absorbs it), a message after its session is over that is
//! not late, or the run stops with a role waiting for ever. It is written from the runs
//! alone, not from E0326's rule. The oracle: **a protocol `mochi check` verifies has no
//! misread run**. And the monitor (`replay.rs`) must read each explored run of a verified
//! protocol as the explorer does: a step as a step, an ignored late message as `Late`, and a
//! run in which every role ended as sessions that ended.
//!
//! Inputs: every timed protocol of `choreographies/mavlink/` (verified ones must not
//! misread, each rejected E0326 twin must), the hand-made cases of E0326's unit tests, and
//! generated protocols (`gen.rs`). Budget: `MOCHI_ASYNC_CASES` generated protocols
//! (default 24); `MOCHI_LONG=1` makes it 1,500 with deeper runs; `MOCHI_GEN_SEED` picks
//! another sequence (as in `generate.rs`). A failure prints the protocol and the run.

#[path = "asyncruns/explore.rs"]
mod explore;
#[path = "asyncruns/gen.rs"]
mod gen;
#[path = "asyncruns/replay.rs"]
mod replay;

use explore::{Explored, Explorer};
use mochi::driver::{Config, Report, Stage, Verdict};
use mochi::hir::Program;
use mochi::source::SourceDb;
use replay::Watch;
use std::path::{Path, PathBuf};

fn long() -> bool {
    std::env::var("MOCHI_LONG").is_ok_and(|v| v == "1")
}

fn cases() -> u32 {
    std::env::var("MOCHI_ASYNC_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(if long() { 1500 } else { 24 })
}

fn seed() -> u64 {
    std::env::var("MOCHI_GEN_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(18)
}

fn lower(src: &str) -> Option<(SourceDb, Program)> {
    lower_at("timed.chor", src)
}

/// `src` lowered under the name `name`, its imports read from disk relative to it (a file
/// of the corpus imports profiles: under another name its check stops at E0105).
fn lower_at(name: &str, src: &str) -> Option<(SourceDb, Program)> {
    let mut db = SourceDb::new();
    let file = db.add(name, src);
    let mut read = |p: &Path| mochi::fsload::read_bytes(p);
    let prog = mochi::driver::prepare(&mut db, file, &mut read, Stage::Names).ok()?;
    Some((db, prog))
}

fn check(src: &str) -> Report {
    check_at("timed.chor", src)
}

fn check_at(name: &str, src: &str) -> Report {
    let mut db = SourceDb::new();
    let mut cfg = Config::default();
    cfg.smt.jobs = 1;
    mochi::fsload::check_source(&mut db, name, src, &cfg)
}

fn codes(r: &Report) -> Vec<&'static str> {
    let mut c: Vec<&str> = r.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code.as_str()).collect();
    c.sort();
    c.dedup();
    c
}

fn explore(prog: &Program) -> Result<Explored, String> {
    let mut x = Explorer::new(prog);
    if long() {
        x.depth = 22;
        x.max_states = 60_000;
    }
    x.explore().map_err(|u| format!("the explorer cannot run it: {}", u.0))
}

/// The oracle on one protocol: if verified, no misread and the monitor agrees. Returns the
/// verdict, the codes and what the explorer found.
fn oracle(src: &str) -> Result<(Verdict, Vec<&'static str>, Explored), String> {
    oracle_at("timed.chor", src)
}

fn oracle_at(name: &str, src: &str) -> Result<(Verdict, Vec<&'static str>, Explored), String> {
    let report = check_at(name, src);
    let Some((db, prog)) = lower_at(name, src) else {
        return Ok((report.verdict, codes(&report), Explored::default()));
    };
    let found = match explore(&prog) {
        Ok(f) => f,
        // A protocol that does not project is rejected; one that verifies must be explored.
        Err(e) if report.verdict == Verdict::Verified => return Err(format!("{e}\n{src}")),
        Err(_) => return Ok((report.verdict, codes(&report), Explored::default())),
    };
    if report.verdict == Verdict::Verified {
        let x = Explorer::new(&prog);
        if let Some(m) = &found.misread {
            return Err(format!("FALSE VERIFIED: {}\n{}\n{src}", m.what, x.render(&m.trace)));
        }
        // The monitor reads a session's messages in the order of the global type; a protocol
        // in which a message may race the one before it (a third role speaking before the
        // session's first message) is refused when compiled (monitor/order.rs), and the
        // replay says "not monitorable". With a third role, runs are watched on the wire
        // only: a log at one role sees its own receptions later than the traffic between the
        // others, in another order than the protocol's.
        let two = prog.roles.len() == 2;
        for (trace, complete) in &found.runs {
            let at_roles = prog.role_ids().filter(|_| two).map(Watch::At);
            let watches = std::iter::once(Watch::Wire).chain(at_roles);
            for w in watches {
                if let Err(e) = replay::replay(&db, &prog, trace, *complete, w) {
                    return Err(format!("the monitor ({w:?}) disagrees: {e}\nthe run:\n{}\n{src}", x.render(trace)));
                }
            }
        }
    }
    Ok((report.verdict, codes(&report), found))
}

fn mavlink(dir: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("choreographies").join(dir);
    let mut out: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("the corpus")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "chor"))
        .filter(|p| std::fs::read_to_string(p).is_ok_and(|s| timed(&s)))
        .collect();
    out.sort();
    out
}

/// Whether the source has a timeout branch outside its comments.
fn timed(src: &str) -> bool {
    src.lines().map(|l| l.split("//").next().unwrap_or("")).any(|l| l.contains(" ms by "))
}

/// Files of the corpus in which the explorer finds a run E0326 lets through, each with
/// what it shows: open findings, kept here so that the test names them and fails when one
/// is fixed (then remove it) or another file joins them.
const KNOWN: &[(&str, &str)] = &[];

#[test]
fn timed_protocols_of_the_corpus_never_misread_and_the_monitor_agrees() {
    let files = mavlink("mavlink");
    assert!(!files.is_empty());
    let mut verified = 0;
    let mut failures = Vec::new();
    for f in files {
        let name = f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let known = KNOWN.iter().any(|(k, _)| *k == name);
        let src = std::fs::read_to_string(&f).expect("readable");
        match oracle_at(&f.display().to_string(), &src) {
            Ok((verdict, codes, found)) => {
                if verdict == Verdict::Verified {
                    verified += 1;
                    assert!(!found.runs.is_empty(), "{}: no run explored", f.display());
                } else if !src.starts_with("// expect:") {
                    // A file of the corpus verifies (its imports read as `mochi check` reads
                    // them); one rejected here would be skipped silently.
                    failures.push(format!("{name}: {verdict:?} {codes:?} in the oracle, verified by `mochi check`"));
                }
                eprintln!("{}: {verdict:?} {codes:?}, {} states", f.display(), found.states);
                if known {
                    failures.push(format!("{name}: listed in KNOWN, but the explorer finds nothing now: remove it"));
                }
            }
            Err(e) if known => eprintln!("{name}: the known finding: {}", e.lines().next().unwrap_or("")),
            Err(e) => failures.push(format!("{}: {e}", f.display())),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    assert!(verified >= 1, "no verified timed protocol in the corpus");
}

/// The oracle can fail: every rejected twin of E0326 has a run the explorer calls a misread.
#[test]
fn the_explorer_finds_each_rejected_crossing() {
    let files: Vec<PathBuf> = mavlink("mavlink/rejected")
        .into_iter()
        .filter(|p| p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("E0326")))
        .collect();
    assert!(files.len() >= 3, "{files:?}");
    for f in files {
        let src = std::fs::read_to_string(&f).expect("readable");
        let (_, prog) = lower(&src).expect("lowers");
        let found = explore(&prog).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert!(found.misread.is_some(), "{}: no misread found in {} states", f.display(), found.states);
    }
}

/// The hand-made cases of E0326's unit tests (`plan/tests/crossing.rs`), with the plain
/// labels they use: where E0326 accepts, the explorer finds no misread.
#[test]
fn the_hand_made_cases_of_the_rule_agree_with_the_explorer() {
    let two = "system S { participant P; participant Q; }";
    let three = "system S { participant P; participant Q; participant B; }";
    let cases: &[(&str, &str, bool)] = &[
        (two, "P -> Q: ask. ( Q -> P: val. P -> Q: more. end + after 10 ms by P. P -> Q: other. end )", false),
        (two, "P -> Q: ask. ( Q -> P: val. end + after 10 ms by P. P -> Q: again. end )", false),
        (two, "P -> Q: ask. ( Q -> P: val. P -> Q: again. end + after 10 ms by P. P -> Q: again. end )", true),
        (two, "P -> Q: ask. ( Q -> P: val. end + after 10 ms by P. end )", true),
        (two, "mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: stop. end )", true),
        (two, "mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: ask. Q -> P: val. end )", false),
        (two, "mu t. ( Q -> P: val. t + after 10 ms by P. P -> Q: ask. Q -> P: done. end )", true),
        (
            two,
            "mu t. ( Q -> P: val(x: int). t + after 10 ms by P. P -> Q: ask. mu w. ( Q -> P: val(y: int). w + after 10 ms by P. end ) )",
            true,
        ),
        (
            two,
            "mu t. ( Q -> P: val(x: int). t + after 10 ms by P. P -> Q: ask. mu w. ( Q -> P: val(y: int). end + after 10 ms by P. end ) )",
            false,
        ),
        (
            two,
            "mu r(n: int {0 <= n} = 3) decreases n. ( P -> Q: [n > 0] ask. ( mu w. ( Q -> P: val. w + after 10 ms by P. r(n - 1) ) ) + after 30 ms by Q. end )",
            true,
        ),
        (
            two,
            "mu r(n: int {0 <= n} = 3) decreases n. ( P -> Q: [n > 0] ask. Q -> P: val. r(n - 1) + after 30 ms by Q. end )",
            false,
        ),
        (
            three,
            "P -> Q: ask. ( Q -> P: val. P -> Q: again. P -> B: log. end + after 10 ms by P. P -> Q: again. P -> B: log. end )",
            true,
        ),
        (
            two,
            "( P -> Q: ask. ( mu w. ( P -> Q: more. w + after 10 ms by Q. Q -> P: ack. end ) ) + after 5 ms by Q. end )",
            true,
        ),
        // The long mode's first false alarm of the explorer itself (generated input
        // 3012547886589669347): Q ignores P's late `set`, P gives up at the next choice and
        // re-requests; Q's answer to the re-request was read as late, because the ignored
        // `set` was not counted as received. Every message is in its place.
        (
            two,
            "( P -> Q: set. Q -> P: count. ( Q -> P: ack. P -> Q: read. Q -> P: count. end + after 10 ms by P. \
             P -> Q: read. Q -> P: count. end ) + after 10 ms by Q. Q -> P: count. ( Q -> P: ack. P -> Q: read. \
             Q -> P: count. end + after 10 ms by P. P -> Q: read. Q -> P: count. end ) )",
            true,
        ),
        // compass-calibration.chor's shape: a refused `ack` crosses P's first timeout, P ends,
        // and Q has no branch it can take at the next choice, whose timeout (P's) ends Q's
        // part too: Q's session is over with P's.
        (two, REFUSED_THEN_SILENCE, true),
        // The same, with Q's part of P's second timeout a message from P: Q waits for ever.
        (two, REFUSED_THEN_WAITS, false),
    ];
    for (system, chor, accepted) in cases {
        let src = format!("{system} choreography G = {chor};");
        let (_, prog) = lower(&src).expect("lowers");
        let found = explore(&prog).unwrap_or_else(|e| panic!("{e}\n{src}"));
        let x = Explorer::new(&prog);
        match (&found.misread, accepted) {
            (Some(m), true) => panic!("E0326 accepts, the explorer finds: {}\n{}\n{src}", m.what, x.render(&m.trace)),
            (None, false) => panic!("E0326 rejects, the explorer finds no misread in {} states\n{src}", found.states),
            _ => {}
        }
    }
}

/// A monitor disagreement the long mode found first (generated input 12311287858256003887,
/// shrunk to this protocol), now closed by the late window of sessions ended by time: the
/// ground station takes the first PARAM_VALUE and gives up waiting for the second; the
/// second and the MISSION_COUNT, sent before the vehicle could know, reach it late and it
/// ignores them. A monitor at the ground station had ended the session by time and read the
/// late PARAM_VALUE, a first message of the protocol, as a new session's first step, where
/// the late MISSION_COUNT was then unexpected. Every run now replays in agreement.
#[test]
fn a_late_first_message_after_a_session_ended_by_time_opens_no_new_session() {
    let src = "dialect common;\nsystem S { participant GCS; participant UAV; }\nchoreography G =\n  \
               ( UAV -> GCS: PARAM_VALUE. ( UAV -> GCS: PARAM_VALUE. ( UAV -> GCS: MISSION_COUNT. end \
               + after 500 ms by GCS. end ) + after 500 ms by GCS. end ) + after 500 ms by GCS. end );\n";
    assert_eq!(check(src).verdict, Verdict::Verified);
    let (db, prog) = lower(src).expect("lowers");
    let mut x = Explorer::new(&prog);
    x.keep = usize::MAX;
    let found = x.explore().expect("explorable");
    assert!(found.misread.is_none() && !found.cut, "{found:?}");
    let gcs = prog.role_ids().next().expect("a role");
    let mut replayed = 0;
    for (trace, complete) in &found.runs {
        match replay::replay(&db, &prog, trace, *complete, Watch::At(gcs)) {
            Ok(None) => replayed += 1,
            Ok(Some(_)) => {}
            Err(e) => panic!("{e}\n{}", x.render(trace)),
        }
    }
    assert!(replayed > 0, "no run of {} was replayed", found.runs.len());
}

/// A refused answer (`res == 1`) leaves `Q` with no branch at the next choice; after the
/// crossing of `ack` and P's first timeout, P has ended.
const REFUSED_THEN_SILENCE: &str = "P -> Q: start. ( Q -> P: ack(res: int {0 <= res && res <= 1}). \
     ( Q -> P: [res == 0] progress. end + after 10 ms by P. end ) + after 10 ms by P. end )";
const REFUSED_THEN_WAITS: &str = "P -> Q: start. ( Q -> P: ack(res: int {0 <= res && res <= 1}). \
     ( Q -> P: [res == 0] progress. P -> Q: bye. end + after 10 ms by P. P -> Q: bye. end ) + after 10 ms by P. end )";

#[test]
fn generated_timed_protocols_that_verify_never_misread() {
    use proptest::test_runner::{Config as RunnerConfig, RngAlgorithm, TestRng, TestRunner};
    let mut s = [0u8; 32];
    s[..8].copy_from_slice(&seed().to_le_bytes());
    let mut runner = TestRunner::new_with_rng(
        RunnerConfig { cases: cases(), failure_persistence: None, ..RunnerConfig::default() },
        TestRng::from_seed(RngAlgorithm::ChaCha, &s),
    );
    let tally = std::sync::Mutex::new(Tally::default());
    let result = runner.run(&proptest::prelude::any::<u64>(), |n| {
        let src = gen::Gen::new(n).protocol();
        let (verdict, codes, found) = oracle(&src).map_err(proptest::test_runner::TestCaseError::fail)?;
        let mut t = tally.lock().expect("tally");
        t.inputs += 1;
        t.states += found.states;
        match verdict {
            Verdict::Verified => t.verified += 1,
            _ if codes == ["E0326"] && found.misread.is_none() && !found.cut => {
                t.e0326_no_misread += 1;
                if t.examples.len() < 3 {
                    t.examples.push(src.clone());
                }
            }
            _ if codes.contains(&"E0326") => t.e0326 += 1,
            _ => {
                t.other += 1;
                for c in &codes {
                    *t.other_codes.entry(c).or_default() += 1;
                }
                if t.other_examples.len() < 4 {
                    t.other_examples.push(format!("{codes:?} {src}"));
                }
            }
        }
        if found.misread.is_some() {
            t.misread += 1;
        }
        Ok(())
    });
    let t = tally.into_inner().expect("tally");
    eprintln!("{t:#?}");
    if let Err(e) = result {
        panic!("{e}");
    }
    assert!(t.verified * 10 >= t.inputs, "too few generated protocols verify to test anything: {t:?}");
}

/// What the generated inputs were: how many verified, were rejected by E0326 (with or without
/// a misread the explorer finds: the rule's conservative cases), or by another check.
#[derive(Default, Debug)]
struct Tally {
    inputs: u32,
    verified: u32,
    e0326: u32,
    /// Rejected by E0326 alone, and the explorer finds no misread within its bound.
    e0326_no_misread: u32,
    other: u32,
    other_codes: std::collections::BTreeMap<&'static str, u32>,
    other_examples: Vec<String>,
    misread: u32,
    states: usize,
    examples: Vec<String>,
}
