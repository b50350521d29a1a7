//! Differential tests: two ways of running the same check must give the same verdict and the
//! same diagnostic codes on every file of the corpus (`choreographies/**`, `tests/data/**`).
//!
//! - **answer cache on and off** (`SmtConfig::no_cache`, `mochi check --no-cache`): a verdict
//!   that depends on an answer reused from another query (a cache key that merges two
//!   different questions, a vacuity answer shared by contexts that differ, a contract
//!   witnessed by the wrong obligation) shows up as a difference;
//! - **one worker and several** (`SmtConfig::jobs`): a verdict that depends on which worker
//!   asked first (a shared answer read before it is written, an order-dependent shortcut)
//!   shows up as a difference.
//!
//! Each file is compared with its reference outcome: for a file of `choreographies/`, the one
//! its golden snapshot records (the corpus harness checks it with the cache on and one SMT
//! worker per core, and fails unless its report is the snapshot's), so this binary runs only
//! the second mode (cache off with one worker; four workers); for a file of `tests/data/`,
//! its check with one worker and the cache on. A run compares the day's quarter of the
//! corpus in each mode (the slices of tests/metamorphic/common.rs, cut per comparison),
//! every file with `MOCHI_META_SLICE=all`. The heavy geometric files (tests/metamorphic/common.rs,
//! `HEAVY`) run only in the long mode (`MOCHI_META_CASES=N`, any N; every slice).
//!
//! Both comparisons run over mutants of the corpus too (the operators of
//! tests/mutation/ops.rs): a fixed sample of 24, all three modes each;
//! `MOCHI_DIFF_MUTANTS=N` runs N.

use crate::common;

use common::{baseline, check, config, corpus, fnv, in_slice, par_map, timed, Outcome, Program};
use std::path::PathBuf;

/// Each file's outcome under the reference configuration and under `b`; the files where
/// they differ. The reference is [`baseline`]: for a file of `choreographies/`, its golden
/// snapshot's outcome, which the corpus harness checks with the answer cache on and one SMT
/// worker per core; for a file of `tests/data/`, its check with one worker, the cache on
/// (`config(1, false)`), computed once and shared by both tests. The files are those of the
/// run's slice of `what` ([`in_slice`]: the day's quarter, every file with
/// `MOCHI_META_SLICE=all`).
fn differences(what: &str, b: &mochi::driver::Config) -> Vec<String> {
    let files = corpus();
    assert!(files.len() > 100, "the corpus was found ({} files)", files.len());
    let files: Vec<PathBuf> = files.into_iter().filter(|p| in_slice(what, p)).collect();
    assert!(files.len() > 10, "{what}: the slice holds files ({})", files.len());
    let rows: Vec<(PathBuf, Outcome, Outcome)> = par_map(&files, 2, |p| {
        let x = timed(&format!("{} (reference)", p.display()), || baseline(p));
        let y = timed(&format!("{} (second)", p.display()), || check(&Program::on_disk(p), b));
        (p.clone(), x, y)
    });
    rows.into_iter().filter(|(_, x, y)| x != y).map(|(p, x, y)| format!("{}: {x} vs {y}", p.display())).collect()
}

#[test]
fn the_answer_cache_changes_no_verdict() {
    let diff = differences("cache off", &config(1, true));
    assert!(diff.is_empty(), "cache on vs off differ on {} file(s):\n{}", diff.len(), diff.join("\n"));
}

#[test]
fn the_number_of_workers_changes_no_verdict() {
    let diff = differences("four workers", &config(4, false));
    assert!(diff.is_empty(), "the reference vs -j 4 differ on {} file(s):\n{}", diff.len(), diff.join("\n"));
}

// ---------------------------------------------------------------------------------------
// The same two comparisons over mutants of the corpus: wrong programs take the paths of
// rejections, counterexamples, replays and unknowns that the corpus, mostly correct, takes
// rarely, and a cache key or a worker order that merges two questions shows there too.

use crate::ops;

/// How many mutants the comparison runs: `MOCHI_DIFF_MUTANTS` (the long mode), else 24.
fn mutant_budget() -> usize {
    std::env::var("MOCHI_DIFF_MUTANTS").ok().and_then(|s| s.parse().ok()).unwrap_or(24)
}

/// A fixed sample of mutants of the corpus's root files (the operators of
/// tests/mutation/ops.rs, MAVLink ones for files with a `dialect`): the `n` ids of least
/// hash, so the sample is the same every run and grows by adding, never by reshuffling.
fn mutant_sample(n: usize) -> Vec<(String, Program)> {
    let mut all: Vec<(u64, String, PathBuf, String)> = Vec::new();
    for p in corpus() {
        let Ok(text) = std::fs::read_to_string(&p) else { continue };
        let (consts, states) = ops::declared_names(&text);
        let dialect = text
            .lines()
            .find_map(|l| l.trim().strip_prefix("dialect "))
            .and_then(|d| mochi::dialect::builtin(d.trim().trim_end_matches(';').trim()));
        for m in ops::mutants(&text, &states, &consts, dialect) {
            let id = format!("{}:{}", p.display(), m.id);
            all.push((fnv(&id), id, p.clone(), m.apply(&text)));
        }
    }
    all.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)));
    all.truncate(n);
    all.into_iter()
        .map(|(_, id, root, text)| {
            let mut texts = std::collections::HashMap::new();
            texts.insert(root.display().to_string(), text);
            (id, Program { root, texts })
        })
        .collect()
}

#[test]
fn mutants_get_the_same_verdict_with_and_without_the_cache_and_with_more_workers() {
    let sample = mutant_sample(mutant_budget());
    assert!(sample.len() >= mutant_budget().min(20), "the sample was drawn ({} mutants)", sample.len());
    let (one, uncached, four) = (config(1, false), config(1, true), config(4, false));
    let rows = par_map(&sample, 2, |(id, prog)| {
        let a = timed(&format!("{id} (cache, -j 1)"), || check(prog, &one));
        let b = timed(&format!("{id} (no cache)"), || check(prog, &uncached));
        let c = timed(&format!("{id} (-j 4)"), || check(prog, &four));
        (id.clone(), a, b, c)
    });
    let kinds: std::collections::BTreeSet<String> = rows.iter().map(|r| format!("{:?}", r.1.verdict)).collect();
    let diff: Vec<String> = rows
        .iter()
        .filter(|(_, a, b, c)| a != b || a != c)
        .map(|(id, a, b, c)| format!("{id}: {a} (cache, -j 1) vs {b} (no cache) vs {c} (-j 4)"))
        .collect();
    assert!(diff.is_empty(), "the modes differ on {} mutant(s):\n{}", diff.len(), diff.join("\n"));
    // Not vacuous: the sample holds mutants with different verdicts.
    assert!(kinds.len() >= 2, "every sampled mutant had one verdict: {kinds:?}");
}
