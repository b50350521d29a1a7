//! The contraction of one box of configurations (the search's hot loop): each run's
//! guarantee and invariant narrow the dimensions of its participant, by bounds read off
//! `x <= e` conjuncts ([`crate::bounds::ranges_from`]), bounds affine in one start value
//! (`affine.rs`) and sums of squares (`squares.rs`).
//!
//! Everything that depends only on the question (which conjuncts give bounds, the
//! expressions' trees, the ranges of the start state, the parameters and the carriers) is
//! compiled once per question ([`RunContraction::new`], [`crate::bounds::compiled`]);
//! a box then costs a few interval operations per conjunct. The enclosures are those the
//! tree-walking evaluator gives for the same ranges (`bounds::compiled`'s module doc and
//! its test), so the argument of each rule (in its module) is unchanged: every
//! configuration of the box that satisfies the constraints stays in the narrowed box.

use super::affine::{self, Side};
use super::squares;
use crate::bounds::compiled::{Compiled, Facts, Scratch};
use crate::bounds::Interval;
use crate::hir::{Expr, Program, Var};

/// Where a variable's range comes from in a box.
#[derive(Clone, Copy, Debug)]
pub(super) enum Leaf {
    /// The box's dimension `i`.
    Dim(usize),
    /// Fixed for the whole question (`None`: unbounded).
    Fixed(Option<Interval>),
}

/// `own op e`, `e` affine in the start value `old` (numbers of [`RunContraction::facts`]).
struct AffineRule {
    own: usize,
    side: Side,
    e: Compiled,
    old: usize,
}

/// `Σ v^2 <= e` (`upper`) or `>=`: the squared variables' dimensions and numbers.
struct SquaresRule {
    dims: Vec<usize>,
    vars: Vec<usize>,
    e: Compiled,
    upper: bool,
}

/// One run's contraction, compiled.
pub(super) struct RunContraction {
    facts: Facts,
    leaves: Vec<Leaf>,
    affine: Vec<AffineRule>,
    squares: Vec<SquaresRule>,
    /// The dimensions this run narrows: (dimension, number of its `Own` variable).
    targets: Vec<(usize, usize)>,
}

impl RunContraction {
    /// `facts`: the run's guarantee and invariant. `dim_of(v)`: the dimension of an `Own`
    /// variable of the run's participant, if it is one; `leaf(v)`: where any variable's
    /// range comes from.
    pub(super) fn new(
        prog: &Program,
        facts: &[&Expr],
        dim_of: &dyn Fn(&Var) -> Option<usize>,
        leaf: &dyn Fn(&Var) -> Leaf,
    ) -> RunContraction {
        let mut compiled = Facts::new(prog, facts);
        let affine = affine::affine_bounds(facts)
            .into_iter()
            .map(|ab| AffineRule {
                own: compiled.index(&ab.own),
                side: ab.side,
                e: compiled.compile(prog, ab.e),
                old: compiled.index(&ab.old),
            })
            .collect();
        let squares = squares::squares_bounds(facts)
            .into_iter()
            .filter_map(|sb| {
                let dims: Option<Vec<usize>> = sb.vars.iter().map(dim_of).collect();
                Some(SquaresRule {
                    dims: dims?,
                    vars: sb.vars.iter().map(|v| compiled.index(v)).collect(),
                    e: compiled.compile(prog, sb.e),
                    upper: sb.upper,
                })
            })
            .collect();
        let vars = compiled.table().vars().to_vec();
        let leaves = vars.iter().map(leaf).collect();
        let targets = vars.iter().enumerate().filter_map(|(k, v)| Some((dim_of(v)?, k))).collect();
        RunContraction { facts: compiled, leaves, affine, squares, targets }
    }

    /// Narrows `[lo, hi]` in place; `false` when no configuration of it satisfies the
    /// run's constraints.
    pub(super) fn narrow(&self, lo: &mut [f64], hi: &mut [f64], work: &mut Scratch) -> bool {
        let start: Vec<Option<Interval>> = self
            .leaves
            .iter()
            .map(|l| match *l {
                Leaf::Dim(i) => Some(Interval::new(lo[i], hi[i])),
                Leaf::Fixed(iv) => iv,
            })
            .collect();
        let mut got = self.facts.ranges(&start, work);
        let meet = |got: &mut Vec<Option<Interval>>, k: usize, iv: Interval| {
            got[k] = Some(got[k].map_or(iv, |o| o.meet(iv)));
        };
        // Bounds affine in one start value, evaluated at its two ends (affine.rs).
        let mut pinned = start.clone();
        for ab in &self.affine {
            let Some(Interval { lo: l, hi: h }) = start[ab.old] else { continue };
            if !(l.is_finite() && h.is_finite()) {
                continue;
            }
            let mut at = |x: f64| {
                pinned[ab.old] = Some(Interval::point(x));
                let v = ab.e.eval(&pinned, &mut work.stack);
                pinned[ab.old] = start[ab.old];
                v
            };
            let (Some(a), Some(b)) = (at(l), at(h)) else { continue };
            let hull = Interval { lo: a.lo.min(b.lo), hi: a.hi.max(b.hi) };
            if hull.lo.is_nan() || hull.hi.is_nan() {
                continue;
            }
            let iv = match ab.side {
                Side::Upper => Interval { lo: f64::NEG_INFINITY, hi: hull.hi },
                Side::Lower => Interval { lo: hull.lo, hi: f64::INFINITY },
                Side::Both => hull,
            };
            meet(&mut got, ab.own, iv);
        }
        // Sums of squares (the rover's annulus), over the box narrowed so far (squares.rs).
        for sb in &self.squares {
            let Some(e) = sb.e.eval(&start, &mut work.stack) else { continue };
            let bound = if sb.upper { e.hi } else { e.lo };
            let mut ranges: Vec<(f64, f64)> = sb
                .dims
                .iter()
                .zip(&sb.vars)
                .map(|(&i, &v)| match got[v] {
                    Some(iv) => (lo[i].max(iv.lo), hi[i].min(iv.hi)),
                    None => (lo[i], hi[i]),
                })
                .collect();
            if ranges.iter().any(|(l, h)| l.is_nan() || h.is_nan()) {
                continue;
            }
            if !squares::narrow(&mut ranges, bound, sb.upper) {
                return false;
            }
            for (&v, (l, h)) in sb.vars.iter().zip(ranges) {
                meet(&mut got, v, Interval { lo: l, hi: h });
            }
        }
        for &(i, k) in &self.targets {
            if let Some(iv) = got[k] {
                if iv.lo.is_nan() || iv.hi.is_nan() {
                    continue;
                }
                lo[i] = lo[i].max(iv.lo);
                hi[i] = hi[i].min(iv.hi);
                if lo[i] > hi[i] {
                    return false;
                }
            }
        }
        true
    }
}
