//! How far apart instants of a schedule are, from the durations of the motions between
//! them (ARCHITECTURE.md, "Timing", "Releases the durations tie").
//!
//! The instants of `timing.rs` are ordered by events alone: a motion's end after its start,
//! a message after the readiness of both parties. Durations say more. A motion with a
//! non-interruptible part ends at an elapsed time in that part's `D` ([NON-INTERRUPT], Fig
//! 3; Def 3.4's `D`), so its end lies in `[start + lo, start + hi]`. Each instant records
//! one *anchor* it is known to follow within a window: the end of a motion its start, a
//! message whose parties become ready at two instants with a common anchor that anchor
//! (the later of two times lies within the hull of their windows' ends). Two instants with
//! a common anchor `c` are ordered when `t_a - t_c <= hi_a <= lo_b <= t_b - t_c`.
//!
//! Windows are kept as sums along the anchor chain from the instant's root (`lo`, the
//! finite part of `hi` and the number of unbounded steps), so the window between an
//! instant and any anchor above it is a difference of two sums.

use crate::exact::{self, Rat, Value};
use crate::hir::{Motion, Program, Var};
use num_traits::{Signed, Zero};

/// The anchors of every instant, by instant number (as in `timing.rs`, 0 is the start).
pub(super) struct Offsets {
    node: Vec<Node>,
}

struct Node {
    /// The anchor, `None` for a root.
    up: Option<usize>,
    depth: u32,
    /// Sums from the root down to this instant: `t - t_root ∈ [lo, hi_fin]` when `inf == 0`.
    lo: Rat,
    hi_fin: Rat,
    inf: u32,
}

/// How many anchors a search walks up before it gives up (and then nothing is known:
/// instants are then only as ordered as the events say).
const MAX_WALK: usize = 4096;

/// A window `[lo, hi]` of elapsed time; `hi = None` is unbounded.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Window {
    pub lo: Rat,
    pub hi: Option<Rat>,
}

impl Window {
    pub fn any() -> Window {
        Window { lo: Rat::zero(), hi: None }
    }
}

impl Offsets {
    pub fn new() -> Offsets {
        Offsets { node: vec![Node { up: None, depth: 0, lo: Rat::zero(), hi_fin: Rat::zero(), inf: 0 }] }
    }

    /// Registers the next instant as a root: nothing known about its distance to others.
    pub fn root(&mut self) {
        self.node.push(Node { up: None, depth: 0, lo: Rat::zero(), hi_fin: Rat::zero(), inf: 0 });
    }

    /// Registers the next instant as following `anchor` within `w`.
    pub fn after(&mut self, anchor: usize, w: &Window) {
        let a = &self.node[anchor];
        let (hi_fin, inf) = match &w.hi {
            Some(h) => (&a.hi_fin + h, a.inf),
            None => (a.hi_fin.clone(), a.inf + 1),
        };
        let n = Node { up: Some(anchor), depth: a.depth + 1, lo: &a.lo + &w.lo, hi_fin, inf };
        self.node.push(n);
    }

    /// The nearest common anchor of `a` and `b` (an instant is its own anchor), if found
    /// within [`MAX_WALK`] steps.
    fn common(&self, mut a: usize, mut b: usize) -> Option<usize> {
        for _ in 0..MAX_WALK {
            if a == b {
                return Some(a);
            }
            let (da, db) = (self.node[a].depth, self.node[b].depth);
            if da >= db {
                a = self.node[a].up?;
            } else {
                b = self.node[b].up?;
            }
        }
        None
    }

    /// The window of `t_x - t_c` for an anchor `c` of `x`.
    fn window(&self, x: usize, c: usize) -> Window {
        let (nx, nc) = (&self.node[x], &self.node[c]);
        let hi = (nx.inf == nc.inf).then(|| &nx.hi_fin - &nc.hi_fin);
        Window { lo: &nx.lo - &nc.lo, hi }
    }

    /// Whether the durations prove `t_a <= t_b`.
    pub fn le(&self, a: usize, b: usize) -> bool {
        let Some(c) = self.common(a, b) else { return false };
        let (wa, wb) = (self.window(a, c), self.window(b, c));
        wa.hi.is_some_and(|h| h <= wb.lo)
    }

