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
//! The heavy geometric files (tests/metamorphic/common.rs, `HEAVY`) run only in the long
//! mode (`MOCHI_META_CASES=N`, any N).

#[path = "metamorphic/common.rs"]
mod common;

use common::{check, config, corpus, par_map, timed, Outcome, Program};
use std::path::PathBuf;

/// Each file's outcome under `a` and under `b`; the files where they differ.
fn differences(files: &[PathBuf], a: &mochi::driver::Config, b: &mochi::driver::Config) -> Vec<String> {
    let rows: Vec<(PathBuf, Outcome, Outcome)> = par_map(files, 2, |p| {
        let x = timed(&format!("{} (first)", p.display()), || check(&Program::on_disk(p), a));
        let y = timed(&format!("{} (second)", p.display()), || check(&Program::on_disk(p), b));
        (p.clone(), x, y)
    });
    rows.into_iter().filter(|(_, x, y)| x != y).map(|(p, x, y)| format!("{}: {x} vs {y}", p.display())).collect()
}

#[test]
fn the_answer_cache_changes_no_verdict() {
    let files = corpus();
    assert!(files.len() > 100, "the corpus was found ({} files)", files.len());
    let diff = differences(&files, &config(1, false), &config(1, true));
    assert!(diff.is_empty(), "cache on vs off differ on {} file(s):\n{}", diff.len(), diff.join("\n"));
}

#[test]
fn the_number_of_workers_changes_no_verdict() {
    let files = corpus();
    let diff = differences(&files, &config(1, false), &config(4, false));
    assert!(diff.is_empty(), "-j 1 vs -j 4 differ on {} file(s):\n{}", diff.len(), diff.join("\n"));
}
