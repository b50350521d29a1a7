//! Whether a robot's body lies within a footprint that is a predicate (written, or the
//! predicate of a geometric footprint of shapes): Sec 3.1's "FP contains geom(p)" (E0512)
//! decided by interval branch and bound, for the footprints whose predicate turns with the
//! state (`cos(theta)`, `sin(theta)`), where the SMT solver's nonlinear arithmetic leaves
//! the question open.
//!
//! The body is known exactly: a point of a part is `P(s) · q` for `q` a point of the
//! shape in its own frame (a box's `[-l/2, l/2] × [-w/2, w/2] × [0, h]`, a cylinder's disc
//! times `[0, h]`, ...) and `P(s)` the part's pose at the state `s`. The footprint's
//! predicate is rewritten with its point replaced by `P(s) · q`, and its sums
//! normalised (every affine combination collected with exact rational coefficients, so
//! that `(x + cos(th) qx - sin(th) qy) - x` is `cos(th) qx - sin(th) qy`: the robot's
//! position cancels, and with it the dependency that would make every enclosure as wide
//! as the workspace). What is left reads the shape's point `q` and a few state variables
//! (the heading), whose ranges come from the invariant, the precondition and the
//! guarantee. The search then splits that box until, in every piece, the footprint's
//! predicate is true at every point (three-valued interval truth, outward rounded:
//! [`crate::bounds`]), or no point of the shape or no state the contract allows is in it.
//!
//! When every comparison of the rewritten predicate is affine in `q`
//! (`Σ a_i(s) q_i + b(s) op 0`, as a footprint in the heading frame around a body placed
//! by the position is: `cos(th) qx + sin(th) qy <= half`), `q` is not split at all: on a
//! piece of the state, the values of `Σ a_i q_i` over the shape lie within the shape's
//! support (a box: the sum of the products' enclosures; a disc or ball of radius r:
//! `[-r|a|, r|a|]`, Cauchy-Schwarz, with `|a|` bounded above), and only the state is
//! split ([`support_search`]). A disc in a square with 5 mm of slack is decided in a few
//! hundred pieces, where splitting the disc's box took tens of thousands.
//!
//! Sound: the normalisation is an identity of real arithmetic (sums and products by
//! constants are exact rationals); each piece discarded is either one where the predicate
//! holds at every point of the piece, enclosures outward, or one the shape's own predicate
//! or the contract's facts rule out entirely (the same three-valued truth). Variables the
//! rewritten predicate does not read are left at their whole ranges (unbounded if need
//! be), so the answer holds for every state, argument and time the contract allows. A
//! search that runs out of pieces, or a predicate reading a variable with no finite range,
//! leaves the question undecided: the caller asks Z3 (never a pass).

mod refute;
mod solid;
pub use refute::{body_outside, body_outside_somewhere};
pub use solid::{solid_parts_in_predicate, Solids};

use crate::bounds::compiled::{Compiled, VarTable};
use crate::bounds::{self, Interval};
use crate::hir::body::{Body, BodyPart, Pose, Shape};
use crate::hir::expr::{BinOp, Builtin, ExprKind, Sort, UnOp};
use crate::hir::{Expr, Footprint, Loc, PrimId, Program, Slot, Var};
pub(crate) use crate::space::literal::exact_double;
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed, Zero};

mod affine;
mod normalise;
mod tree;

use affine::*;
use normalise::*;
use tree::*;

/// Pieces examined per body part before the question is left undecided.
pub const BUDGET: usize = 200_000;

/// A first pass's pieces per body part: enough for the footprints whose every comparison is
/// affine in the body's point (the support search below decides them in a few hundred
/// pieces), little enough to cost a few milliseconds when it does not decide.
pub const QUICK_BUDGET: usize = 20_000;

/// Why the search did not show containment.
#[derive(Debug)]
pub struct Undecided {
    pub why: String,
    /// The search ran out of pieces (a larger budget may decide it); otherwise it cannot
    /// decide the question at all.
    pub ran_out: bool,
}

impl std::fmt::Display for Undecided {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.why)
    }
}

