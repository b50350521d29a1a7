//! A footprint written as a predicate that turns with the state (`cos(theta)`,
//! `sin(theta)` of a state variable or of `clock`) against a static obstacle (E0510, the
//! [AGCOMP] part `ClearOf`): decided by interval branch and bound over the obstacle's box
//! and the state variables the footprint reads, before Z3 is asked. Z3 gets `cos`/`sin` of
//! a variable only as a point on the unit circle with polynomial bounds, and its nonlinear
//! arithmetic times out on these questions or returns models the real functions do not
//! take.
//!
//! **The question.** Sec 3.3: the footprint of every motion never meets a static obstacle.
//! Its violation is a configuration: a world point `P`, the participant's state `s` at a
//! time `t` of the motion, the start state, the arguments, such that the context Σ holds at
//! the start, the guarantee and the invariant hold at `t` (`t` within the duration's upper
//! end), `P` lies in the obstacle, and the footprint (read in the participant's frame,
//! `R^T (P - o)` for its constant `at:` pose) holds of `P` at `s`, `t`.
//!
//! **The search.** The dimensions are `P` (its root the obstacle's box: each part's shape
//! box moved by its pose and the obstacle's, enclosed by outward-rounded interval
//! evaluation), every state variable the footprint reads (its root the ranges the guarantee
//! and invariant give it from Σ's ranges of the start state and arguments, as the geometric
//! procedure's `own` ranges) and the clock when the footprint, guarantee or invariant reads
//! it (`[0, T]`, `T` the duration's upper end). The start state and the arguments are not
//! split: they range over what Σ gives them. A box is dropped when the obstacle's
//! predicate, the footprint, the guarantee or the invariant is false at every point of it
//! (three-valued truth by outward-rounded interval evaluation, [`crate::bounds`], compiled
//! once), and halved along its widest dimension relative to the root otherwise. Boxes are
//! taken breadth first (every box before its halves' halves): a contact on a face of a box
//! (a ball centred on the footprint's floor meets it on the plane `pz == 0` in its lower
//! half) never yields a box inside both, and a depth-first search drilled into it until
//! the limit, never reaching the half where whole boxes of contact are.
//!
//! **Sound.** Every configuration of a violation projects into the root box: `P` is in the
//! obstacle, hence in its box; the state at `t` satisfies the guarantee and the invariant
//! with the start state and arguments inside Σ's ranges, hence lies in the ranges read off
//! them (`bounds::ranges_from`, outward); `t` is within `[0, T]`. In the box of the search
//! that holds it, each of the four predicates is true at it, so none is false everywhere on
//! that box (the enclosures hold every value of the box, the start state and arguments
//! included at their ranges). So a search that drops every box proves that no violation
//! exists: **apart**. A box where all four predicates are true at every point is a
//! candidate: its centre, pinned in the part's own Z3 query (which adds Σ exactly), gives a
//! model whose values are replayed exactly against the part's goal
//! ([`crate::smt::replay`]) before it is shown; only then is it a **contact**. A candidate
//! whose model does not come or does not replay, a box at the resolution, an exhausted
//! budget of boxes or the time limit make the question **unknown** (`Why::Interval`), never
//! apart.

pub(crate) use super::earliest::Earliest;
use crate::bounds::compiled::{Compiled, VarTable};
use crate::bounds::{self, Interval};
use crate::hir::body::Pose;
use crate::hir::expr::{mentions, BinOp, Builtin, ExprKind, Sort, UnOp};
use crate::hir::{Expr, Footprint, Loc, Program, RoleId, Slot, Var};
use crate::obligation::{Goal, Obligation};
use crate::smt::goals::Part;
use std::time::{Duration, Instant};

/// Boxes examined before the question is left undecided.
pub const BUDGET: usize = 400_000;

/// Candidate boxes whose centre is put to Z3 before the search stops confirming.
const CONFIRMATIONS: usize = 8;

/// One pinned value of a candidate: the name the part's query gives the variable
/// (`point.x`, `Cart.theta(t)`, `time`) and its value.
pub(crate) type Pins = Vec<(String, f64)>;

/// What the search found.
pub(crate) enum Found<T> {
    /// Every box dropped: no point of the obstacle is in the footprint at any state and
    /// time the contract allows.
    Apart,
    /// A candidate confirmed by the caller (a Z3 model with the candidate pinned, replayed
    /// exactly).
    Contact(T),
    /// Neither, with why.
    Undecided(String),
}

/// A predicate compiled for three-valued interval truth: the shape of
/// [`crate::bounds::truth::truth`] with its comparisons' sides compiled.
enum Pred {
    Const(bool),
    Not(Box<Pred>),
    And(Box<Pred>, Box<Pred>),
    Or(Box<Pred>, Box<Pred>),
    Implies(Box<Pred>, Box<Pred>),
    /// A comparison, and the dimensions its sides read (a bit each).
    Cmp(BinOp, Compiled, Compiled, u64),
    /// A construct interval truth does not decide (undecided everywhere).
    Opaque,
}

