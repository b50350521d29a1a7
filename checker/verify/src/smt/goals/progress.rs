//! Progress (E0419): the query of a [`Goal::Progress`](crate::obligation::Goal) part.
//! A branch can be taken when its guard holds and some payload satisfies its
//! refinements: `guard ∧ ∃ fields. refinement`, the fields bound by an existential over
//! the very constants the encoder gives their values (Z3 abstracts them inside the
//! body only, so a fact of Σ about the same field's earlier value, from an earlier
//! iteration of a loop, stays about that value). The part's query is Σ ∧ ¬∨ branches;
//! sat is a state of Σ in which no branch can be taken. Quantified queries go to Z3's
//! default solver (MBQI), never nlsat; undecided is unknown, never a pass.
//!
//! The guard and the refinement arrive with their definedness conjoined
//! (`plan::progress::enabled`, [`crate::hir::expr::definedness`]): the encoder makes `sqrt` of a
//! negative and a quotient by zero unconstrained values, which some payload would equal, so
//! without it "some payload exists" held where no value on the wire satisfies the refinement.

use super::super::encode::{as_real, Encoder, Term, Unsupported};
use crate::hir::expr::{mentions, value_expr, BinOp, UnOp};
use crate::hir::{Expr, ExprKind, Sort, ValueId, Var};
use crate::obligation::Enabled;
use num_rational::BigRational;
use num_traits::{One, Zero};
use z3::ast::{Ast, Bool, Int, Real};

/// `guard ∧ ∃ fields. refinement` as a Z3 formula.
pub fn enabled(enc: &mut Encoder, b: &Enabled) -> Result<Bool, Unsupported> {
    let guard = match &b.guard {
        Some(g) => enc.boolean(g)?,
        None => Bool::from_bool(true),
    };
    if b.fields.is_empty() {
        return Ok(Bool::and(&[guard, enc.boolean(&b.refinement)?]));
    }
    let side_before = enc.side_conditions().count();
    // Integer fields whose every conjunct is a linear bound are eliminated exactly
    // (`eliminable`); the others stay bound by the existential.
    let conjuncts = b.refinement.conjuncts();
    let eliminated = eliminable(enc, b, &conjuncts);
    let kept: Vec<_> = b.fields.iter().filter(|(id, _, _)| !eliminated.iter().any(|(e, _, _)| e == id)).collect();
    let mut bound: Vec<Term> = Vec::new();
    for (id, name, sort) in &kept {
        bound.push(enc.any(&value_expr(*id, name, sort))?);
    }
    // A chosen `float` value is a binary32 (`Encoder::choosing`): its significand is
    // bound with it.
    let ids: Vec<_> = kept.iter().map(|(id, _, _)| *id).collect();
    let (body, significands) = enc.choosing(&ids, |enc| -> Result<Bool, Unsupported> {
        let mut parts = Vec::new();
        let replaced = |c: &Expr| eliminated.iter().any(|(_, _, used)| used.iter().any(|u| std::ptr::eq(*u, c)));
        for c in conjuncts.iter().filter(|c| !replaced(c)) {
            parts.push(enc.boolean(c)?);
        }
        for (_, bounds, _) in &eliminated {
            parts.push(some_integer_between(enc, bounds)?);
        }
        Ok(Bool::and(&parts))
    });
    let body = body?;
    if enc.side_conditions().count() != side_before {
        // A side condition (of `sqrt`, `/`, trigonometry) about a bound value would be
        // asserted outside its quantifier: refuse rather than mis-state it.
        return Err(Unsupported(format!(
            "a payload refinement of {} with `sqrt`, division or trigonometry, under \"some value exists\"",
            b.what
        )));
    }
    if !eliminated.is_empty() {
        enc.integer_terms();
    }
    if bound.is_empty() && significands.is_empty() {
        return Ok(Bool::and(&[guard, body]));
    }
    let mut consts: Vec<&dyn Ast> = Vec::new();
    for t in &bound {
        match t {
            Term::B(x) => consts.push(x),
            Term::I(x) => consts.push(x),
            Term::R(x) => consts.push(x),
            Term::V(xs) => xs.iter().for_each(|x| consts.push(x)),
        }
    }
    significands.iter().for_each(|m| consts.push(m));
    enc.quantified();
    let some = z3::ast::exists_const(&consts, &[], &body);
    Ok(Bool::and(&[guard, some]))
}

