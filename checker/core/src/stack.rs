//! Stack growth for the recursive passes. Every stage recurses over trees as deep as the
//! parser admits (E0108: 1,000 levels, each operator and prefix counted) or deeper where a
//! stage builds terms itself (substitution, unfolding), so every recursive step goes
//! through [`deep`]: when less than [`RED_ZONE`] bytes of stack are left, the closure runs
//! on a fresh segment of [`GROWTH`] bytes (the `stacker` crate, as rustc does). The check
//! is a comparison with the stack pointer, cheap enough for every node.

/// When less than this much stack is left, a new segment is allocated...
pub const RED_ZONE: usize = 64 * 1024;
/// ...of this size.
pub const GROWTH: usize = 4 * 1024 * 1024;

/// Runs `f`, on a new stack segment if the current one is nearly exhausted. Wrap the
/// recursive call of every pass over a tree in it: `fn walk(..) { deep(|| walk_inner(..)) }`.
#[inline]
pub fn deep<R>(f: impl FnOnce() -> R) -> R {
    stacker::maybe_grow(RED_ZONE, GROWTH, f)
}