    /// Registers the next instant as the later of `a` and `b` (neither known to be the
    /// later): anchored where they are, within the hull of their windows' upper ends.
    pub fn later_of(&mut self, a: usize, b: usize) {
        match self.common(a, b) {
            Some(c) => {
                let (wa, wb) = (self.window(a, c), self.window(b, c));
                let lo = wa.lo.max(wb.lo);
                let hi = match (wa.hi, wb.hi) {
                    (Some(x), Some(y)) => Some(x.max(y)),
                    _ => None,
                };
                self.after(c, &Window { lo, hi });
            }
            None => self.root(),
        }
    }
}

/// When a motion ends after it starts, from the durations of its non-interruptible parts
/// (every one of them ends at an elapsed time in its `D`: under joint end, E0401, they end
/// together, so the end lies in each). A bound that does not evaluate to a number from the
/// part's arguments (it reads the start state, a value, a participant) is dropped: `lo`
/// becomes 0, `hi` unbounded. A motion whose parts are all interruptible ends when its
/// minimal sender sends: any time.
pub(super) fn motion_window(prog: &Program, m: &Motion) -> Window {
    let mut w = Window::any();
    for (_, app) in &m.parts {
        let prim = prog.prim(app.prim);
        if prim.interruptible {
            continue;
        }
        let args = |v: &Var| -> Option<Value> {
            match v {
                Var::Param(i) => exact::eval(prog, app.args.get(*i)?, &|_: &Var| None).ok(),
                _ => None,
            }
        };
        let num = |e: &crate::hir::Expr| exact::eval(prog, e, &args).ok().and_then(|v| v.num().ok().cloned());
        if let Some(lo) = num(&prim.duration.lo) {
            if lo.lo > w.lo {
                w.lo = lo.lo;
            }
        }
        if let Some(hi) = prim.duration.hi.as_ref().and_then(num) {
            if w.hi.as_ref().is_none_or(|h| hi.hi < *h) {
                w.hi = Some(hi.hi);
            }
        }
    }
    if w.lo.is_negative() {
        w.lo = Rat::zero();
    }
    // An empty window describes a motion that cannot end (E0401, E0408 say so): claim nothing.
    if w.hi.as_ref().is_some_and(|h| *h < w.lo) {
        return Window::any();
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(i: i64) -> Rat {
        Rat::from_integer(i.into())
    }
    fn w(lo: i64, hi: Option<i64>) -> Window {
        Window { lo: r(lo), hi: hi.map(r) }
    }

    #[test]
    fn ends_of_fixed_durations_are_ordered_and_open_ones_are_not() {
        let mut o = Offsets::new();
        o.after(0, &w(5, Some(5))); // 1: a 5 s motion's end
        o.after(0, &w(0, Some(1))); // 2: a motion of at most 1 s
        o.after(0, &w(2, None)); // 3: at least 2 s
        assert!(o.le(2, 1) && !o.le(1, 2));
        assert!(!o.le(1, 3) && !o.le(3, 1) && o.le(2, 3) && o.le(0, 3));
        // The later of 1 and 3 lies in [5, inf] after 0 (that it follows 3, unbounded, is
        // the events' to say); the later of 1 and 2 in [5, 5].
        o.later_of(1, 3); // 4
        assert!(o.le(1, 4) && !o.le(4, 1) && !o.le(4, 3));
        o.later_of(1, 2); // 5
        assert!(o.le(5, 1) && o.le(1, 5));
    }

    #[test]
    fn windows_add_up_along_a_chain_and_only_between_common_anchors() {
        let mut o = Offsets::new();
        o.after(0, &w(0, None)); // 1: unbounded
        o.after(1, &w(2, Some(2))); // 2
        o.after(1, &w(1, Some(2))); // 3
        o.after(3, &w(0, Some(0))); // 4
        assert!(o.le(3, 2) && o.le(4, 2) && !o.le(2, 4));
        o.root(); // 5: unrelated
        assert!(!o.le(5, 2) && !o.le(2, 5));
    }
}