/// A linear bound on an integer payload value `y`: `y >= t` (`lower`) or `y <= t`, strict
/// or not, `t` as `Σ k·e` over expressions without `y`.
struct Bound<'e> {
    lower: bool,
    strict: bool,
    terms: Vec<(BigRational, &'e Expr)>,
}

/// The integer payload fields of `b` that can be eliminated exactly, with the conjuncts of
/// the refinement that mention them as bounds. A field `y` of sort `int` qualifies when
/// every conjunct mentioning it is a comparison (`<`, `<=`, `>`, `>=`, `==`) linear in `y`
/// with a constant non-zero coefficient, whose other side mentions no other chosen integer
/// field: then `∃ y. ∧ bounds` is exactly "the bounds leave an integer between them",
/// [`some_integer_between`] (one variable with only bounds: every lower bound's ceiling is
/// at most every upper bound's floor). Z3's quantifier instantiation does not find the
/// witness `y = ⌈l⌉` when a bound is a real (a `float` command parameter scaled by 1e7
/// against an `int32_t` latitude) and times out; the quantifier-free form is decided at once.
fn eliminable<'e>(enc: &Encoder, b: &Enabled, conjuncts: &[&'e Expr]) -> Vec<(ValueId, Vec<Bound<'e>>, Vec<&'e Expr>)> {
    let ints: Vec<ValueId> = b.fields.iter().filter(|(_, _, s)| *s == Sort::Int).map(|(id, _, _)| *id).collect();
    let mut out = Vec::new();
    'fields: for &y in &ints {
        let others = |e: &Expr| mentions(e, &|v| matches!(v, Var::Value(id, _) if *id != y && ints.contains(id)));
        let mut bounds = Vec::new();
        let mut used = Vec::new();
        for c in conjuncts.iter().copied() {
            if !mentions(c, &|v| matches!(v, Var::Value(id, _) if *id == y)) {
                continue;
            }
            let ExprKind::Binary(op, l, r) = &c.kind else { continue 'fields };
            if !matches!(op, BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq) || others(c) {
                continue 'fields;
            }
            let (Some((ka, ta)), Some((kb, tb))) = (linear(enc.prog(), l, y), linear(enc.prog(), r, y)) else {
                continue 'fields;
            };
            // l op r  <=>  k·y op' t, with k = ka - kb and t = Σ tb - Σ ta.
            let k = &ka - &kb;
            if k.is_zero() {
                continue 'fields;
            }
            let mut t: Vec<(BigRational, &Expr)> = tb;
            t.extend(ta.into_iter().map(|(q, e)| (-q, e)));
            let t: Vec<_> = t.into_iter().map(|(q, e)| (q / &k, e)).collect();
            let flip = k < BigRational::zero();
            let mut push = |lower: bool, strict: bool| {
                bounds.push(Bound { lower: lower != flip, strict, terms: t.clone() });
            };
            match op {
                BinOp::Lt => push(false, true),
                BinOp::Le => push(false, false),
                BinOp::Gt => push(true, true),
                BinOp::Ge => push(true, false),
                _ => {
                    push(true, false);
                    push(false, false);
                }
            }
            used.push(c);
        }
        out.push((y, bounds, used));
    }
    out
}

