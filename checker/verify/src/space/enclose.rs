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

mod solid;
pub use solid::{solid_parts_in_predicate, Solids};

use crate::bounds::compiled::{Compiled, VarTable};
use crate::bounds::{self, Interval};
use crate::hir::body::{Body, Part, Pose, Shape};
use crate::hir::expr::{BinOp, Builtin, ExprKind, Sort, UnOp};
use crate::hir::{Expr, Footprint, Loc, PrimId, Program, Slot, Var};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};

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

/// The search for one part; `Ok(pieces examined)` when the part lies within `fp`.
fn part_within(prog: &Program, part: &Part, fp: &Expr, facts: &Facts, budget: usize) -> Result<usize, Undecided> {
    let loc = Loc::default();
    let q: [Expr; 3] = [0, 1, 2].map(|k| Expr { kind: ExprKind::Var(Var::Point(k)), sort: Sort::Real, loc });
    // The shape in its own frame, and a box around it.
    let unplaced = Body { parts: vec![Part { place: None, ..part.clone() }], span: part.span };
    let shape = crate::space::region::region(prog, &unplaced, &q).ok_or_else(|| undecided("a URDF or mesh part"))?;
    let exact =
        shape_box(prog, &part.shape).ok_or_else(|| undecided("a shape whose sizes are not rational constants"))?;
    let extent = exact.clone().map(|(l, h)| Interval::new(Interval::of_rational(&l).lo, Interval::of_rational(&h).hi));
    // The footprint's predicate at the placed point, normalised.
    let placed = match &part.place {
        Some(pose) => place(prog, pose, &q),
        None => q.clone(),
    };
    let goal = crate::hir::expr::map_vars(fp, &mut |v, _| match v {
        Var::Point(i) => placed.get(*i).cloned(),
        _ => None,
    });
    let goal = normalise_bool(prog, &split_abs(&strip(&goal)), &exact);
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

/// A goal whose comparisons are affine in the shape's point, compiled over the state.
enum ATree {
    Const(bool),
    Not(Box<ATree>),
    And(Box<ATree>, Box<ATree>),
    Or(Box<ATree>, Box<ATree>),
    /// `Σ a_i q_i + b op 0` (a missing coefficient is 0).
    Cmp {
        op: BinOp,
        a: [Option<Compiled>; 3],
        b: Compiled,
    },
}

/// `Σ a_i q_i + b`, each coefficient an expression free of the point (`None`: 0).
type Affine = ([Option<Expr>; 3], Option<Expr>);

impl ATree {
    /// `None` unless every comparison of `e` is affine in the shape's point.
    fn new(prog: &Program, e: &Expr, table: &mut VarTable) -> Option<ATree> {
        crate::stack::deep(|| {
            Some(match &e.kind {
                ExprKind::Bool(b) => ATree::Const(*b),
                ExprKind::Unary(UnOp::Not, a) => ATree::Not(Box::new(ATree::new(prog, a, table)?)),
                ExprKind::Binary(BinOp::And, a, b) => {
                    ATree::And(Box::new(ATree::new(prog, a, table)?), Box::new(ATree::new(prog, b, table)?))
                }
                ExprKind::Binary(BinOp::Or, a, b) => {
                    ATree::Or(Box::new(ATree::new(prog, a, table)?), Box::new(ATree::new(prog, b, table)?))
                }
                ExprKind::Binary(BinOp::Implies, a, b) => ATree::Or(
                    Box::new(ATree::Not(Box::new(ATree::new(prog, a, table)?))),
                    Box::new(ATree::new(prog, b, table)?),
                ),
                ExprKind::Binary(
                    op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne),
                    l,
                    r,
                ) if l.sort.is_numeric() && r.sort.is_numeric() => {
                    let (a, b) = affine(&bin(BinOp::Sub, (**l).clone(), (**r).clone()))?;
                    let a = a.map(|c| c.map(|c| Compiled::new(prog, &c, table)));
                    let b = Compiled::new(prog, &b.unwrap_or_else(|| int(0)), table);
                    ATree::Cmp { op: *op, a, b }
                }
                _ => return None,
            })
        })
    }

    /// `Some(v)` when the goal is `v` at every point of the shape, at every state of `env`.
    fn truth(&self, env: &[Option<Interval>], work: &mut Vec<Option<Interval>>, support: &Support) -> Option<bool> {
        match self {
            ATree::Const(b) => Some(*b),
            ATree::Not(a) => a.truth(env, work, support).map(|b| !b),
            ATree::And(a, b) => match a.truth(env, work, support) {
                Some(false) => Some(false),
                x => match (x, b.truth(env, work, support)) {
                    (_, Some(false)) => Some(false),
                    (Some(true), Some(true)) => Some(true),
                    _ => None,
                },
            },
            ATree::Or(a, b) => match a.truth(env, work, support) {
                Some(true) => Some(true),
                x => match (x, b.truth(env, work, support)) {
                    (_, Some(true)) => Some(true),
                    (Some(false), Some(false)) => Some(false),
                    _ => None,
                },
            },
            ATree::Cmp { op, a, b } => {
                let b = b.eval(env, work)?;
                let mut coef = [Interval::point(0.0); 3];
                for (c, x) in coef.iter_mut().zip(a) {
                    if let Some(x) = x {
                        *c = x.eval(env, work)?;
                    }
                }
                super::truth::compare(*op, support.range(coef, b), Interval::point(0.0))
            }
        }
    }
}

