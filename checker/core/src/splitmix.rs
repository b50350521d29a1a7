//! SplitMix64 (Steele, Lea and Flood, *Fast splittable pseudorandom number generators*,
//! OOPSLA 2014): the one small deterministic generator of the simulator's draws and of the
//! tests' generators, so that a seed names the same run everywhere.
//!
//! Written here rather than taken from a crate: it is six lines, and the exact stream is part
//! of what the repository records (seeds in docs/testing.md, regression files, commit
//! messages name scenes by seed), which a dependency's version bump must not change.

/// The generator's state; `SplitMix64(seed)` starts a stream.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next value of the stream.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix(self.0)
    }

    /// A value in `0..n` (`0` when `n` is 0); the modulo bias is far below what the tests
    /// could notice.
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }
}

/// SplitMix64's finaliser: a well-spread hash of `z`.
pub fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference stream for seed 1234567 (the published C implementation's first
    /// outputs), so a change of the stream cannot pass unnoticed.
    #[test]
    fn the_stream_is_splitmix64s() {
        let mut g = SplitMix64(1234567);
        let first: Vec<u64> = (0..3).map(|_| g.next_u64()).collect();
        assert_eq!(first, [6457827717110365317, 3203168211198807973, 9817491932198370423]);
    }
}
