//! Interval arithmetic over predicates: sound enclosures of terms, and axis-aligned
//! boxes around the points a footprint may occupy. The SMT stage uses them to settle
//! the separation of `g1 * ... * gn` without a solver when each side's footprints fit
//! in a box and the boxes are pairwise disjoint (the boxes are then the partition
//! `∃ FP1, FP2` of [AGCOMP], inferred), and to bound `sin`/`cos` of constants.
//!
//! Everything here over-approximates: an interval contains every value the term can
//! take when the variables range over their intervals. Floating-point results are
//! widened outward by a relative 1e-12 (far above f64's rounding error of about 1e-16
//! per operation for the short terms of contracts), so no rounding can make an interval
//! too small. `None` means "unbounded or unknown".

use crate::hir::expr::{BinOp, UnOp};
use crate::hir::{Builtin, Expr, ExprKind, Program, Var};
use std::collections::HashMap;

/// A closed interval `[lo, hi]`, possibly with infinite ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

const ALL: Interval = Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY };

impl Interval {
    pub fn point(v: f64) -> Interval {
        Interval { lo: v, hi: v }.widen()
    }

    pub fn new(lo: f64, hi: f64) -> Interval {
        Interval { lo, hi }.widen()
    }

    pub fn is_finite(&self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    /// Whether the interval is exactly the number `v` (no widening happened).
    pub fn is_exactly(&self, v: f64) -> bool {
        self.lo == v && self.hi == v
    }

    /// Moves both ends outward by a relative 1e-12 (and an absolute 1e-300), so that
    /// floating-point rounding cannot leave the true value outside.
    fn widen(self) -> Interval {
        if self.lo == self.hi && self.lo.fract() == 0.0 && self.lo.abs() < 1e15 {
            return self; // small integers are exact in f64
        }
        let down = |x: f64| if x.is_finite() { x - x.abs() * 1e-12 - 1e-300 } else { x };
        let up = |x: f64| if x.is_finite() { x + x.abs() * 1e-12 + 1e-300 } else { x };
        Interval { lo: down(self.lo), hi: up(self.hi) }
    }

    pub fn hull(self, o: Interval) -> Interval {
        Interval { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    pub fn meet(self, o: Interval) -> Interval {
        Interval { lo: self.lo.max(o.lo), hi: self.hi.min(o.hi) }
    }

    pub fn disjoint(self, o: Interval) -> bool {
        self.hi < o.lo || o.hi < self.lo
    }

    fn div(self, o: Interval) -> Option<Interval> {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return None; // the divisor may be zero
        }
        let inv = Interval { lo: 1.0 / o.hi, hi: 1.0 / o.lo }.widen();
        Some(self * inv)
    }

    fn pow(self, n: i64) -> Interval {
        match n {
            0 => Interval::point(1.0),
            1 => self,
            _ if n % 2 == 0 && self.lo <= 0.0 && self.hi >= 0.0 => {
                Interval { lo: 0.0, hi: self.lo.abs().max(self.hi.abs()).powi(n as i32) }.widen()
            }
            _ if n % 2 == 0 && self.hi < 0.0 => {
                Interval { lo: self.hi.powi(n as i32), hi: self.lo.powi(n as i32) }.widen()
            }
            _ => Interval { lo: self.lo.powi(n as i32), hi: self.hi.powi(n as i32) }.widen(),
        }
    }
}

/// Sums, negations and products enclose the exact result (outward rounding).
impl std::ops::Add for Interval {
    type Output = Interval;
    fn add(self, o: Interval) -> Interval {
        Interval { lo: self.lo + o.lo, hi: self.hi + o.hi }.widen()
    }
}

impl std::ops::Neg for Interval {
    type Output = Interval;
    fn neg(self) -> Interval {
        Interval { lo: -self.hi, hi: -self.lo }
    }
}

impl std::ops::Mul for Interval {
    type Output = Interval;
    fn mul(self, o: Interval) -> Interval {
        let ps = [self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi];
        if ps.iter().any(|p| p.is_nan()) {
            // 0 * inf: the product is unbounded on the side of the infinite factor.
            return ALL;
        }
        let lo = ps.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = ps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval { lo, hi }.widen()
    }
}

/// Where variables range; `None` is unbounded.
pub trait Ranges {
    fn range(&self, v: &Var) -> Option<Interval>;
}

impl<F: Fn(&Var) -> Option<Interval>> Ranges for F {
    fn range(&self, v: &Var) -> Option<Interval> {
        self(v)
    }
}

/// Constants only: every other variable is unbounded.
pub fn closed(_: &Var) -> Option<Interval> {
    None
}

/// An enclosure of the numeric term `e`, or `None` when it cannot be bounded.
pub fn eval(prog: &Program, e: &Expr, ranges: &dyn Ranges) -> Option<Interval> {
    stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || eval_inner(prog, e, ranges))
}

fn eval_inner(prog: &Program, e: &Expr, ranges: &dyn Ranges) -> Option<Interval> {
    let iv = match &e.kind {
        ExprKind::Int(i) => Interval::point(*i as f64),
        ExprKind::Real(r) => Interval::point(r.parse().ok()?),
        ExprKind::Var(Var::Const(c)) => eval(prog, &prog.consts[c.idx()].value, ranges)?,
        ExprKind::Var(v) => ranges.range(v)?,
        ExprKind::Unary(UnOp::Neg, a) => -eval(prog, a, ranges)?,
        ExprKind::Binary(op, a, b) => {
            let x = eval(prog, a, ranges)?;
            if *op == BinOp::Pow {
                let ExprKind::Int(n) = b.kind else { return None };
                return (n >= 0).then(|| x.pow(n));
            }
            let y = eval(prog, b, ranges)?;
            match op {
                BinOp::Add => x + y,
                BinOp::Sub => x + -y,
                BinOp::Mul => x * y,
                BinOp::Div => x.div(y)?,
                _ => return None,
            }
        }
        ExprKind::If(_, a, b) => eval(prog, a, ranges)?.hull(eval(prog, b, ranges)?),
        ExprKind::Call(f, args) => {
            let arg = |i: usize| args.get(i).and_then(|a| eval(prog, a, ranges));
            match f {
                Builtin::Min => {
                    let (x, y) = (arg(0)?, arg(1)?);
                    Interval { lo: x.lo.min(y.lo), hi: x.hi.min(y.hi) }
                }
                Builtin::Max => {
                    let (x, y) = (arg(0)?, arg(1)?);
                    Interval { lo: x.lo.max(y.lo), hi: x.hi.max(y.hi) }
                }
                Builtin::Abs => {
                    let x = arg(0)?;
                    if x.lo >= 0.0 {
                        x
                    } else if x.hi <= 0.0 {
                        -x
                    } else {
                        Interval { lo: 0.0, hi: x.hi.max(-x.lo) }
                    }
                }
                Builtin::Sqrt => {
                    let x = arg(0)?;
                    if x.lo < 0.0 {
                        return None;
                    }
                    Interval::new(x.lo.sqrt(), x.hi.sqrt())
                }
                Builtin::Sin | Builtin::Cos => trig(*f, arg(0)),
                _ => return None,
            }
        }
        _ => return None,
    };
    Some(iv)
}

/// An enclosure of `sin` or `cos` over `arg`: Lipschitz 1 around the midpoint, capped
/// to [-1, 1]; [-1, 1] when the argument is unbounded.
pub fn trig(f: Builtin, arg: Option<Interval>) -> Interval {
    let unit = Interval { lo: -1.0, hi: 1.0 };
    let Some(x) = arg.filter(Interval::is_finite) else { return unit };
    if x.is_exactly(0.0) {
        // The one argument where both are rational: exact, so `sin(0) == 0` holds.
        let v = if f == Builtin::Sin { 0.0 } else { 1.0 };
        return Interval { lo: v, hi: v };
    }
    let mid = (x.lo + x.hi) / 2.0;
    let half = (x.hi - x.lo) / 2.0;
    let v = if f == Builtin::Sin { mid.sin() } else { mid.cos() };
    // libm's sin and cos are within an ulp; 1e-12 absolute covers it with room.
    Interval { lo: v - half - 1e-12, hi: v + half + 1e-12 }.meet(unit)
}

/// A box around the points `(x, y, z)` satisfying `pred`, where `point(v)` says which
/// coordinate (0, 1, 2) a variable is, if any. Each coordinate may stay unbounded.
pub fn point_box(
    prog: &Program,
    pred: &Expr,
    point: &dyn Fn(&Var) -> Option<usize>,
    ranges: &dyn Ranges,
) -> [Interval; 3] {
    stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || point_box_inner(prog, pred, point, ranges))
}