/// `e` as `Σ a_i q_i + b` with every `a_i` and `b` free of the point, by the identities of
/// sums and of products and quotients by a factor free of the point; `None` otherwise.
fn affine(e: &Expr) -> Option<Affine> {
    let has_q = |e: &Expr| crate::hir::expr::mentions(e, &|v| matches!(v, Var::Point(_)));
    if !has_q(e) {
        return Some(([None, None, None], Some(e.clone())));
    }
    let add = |x: Option<Expr>, y: Option<Expr>| match (x, y) {
        (Some(x), Some(y)) => Some(bin(BinOp::Add, x, y)),
        (x, None) => x,
        (None, y) => y,
    };
    let map = |(a, b): Affine, f: &dyn Fn(Expr) -> Expr| -> Affine { (a.map(|c| c.map(f)), b.map(f)) };
    let neg = |x: Expr| Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(x)), sort: Sort::Real, loc: Loc::default() };
    crate::stack::deep(|| match &e.kind {
        ExprKind::Var(Var::Point(i)) if *i < 3 => {
            let mut a = [None, None, None];
            a[*i] = Some(int(1));
            Some((a, None))
        }
        ExprKind::Unary(UnOp::Neg, x) => Some(map(affine(x)?, &neg)),
        ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub), x, y) => {
            let (ax, bx) = affine(x)?;
            let mut y = affine(y)?;
            if *op == BinOp::Sub {
                y = map(y, &neg);
            }
            let (ay, by) = y;
            let [x0, x1, x2] = ax;
            let [y0, y1, y2] = ay;
            Some(([add(x0, y0), add(x1, y1), add(x2, y2)], add(bx, by)))
        }
        ExprKind::Binary(BinOp::Mul, x, y) if !has_q(x) => {
            Some(map(affine(y)?, &|t| bin(BinOp::Mul, (**x).clone(), t)))
        }
        ExprKind::Binary(BinOp::Mul, x, y) if !has_q(y) => {
            Some(map(affine(x)?, &|t| bin(BinOp::Mul, t, (**y).clone())))
        }
        ExprKind::Binary(BinOp::Div, x, y) if !has_q(y) => {
            Some(map(affine(x)?, &|t| bin(BinOp::Div, t, (**y).clone())))
        }
        _ => None,
    })
}