fn undecided(why: impl Into<String>) -> Undecided {
    Undecided { why: why.into(), ran_out: false }
}

/// Splits the piece `lo..hi` in half along variable `d` and pushes both halves (the lower
/// one searched first). Undecided when the midpoint is no longer strictly inside: the
/// search has reached the resolution of floating point on that variable.
fn bisect(
    stack: &mut Vec<(Vec<f64>, Vec<f64>)>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    d: usize,
    split_vars: &[Var],
) -> Result<(), Undecided> {
    let mid = lo[d] + (hi[d] - lo[d]) / 2.0;
    if !(mid > lo[d] && mid < hi[d]) {
        return Err(undecided(format!(
            "the search reached the resolution of {} without deciding",
            describe(&split_vars[d])
        )));
    }
    let (mut lo2, mut hi1) = (lo.clone(), hi.clone());
    hi1[d] = mid;
    lo2[d] = mid;
    stack.push((lo2, hi));
    stack.push((lo, hi1));
    Ok(())
}

/// Whether the body of `prim`'s kind lies within its footprint at every time and state its
/// contract allows, by the search above, examining at most `budget` pieces per part:
/// `Ok(note)` when shown, `Err(why)` when not.
pub fn body_in_predicate(prog: &Program, prim: PrimId, budget: usize) -> Result<String, Undecided> {
    let p = prog.prim(prim);
    let fp = match &p.footprint {
        Footprint::Predicate(fp) | Footprint::Shapes { region: fp, .. } => &fp.pred,
        Footprint::Everywhere | Footprint::Solid { .. } => return Err(undecided("a footprint without a predicate")),
    };
    let kind = prog.kind(p.kind);
    let body = kind.body.as_ref().ok_or_else(|| undecided("a kind with no body"))?;
    let facts = Facts::of(prog, prim);
    let mut pieces = 0;
    for (k, part) in body.parts.iter().enumerate() {
        pieces += part_within(prog, part, fp, &facts, budget)
            .map_err(|u| Undecided { why: format!("part {} of the body: {}", k + 1, u.why), ..u })?;
    }
    Ok(format!(
        "each part of the body lies within the footprint at every state its contract allows (interval branch and bound, {pieces} pieces)"
    ))
}

/// The contract's facts about the state at a time of the motion, and the ranges they give.
struct Facts {
    /// The guarantee and the invariant (of the state now), read three-valued on a piece.
    now: Vec<Expr>,
    /// Ranges of the variables: the state now, the start state, the clock.
    ranges: std::collections::HashMap<Var, Interval>,
}

impl Facts {
    fn of(prog: &Program, prim: PrimId) -> Facts {
        let p = prog.prim(prim);
        let kind = prog.kind(p.kind);
        let inv = kind.invariant.clone();
        // The start state: the precondition and the invariant, read of `Own` and moved to
        // `Old` (the same variables at the start).
        let mut at_start: Vec<&Expr> = vec![&p.pre];
        at_start.extend(inv.iter());
        let start = bounds::ranges_from(prog, &at_start, &bounds::closed);
        let mut ranges = std::collections::HashMap::new();
        for (v, iv) in &start {
            if let Var::Own(Slot::State(i)) = v {
                ranges.insert(Var::Old(*i), *iv);
            }
        }
        // The clock: within the duration's upper end, over the start's ranges.
        let old = |v: &Var| match v {
            Var::Own(Slot::State(i)) => ranges.get(&Var::Old(*i)).copied(),
            _ => None,
        };
        let hi = p.duration.hi.as_ref().and_then(|h| bounds::eval(prog, h, &old)).map_or(f64::INFINITY, |i| i.hi);
        let clock = Interval::new(0.0, if hi.is_nan() { f64::INFINITY } else { hi.max(0.0) });
        ranges.insert(Var::Clock, clock);
        let mut now: Vec<Expr> = vec![p.guarantee.clone()];
        now.extend(inv);
        let known = ranges.clone();
        let lookup = |v: &Var| known.get(v).copied();
        let refs: Vec<&Expr> = now.iter().collect();
        for (v, iv) in bounds::ranges_from(prog, &refs, &lookup) {
            let iv = match ranges.get(&v) {
                Some(o) => o.meet(iv),
                None => iv,
            };
            ranges.insert(v, iv);
        }
        Facts { now, ranges }
    }
}