impl Pred {
    fn new(prog: &Program, e: &Expr, table: &mut VarTable, dim: &dyn Fn(&Var) -> Option<usize>) -> Pred {
        crate::stack::deep(|| match &e.kind {
            ExprKind::Bool(b) => Pred::Const(*b),
            ExprKind::Unary(UnOp::Not, a) => Pred::Not(Box::new(Pred::new(prog, a, table, dim))),
            ExprKind::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => {
                let (a, b) = (Box::new(Pred::new(prog, a, table, dim)), Box::new(Pred::new(prog, b, table, dim)));
                match op {
                    BinOp::And => Pred::And(a, b),
                    BinOp::Or => Pred::Or(a, b),
                    _ => Pred::Implies(a, b),
                }
            }
            ExprKind::Binary(op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne), a, b)
                if a.sort.is_numeric() && b.sort.is_numeric() =>
            {
                let mut mask = 0u64;
                for side in [a, b] {
                    side.visit_vars(&mut |v, _| {
                        if let Some(d) = dim(v) {
                            mask |= 1 << d.min(63);
                        }
                    });
                }
                Pred::Cmp(*op, Compiled::new(prog, a, table), Compiled::new(prog, b, table), mask)
            }
            _ => Pred::Opaque,
        })
    }

    /// `Some(b)` when the predicate is `b` at every point of the box `env`; the
    /// dimensions read by the comparisons left undecided are added to `open`.
    fn truth(&self, env: &[Option<Interval>], stack: &mut Vec<Option<Interval>>, open: &mut u64) -> Option<bool> {
        match self {
            Pred::Const(b) => Some(*b),
            Pred::Not(a) => a.truth(env, stack, open).map(|b| !b),
            Pred::And(a, b) => match a.truth(env, stack, open) {
                Some(false) => Some(false),
                x => match (x, b.truth(env, stack, open)) {
                    (_, Some(false)) => Some(false),
                    (Some(true), Some(true)) => Some(true),
                    _ => None,
                },
            },
            Pred::Or(a, b) => match a.truth(env, stack, open) {
                Some(true) => Some(true),
                x => match (x, b.truth(env, stack, open)) {
                    (_, Some(true)) => Some(true),
                    (Some(false), Some(false)) => Some(false),
                    _ => None,
                },
            },
            Pred::Implies(a, b) => match (a.truth(env, stack, open), b.truth(env, stack, open)) {
                (Some(false), _) | (_, Some(true)) => Some(true),
                (Some(true), Some(false)) => Some(false),
                _ => None,
            },
            Pred::Cmp(op, a, b, mask) => {
                let t = match (a.eval(env, stack), b.eval(env, stack)) {
                    (Some(x), Some(y)) => crate::bounds::truth::compare(*op, x, y),
                    _ => None,
                };
                if t.is_none() {
                    *open |= mask;
                }
                t
            }
            Pred::Opaque => None,
        }
    }
}

/// A dimension of the search.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Dim {
    Point(usize),
    State(usize),
    Clock,
}

/// The question laid out: the compiled predicates, the variable table's ranges outside
/// the dimensions, the dimensions and their root box.
struct Layout {
    preds: Vec<Pred>,
    /// Per variable of the table: the dimension it is, or its fixed range.
    slots: Vec<Result<usize, Option<Interval>>>,
    dims: Vec<Dim>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// The names of the dimensions in the part's query, for pinning.
    names: Vec<String>,
}

/// Whether `part` of `ob` is this search's: an obstacle with a predicate against a
/// footprint written as a predicate (not mounted, no input read) whose `cos`/`sin` read the
/// participant's state or the clock.
pub(crate) fn applies(prog: &Program, ob: &Obligation, part: &Part) -> bool {
    target(prog, ob, part).is_some()
}

/// The participant, its application's index, the footprint and the obstacle of an
/// applicable part.
fn target<'a>(
    prog: &'a Program,
    ob: &'a Obligation,
    part: &Part,
) -> Option<(RoleId, &'a crate::hir::PrimApp, &'a Expr, &'a crate::hir::body::Obstacle)> {
    let (Goal::Compatible { parts }, Part::ClearOf { i, o }) = (&ob.goal, part) else { return None };
    let (role, app) = parts.get(*i)?;
    let obstacle = prog.obstacles.get(*o)?;
    let Footprint::Predicate(fp) = &prog.prim(app.prim).footprint else { return None };
    if prog.role(*role).mounted_on.is_some() || crate::space::region::obstacle_region(prog, obstacle).is_none() {
        return None;
    }
    let moving = |v: &Var| matches!(v, Var::Own(Slot::State(_)) | Var::Clock);
    let turns = fp.pred.any(|e| match &e.kind {
        ExprKind::Call(Builtin::Sin | Builtin::Cos, args) => args.iter().any(|a| mentions(a, &moving)),
        _ => false,
    });
    let reads_input = mentions(&fp.pred, &|v| matches!(v, Var::Own(Slot::Input(_))));
    (turns && !reads_input).then_some((*role, app, &fp.pred, obstacle))
}

/// Decides `part` of `ob` by the search, within `limit`; `confirm` is asked for a
/// counterexample at a candidate's pinned values. `None` when the part is not this
/// search's, or its root box cannot be bounded (Z3 is asked as before).
///
/// A confirmed contact comes with the window of the earliest one ([`earliest`]): `time_of`
/// reads a counterexample's time (since the motion's start).
pub(crate) fn decide<T>(
    prog: &Program,
    ob: &Obligation,
    part: &Part,
    limit: Duration,
    confirm: &mut dyn FnMut(&Pins) -> Option<T>,
    time_of: &dyn Fn(&T) -> Option<f64>,
) -> Option<Found<(T, Earliest)>> {
    let layout = layout(prog, ob, part, None)?;
    let start = Instant::now();
    Some(match search(&layout, limit, BUDGET, confirm) {
        Found::Apart => Found::Apart,
        Found::Undecided(why) => Found::Undecided(why),
        Found::Contact(found) => {
            let left = limit.saturating_sub(start.elapsed());
            Found::Contact(earliest(prog, ob, part, found, left, confirm, time_of))
        }
    })
}

