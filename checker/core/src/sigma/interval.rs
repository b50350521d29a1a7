//! Bounds by constants (ARCHITECTURE.md, "The logical context Σ"): the lower and upper
//! bounds of Σ's variables by constant terms (number literals, named constants and
//! arithmetic on them), stated by a fact or implied by one step of interval reasoning.
//!
//! A fact `c <= t`, `c < t` or `t == c` with `c` constant bounds `t` directly. A fact
//! `e <= t` (or `e < t`, `t == e`) with `e` not constant bounds a variable `t` by a lower
//! bound of `e`, computed from the direct bounds of `e`'s parts: `min(a, b)` is at least
//! the smaller of their lower bounds, `max(a, b)` at least either's (and symmetrically for
//! upper bounds). So `min(clear_z, old(ze)) <= ze` with `hover_z <= old(ze)` bounds `ze`
//! below by `min(clear_z, hover_z)`, which is `hover_z` when the constants' values order
//! them. No arithmetic is done on bounds: a derived bound is always a constant term that a
//! fact names, so the bounds a loop's contexts can hold are finitely many and the loop
//! handling still reaches its fixpoint (`x == old(x) + 1` would otherwise raise `x`'s
//! bound by one each round).
//! Each such bound is implied by the facts it comes from (interval arithmetic is sound),
//! so adding it, or keeping it where those facts are dropped, only restates what Σ says.
//!
//! Constants are compared by their exact values (`exact::eval`, rational intervals; a
//! constant with an enclosure such as `pi / 2` compares only where its enclosure decides
//! the order). A `min` (for a lower bound) of two constants the values do not order gives
//! no bound.

use super::normal::{binary, normalize};
use crate::exact::{self, Num};
use crate::hir::expr::BinOp;
use crate::hir::*;
use rustc_hash::FxHashMap;

/// A bound by a constant term: its term, its value (a rational interval) and whether
/// it is strict.
#[derive(Clone, Debug)]
pub(super) struct Bound {
    pub lit: Expr,
    pub value: Num,
    pub strict: bool,
}

impl Bound {
    /// Whether this bound says strictly more than `o` (as lower bounds, or upper ones),
    /// decided by the values; `None` when their enclosures do not decide it.
    pub fn tighter(&self, o: &Bound, lower: bool) -> Option<bool> {
        let (a, b) = (&self.value, &o.value);
        if a.is_exact() && b.is_exact() && a.lo == b.lo {
            return Some(self.strict && !o.strict);
        }
        if a.hi < b.lo {
            return Some(!lower);
        }
        if a.lo > b.hi {
            return Some(lower);
        }
        None
    }

    pub fn op(&self) -> BinOp {
        if self.strict {
            BinOp::Lt
        } else {
            BinOp::Le
        }
    }

    /// The fact this bound states of `term`.
    pub fn fact(&self, term: &Expr, lower: bool) -> Expr {
        if lower {
            normalize(binary(self.op(), &self.lit, term))
        } else {
            normalize(binary(self.op(), term, &self.lit))
        }
    }
}

/// The tightest lower and upper bound of each term.
pub(super) type Bounds<'s> = FxHashMap<&'s Expr, (Option<Bound>, Option<Bound>)>;

/// Whether `e` is a constant term: no variable but named constants.
pub(super) fn constant(e: &Expr) -> bool {
    let mut only = true;
    e.visit_vars(&mut |v, _| only &= matches!(v, Var::Const(_)));
    only
}

/// The value of a constant term, as a rational interval.
pub(super) fn value(prog: &Program, e: &Expr) -> Option<Num> {
    let none = |_: &Var| None;
    exact::eval(prog, e, &none).ok()?.num().ok().cloned()
}

/// Puts `b` in `slot` when it is tighter than what is there (or the slot is empty).
fn offer(slot: &mut Option<Bound>, b: Bound, lower: bool) {
    if slot.as_ref().is_none_or(|old| b.tighter(old, lower) == Some(true)) {
        *slot = Some(b);
    }
}

/// The bounds the facts state directly: `c <= t`, `c < t`, `t <= c`, `t < c`, `t == c`
/// with `c` a constant term whose value can be computed.
pub(super) fn direct<'s>(prog: &Program, facts: &'s [Expr]) -> Bounds<'s> {
    let mut out: Bounds<'s> = FxHashMap::default();
    for f in facts {
        let ExprKind::Binary(op, a, b) = &f.kind else { continue };
        let strict = match op {
            BinOp::Le | BinOp::Eq => false,
            BinOp::Lt => true,
            _ => continue,
        };
        let (ca, cb) = (constant(a), constant(b));
        if ca == cb {
            continue;
        }
        let (term, lit, lit_is_lower) = if ca { (&**b, &**a, true) } else { (&**a, &**b, false) };
        let Some(value) = value(prog, lit) else { continue };
        let bound = Bound { lit: lit.clone(), value, strict };
        let e = out.entry(term).or_default();
        if *op == BinOp::Eq || lit_is_lower {
            offer(&mut e.0, bound.clone(), true);
        }
        if *op == BinOp::Eq || !lit_is_lower {
            offer(&mut e.1, bound, false);
        }
    }
    out
}