/// One body part against a footprint predicate, as both the proof ([`part_within`]) and the
/// refutation (`refute.rs`) read it: the shape in its own frame (a predicate over the point
/// `Var::Point`), its exact box, and the footprint's predicate at the placed point,
/// normalised over that box.
struct PartGoal {
    shape: Expr,
    exact: [(BigRational, BigRational); 3],
    goal: Expr,
}

fn part_goal(prog: &Program, part: &BodyPart, fp: &Expr) -> Result<PartGoal, Undecided> {
    let loc = Loc::default();
    let q: [Expr; 3] = [0, 1, 2].map(|k| Expr { kind: ExprKind::Var(Var::Point(k)), sort: Sort::Real, loc });
    let unplaced = Body { parts: vec![BodyPart { place: None, ..part.clone() }], span: part.span };
    let shape = crate::space::region::region(prog, &unplaced, &q).ok_or_else(|| undecided("a URDF or mesh part"))?;
    let exact =
        shape_box(prog, &part.shape).ok_or_else(|| undecided("a shape whose sizes are not rational constants"))?;
    let placed = match &part.place {
        Some(pose) => place(prog, pose, &q),
        None => q.clone(),
    };
    let goal = crate::hir::expr::map_vars(fp, &mut |v, _| match v {
        Var::Point(i) => placed.get(*i).cloned(),
        _ => None,
    });
    let goal = normalise_bool(prog, &split_abs(&strip(&goal)), &exact);
    Ok(PartGoal { shape, exact, goal })
}

/// The search for one part; `Ok(pieces examined)` when the part lies within `fp`.
fn part_within(prog: &Program, part: &BodyPart, fp: &Expr, facts: &Facts, budget: usize) -> Result<usize, Undecided> {
    let PartGoal { shape, exact, goal } = part_goal(prog, part, fp)?;
    let extent = exact.clone().map(|(l, h)| Interval::new(Interval::of_rational(&l).lo, Interval::of_rational(&h).hi));
    // Every comparison affine in the shape's point: its extremes over the shape are
    // bounded directly (the shape's support), and only the state is split.
    if let Some(support) = Support::of(&part.shape, &exact) {
        let mut table = VarTable::new();
        if let Some(tree) = ATree::new(prog, &goal, &mut table) {
            return support_search(prog, &tree, support, table, facts, budget);
        }
    }
    // The variables to split: those the goal reads (the shape's point among them).
    let mut table = VarTable::new();
    let goal = Tree::new(prog, &goal, &mut table);
    let shape = Tree::new(prog, &strip(&shape), &mut table);
    let split_vars = table.vars().to_vec();
    let now: Vec<Tree> = facts.now.iter().map(|f| Tree::new(prog, &strip(f), &mut table)).collect();
    let mut lo = Vec::new();
    let mut hi = Vec::new();
    for v in &split_vars {
        let iv = match v {
            Var::Point(i) => extent[*i],
            v => match facts.ranges.get(v) {
                Some(iv) => *iv,
                None => return Err(undecided(format!("the footprint reads {}, which has no bound", describe(v)))),
            },
        };
        if !(iv.lo.is_finite() && iv.hi.is_finite()) || iv.lo > iv.hi {
            return Err(undecided(format!("the footprint reads {}, which has no finite bound", describe(v))));
        }
        lo.push(iv.lo);
        hi.push(iv.hi);
    }
    // The other variables (facts only) at their whole ranges.
    let fixed: Vec<Option<Interval>> =
        table.vars()[split_vars.len()..].iter().map(|v| facts.ranges.get(v).copied()).collect();
    let n = split_vars.len();
    // A round shape's coordinates narrowed on each piece to the points of the shape.
    let dim = |i: usize| split_vars.iter().position(|v| *v == Var::Point(i));
    let radius = |r: &Expr| bounds::eval(prog, r, &bounds::closed).filter(Interval::is_finite);
    let round: Option<(Interval, Vec<usize>)> = match &part.shape {
        Shape::Cylinder(r, _) => radius(r).zip([dim(0), dim(1)].into_iter().collect::<Option<Vec<_>>>()),
        Shape::Sphere(r) => radius(r).zip([dim(0), dim(1), dim(2)].into_iter().collect::<Option<Vec<_>>>()),
        _ => None,
    };
    let widths: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| (h - l).max(f64::MIN_POSITIVE)).collect();
    let mut stack = vec![(lo, hi)];
    let mut env: Vec<Option<Interval>> = vec![None; table.len()];
    let mut work = Vec::new();
    let mut pieces = 0usize;
    while let Some((mut lo, mut hi)) = stack.pop() {
        pieces += 1;
        if pieces > budget {
            return Err(Undecided { why: format!("the search ran out after {budget} pieces"), ran_out: true });
        }
        if let Some((r, dims)) = &round {
            if !narrow_round(*r, dims, &mut lo, &mut hi) {
                continue;
            }
        }
        for k in 0..n {
            env[k] = Some(Interval::new(lo[k], hi[k]));
        }
        for (k, f) in fixed.iter().enumerate() {
            env[n + k] = *f;
        }
        if goal.truth(&env, &mut work) == Some(true) {
            continue;
        }
        if shape.truth(&env, &mut work) == Some(false) || now.iter().any(|f| f.truth(&env, &mut work) == Some(false)) {
            continue;
        }
        let Some(d) = choose(&goal, &mut env, &lo, &hi, &widths, &mut work) else {
            return Err(undecided("the footprint does not hold of the body, by its enclosures"));
        };
        bisect(&mut stack, lo, hi, d, &split_vars)?;
    }
    Ok(pieces)
}