/// Boxes each step of [`earliest`] may search: a budget of boxes, not of time, so that the
/// window does not depend on the machine's load (the time limit still applies).
const WINDOW_BUDGET: usize = BUDGET / 8;

/// The window of the first contact below `found`'s ([`super::earliest::bisect`]): each
/// step is the search with the times capped at `mid` ([`layout`]'s `cap`), whose apart is
/// the module doc's argument over the capped box, and whose contact is confirmed by
/// `confirm` as any.
fn earliest<T>(
    prog: &Program,
    ob: &Obligation,
    part: &Part,
    found: T,
    limit: Duration,
    confirm: &mut dyn FnMut(&Pins) -> Option<T>,
    time_of: &dyn Fn(&T) -> Option<f64>,
) -> (T, Earliest) {
    use super::earliest::{bisect, Step};
    let deadline = Instant::now() + limit;
    let at = time_of(&found).unwrap_or(f64::NAN);
    let (best, _, window) = bisect(found, at, None, &mut |_, mid| {
        let Some(layout) = layout(prog, ob, part, Some(mid)) else {
            return Step::Undecided("the states up to that time cannot be bounded".to_string());
        };
        match search(&layout, deadline.saturating_duration_since(Instant::now()), WINDOW_BUDGET, confirm) {
            Found::Apart => Step::Apart,
            Found::Contact(c) => {
                let t = time_of(&c).unwrap_or(f64::NAN);
                Step::Contact(c, t)
            }
            Found::Undecided(why) => Step::Undecided(why),
        }
    });
    (best, window)
}

/// The question laid out; with `cap`, only the times in `[0, cap]` (the clock a dimension
/// whether or not the footprint reads it, and the state's ranges those the guarantee and
/// invariant give over these times): the question of a contact at or before `cap`.
fn layout(prog: &Program, ob: &Obligation, part: &Part, cap: Option<f64>) -> Option<Layout> {
    let (role, app, fp, obstacle) = target(prog, ob, part)?;
    let prim = prog.prim(app.prim);
    let kind = prog.kind(prim.kind);
    let region = crate::space::region::obstacle_region(prog, obstacle)?;
    // The footprint read at the world point: its point is `R^T (P - o)`, `P` the world
    // point (`Var::Point`), for the participant's constant pose.
    let pose = role_pose(prog, role);
    let world = [0, 1, 2].map(|k| point_var(k, Loc::default()));
    let local = crate::space::region::to_part_frame(prog, &pose, &world);
    let fp_world = fp.map(&mut |e: Expr| match e.kind {
        ExprKind::Var(Var::Point(k)) => local[k].clone(),
        _ => e,
    });
    // Σ's ranges of the start state and values, the arguments over them, and the ranges
    // the guarantee and invariant give the state while the motion runs.
    let facts: Vec<&Expr> = ob.hyps.iter().collect();
    let shared = bounds::ranges_from(prog, &facts, &bounds::closed);
    let lookup = |v: &Var| shared.get(v).copied();
    let params: Vec<Option<Interval>> = app.args.iter().map(|a| bounds::eval(prog, a, &lookup)).collect();
    let start = |v: &Var| -> Option<Interval> {
        match v {
            Var::Old(i) => shared.get(&Var::Role(role, Slot::State(*i))).copied(),
            Var::Param(i) => params.get(*i).copied().flatten(),
            Var::Clock => Some(Interval::new(0.0, f64::INFINITY)),
            other => shared.get(other).copied(),
        }
    };
    let clock_hi = match &prim.duration.hi {
        Some(h) => bounds::eval(prog, h, &start).map_or(f64::INFINITY, |i| i.hi),
        None => f64::INFINITY,
    };
    let clock_hi = if clock_hi.is_nan() { f64::INFINITY } else { clock_hi.max(0.0) };
    let clock = Interval::new(0.0, cap.map_or(clock_hi, |c| c.max(0.0).min(clock_hi)));
    let lift = |v: &Var| match v {
        Var::Clock => Some(clock),
        other => start(other),
    };
    let mut now: Vec<&Expr> = vec![&prim.guarantee];
    now.extend(kind.invariant.as_ref());
    let own = bounds::ranges_from(prog, &now, &lift);
    let mut preds_src: Vec<Expr> = vec![region, fp_world.clone(), prim.guarantee.clone()];
    preds_src.extend(kind.invariant.clone());
    // The dimensions: the point, the state the footprint reads, the clock if read.
    let mut dims = vec![Dim::Point(0), Dim::Point(1), Dim::Point(2)];
    fp_world.visit_vars(&mut |v, _| {
        if let Var::Own(Slot::State(i)) = v {
            if !dims.contains(&Dim::State(*i)) {
                dims.push(Dim::State(*i));
            }
        }
    });
    // The clock only when the footprint reads it: the guarantee's and invariant's
    // dependence on it is already in the state's ranges, and a dimension the footprint
    // does not read would only multiply the boxes (its whole range is taken instead).
    // With a cap, the clock relates the guarantee's states to the time asked about.
    if cap.is_some() || mentions(&fp_world, &|v| matches!(v, Var::Clock)) {
        dims.push(Dim::Clock);
    }
    let obox = obstacle_box(prog, obstacle)?;
    let (mut lo, mut hi, mut names) = (Vec::new(), Vec::new(), Vec::new());
    let role_name = prog.role_name(role);
    for d in &dims {
        let (iv, name) = match d {
            Dim::Point(k) => (obox[*k], ["point.x", "point.y", "point.z"][*k].to_string()),
            Dim::State(i) => (
                own.get(&Var::Own(Slot::State(*i))).copied()?,
                format!("{role_name}.{}(t)", kind.var(Slot::State(*i)).0),
            ),
            Dim::Clock => (clock, "time".to_string()),
        };
        if !iv.is_finite() || iv.lo > iv.hi {
            return None;
        }
        lo.push(iv.lo);
        hi.push(iv.hi);
        names.push(name);
    }
    let mut table = VarTable::new();
    let dim_of = |v: &Var| {
        let d = match v {
            Var::Point(k) => Dim::Point(*k),
            Var::Own(Slot::State(i)) => Dim::State(*i),
            Var::Clock => Dim::Clock,
            _ => return None,
        };
        dims.iter().position(|x| *x == d)
    };
    let preds: Vec<Pred> = preds_src.iter().map(|e| Pred::new(prog, e, &mut table, &dim_of)).collect();
    let slots = table
        .vars()
        .iter()
        .map(|v| {
            let dim = match v {
                Var::Point(k) => Some(Dim::Point(*k)),
                Var::Own(Slot::State(i)) => Some(Dim::State(*i)),
                Var::Clock => Some(Dim::Clock),
                _ => None,
            };
            match dim.and_then(|d| dims.iter().position(|x| *x == d)) {
                Some(k) => Ok(k),
                None => Err(match v {
                    Var::Own(slot) => own.get(&Var::Own(*slot)).copied(),
                    Var::Clock => Some(clock),
                    other => start(other),
                }),
            }
        })
        .collect();
    Some(Layout { preds, slots, dims, lo, hi, names })
}