/// Whether `e` is a variable of the state or a value (what derived bounds are about).
fn is_var(e: &Expr) -> bool {
    matches!(e.kind, ExprKind::Var(Var::Role(..) | Var::Snap(..) | Var::Value(..)))
}

/// The bounds one step of interval reasoning derives for variables from the facts for
/// which `from` answers true, over the direct bounds `known`: for a fact `e <= t`
/// (`e < t`, `t == e`) with `t` a variable and `e` not constant, a lower bound of `e`
/// bounds `t`; symmetrically for upper bounds. A derived bound is offered to the
/// variable's slot in `known` only where it is tighter than the bound there.
pub(super) fn derive<'s>(prog: &Program, facts: &'s [Expr], known: &mut Bounds<'s>, from: &dyn Fn(&Expr) -> bool) {
    let mut found: Vec<(&'s Expr, Bound, bool)> = Vec::new();
    for f in facts.iter().filter(|f| from(f)) {
        let ExprKind::Binary(op, a, b) = &f.kind else { continue };
        let strict = match op {
            BinOp::Le | BinOp::Eq => false,
            BinOp::Lt => true,
            _ => continue,
        };
        // (variable, other side, whether the other side is below the variable)
        let mut cases: Vec<(&'s Expr, &'s Expr, bool)> = Vec::new();
        if is_var(b) && !constant(a) {
            cases.push((b, a, true));
            if *op == BinOp::Eq {
                cases.push((b, a, false));
            }
        }
        if is_var(a) && !constant(b) {
            cases.push((a, b, false));
            if *op == BinOp::Eq {
                cases.push((a, b, true));
            }
        }
        for (t, e, below) in cases {
            let lit = if below { bound_expr(prog, e, known, true) } else { bound_expr(prog, e, known, false) };
            let Some(lit) = lit else { continue };
            let Some(value) = value(prog, &lit) else { continue };
            found.push((t, Bound { lit, value, strict }, below));
        }
    }
    for (t, b, lower) in found {
        let e = known.entry(t).or_default();
        offer(if lower { &mut e.0 } else { &mut e.1 }, b, lower);
    }
}

/// A constant lower (`lower`) or upper bound of `e` from the direct bounds `known`: `e`
/// itself when constant, its tightest direct bound, or through `min`/`max` the one of
/// their arguments' bounds the values pick. So a bound is always a constant term some fact
/// names: a loop's contexts draw their bounds from a finite set and still converge.
fn bound_expr(prog: &Program, e: &Expr, known: &Bounds<'_>, lower: bool) -> Option<Expr> {
    if constant(e) {
        return Some(e.clone());
    }
    if let Some((lo, hi)) = known.get(e) {
        let b = if lower { lo } else { hi };
        if let Some(b) = b {
            return Some(b.lit.clone());
        }
    }
    match &e.kind {
        ExprKind::Call(f @ (Builtin::Min | Builtin::Max), args) if args.len() == 2 => {
            let (a, b) = (&args[0], &args[1]);
            let (x, y) = (bound_expr(prog, a, known, lower), bound_expr(prog, b, known, lower));
            // min's lower bound needs both (the smaller); its upper bound either. max the other way.
            let both = (*f == Builtin::Min) == lower;
            match (x, y) {
                (Some(x), Some(y)) => pick(prog, *f, x.clone(), y).or(if both { None } else { Some(x) }),
                (Some(x), None) | (None, Some(x)) if !both => Some(x),
                _ => None,
            }
        }
        _ => None,
    }
}

/// `min(x, y)` or `max(x, y)` of two constant terms, resolved to the one it is where
/// their values decide it; `None` where they do not.
fn pick(prog: &Program, f: Builtin, x: Expr, y: Expr) -> Option<Expr> {
    let (vx, vy) = (value(prog, &x)?, value(prog, &y)?);
    let x_le_y = if vx.hi <= vy.lo {
        true
    } else if vy.hi <= vx.lo {
        false
    } else {
        return None;
    };
    Some(if x_le_y == (f == Builtin::Min) { x } else { y })
}