/// The search when every comparison of the goal is affine in the shape's point `q`:
/// `Σ a_i(s) q_i + b(s) op 0`. On a piece of the state, the values such a comparison takes
/// over the whole shape lie within `b + support(a)` ([`Support::range`]), so only the state
/// is split (a disc's support is its radius times `|a|`, which no box around the disc
/// bounds as tightly). `Ok(pieces)` when the goal is true at every point of the shape on
/// every piece the contract's facts allow.
fn support_search(
    prog: &Program,
    tree: &ATree,
    support: Support,
    mut table: VarTable,
    facts: &Facts,
    budget: usize,
) -> Result<usize, Undecided> {
    let split_vars = table.vars().to_vec();
    let now: Vec<Tree> = facts.now.iter().map(|f| Tree::new(prog, &strip(f), &mut table)).collect();
    let n = split_vars.len();
    let mut lo = Vec::with_capacity(n);
    let mut hi = Vec::with_capacity(n);
    for v in &split_vars {
        let Some(iv) = facts.ranges.get(v).copied() else {
            return Err(undecided(format!("the footprint reads {}, which has no bound", describe(v))));
        };
        if !(iv.lo.is_finite() && iv.hi.is_finite()) || iv.lo > iv.hi {
            return Err(undecided(format!("the footprint reads {}, which has no finite bound", describe(v))));
        }
        lo.push(iv.lo);
        hi.push(iv.hi);
    }
    let fixed: Vec<Option<Interval>> = table.vars()[n..].iter().map(|v| facts.ranges.get(v).copied()).collect();
    let widths: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| (h - l).max(f64::MIN_POSITIVE)).collect();
    let mut stack = vec![(lo, hi)];
    let mut env: Vec<Option<Interval>> = vec![None; table.len()];
    let mut work = Vec::new();
    let mut pieces = 0usize;
    while let Some((lo, hi)) = stack.pop() {
        pieces += 1;
        if pieces > budget {
            return Err(Undecided { why: format!("the search ran out after {budget} pieces"), ran_out: true });
        }
        for k in 0..n {
            env[k] = Some(Interval::new(lo[k], hi[k]));
        }
        for (k, f) in fixed.iter().enumerate() {
            env[n + k] = *f;
        }
        match tree.truth(&env, &mut work, &support) {
            Some(true) => continue,
            truth => {
                if now.iter().any(|f| f.truth(&env, &mut work) == Some(false)) {
                    continue;
                }
                if truth == Some(false) {
                    // False at every point of the shape at every state of the piece; the
                    // piece may still hold no state the contract allows, which a finer
                    // split would show: left to Z3, never a pass.
                    return Err(undecided("the footprint does not hold of the body at some states, by its enclosures"));
                }
            }
        }
        let Some(d) = (0..n)
            .filter(|d| hi[*d] > lo[*d])
            .max_by(|a, b| ((hi[*a] - lo[*a]) / widths[*a]).total_cmp(&((hi[*b] - lo[*b]) / widths[*b])))
        else {
            return Err(undecided("the footprint does not hold of the body, by its enclosures"));
        };
        bisect(&mut stack, lo, hi, d, &split_vars)?;
    }
    Ok(pieces)
}

