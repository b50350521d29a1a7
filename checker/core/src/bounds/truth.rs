//! Three-valued truth of a predicate over a box of its variables, by interval
//! evaluation ([`crate::bounds::eval`], outward-rounded): the geometric decision
//! procedure prunes boxes of state and time where a guarantee, an invariant or the
//! context cannot hold, and a box where everything holds at every point needs no
//! witness.
//!
//! Sound by construction: `Some(false)` only when no point of the box satisfies `e`
//! (a comparison whose enclosures are strictly ordered the wrong way, a conjunction
//! with such a conjunct, ...), `Some(true)` only when every point does. Anything the
//! enclosures cannot settle is `None`.

use crate::bounds::{self, Ranges};
use crate::hir::expr::{BinOp, ExprKind, UnOp};
use crate::hir::{Expr, Program};

/// `Some(b)` when `e` has the value `b` at every point of the box `ranges` describes.
pub fn truth(prog: &Program, e: &Expr, ranges: &dyn Ranges) -> Option<bool> {
    crate::stack::deep(|| truth_inner(prog, e, ranges))
}

fn truth_inner(prog: &Program, e: &Expr, ranges: &dyn Ranges) -> Option<bool> {
    match &e.kind {
        ExprKind::Bool(b) => Some(*b),
        ExprKind::Unary(UnOp::Not, a) => truth(prog, a, ranges).map(|b| !b),
        ExprKind::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => {
            let (x, y) = (truth(prog, a, ranges), truth(prog, b, ranges));
            match op {
                BinOp::And => match (x, y) {
                    (Some(false), _) | (_, Some(false)) => Some(false),
                    (Some(true), Some(true)) => Some(true),
                    _ => None,
                },
                BinOp::Or => match (x, y) {
                    (Some(true), _) | (_, Some(true)) => Some(true),
                    (Some(false), Some(false)) => Some(false),
                    _ => None,
                },
                _ => match (x, y) {
                    (Some(false), _) | (_, Some(true)) => Some(true),
                    (Some(true), Some(false)) => Some(false),
                    _ => None,
                },
            }
        }
        ExprKind::Binary(op @ (BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne), a, b)
            if a.sort.is_numeric() && b.sort.is_numeric() =>
        {
            compare(*op, bounds::eval(prog, a, ranges)?, bounds::eval(prog, b, ranges)?)
        }
        ExprKind::If(c, a, b) if e.sort == crate::hir::Sort::Bool => match truth(prog, c, ranges) {
            Some(true) => truth(prog, a, ranges),
            Some(false) => truth(prog, b, ranges),
            None => match (truth(prog, a, ranges), truth(prog, b, ranges)) {
                (Some(x), Some(y)) if x == y => Some(x),
                _ => None,
            },
        },
        _ => None,
    }
}

/// `x op y` for every pair of values of the two intervals (`Some(true)`), for none
/// (`Some(false)`), or undecided; NaN ends decide nothing. `op` is a comparison (`Ne` for
/// any other operator).
pub fn compare(op: BinOp, x: bounds::Interval, y: bounds::Interval) -> Option<bool> {
    if x.lo.is_nan() || x.hi.is_nan() || y.lo.is_nan() || y.hi.is_nan() {
        return None;
    }
    // `a < b` everywhere when x.hi < y.lo; nowhere when x.lo >= y.hi; and so on.
    match op {
        BinOp::Lt => decide(x.hi < y.lo, x.lo >= y.hi),
        BinOp::Le => decide(x.hi <= y.lo, x.lo > y.hi),
        BinOp::Gt => decide(x.lo > y.hi, x.hi <= y.lo),
        BinOp::Ge => decide(x.lo >= y.hi, x.hi < y.lo),
        BinOp::Eq => decide(x.lo == x.hi && y.lo == y.hi && x.lo == y.lo, x.hi < y.lo || y.hi < x.lo),
        _ => decide(x.hi < y.lo || y.hi < x.lo, x.lo == x.hi && y.lo == y.hi && x.lo == y.lo),
    }
}

fn decide(always: bool, never: bool) -> Option<bool> {
    if always {
        Some(true)
    } else if never {
        Some(false)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bounds::Interval;
    use crate::hir::{Slot, Var};

    fn guarantee(g: &str) -> (Program, Expr) {
        let (prog, d) = crate::lower::tests::lower_src(&format!(
            "robot R {{ state x: real; }} motion R.m {{ interruptible: true; guarantee: {g}; }}
             system S {{ participant A: R; }} choreography G = dt<A: m>. end;"
        ));
        assert!(d.is_empty(), "{d:?}");
        let e = prog.prims[0].guarantee.clone();
        (prog, e)
    }

    fn at(prog: &Program, e: &Expr, x: (f64, f64), old: (f64, f64), t: (f64, f64)) -> Option<bool> {
        let r = move |v: &Var| match v {
            Var::Own(Slot::State(0)) => Some(Interval::new(x.0, x.1)),
            Var::Old(0) => Some(Interval::new(old.0, old.1)),
            Var::Clock => Some(Interval::new(t.0, t.1)),
            _ => None,
        };
        truth(prog, e, &r)
    }

    #[test]
    fn a_box_where_the_guarantee_cannot_hold_is_false_and_one_where_it_must_is_true() {
        let (p, g) = guarantee("old(x) <= x && x <= old(x) + clock^2 / 8");
        assert_eq!(at(&p, &g, (0.5, 1.0), (0.0, 0.0), (0.0, 1.0)), Some(false), "x > clock^2/8 everywhere");
        assert_eq!(at(&p, &g, (0.0, 0.1), (0.0, 0.0), (1.0, 2.0)), Some(true));
        assert_eq!(at(&p, &g, (0.0, 0.2), (0.0, 0.0), (1.0, 2.0)), None);
    }

    #[test]
    fn equalities_are_true_only_on_points_and_false_when_apart() {
        let (p, g) = guarantee("x == old(x)");
        assert_eq!(at(&p, &g, (1.0, 2.0), (3.0, 3.0), (0.0, 1.0)), Some(false));
        assert_eq!(at(&p, &g, (1.0, 2.0), (1.5, 1.5), (0.0, 1.0)), None);
        assert_eq!(at(&p, &g, (3.0, 3.0), (3.0, 3.0), (0.0, 1.0)), Some(true));
        let (p, g) = guarantee("!(x == old(x)) || x > 5 => x < 0");
        assert_eq!(at(&p, &g, (1.0, 2.0), (3.0, 3.0), (0.0, 1.0)), Some(false));
    }

    #[test]
    fn unbounded_variables_settle_nothing() {
        let (p, g) = guarantee("x <= 1");
        let r = |_: &Var| None;
        assert_eq!(truth(&p, &g, &r), None);
    }
}