/// `e` with every comparison `abs(u) <= v` (`<`, and `v >= abs(u)`, `v > abs(u)`) written
/// `u <= v && -u <= v`: the same truth at every point (`abs` is total), and two comparisons
/// each affine where `u` and `v` are.
fn split_abs(e: &Expr) -> Expr {
    let neg =
        |x: &Expr| Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(x.clone())), sort: x.sort.clone(), loc: x.loc };
    let abs_of = |x: &Expr| match &x.kind {
        ExprKind::Call(Builtin::Abs, args) if args.len() == 1 => Some(args[0].clone()),
        _ => None,
    };
    crate::stack::deep(|| match &e.kind {
        ExprKind::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => bin(*op, split_abs(a), split_abs(b)),
        ExprKind::Unary(UnOp::Not, a) => Expr { kind: ExprKind::Unary(UnOp::Not, Box::new(split_abs(a))), ..e.clone() },
        ExprKind::Binary(op @ (BinOp::Le | BinOp::Lt), a, b) if abs_of(a).is_some() => {
            let u = abs_of(a).unwrap_or_else(|| (**a).clone());
            bin(BinOp::And, bin(*op, u.clone(), (**b).clone()), bin(*op, neg(&u), (**b).clone()))
        }
        ExprKind::Binary(op @ (BinOp::Ge | BinOp::Gt), a, b) if abs_of(b).is_some() => {
            let u = abs_of(b).unwrap_or_else(|| (**b).clone());
            bin(BinOp::And, bin(*op, (**a).clone(), u.clone()), bin(*op, (**a).clone(), neg(&u)))
        }
        _ => e.clone(),
    })
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

/// The box around the shape in its own frame, exactly (mochi's conventions: boxes,
/// cylinders and capsules stand on z = 0, centred in x and y; a sphere is centred on the
/// origin). `None` unless every size is a rational constant.
fn shape_box(prog: &Program, shape: &Shape) -> Option<[(BigRational, BigRational); 3]> {
    let size = |e: &Expr| bounds::exact(prog, e).filter(|q| !q.is_negative());
    let two = BigRational::from_integer(BigInt::from(2));
    let sym = |h: BigRational| (-h.clone(), h);
    Some(match shape {
        Shape::Box([x, y, z]) => [sym(size(x)? / &two), sym(size(y)? / &two), (BigRational::zero(), size(z)?)],
        Shape::Sphere(r) => {
            let r = size(r)?;
            [sym(r.clone()), sym(r.clone()), sym(r)]
        }
        Shape::Cylinder(r, h) | Shape::Capsule(r, h) => {
            let r = size(r)?;
            [sym(r.clone()), sym(r), (BigRational::zero(), size(h)?)]
        }
        Shape::Urdf { .. } | Shape::Mesh { .. } => return None,
    })
}

/// `t + Rz(yaw) Ry(pitch) Rx(roll) q` for `pose(t, roll, pitch, yaw)`: the point `q` of the
/// part's frame in its owner's frame (the inverse of [`super::region::to_part_frame`]). An
/// angle that is exactly 0 is skipped; a quarter turn rotates by 0 and ±1.
fn place(prog: &Program, pose: &Pose, q: &[Expr; 3]) -> [Expr; 3] {
    let mut v = q.clone();
    // Roll about x (y, z), then pitch about y (z, x), then yaw about z (x, y).
    for (idx, (a, b)) in [(3usize, (1usize, 2usize)), (4, (2, 0)), (5, (0, 1))] {
        let angle = &pose.args[idx];
        if bounds::exact(prog, angle).is_some_and(|q| q.is_zero()) {
            continue;
        }
        let (c, s) = match bounds::quarter_turn(prog, angle) {
            Some((c, s)) => (int(c), int(s)),
            None => (call(Builtin::Cos, angle), call(Builtin::Sin, angle)),
        };
        let (x, y) = (v[a].clone(), v[b].clone());
        // x' = c x - s y, y' = s x + c y.
        v[a] = bin(BinOp::Sub, bin(BinOp::Mul, c.clone(), x.clone()), bin(BinOp::Mul, s.clone(), y.clone()));
        v[b] = bin(BinOp::Add, bin(BinOp::Mul, s, x), bin(BinOp::Mul, c, y));
    }
    for (k, c) in v.iter_mut().enumerate() {
        *c = bin(BinOp::Add, pose.args[k].clone(), c.clone());
    }
    v
}