/// At one state the simulator reached (every variable but the point known, as `value`
/// gives it): whether some point of `obstacle` is in participant `role`'s footprint
/// predicate `fp` (in its own frame), by the same search over the obstacle's points alone.
/// `None` when the footprint does not turn with the state (Z3 is asked as before);
/// `Some(Ok(None))` when no point is; `Some(Ok(Some(p)))` a point in both, checked exactly
/// ([`crate::exact`]); `Some(Err(why))` undecided.
pub(crate) fn point_in_obstacle(
    prog: &Program,
    role: RoleId,
    fp: &Expr,
    obstacle: &crate::hir::body::Obstacle,
    value: &dyn Fn(&Var) -> Option<crate::exact::Value>,
    limit: Duration,
) -> Option<Result<Option<[crate::exact::Num; 3]>, String>> {
    use crate::exact::{self, Num, Tri, Value};
    let moving = |v: &Var| matches!(v, Var::Own(Slot::State(_)) | Var::Clock);
    let turns = fp.any(|e| match &e.kind {
        ExprKind::Call(Builtin::Sin | Builtin::Cos, args) => args.iter().any(|a| mentions(a, &moving)),
        _ => false,
    });
    if !turns || prog.role(role).mounted_on.is_some() {
        return None;
    }
    let region = crate::space::region::obstacle_region(prog, obstacle)?;
    let world = [0, 1, 2].map(|k| point_var(k, Loc::default()));
    let local = crate::space::region::to_part_frame(prog, &role_pose(prog, role), &world);
    let fp_world = fp.map(&mut |e: Expr| match e.kind {
        ExprKind::Var(Var::Point(k)) => local[k].clone(),
        _ => e,
    });
    let obox = obstacle_box(prog, obstacle)?;
    let dims = vec![Dim::Point(0), Dim::Point(1), Dim::Point(2)];
    let dim_of = |v: &Var| match v {
        Var::Point(k) => Some(*k),
        _ => None,
    };
    let mut table = VarTable::new();
    let preds = vec![Pred::new(prog, &region, &mut table, &dim_of), Pred::new(prog, &fp_world, &mut table, &dim_of)];
    let enclose = |n: &Num| Interval::new(Interval::of_rational(&n.lo).lo, Interval::of_rational(&n.hi).hi);
    let slots = table
        .vars()
        .iter()
        .map(|v| match v {
            Var::Point(k) => Ok(*k),
            other => Err(match value(other) {
                Some(Value::Num(n)) => Some(enclose(&n)),
                _ => None,
            }),
        })
        .collect();
    let layout = Layout {
        preds,
        slots,
        dims,
        lo: obox.iter().map(|i| i.lo).collect(),
        hi: obox.iter().map(|i| i.hi).collect(),
        names: ["point.x", "point.y", "point.z"].map(String::from).to_vec(),
    };
    // A candidate is a point only when both predicates hold of it exactly.
    let mut exactly = |pins: &Pins| -> Option<[Num; 3]> {
        let p: Vec<Num> =
            pins.iter().map(|(_, v)| bounds::decimal(&format!("{v}")).map(Num::exact)).collect::<Option<_>>()?;
        let p: [Num; 3] = p.try_into().ok()?;
        let env = |v: &Var| match v {
            Var::Point(k) => p.get(*k).cloned().map(Value::Num),
            other => value(other),
        };
        (exact::holds(prog, &region, &env) == Tri::True && exact::holds(prog, &fp_world, &env) == Tri::True)
            .then(|| p.clone())
    };
    Some(match search(&layout, limit, BUDGET, &mut exactly) {
        Found::Apart => Ok(None),
        Found::Contact(p) => Ok(Some(p)),
        Found::Undecided(why) => Err(why),
    })
}

