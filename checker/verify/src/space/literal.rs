//! Exact numbers as terms: a rational as a quotient of integer literals, and a double as the
//! exact rational it denotes. Shared by the geometry stage (`world.rs`: URDF joint limits)
//! and the body-containment search (`enclose`), which is why it is a module of its own.

use crate::hir::expr::{BinOp, ExprKind, UnOp};
use crate::hir::{Expr, Loc, Sort};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive};

fn int(i: i64) -> Expr {
    Expr { kind: ExprKind::Int(i), sort: Sort::Int, loc: Loc::default() }
}

fn bin(op: BinOp, a: Expr, b: Expr) -> Expr {
    Expr { kind: ExprKind::Binary(op, Box::new(a), Box::new(b)), sort: Sort::Real, loc: Loc::default() }
}

/// The exact rational `q` as a term (a quotient of two integer literals).
pub(crate) fn rational(q: &BigRational) -> Expr {
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

/// The double `v` as an exact rational term (a quotient of integer literals); `None` for
/// an infinite or NaN value.
pub(crate) fn exact_double(v: f64, loc: Loc) -> Option<Expr> {
    let q = BigRational::from_float(v)?;
    let e = rational(&q);
    Some(e.map(&mut |n| Expr { loc, ..n }))
}