fn point_box_inner(
    prog: &Program,
    pred: &Expr,
    point: &dyn Fn(&Var) -> Option<usize>,
    ranges: &dyn Ranges,
) -> [Interval; 3] {
    let coord = |e: &Expr| match &e.kind {
        ExprKind::Var(v) => point(v),
        _ => None,
    };
    let mut out = [ALL; 3];
    match &pred.kind {
        ExprKind::Binary(BinOp::And, a, b) => {
            let (x, y) = (point_box(prog, a, point, ranges), point_box(prog, b, point, ranges));
            for k in 0..3 {
                out[k] = x[k].meet(y[k]);
            }
        }
        ExprKind::Binary(BinOp::Or, a, b) => {
            let (x, y) = (point_box(prog, a, point, ranges), point_box(prog, b, point, ranges));
            for k in 0..3 {
                out[k] = x[k].hull(y[k]);
            }
        }
        ExprKind::Binary(op @ (BinOp::Le | BinOp::Lt | BinOp::Ge | BinOp::Gt | BinOp::Eq), a, b) => {
            // `p <= e`, `e <= p`, `p == e` and their mirrors.
            let (lhs, rhs) = match op {
                BinOp::Ge | BinOp::Gt => (b, a),
                _ => (a, b),
            };
            if let Some(k) = coord(lhs) {
                if let Some(r) = eval(prog, rhs, ranges) {
                    out[k].hi = r.hi;
                    if *op == BinOp::Eq {
                        out[k].lo = r.lo;
                    }
                }
            } else if let Some(k) = coord(rhs) {
                if let Some(l) = eval(prog, lhs, ranges) {
                    out[k].lo = l.lo;
                    if *op == BinOp::Eq {
                        out[k].hi = l.hi;
                    }
                }
            } else if matches!(op, BinOp::Le | BinOp::Lt) {
                // A sum of even powers of coordinates below a bound: `px^2 + py^2 <= r^2`.
                if let (Some(squares), Some(r)) = (even_powers(lhs, &coord), eval(prog, rhs, ranges)) {
                    for (k, n) in squares {
                        let m = r.hi.max(0.0).powf(1.0 / n as f64) * (1.0 + 1e-12) + 1e-300;
                        out[k] = out[k].meet(Interval { lo: -m, hi: m });
                    }
                }
            }
        }
        _ => {}
    }
    out
}