fn int(n: i64) -> Expr {
    Expr { kind: ExprKind::Int(n), sort: Sort::Int, loc: Loc::default() }
}

fn call(f: Builtin, a: &Expr) -> Expr {
    Expr { kind: ExprKind::Call(f, vec![a.clone()]), sort: Sort::Real, loc: Loc::default() }
}

fn bin(op: BinOp, a: Expr, b: Expr) -> Expr {
    let sort = if matches!(
        op,
        BinOp::And | BinOp::Or | BinOp::Implies | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne
    ) {
        Sort::Bool
    } else {
        Sort::Real
    };
    Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort, loc: Loc::default() }
}

/// `e` with every location erased, so that equal terms compare equal wherever written.
fn strip(e: &Expr) -> Expr {
    e.map(&mut |n| Expr { loc: Loc::default(), ..n })
}

// ---- normalisation: affine combinations with exact coefficients ----------------------

/// `c + Σ k_i · atom_i`: an atom is a variable or a term that is not a sum (a product of
/// two non-constant terms, a power, a call, ...), its own arguments normalised.
#[derive(Clone, Debug)]
struct Lin {
    c: BigRational,
    terms: Vec<(Expr, BigRational)>,
}

impl Lin {
    fn constant(c: BigRational) -> Lin {
        Lin { c, terms: Vec::new() }
    }

    fn atom(e: Expr) -> Lin {
        Lin { c: BigRational::zero(), terms: vec![(e, BigRational::one())] }
    }

    fn scale(mut self, k: &BigRational) -> Lin {
        self.c *= k;
        for (_, x) in &mut self.terms {
            *x *= k;
        }
        self.terms.retain(|(_, x)| !x.is_zero());
        self
    }

    fn add(mut self, o: Lin) -> Lin {
        self.c += o.c;
        for (e, k) in o.terms {
            match self.terms.iter_mut().find(|(a, _)| *a == e) {
                Some((_, x)) => *x += k,
                None => self.terms.push((e, k)),
            }
        }
        self.terms.retain(|(_, x)| !x.is_zero());
        self
    }

    fn as_const(&self) -> Option<&BigRational> {
        self.terms.is_empty().then_some(&self.c)
    }

    /// Back to a term: `Σ k_i · atom_i + c`.
    fn expr(&self) -> Expr {
        let mut out: Option<Expr> = None;
        for (a, k) in &self.terms {
            let t = if k.is_one() {
                a.clone()
            } else if (-k).is_one() {
                Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(a.clone())), sort: Sort::Real, loc: Loc::default() }
            } else {
                bin(BinOp::Mul, rational(k), a.clone())
            };
            out = Some(match out {
                Some(s) => bin(BinOp::Add, s, t),
                None => t,
            });
        }
        match out {
            Some(s) if self.c.is_zero() => s,
            Some(s) => bin(BinOp::Add, s, rational(&self.c)),
            None => rational(&self.c),
        }
    }
}

/// The exact rational `q` as a term (a quotient of two integer literals).
fn rational(q: &BigRational) -> Expr {
    let lit = |n: &BigInt| match n.to_i64() {
        Some(i) => int(i),
        None => Expr { kind: ExprKind::Real(n.to_string()), sort: Sort::Real, loc: Loc::default() },
    };
    let num = lit(&q.numer().abs());
    let e = if q.denom().is_one() { num } else { bin(BinOp::Div, num, lit(q.denom())) };
    if q.is_negative() {
        Expr { kind: ExprKind::Unary(UnOp::Neg, Box::new(e)), sort: Sort::Real, loc: Loc::default() }
    } else {
        e
    }
}

