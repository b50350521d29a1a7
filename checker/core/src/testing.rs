//! Helpers shared by the unit tests of several stages (compiled for tests only).

use std::time::Duration;

/// Asserts that `time(n)` grows about linearly: at `big` = 8 x `small` the time may be at
/// most 24 times as long (linear is x8, the quadratic code these tests guard against was
/// x40 and more). Timings on a loaded machine stray, so one of three attempts must pass.
/// The tests that use it are `#[ignore]`d: speed is the benchmarks' to measure, and these
/// are for a quiet machine (`cargo test -- --ignored`).
pub(crate) fn assert_near_linear(what: &str, small: usize, big: usize, time: impl Fn(usize) -> Duration) {
    let mut seen = Vec::new();
    for _ in 0..3 {
        let (s, b) = (time(small), time(big));
        seen.push((s, b));
        if b < s * 24 {
            return;
        }
    }
    panic!("{what}: {small} vs {big}: {seen:?}");
}