/// The shape of a part in its own frame, for [`Support::range`]: its box (outward), and
/// whether it is round in x and y (a cylinder: a disc times `[0, h]`) or in all three (a
/// sphere), with the radius rounded up.
#[derive(Clone, Copy, Debug)]
struct Support {
    round: Round,
    lo: [f64; 3],
    hi: [f64; 3],
}

#[derive(Clone, Copy, Debug)]
enum Round {
    Not,
    Disc(f64),
    Ball(f64),
}

impl Support {
    /// `None` for a capsule (its ends are not a disc times an interval) and the shapes
    /// without exact sizes.
    fn of(shape: &Shape, exact: &[(BigRational, BigRational); 3]) -> Option<Support> {
        let lo = [0, 1, 2].map(|i| Interval::of_rational(&exact[i].0).lo);
        let hi = [0, 1, 2].map(|i| Interval::of_rational(&exact[i].1).hi);
        let r = hi[0];
        let round = match shape {
            Shape::Box(_) => Round::Not,
            Shape::Cylinder(..) => Round::Disc(r),
            Shape::Sphere(_) => Round::Ball(r),
            Shape::Capsule(..) | Shape::Urdf { .. } | Shape::Mesh { .. } => return None,
        };
        (lo.iter().chain(&hi).all(|v| v.is_finite())).then_some(Support { round, lo, hi })
    }

    /// An interval holding `b + Σ a_i q_i` for every coefficient in `a`, constant in `b`
    /// and point `q` of the shape: over a box, the sum of the products' enclosures; over a
    /// disc (ball) of radius r centred on the axis (origin), `|Σ a_i q_i| <= r |a|` by
    /// Cauchy-Schwarz, `|a|` bounded above by the square root of the upper ends of the
    /// squares. Outward rounded throughout.
    fn range(&self, a: [Interval; 3], b: Interval) -> Interval {
        let boxed = |i: usize| a[i] * Interval::new(self.lo[i], self.hi[i]);
        let ball = |r: f64, dims: &[usize]| {
            let sq = dims.iter().fold(Interval::point(0.0), |s, &i| s + a[i].pow(2));
            let norm = Interval::point(sq.hi).sqrt().map_or(f64::INFINITY, |x| x.hi);
            let reach = (Interval::point(norm) * Interval::point(r)).hi;
            if reach.is_nan() {
                Interval::new(f64::NEG_INFINITY, f64::INFINITY)
            } else {
                Interval::new(-reach, reach)
            }
        };
        match self.round {
            Round::Not => b + boxed(0) + boxed(1) + boxed(2),
            Round::Disc(r) => b + ball(r, &[0, 1]) + boxed(2),
            Round::Ball(r) => b + ball(r, &[0, 1, 2]),
        }
    }
}