fn lin(prog: &Program, e: &Expr) -> Lin {
    crate::stack::deep(|| lin_inner(prog, e))
}

fn lin_inner(prog: &Program, e: &Expr) -> Lin {
    if let Some(q) = bounds::exact(prog, e) {
        return Lin::constant(q);
    }
    match &e.kind {
        ExprKind::Unary(UnOp::Neg, a) => lin(prog, a).scale(&-BigRational::one()),
        ExprKind::Binary(BinOp::Add, a, b) => lin(prog, a).add(lin(prog, b)),
        ExprKind::Binary(BinOp::Sub, a, b) => lin(prog, a).add(lin(prog, b).scale(&-BigRational::one())),
        ExprKind::Binary(BinOp::Mul, a, b) => {
            let (x, y) = (lin(prog, a), lin(prog, b));
            match (x.as_const(), y.as_const()) {
                (Some(k), _) => {
                    let k = k.clone();
                    y.scale(&k)
                }
                (_, Some(k)) => {
                    let k = k.clone();
                    x.scale(&k)
                }
                _ => Lin::atom(bin(BinOp::Mul, x.expr(), y.expr())),
            }
        }
        ExprKind::Binary(BinOp::Div, a, b) => {
            let (x, y) = (lin(prog, a), lin(prog, b));
            match y.as_const() {
                Some(k) if !k.is_zero() => {
                    let k = k.recip();
                    x.scale(&k)
                }
                _ => Lin::atom(bin(BinOp::Div, x.expr(), y.expr())),
            }
        }
        ExprKind::Binary(BinOp::Pow, a, n) => Lin::atom(Expr {
            kind: ExprKind::Binary(BinOp::Pow, Box::new(lin(prog, a).expr()), n.clone()),
            ..e.clone()
        }),
        ExprKind::Call(f, args) if e.sort.is_numeric() => Lin::atom(Expr {
            kind: ExprKind::Call(
                *f,
                args.iter().map(|a| if a.sort.is_numeric() { lin(prog, a).expr() } else { a.clone() }).collect(),
            ),
            ..e.clone()
        }),
        _ => Lin::atom(e.clone()),
    }
}

/// A predicate with each comparison `a op b` written `a - b op 0`, normalised. A
/// comparison affine in the shape's point alone (`pz <= h`: the footprint's floor and
/// ceiling) is decided exactly over the shape's box `extent` (its extreme value over the
/// box, in rationals) and becomes `true` when it holds there: faces that touch exactly are
/// beyond any outward enclosure.
fn normalise_bool(prog: &Program, e: &Expr, extent: &[(BigRational, BigRational); 3]) -> Expr {
    crate::stack::deep(|| match &e.kind {
        ExprKind::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => {
            bin(*op, normalise_bool(prog, a, extent), normalise_bool(prog, b, extent))
        }
        ExprKind::Unary(UnOp::Not, a) => {
            Expr { kind: ExprKind::Unary(UnOp::Not, Box::new(normalise_bool(prog, a, extent))), ..e.clone() }
        }
        ExprKind::Binary(op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne), a, b)
            if a.sort.is_numeric() && b.sort.is_numeric() =>
        {
            let d = lin(prog, a).add(lin(prog, b).scale(&-BigRational::one()));
            if holds_on_box(&d, *op, extent) {
                return Expr::bool(true, Loc::default());
            }
            bin(*op, d.expr(), int(0))
        }
        _ => e.clone(),
    })
}

/// Whether `d op 0` holds at every point of the box, `d` affine in the point's coordinates
/// only (exact: the extreme of an affine function over a box is at the corner its
/// coefficients' signs pick).
fn holds_on_box(d: &Lin, op: BinOp, extent: &[(BigRational, BigRational); 3]) -> bool {
    let (mut lo, mut hi) = (d.c.clone(), d.c.clone());
    for (atom, k) in &d.terms {
        let ExprKind::Var(Var::Point(i)) = atom.kind else { return false };
        let Some((l, h)) = extent.get(i) else { return false };
        let (a, b) = (k * l, k * h);
        if a <= b {
            lo += a;
            hi += b;
        } else {
            lo += b;
            hi += a;
        }
    }
    let zero = BigRational::zero();
    match op {
        BinOp::Le => hi <= zero,
        BinOp::Lt => hi < zero,
        BinOp::Ge => lo >= zero,
        BinOp::Gt => lo > zero,
        _ => false,
    }
}