/// `e` as a sum of terms `p_k ^ n` with even `n`, each coordinate at most once.
fn even_powers(e: &Expr, coord: &dyn Fn(&Expr) -> Option<usize>) -> Option<Vec<(usize, i64)>> {
    match &e.kind {
        ExprKind::Binary(BinOp::Add, a, b) => {
            let mut v = even_powers(a, coord)?;
            v.extend(even_powers(b, coord)?);
            Some(v)
        }
        ExprKind::Binary(BinOp::Pow, a, n) => match (coord(a), &n.kind) {
            (Some(k), ExprKind::Int(n)) if *n > 0 && n % 2 == 0 => Some(vec![(k, *n)]),
            _ => None,
        },
        ExprKind::Binary(BinOp::Mul, a, b) if a == b => coord(a).map(|k| vec![(k, 2)]),
        _ => None,
    }
}

/// Ranges of variables read off conjuncts of the form `v op e`, `e op v` or `v == e`
/// where `e` can be bounded from what is already known (two passes, so that
/// `x == y` after `y == 1` is found).
pub fn ranges_from(prog: &Program, facts: &[&Expr], start: &dyn Ranges) -> HashMap<Var, Interval> {
    let mut known: HashMap<Var, Interval> = HashMap::new();
    let cs: Vec<&Expr> = facts.iter().flat_map(|f| f.conjuncts()).collect();
    let is_var = |e: &Expr| match &e.kind {
        ExprKind::Var(v @ (Var::Role(..) | Var::Value(..) | Var::Own(_) | Var::Old(_) | Var::Snap(..))) => {
            Some(v.clone())
        }
        _ => None,
    };
    for _ in 0..2 {
        for c in &cs {
            let ExprKind::Binary(op, a, b) = &c.kind else { continue };
            let (lhs, rhs, op) = match op {
                BinOp::Ge => (b, a, BinOp::Le),
                BinOp::Gt => (b, a, BinOp::Lt),
                op => (a, b, *op),
            };
            if !matches!(op, BinOp::Le | BinOp::Lt | BinOp::Eq) {
                continue;
            }
            let found = {
                let lookup = |v: &Var| match (known.get(v).copied(), start.range(v)) {
                    (Some(a), Some(b)) => Some(a.meet(b)),
                    (a, b) => a.or(b),
                };
                let from_left = is_var(lhs).and_then(|v| {
                    let r = eval(prog, rhs, &lookup)?;
                    let lo = if op == BinOp::Eq { r.lo } else { f64::NEG_INFINITY };
                    Some((v, Interval { lo, hi: r.hi }))
                });
                from_left.or_else(|| {
                    let v = is_var(rhs)?;
                    let l = eval(prog, lhs, &lookup)?;
                    let hi = if op == BinOp::Eq { l.hi } else { f64::INFINITY };
                    Some((v, Interval { lo: l.lo, hi }))
                })
            };
            if let Some((v, iv)) = found {
                known.entry(v).and_modify(|old| *old = old.meet(iv)).or_insert(iv);
            }
        }
    }
    known
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::lower_src;

    fn guard(p: &str) -> (Program, Expr) {
        let src = format!(
            "const r = 0.5; robot R {{ state x: real, y: real, z: real; }}
             system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{p}] go. end;"
        );
        let (prog, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let Some(crate::hir::Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("expected a sequence")
        };
        let crate::hir::Global::Msg(m) = &items[0] else { panic!("expected a message") };
        (prog, m.guard.clone().expect("guard"))
    }

    fn slot(v: &Var) -> Option<usize> {
        match v {
            Var::Role(_, crate::hir::Slot::State(i)) => Some(*i),
            _ => None,
        }
    }

    #[test]
    fn boxes_enclose_linear_bounds_and_spheres() {
        let (prog, e) = guard("0 <= x <= 2 * r && (y^2 + z^2 <= r^2 || y == 3)");
        let b = point_box(&prog, &e, &slot, &closed);
        assert!(b[0].lo <= 0.0 && b[0].hi >= 1.0 && b[0].hi < 1.0 + 1e-9, "{b:?}");
        assert!(b[1].lo <= -0.5 && b[1].hi >= 3.0 && b[1].hi < 3.0 + 1e-9, "{b:?}");
        // `y == 3` leaves z free, so the hull over the disjunction is unbounded in z.
        assert!(!b[2].is_finite(), "{b:?}");
        let (prog, e) = guard("x^2 + y^2 + z^2 <= r^2 && z >= 0");
        let b = point_box(&prog, &e, &slot, &closed);
        assert!(b[2].lo == 0.0 && b[2].hi >= 0.5 && b[2].hi < 0.5 + 1e-9, "{b:?}");
        assert!(b[0].lo <= -0.5 && b[0].lo > -0.5 - 1e-9, "{b:?}");
    }

    #[test]
    fn unbounded_coordinates_stay_unbounded() {
        let (prog, e) = guard("x >= 0 || y > 1");
        let b = point_box(&prog, &e, &slot, &closed);
        assert!(!b[0].is_finite() && !b[1].is_finite() && !b[2].is_finite());
    }

    #[test]
    fn intervals_contain_the_true_value() {
        let (prog, e) = guard("x == sqrt(2) * sqrt(2) - 2 + r / 3");
        let ExprKind::Binary(_, _, rhs) = &e.kind else { panic!() };
        let iv = eval(&prog, rhs, &closed).expect("closed term");
        let v = 2f64.sqrt() * 2f64.sqrt() - 2.0 + 0.5 / 3.0;
        assert!(iv.lo <= v && v <= iv.hi && iv.hi - iv.lo < 1e-9, "{iv:?}");
        let s = trig(Builtin::Sin, Some(Interval::point(1.2)));
        assert!(s.lo <= 1.2f64.sin() && 1.2f64.sin() <= s.hi && s.hi <= 1.0);
    }

    #[test]
    fn ranges_are_read_off_facts() {
        let (prog, e) = guard("y == 2 && x <= y + 1 && 0 <= x && z > 1");
        let rs = ranges_from(&prog, &[&e], &closed);
        let get = |i| rs.iter().find(|(v, _)| slot(v) == Some(i)).map(|(_, r)| *r);
        assert_eq!(get(1), Some(Interval::point(2.0)));
        let x = get(0).expect("x bounded");
        assert!(x.lo == 0.0 && (3.0..3.0 + 1e-9).contains(&x.hi), "{x:?}");
        assert_eq!(get(2).map(|r| r.hi), Some(f64::INFINITY));
    }
}