/// `e` as `k·y + Σ q·t` (`k`, `q` exact constants, no `t` mentioning `y`), if it is linear
/// in `y` with constant coefficients; an `e` without `y` is one term.
fn linear<'e>(
    prog: &crate::hir::Program,
    e: &'e Expr,
    y: ValueId,
) -> Option<(BigRational, Vec<(BigRational, &'e Expr)>)> {
    let has_y = |e: &Expr| mentions(e, &|v| matches!(v, Var::Value(id, _) if *id == y));
    if !has_y(e) {
        return Some((BigRational::zero(), vec![(BigRational::one(), e)]));
    }
    let scale = |(k, t): (BigRational, Vec<(BigRational, &'e Expr)>), q: &BigRational| {
        (&k * q, t.into_iter().map(|(p, e)| (p * q, e)).collect::<Vec<_>>())
    };
    match &e.kind {
        ExprKind::Var(Var::Value(id, _)) if *id == y => Some((BigRational::one(), Vec::new())),
        ExprKind::Unary(UnOp::Neg, a) => Some(scale(linear(prog, a, y)?, &-BigRational::one())),
        ExprKind::Binary(op @ (BinOp::Add | BinOp::Sub), a, b) => {
            let (ka, mut ta) = linear(prog, a, y)?;
            let sign = if *op == BinOp::Add { BigRational::one() } else { -BigRational::one() };
            let (kb, tb) = scale(linear(prog, b, y)?, &sign);
            ta.extend(tb);
            Some((ka + kb, ta))
        }
        ExprKind::Binary(BinOp::Mul, a, b) => {
            let (q, rest) = if has_y(a) {
                (crate::lower::exact_constant(prog, b)?, a)
            } else {
                (crate::lower::exact_constant(prog, a)?, b)
            };
            Some(scale(linear(prog, rest, y)?, &q))
        }
        _ => None,
    }
}

/// "Some integer `y` satisfies every bound" without `y`: each lower bound rounded up to an
/// integer is at most each upper bound rounded down (`true` without a lower or without
/// an upper bound: the integers are unbounded). A bound that is an integer term is used
/// as it is; a real one is rounded with `to_int` (the floor). Exact.
fn some_integer_between(enc: &mut Encoder, bounds: &[Bound]) -> Result<Bool, Unsupported> {
    let mut lowers = Vec::new();
    let mut uppers = Vec::new();
    for bd in bounds {
        let mut ints = Vec::new();
        let mut reals = Vec::new();
        for (q, e) in &bd.terms {
            match enc.any(e)? {
                Term::I(i) if q.is_integer() => {
                    let k = q.numer().to_string().parse::<Int>().map_err(|_| Unsupported("a coefficient".into()))?;
                    ints.push(Int::mul(&[k, i]));
                }
                t => {
                    let k =
                        super::super::encode::real_of_rational(q).ok_or_else(|| Unsupported("a coefficient".into()))?;
                    reals.push(Real::mul(&[k, as_real(t)?]));
                }
            }
        }
        let one = Int::from_i64(1);
        // The least (lower bound) or greatest (upper) integer the bound admits.
        let edge = if reals.is_empty() {
            let t = if ints.is_empty() { Int::from_i64(0) } else { Int::add(&ints) };
            match (bd.lower, bd.strict) {
                (true, true) => Int::add(&[t, one]),
                (false, true) => Int::sub(&[t, one]),
                _ => t,
            }
        } else {
            reals.extend(ints.iter().map(|i| i.to_real()));
            let t = Real::add(&reals);
            let floor = |r: &Real| r.to_int();
            let ceil = |r: &Real| floor(&r.unary_minus()).unary_minus();
            match (bd.lower, bd.strict) {
                (true, false) => ceil(&t),
                (true, true) => Int::add(&[floor(&t), one]),
                (false, false) => floor(&t),
                (false, true) => Int::sub(&[ceil(&t), one]),
            }
        };
        if bd.lower {
            lowers.push(edge)
        } else {
            uppers.push(edge)
        }
    }
    let mut pairs = Vec::new();
    for l in &lowers {
        for u in &uppers {
            pairs.push(l.le(u));
        }
    }
    Ok(Bool::and(&pairs))
}
