//! Contraction by bounds affine in one start value: a guarantee conjunct `x <= e` (or
//! `e <= x`, `x == e`) whose other side `e` is affine in exactly one `old(y)` (the joint-space
//! moves' `old(J) + (a - old(J)) * clock / d ± err`). Interval evaluation of `e` over the
//! whole range of `old(y)` counts `old(y)` twice (the dependency problem: the band at the end
//! of a move is three times the tracking error wide instead of one); here `e` is evaluated
//! with `old(y)` pinned at each end of its range instead, and the bound is the hull of the
//! two.
//!
//! Sound: if `e = α(w) + β(w) · v` for every value `w` of the other variables (affine in
//! `v`), then for each `w` the values of `e` over `v ∈ [l, h]` lie between `e(l, w)` and
//! `e(h, w)`; each of those lies in the interval evaluation of `e` with `v := [l, l]`
//! (resp. `[h, h]`) and `w` over its box, which is outward rounded. So every value of `e`
//! over the box lies in the hull of the two enclosures.

use crate::hir::expr::{mentions, ExprKind};
use crate::hir::{Expr, Var};
use crate::syntax::ast::{BinOp, UnOp};

/// Which side of the variable a conjunct bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Side {
    /// `x <= e` (or `x < e`: its closure, a superset).
    Upper,
    /// `e <= x`.
    Lower,
    /// `x == e`.
    Both,
}

/// A conjunct `x op e` with `e` affine in one start value `old`.
#[derive(Clone, Debug)]
pub(super) struct AffineBound<'a> {
    pub own: Var,
    pub side: Side,
    pub e: &'a Expr,
    pub old: Var,
}

/// The conjuncts of `facts` that bound a variable `Own(_)` by an expression affine in
/// exactly one `Old(_)` (and mentioning no `Own(_)`).
pub(super) fn affine_bounds<'a>(facts: &[&'a Expr]) -> Vec<AffineBound<'a>> {
    let mut out = Vec::new();
    for c in facts.iter().flat_map(|f| f.conjuncts()) {
        let ExprKind::Binary(op, a, b) = &c.kind else { continue };
        let (x, e, side) = match (op, &a.kind, &b.kind) {
            (BinOp::Le | BinOp::Lt, ExprKind::Var(v @ Var::Own(_)), _) => (v, &**b, Side::Upper),
            (BinOp::Le | BinOp::Lt, _, ExprKind::Var(v @ Var::Own(_))) => (v, &**a, Side::Lower),
            (BinOp::Ge | BinOp::Gt, ExprKind::Var(v @ Var::Own(_)), _) => (v, &**b, Side::Lower),
            (BinOp::Ge | BinOp::Gt, _, ExprKind::Var(v @ Var::Own(_))) => (v, &**a, Side::Upper),
            (BinOp::Eq, ExprKind::Var(v @ Var::Own(_)), _) => (v, &**b, Side::Both),
            (BinOp::Eq, _, ExprKind::Var(v @ Var::Own(_))) => (v, &**a, Side::Both),
            _ => continue,
        };
        if mentions(e, &|v| matches!(v, Var::Own(_))) {
            continue;
        }
        let mut olds: Vec<Var> = Vec::new();
        e.visit_vars(&mut |v, _| {
            if matches!(v, Var::Old(_)) && !olds.contains(v) {
                olds.push(v.clone());
            }
        });
        let [old] = &olds[..] else { continue };
        if affine_in(e, old) == Some(true) {
            out.push(AffineBound { own: x.clone(), side, e, old: old.clone() });
        }
    }
    out
}

/// `Some(true)`: `e` is affine in `v` and mentions it; `Some(false)`: `e` does not mention
/// `v`; `None`: `v` occurs non-affinely (under a product with itself, a power, a function,
/// a division by it, a condition).
pub(super) fn affine_in(e: &Expr, v: &Var) -> Option<bool> {
    if !mentions(e, &|x| x == v) {
        return Some(false);
    }
    match &e.kind {
        ExprKind::Var(x) => Some(x == v),
        ExprKind::Unary(UnOp::Neg, a) => affine_in(a, v),
        ExprKind::Binary(BinOp::Add | BinOp::Sub, a, b) => Some(affine_in(a, v)? | affine_in(b, v)?),
        ExprKind::Binary(BinOp::Mul, a, b) => match (affine_in(a, v)?, affine_in(b, v)?) {
            (true, true) => None,
            (x, y) => Some(x | y),
        },
        ExprKind::Binary(BinOp::Div, a, b) => match affine_in(b, v)? {
            false => affine_in(a, v),
            true => None,
        },
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hir::Loc;
    use crate::hir::Slot;

    fn var(v: Var) -> Expr {
        Expr { kind: ExprKind::Var(v), sort: crate::hir::Sort::Real, loc: Loc::default() }
    }
    fn bin(op: BinOp, a: Expr, b: Expr) -> Expr {
        Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort: crate::hir::Sort::Real, loc: Loc::default() }
    }

    #[test]
    fn the_moves_band_is_affine_in_its_start_and_a_square_is_not() {
        let old = Var::Old(0);
        let (a, t, d) = (var(Var::Param(0)), var(Var::Clock), var(Var::Param(1)));
        // old + (a - old) * clock / d
        let line = bin(
            BinOp::Add,
            var(old.clone()),
            bin(BinOp::Div, bin(BinOp::Mul, bin(BinOp::Sub, a.clone(), var(old.clone())), t.clone()), d.clone()),
        );
        assert_eq!(affine_in(&line, &old), Some(true));
        assert_eq!(affine_in(&a, &old), Some(false));
        let square = bin(BinOp::Mul, var(old.clone()), var(old.clone()));
        assert_eq!(affine_in(&square, &old), None);
        let by_old = bin(BinOp::Div, a.clone(), var(old.clone()));
        assert_eq!(affine_in(&by_old, &old), None);
        // x <= line is found; x <= old * old is not
        let x = var(Var::Own(Slot::State(0)));
        let c1 = bin(BinOp::Le, x.clone(), line);
        let c2 = bin(BinOp::Le, x, square);
        let found = affine_bounds(&[&c1, &c2]);
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].side, Side::Upper);
    }
}