/// Narrows the coordinates `dims` of a piece to the points of the ball (or disc) of radius
/// `r`: `q_d^2 <= r^2 - Σ_{e != d} q_e^2`, each bound outward rounded. `false` when the
/// piece holds no point of it.
fn narrow_round(r: Interval, dims: &[usize], lo: &mut [f64], hi: &mut [f64]) -> bool {
    let r2 = r.pow(2).hi;
    for &d in dims {
        let mut others = Interval::point(0.0);
        for &e in dims.iter().filter(|e| **e != d) {
            others = others + Interval::new(lo[e], hi[e]).pow(2);
        }
        let room = (Interval::point(r2) + -Interval::point(others.lo)).hi;
        if room.is_nan() || room < 0.0 {
            return false;
        }
        let Some(s) = Interval::point(room).sqrt() else { return false };
        lo[d] = lo[d].max(-s.hi);
        hi[d] = hi[d].min(s.hi);
        if lo[d] > hi[d] {
            return false;
        }
    }
    true
}

/// The dimension to split: the one whose halving narrows most the first comparison of the
/// goal left undecided (its two sides' widths with the dimension pinned at its midpoint),
/// else the one widest relative to its whole range. `None` with no dimension left.
fn choose(
    goal: &Tree,
    env: &mut [Option<Interval>],
    lo: &[f64],
    hi: &[f64],
    widths: &[f64],
    work: &mut Vec<Option<Interval>>,
) -> Option<usize> {
    let n = lo.len();
    let width = |a: Option<Interval>, b: Option<Interval>| match (a, b) {
        (Some(x), Some(y)) => (x.hi - x.lo) + (y.hi - y.lo),
        _ => f64::INFINITY,
    };
    if let Some(Tree::Cmp(_, a, b)) = goal.undecided(env, work) {
        let before = width(a.eval(env, work), b.eval(env, work));
        let mut best: Option<(usize, f64)> = None;
        for d in 0..n {
            if hi[d] <= lo[d] {
                continue;
            }
            let keep = env[d];
            env[d] = Some(Interval::point(lo[d] + (hi[d] - lo[d]) / 2.0));
            let w = width(a.eval(env, work), b.eval(env, work));
            env[d] = keep;
            if w < before && best.is_none_or(|(_, x)| w < x) {
                best = Some((d, w));
            }
        }
        if let Some((d, _)) = best {
            return Some(d);
        }
    }
    (0..n)
        .filter(|d| hi[*d] > lo[*d])
        .max_by(|a, b| ((hi[*a] - lo[*a]) / widths[*a]).total_cmp(&((hi[*b] - lo[*b]) / widths[*b])))
}

fn describe(v: &Var) -> String {
    match v {
        Var::Point(i) => format!("the shape's {} coordinate", ["x", "y", "z"].get(*i).unwrap_or(&"?")),
        Var::Own(Slot::State(i)) => format!("state variable {}", i + 1),
        Var::Old(i) => format!("the start value of state variable {}", i + 1),
        Var::Param(i) => format!("parameter {}", i + 1),
        Var::Clock => "the clock".into(),
        _ => "a variable".into(),
    }
}

/// Whether the containment question of `prim` reads the cosine or sine of a variable (the
/// footprint's own, or its body placed by a turning pose): the questions Z3's nonlinear
/// arithmetic decides only partially, for which [`body_in_predicate`] is tried first.
pub fn turns(prog: &Program, prim: PrimId) -> bool {
    let p = prog.prim(prim);
    let trig_of_var = |e: &Expr| {
        e.any(|n| {
            matches!(&n.kind, ExprKind::Call(Builtin::Sin | Builtin::Cos, args)
                if args.iter().any(|a| crate::hir::expr::mentions(a, &|v| !matches!(v, Var::Const(_)))))
        })
    };
    let fp = p.footprint.predicate().is_some_and(|fp| trig_of_var(&fp.pred));
    let body = prog.kind(p.kind).body.as_ref().is_some_and(|b| {
        b.parts.iter().any(|part| {
            part.place.as_ref().is_some_and(|pose| {
                pose.args[3..].iter().any(|a| crate::hir::expr::mentions(a, &|v| !matches!(v, Var::Const(_))))
            })
        })
    });
    fp || body
}

#[cfg(test)]
mod tests;