/// The participant's constant `at:` pose (missing arguments 0).
fn role_pose(prog: &Program, role: RoleId) -> Pose {
    let given = &prog.role(role).pose;
    let zero = || Expr { kind: ExprKind::Int(0), sort: Sort::Int, loc: Loc::default() };
    let args: [Expr; 6] = std::array::from_fn(|k| given.get(k).cloned().unwrap_or_else(zero));
    Pose { args, span: prog.role(role).span }
}

fn point_var(k: usize, loc: Loc) -> Expr {
    Expr { kind: ExprKind::Var(Var::Point(k)), sort: Sort::Real, loc }
}

/// An outward-rounded box holding the obstacle: each part's shape box in its own frame
/// (`[-l/2, l/2] × [-w/2, w/2] × [0, h]` for a box, `[-r, r]^2 × [0, h]` for a cylinder
/// or a capsule, `[-r, r]^3` for a sphere) moved by the part's pose and the obstacle's,
/// `R q + t` evaluated over the shape box by interval arithmetic; the hull of the parts.
/// `None` for a URDF or mesh part, or sizes that cannot be bounded.
fn obstacle_box(prog: &Program, o: &crate::hir::body::Obstacle) -> Option<[Interval; 3]> {
    use crate::hir::body::Shape;
    let mut out: Option<[Interval; 3]> = None;
    for part in &o.body.parts {
        let size = |e: &Expr| bounds::eval(prog, e, &bounds::closed).filter(Interval::is_finite).map(|i| i.hi.abs());
        let (xy, z) = match &part.shape {
            Shape::Box([l, w, h]) => {
                let (l, w, h) = (size(l)?, size(w)?, size(h)?);
                ([Interval::new(-l / 2.0, l / 2.0), Interval::new(-w / 2.0, w / 2.0)], Interval::new(0.0, h))
            }
            Shape::Sphere(r) => {
                let r = size(r)?;
                ([Interval::new(-r, r), Interval::new(-r, r)], Interval::new(-r, r))
            }
            Shape::Cylinder(r, h) | Shape::Capsule(r, h) => {
                let (r, h) = (size(r)?, size(h)?);
                ([Interval::new(-r, r), Interval::new(-r, r)], Interval::new(0.0, h))
            }
            Shape::Urdf { .. } | Shape::Mesh { .. } => return None,
        };
        // (Halving a double is exact; each size is its enclosure's upper end.)
        let shape = [xy[0], xy[1], z];
        let mut q: [Expr; 3] = [0, 1, 2].map(|k| point_var(k, Loc(part.span)));
        if let Some(p) = &part.place {
            q = forward(p, q);
        }
        if let Some(p) = &o.pose {
            q = forward(p, q);
        }
        let ranges = |v: &Var| match v {
            Var::Point(k) => shape.get(*k).copied(),
            _ => None,
        };
        let mut b = [Interval::point(0.0); 3];
        for k in 0..3 {
            b[k] = bounds::eval(prog, &q[k], &ranges).filter(Interval::is_finite)?;
        }
        out = Some(match out {
            None => b,
            Some(a) => [a[0].hull(b[0]), a[1].hull(b[1]), a[2].hull(b[2])],
        });
    }
    out
}

/// `R q + t` for `pose(t, roll, pitch, yaw)`, `R = Rz(yaw) Ry(pitch) Rx(roll)`, as
/// expressions (the inverse of [`crate::space::region::to_part_frame`]).
fn forward(pose: &Pose, q: [Expr; 3]) -> [Expr; 3] {
    let loc = Loc(pose.span);
    let bin = |op: BinOp, a: Expr, b: Expr| Expr {
        kind: ExprKind::Binary(op, Box::new(a), Box::new(b)),
        sort: Sort::Real,
        loc,
    };
    let call = |f: Builtin, a: &Expr| Expr { kind: ExprKind::Call(f, vec![a.clone()]), sort: Sort::Real, loc };
    let mut v = q;
    // Roll about x (y, z), then pitch about y (z, x), then yaw about z (x, y):
    // a' = c a - s b, b' = s a + c b.
    for (idx, (a, b)) in [(3usize, (1usize, 2usize)), (4, (2, 0)), (5, (0, 1))] {
        let angle = &pose.args[idx];
        let (c, s) = (call(Builtin::Cos, angle), call(Builtin::Sin, angle));
        let (x, y) = (v[a].clone(), v[b].clone());
        v[a] = bin(BinOp::Sub, bin(BinOp::Mul, c.clone(), x.clone()), bin(BinOp::Mul, s.clone(), y.clone()));
        v[b] = bin(BinOp::Add, bin(BinOp::Mul, s, x), bin(BinOp::Mul, c, y));
    }
    for (k, c) in v.iter_mut().enumerate() {
        *c = bin(BinOp::Add, c.clone(), pose.args[k].clone());
    }
    v
}