// ---- three-valued truth on compiled terms --------------------------------------------

/// A predicate compiled for many three-valued evaluations (the rules of
/// [`crate::space::truth`], on [`Compiled`] terms).
enum Tree {
    Const(bool),
    Not(Box<Tree>),
    And(Box<Tree>, Box<Tree>),
    Or(Box<Tree>, Box<Tree>),
    Cmp(BinOp, Compiled, Compiled),
    Unknown,
}

impl Tree {
    fn new(prog: &Program, e: &Expr, table: &mut VarTable) -> Tree {
        crate::stack::deep(|| match &e.kind {
            ExprKind::Bool(b) => Tree::Const(*b),
            ExprKind::Unary(UnOp::Not, a) => Tree::Not(Box::new(Tree::new(prog, a, table))),
            ExprKind::Binary(BinOp::And, a, b) => {
                Tree::And(Box::new(Tree::new(prog, a, table)), Box::new(Tree::new(prog, b, table)))
            }
            ExprKind::Binary(BinOp::Or, a, b) => {
                Tree::Or(Box::new(Tree::new(prog, a, table)), Box::new(Tree::new(prog, b, table)))
            }
            ExprKind::Binary(BinOp::Implies, a, b) => {
                Tree::Or(Box::new(Tree::Not(Box::new(Tree::new(prog, a, table)))), Box::new(Tree::new(prog, b, table)))
            }
            ExprKind::Binary(op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne), a, b)
                if a.sort.is_numeric() && b.sort.is_numeric() =>
            {
                Tree::Cmp(*op, Compiled::new(prog, a, table), Compiled::new(prog, b, table))
            }
            _ => Tree::Unknown,
        })
    }

    /// The first comparison (in the order the connectives read them) whose truth is not
    /// settled on the box, if the predicate's is not.
    fn undecided(&self, env: &[Option<Interval>], work: &mut Vec<Option<Interval>>) -> Option<&Tree> {
        match self {
            Tree::Const(_) | Tree::Unknown => None,
            Tree::Not(a) => a.undecided(env, work),
            Tree::And(a, b) | Tree::Or(a, b) => match a.truth(env, work) {
                None => a.undecided(env, work),
                Some(_) => b.undecided(env, work),
            },
            Tree::Cmp(..) => (self.truth(env, work).is_none()).then_some(self),
        }
    }

    /// `Some(b)` when the predicate is `b` at every point of the box `env`.
    fn truth(&self, env: &[Option<Interval>], work: &mut Vec<Option<Interval>>) -> Option<bool> {
        match self {
            Tree::Const(b) => Some(*b),
            Tree::Unknown => None,
            Tree::Not(a) => a.truth(env, work).map(|b| !b),
            Tree::And(a, b) => match a.truth(env, work) {
                Some(false) => Some(false),
                x => match (x, b.truth(env, work)) {
                    (_, Some(false)) => Some(false),
                    (Some(true), Some(true)) => Some(true),
                    _ => None,
                },
            },
            Tree::Or(a, b) => match a.truth(env, work) {
                Some(true) => Some(true),
                x => match (x, b.truth(env, work)) {
                    (_, Some(true)) => Some(true),
                    (Some(false), Some(false)) => Some(false),
                    _ => None,
                },
            },
            Tree::Cmp(op, a, b) => {
                let (x, y) = (a.eval(env, work)?, b.eval(env, work)?);
                super::truth::compare(*op, x, y)
            }
        }
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

/// The double `v` as an exact rational term (a quotient of integer literals); `None` for
/// an infinite or NaN value.
pub(crate) fn exact_double(v: f64, loc: Loc) -> Option<Expr> {
    let q = BigRational::from_float(v)?;
    let e = rational(&q);
    Some(e.map(&mut |n| Expr { loc, ..n }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The answer of the search for primitive `m` of a kind with `geometry` and `footprint`.
    fn search(geometry: &str, footprint: &str) -> Result<String, String> {
        search_within(geometry, footprint, BUDGET).map_err(|u| u.why)
    }

    /// The same, with at most `budget` pieces per part.
    fn search_within(geometry: &str, footprint: &str, budget: usize) -> Result<String, Undecided> {
        let src = format!(
            "robot R {{ state x: real, y: real, theta: real; geometry: {geometry};
               invariant: -10 <= x <= 10 && -10 <= y <= 10 && -pi <= theta <= pi; }}
             motion R.m(xf: real, d: real) {{ interruptible: false; pre: d > 0 && x <= xf;
               guarantee: old(x) <= x && x <= xf && y == old(y) && theta == old(theta);
               post: x == xf && y == old(y) && theta == old(theta);
               footprint(px, py, pz): {footprint}; duration: [d, d]; }}
             system S {{ participant A: R {{ init: x == 0 && y == 0 && theta == 0.3; }} }}
             choreography G = dt<A: m(1, 5)>. end;"
        );
        let (prog, d) = crate::lower::tests::lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let prim = PrimId(prog.prims.iter().position(|p| p.name == "m").expect("m") as u32);
        assert!(turns(&prog, prim));
        body_in_predicate(&prog, prim, budget)
    }

    const SQUARE: &str = "abs(cos(theta) * (px - x) + sin(theta) * (py - y)) <= HALF
        && abs(cos(theta) * (py - y) - sin(theta) * (px - x)) <= HALF && 0 <= pz <= 0.08";

    #[test]
    fn a_disc_within_a_square_turned_with_the_heading() {
        let r = search("cylinder(0.25, 0.08) at pose(x, y, 0)", &SQUARE.replace("HALF", "0.26"));
        assert!(r.is_ok(), "{r:?}");
        let r = search("cylinder(0.25, 0.08) at pose(x, y, 0)", &SQUARE.replace("HALF", "0.24"));
        assert!(r.is_err(), "{r:?}");
    }

    #[test]
    fn a_turned_box_within_a_disc() {
        let disc = "(px - x)^2 + (py - y)^2 <= R^2 && 0 <= pz <= 0.16";
        let body = "box(0.17, 0.18, 0.16) at pose(x, y, 0, 0, 0, theta)";
        // The box's corners are sqrt(0.085^2 + 0.09^2) = 0.1238 from its centre.
        let r = search(body, &disc.replace('R', "0.13"));
        assert!(r.is_ok(), "{r:?}");
        let r = search(body, &disc.replace('R', "0.1138"));
        assert!(r.is_err(), "{r:?}");
    }

    /// PGCD's Underpass: a disc of radius 0.257 in a square of half-side 0.262 turned with
    /// the heading, over every heading in [-pi, pi]. Only 5 mm of slack: splitting the disc's
    /// box took the search of the body's points 67,007 pieces; its support (the radius times
    /// `|(cos, sin)|`) decides it within the first pass's budget.
    #[test]
    fn a_disc_in_a_turned_square_with_5_mm_to_spare_is_decided_in_the_first_pass() {
        let fp = SQUARE.replace("HALF", "0.262").replace("0.08", "0.085");
        let r = search_within("cylinder(0.257, 0.08) at pose(x, y, 0)", &fp, QUICK_BUDGET);
        let note = r.unwrap_or_else(|u| panic!("{u}"));
        let pieces: usize =
            note.split(", ").nth(1).and_then(|t| t.split(' ').next()).and_then(|n| n.parse().ok()).expect("a count");
        assert!(pieces < 2_000, "{note}");
        // 5 mm too small: never shown, whatever the budget, and not for lack of pieces.
        let small = SQUARE.replace("HALF", "0.252").replace("0.08", "0.085");
        let r = search_within("cylinder(0.257, 0.08) at pose(x, y, 0)", &small, BUDGET);
        assert!(r.as_ref().is_err_and(|u| !u.ran_out), "{r:?}");
    }

    /// The support of each shape, against footprints just wide enough and just too small: a
    /// box turned with the heading (its corners reach 0.1238 from its centre), a ball, and a
    /// bound written `HALF >= abs(...)`.
    #[test]
    fn the_support_bounds_each_shape_and_never_shows_a_footprint_too_small() {
        let disc = "(px - x) * cos(theta) + (py - y) * sin(theta) <= R && -R <= (px - x) * cos(theta) + (py - y) * sin(theta)
                    && -R <= (py - y) * cos(theta) - (px - x) * sin(theta) && (py - y) * cos(theta) - (px - x) * sin(theta) <= R
                    && 0 <= pz <= 0.16";
        // An axis-aligned box in a square turned with the heading: the box's corner at
        // (0.085, 0.09) reaches cos(pi/4) (0.085 + 0.09) = 0.1237 along the diagonal.
        let body = "box(0.17, 0.18, 0.16) at pose(x, y, 0)";
        assert!(search(body, &disc.replace('R', "0.125")).is_ok());
        assert!(search(body, &disc.replace('R', "0.12")).is_err());
        let ball = "sphere(0.1) at pose(x, y, 0.1)";
        let fp = "0.101 >= abs(cos(theta) * (px - x) + sin(theta) * (py - y)) && 0 <= pz <= 0.2";
        assert!(search(ball, fp).is_ok());
        assert!(search(ball, &fp.replace("0.101", "0.099")).is_err());
    }

    /// Coefficients that may divide by zero are never bounded: the question is left open.
    #[test]
    fn a_coefficient_divided_by_a_value_that_may_be_zero_decides_nothing() {
        let fp = "abs(cos(theta) * (px - x) / theta) <= 100 && abs(py - y) <= 1 && 0 <= pz <= 1";
        assert!(search("cylinder(0.1, 0.1) at pose(x, y, 0)", fp).is_err());
    }

    #[test]
    fn affine_forms_distribute_products_and_quotients_by_factors_free_of_the_point() {
        let (prog, _) = crate::lower::tests::lower_src("const c: real = 1;");
        let q = |i: usize| Expr { kind: ExprKind::Var(Var::Point(i)), sort: Sort::Real, loc: Loc::default() };
        let th = Expr { kind: ExprKind::Var(Var::Own(Slot::State(0))), sort: Sort::Real, loc: Loc::default() };
        // cos(th) * (q0 + 2 q1) / 4 - th
        let e = bin(
            BinOp::Sub,
            bin(
                BinOp::Div,
                bin(BinOp::Mul, call(Builtin::Cos, &th), bin(BinOp::Add, q(0), bin(BinOp::Mul, int(2), q(1)))),
                int(4),
            ),
            th.clone(),
        );
        let (a, b) = affine(&e).expect("affine");
        let at = |e: &Expr, v: f64| {
            bounds::eval(&prog, e, &|x: &Var| (*x == Var::Own(Slot::State(0))).then_some(Interval::point(v)))
        };
        let a0 = at(a[0].as_ref().expect("a0"), 0.0).expect("value");
        let a1 = at(a[1].as_ref().expect("a1"), 0.0).expect("value");
        assert!(a0.lo <= 0.25 && 0.25 <= a0.hi && a1.lo <= 0.5 && 0.5 <= a1.hi, "{a0:?} {a1:?}");
        assert!(a[2].is_none());
        let b = at(b.as_ref().expect("b"), 1.5).expect("value");
        assert!(b.lo <= -1.5 && -1.5 <= b.hi);
        // A product of two terms with the point is not affine.
        assert!(affine(&bin(BinOp::Mul, q(0), q(1))).is_none());
    }
}