/// A value of `[lo, hi]` with few decimal digits (the counterexample shows it): the
/// centre rounded to the fewest significant digits that stay within the interval.
fn short(lo: f64, hi: f64) -> f64 {
    let centre = lo + (hi - lo) / 2.0;
    (0..17)
        .filter_map(|k| format!("{centre:.k$e}").parse::<f64>().ok())
        .find(|v| lo <= *v && *v <= hi)
        .unwrap_or(centre)
}

/// The branch and bound (module doc).
fn search<T>(l: &Layout, limit: Duration, budget: usize, confirm: &mut dyn FnMut(&Pins) -> Option<T>) -> Found<T> {
    let deadline = Instant::now() + limit;
    let n = l.dims.len();
    let width: Vec<f64> = (0..n).map(|d| l.hi[d] - l.lo[d]).collect();
    // Breadth first: a box is split only after every wider box, so a candidate inside both
    // predicates is met at the coarse level where it fits, and the search is not drawn down
    // one surface (where the footprint's or obstacle's comparison stays undecided) to the
    // resolution before it.
    let mut queue = std::collections::VecDeque::from([(l.lo.clone(), l.hi.clone())]);
    let mut env: Vec<Option<Interval>> = vec![None; l.slots.len()];
    let mut scratch = Vec::new();
    let (mut boxes, mut asked) = (0usize, 0usize);
    let mut open: Option<String> = None;
    while let Some((lo, hi)) = queue.pop_front() {
        boxes += 1;
        if boxes > budget {
            return Found::Undecided(format!(
                "{budget} boxes of the obstacle's points, the state and the time searched without deciding"
            ));
        }
        if boxes % 256 == 0 && Instant::now() > deadline {
            return Found::Undecided(format!(
                "the time limit of {} ms was reached after {boxes} boxes (raise it with --timeout)",
                limit.as_millis()
            ));
        }
        for (k, s) in l.slots.iter().enumerate() {
            env[k] = match s {
                Ok(d) => Some(Interval::new(lo[*d], hi[*d])),
                Err(r) => *r,
            };
        }
        // The obstacle's predicate and the footprint (the first two) decide where the
        // point is; the guarantee and the invariant, where the state may be.
        let mut inside = true;
        let mut allowed = true;
        let mut dropped = false;
        let mut undecided = 0u64;
        for (k, p) in l.preds.iter().enumerate() {
            match p.truth(&env, &mut scratch, &mut undecided) {
                Some(false) => {
                    dropped = true;
                    break;
                }
                Some(true) => {}
                None if k < 2 => inside = false,
                None => allowed = false,
            }
        }
        if dropped {
            continue;
        }
        if inside {
            // Every point of the box is in the obstacle and the footprint at its state and
            // time: its centre, with Σ, the guarantee and the invariant exactly, is put to
            // Z3 (an equality of the guarantee, `theta == old(theta) + w * clock`, is never
            // true of a whole box, so a box whose contract is undecided is put too).
            if asked < CONFIRMATIONS {
                asked += 1;
                let pins: Pins = (0..n).map(|d| (l.names[d].clone(), short(lo[d], hi[d]))).collect();
                if let Some(found) = confirm(&pins) {
                    return Found::Contact(found);
                }
            }
            // Never apart; split only where the contract is undecided, until it decides.
            if allowed {
                open.get_or_insert_with(|| {
                    "a box of points in the obstacle and the footprint, whose centre no model of the context completes into a counterexample that replays exactly".to_string()
                });
                continue;
            }
        }
        // Halve the widest dimension relative to its root width among those an undecided
        // comparison reads (splitting another cannot decide it).
        let d = (0..n)
            .filter(|&d| width[d] > 0.0 && undecided & (1 << d.min(63)) != 0)
            .max_by(|&a, &b| ((hi[a] - lo[a]) / width[a]).total_cmp(&((hi[b] - lo[b]) / width[b])));
        let Some(d) = d else {
            open.get_or_insert_with(|| "a configuration interval truth cannot decide".to_string());
            continue;
        };
        let mid = lo[d] + (hi[d] - lo[d]) / 2.0;
        if !(mid > lo[d] && mid < hi[d]) || (hi[d] - lo[d]) < width[d] * 1e-12 {
            open.get_or_insert_with(|| {
                format!(
                    "the search reached its resolution on {} without deciding (the footprint may graze the obstacle)",
                    l.names[d]
                )
            });
            continue;
        }
        let (mut lo2, mut hi1) = (lo.clone(), hi.clone());
        hi1[d] = mid;
        lo2[d] = mid;
        queue.push_back((lo, hi1));
        queue.push_back((lo2, hi));
    }
    match open {
        Some(why) => Found::Undecided(format!("{why} ({boxes} boxes)")),
        None => Found::Apart,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::Code;
    use crate::driver::{Config, Verdict};

    /// A cart at the origin whose square footprint (half-side 0.262, in its heading frame)
    /// turns with its heading from 0 to `turn`, beside a post whose near face is at
    /// `face` m along x (the square's corners reach 0.3705 m).
    fn spin(face: &str, turn: &str) -> String {
        format!(
            "robot C {{ state x: real, y: real, th: real;
               invariant: -10 <= x <= 10 && -10 <= y <= 10 && -4 <= th <= 4; }}
             motion C.turn(a: real) {{ interruptible: false; pre: true;
               guarantee: min(old(th), a) <= th <= max(old(th), a) && x == old(x) && y == old(y);
               post: th == a && x == old(x) && y == old(y);
               footprint(px, py, pz): abs(cos(th) * (px - x) + sin(th) * (py - y)) <= 0.262
                 && abs(cos(th) * (py - y) - sin(th) * (px - x)) <= 0.262 && 0 <= pz <= 0.1;
               duration: [5, 5]; }}
             system S {{
               participant A: C {{ init: x == 0 && y == 0 && th == 0; }}
               obstacle Post {{ geometry: box(0.1, 0.1, 1); at: pose({face} + 0.05, 0, 0); }}
             }}
             choreography S = dt<A: turn({turn})>. end;
             process A = dt<turn({turn})>.end;"
        )
    }

    fn check(src: &str) -> crate::driver::Report {
        let mut db = crate::source::SourceDb::new();
        let path = crate::testing::repo("choreographies/spin-test.chor").display().to_string();
        crate::fsload::check_source(&mut db, &path, src, &Config::default())
    }

    /// The layout of the report's first obstacle question, if it is this search's.
    fn question(r: &crate::driver::Report) -> (Program, Obligation, Part) {
        let planned = r.planned.as_ref().expect("planned");
        for ob in &planned.obligations {
            if let crate::smt::goals::Plan::Parts(parts) = crate::smt::goals::plan(&planned.program, ob) {
                if let Some(p) = parts.into_iter().find(|p| matches!(p, Part::ClearOf { .. })) {
                    return (planned.program.clone(), ob.clone(), p);
                }
            }
        }
        panic!("no obstacle question")
    }

    #[test]
    fn a_turning_footprint_is_kept_clear_of_a_post_or_shown_to_meet_it() {
        let clear = check(&spin("0.38", "1.5"));
        assert_eq!(clear.verdict, Verdict::Verified, "{:?}", clear.diagnostics);
        let hit = check(&spin("0.36", "1.5"));
        assert_eq!(hit.verdict, Verdict::Rejected, "{:?}", hit.diagnostics);
        let d = hit.diagnostics.iter().find(|d| d.code == Code::ObstacleHit).expect("E0510");
        assert!(d.notes.iter().any(|n| n.contains("found by the interval search")), "{:?}", d.notes);
        let cx = d.counterexample.as_deref().expect("a counterexample");
        assert!(cx.overlap.is_some() && cx.values.iter().any(|a| a.name == "A.th(t)"), "{cx:?}");
        // Only headings near pi / 4 bring a corner that far: turned to 0.5 rad the square
        // stays clear of the nearer post too.
        assert_eq!(check(&spin("0.36", "0.5")).verdict, Verdict::Verified);
    }

    /// A ball centred on the footprint's floor (`pz == 0`): its lower half meets the
    /// footprint only on that plane, where no box of positive size is inside both, so a
    /// depth-first search drilled into that half forever and ran out of time (unknown)
    /// although the upper half holds whole boxes of contact. Breadth first, the search
    /// reaches them.
    #[test]
    fn a_ball_on_the_footprints_floor_is_found_to_meet_it() {
        let ball = spin("0.30", "1.5")
            .replace("box(0.1, 0.1, 1); at: pose(0.30 + 0.05, 0, 0)", "sphere(0.05); at: pose(0.33, 0, 0)");
        assert!(ball.contains("sphere"), "the scene changed: {ball}");
        let hit = check(&ball);
        assert_eq!(hit.verdict, Verdict::Rejected, "{:?}", hit.diagnostics);
        assert!(hit.diagnostics.iter().any(|d| d.code == Code::ObstacleHit), "{:?}", hit.diagnostics);
        let clear = check(&ball.replace("pose(0.33, 0, 0)", "pose(0.43, 0, 0)"));
        assert_eq!(clear.verdict, Verdict::Verified, "{:?}", clear.diagnostics);
    }

    #[test]
    fn a_candidate_is_a_contact_only_when_confirmed_and_never_apart() {
        let (prog, ob, part) = question(&check(&spin("0.36", "1.5")));
        let l = layout(&prog, &ob, &part, None).expect("the search's question");
        let mut asked = 0;
        let found = search(&l, Duration::from_secs(10), BUDGET, &mut |_pins: &Pins| -> Option<()> {
            asked += 1;
            None
        });
        assert!(matches!(found, Found::Undecided(_)), "an unconfirmed candidate leaves it open");
        assert!(asked > 0);
        let found = search(&l, Duration::from_secs(10), BUDGET, &mut |pins: &Pins| Some(pins.clone()));
        let Found::Contact(pins) = found else { panic!("a contact") };
        let names: Vec<&str> = pins.iter().map(|(n, _)| n.as_str()).collect();
        assert!(names.contains(&"point.x") && names.contains(&"A.th(t)"), "{names:?}");
        // The clear post is apart without a question.
        let (prog, ob, part) = question(&check(&spin("0.38", "1.5")));
        let l = layout(&prog, &ob, &part, None).expect("the search's question");
        let found =
            search(&l, Duration::from_secs(10), BUDGET, &mut |_pins: &Pins| -> Option<()> { panic!("no candidate") });
        assert!(matches!(found, Found::Apart));
    }

    #[test]
    fn a_footprint_touching_the_post_or_a_search_out_of_time_is_never_apart() {
        // Heading 0 only: the square's face is at x = 0.262, the post's face too.
        let (prog, ob, part) = question(&check(&spin("0.262", "0")));
        let l = layout(&prog, &ob, &part, None).expect("the search's question");
        let found = search(&l, Duration::from_secs(10), BUDGET, &mut |_pins: &Pins| -> Option<()> { None });
        assert!(matches!(found, Found::Undecided(_)));
        let (prog, ob, part) = question(&check(&spin("0.371", "1.5")));
        let l = layout(&prog, &ob, &part, None).expect("the search's question");
        let found = search(&l, Duration::ZERO, BUDGET, &mut |_pins: &Pins| -> Option<()> { None });
        match found {
            Found::Undecided(why) => assert!(why.contains("time limit"), "{why}"),
            _ => panic!("out of time is undecided"),
        }
    }

    /// A cart whose square footprint (half-side 0.25, written turned by its constant
    /// heading) drives along x at 0.2 m/s from 0 for 10 s towards a post whose near face is at
    /// x = 1: by hand, its front face `x + 0.25` first reaches the post at `x = 0.75`, at
    /// `t = 0.75 / 0.2 = 3.75 s`, and at no time before.
    const DRIVE: &str = "robot C { state x: real, th: real; invariant: -10 <= x <= 10 && -4 <= th <= 4; }
         motion C.go() { interruptible: false; pre: true;
           guarantee: x == old(x) + 0.2 * clock && th == old(th);
           post: x == old(x) + 2 && th == old(th);
           footprint(px, py, pz): abs(cos(th) * (px - x) + sin(th) * py) <= 0.25
             && abs(cos(th) * py - sin(th) * (px - x)) <= 0.25 && 0 <= pz <= 0.1;
           duration: [10, 10]; }
         system S {
           participant A: C { init: x == 0 && th == 0; }
           obstacle Post { geometry: box(0.1, 0.1, 1); at: pose(1.05, 0, 0); }
         }
         choreography S = dt<A: go>. end;
         process A = dt<go>.end;";

    #[test]
    fn the_earliest_contact_is_in_a_narrow_proved_window_around_the_time_by_hand() {
        let r = check(DRIVE);
        let d = r.diagnostics.iter().find(|d| d.code == Code::ObstacleHit).expect("E0510");
        assert!(d.notes.iter().any(|n| n.contains("found by the interval search")), "{:?}", d.notes);
        let o = d.counterexample.as_deref().and_then(|c| c.overlap.clone()).expect("a contact");
        let (lo, t) = (o.not_before.expect("a proved bound"), o.times[0]);
        assert!(lo < 3.75 && 3.75 <= t + 1e-9, "window [{lo}, {t}]");
        assert!(t - lo <= 0.05 * t, "window [{lo}, {t}] wider than 5 %");
        // Narrowing further may run out of boxes: then it says at which time.
        assert!(o.earliest_open.as_deref().is_none_or(|w| w.contains("was not decided")), "{o:?}");
        let shown = d.notes.iter().find(|n| n.starts_with("counterexample")).expect("the note");
        assert!(
            shown.contains("no meeting is possible at or before") && shown.contains("since the choreography started"),
            "{shown}"
        );
    }

    #[test]
    fn a_window_out_of_budget_claims_no_time_and_says_why() {
        let (prog, ob, part) = question(&check(DRIVE));
        let mut confirm = |pins: &Pins| -> Option<f64> { pins.iter().find(|(n, _)| n == "time").map(|(_, v)| *v) };
        let time_of = |t: &f64| Some(*t);
        let (t, w) = earliest(&prog, &ob, &part, 9.0, Duration::ZERO, &mut confirm, &time_of);
        // (The start alone is decided in fewer boxes than the search checks its clock after.)
        assert_eq!(t, 9.0);
        assert!(w.not_before.is_none_or(|lo| lo == 0.0), "{w:?}");
        assert!(w.open.is_some_and(|o| o.contains("time limit")));
    }

    fn lower(src: &str) -> Program {
        let (prog, d) = crate::lower::tests::lower_src(src);
        assert!(d.is_empty(), "{d:?}");
        prog
    }

    #[test]
    fn the_obstacle_box_holds_a_turned_part() {
        // A 2 x 1 x 1 box at (5, 0, 0), turned by 0.3 about z: its corners
        // (+-1, +-0.5) turned lie within the box found, which is not much wider.
        let prog = lower(
            "robot R { state x: real; } system S { participant A: R;
             obstacle O { geometry: box(2, 1, 1) at pose(5, 0, 0, 0, 0, 0.3); } } choreography G = end;",
        );
        let b = obstacle_box(&prog, &prog.obstacles[0]).expect("a box");
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        for (x, y) in [(1.0, 0.5), (1.0, -0.5), (-1.0, 0.5), (-1.0, -0.5)] {
            let (wx, wy) = (5.0 + c * x - s * y, s * x + c * y);
            assert!(b[0].lo <= wx && wx <= b[0].hi && b[1].lo <= wy && wy <= b[1].hi, "{b:?} misses ({wx}, {wy})");
        }
        assert!(b[2].lo <= 0.0 && b[2].hi >= 1.0);
        assert!(b[0].hi - b[0].lo < 2.5 && b[1].hi - b[1].lo < 2.5, "{b:?}");
    }
}
