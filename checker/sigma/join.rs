//! The join of two contexts (ARCHITECTURE.md, "The logical context Σ"): where two
//! paths meet (the branches of a choice, an `if`), Σ is a context implied by each
//! side's, so that it over-approximates the states reachable at the meeting point.
//! Besides the facts both hold literally, it keeps the weaker of two bounds by number
//! literals on one term (the interval join).

use super::normal::{binary, literal, normalize, Decimal};
use super::Sigma;
use crate::hir::expr::BinOp;
use crate::hir::*;
use rustc_hash::{FxHashMap, FxHashSet};

impl Sigma {
    /// A context implied by each of the two (their disjunction, weakened): the facts
    /// both hold literally, and for each term both bound by a number literal (`0 <= x`,
    /// `x < 2.5`, `x == 1`), the weaker of the two bounds (the interval join: the lower
    /// bound is the smaller, the upper the larger). So `1 <= x` and `2 <= x` join to
    /// `1 <= x`, and `x == 0` and `x == 1` to `0 <= x && x <= 1`, where keeping only the
    /// common facts would lose every fact about `x`. Each added bound is implied by a
    /// fact of each side, so the result is implied by each.
    pub fn join(&self, other: &Sigma) -> Sigma {
        let mut s = self.clone();
        s.retain(|f| other.contains(f));
        if s.len() == self.len() {
            return s;
        }
        let (mine, theirs, kept) = (self.bounds(), other.bounds(), s.bounds());
        let mut adds = Vec::new();
        let mut seen: FxHashSet<&Expr> = FxHashSet::default();
        for f in &self.facts {
            let Some((term, _, _)) = bound_of(f) else { continue };
            if !seen.insert(term) {
                continue;
            }
            let (Some(a), Some(b)) = (mine.get(term), theirs.get(term)) else { continue };
            let k = kept.get(term);
            if let (Some(x), Some(y)) = (&a.0, &b.0) {
                let w = if x.tighter(y, true) { y } else { x };
                if k.and_then(|k| k.0.as_ref()).is_none_or(|have| w.tighter(have, true)) {
                    adds.push(normalize(binary(w.op(), &w.lit, term)));
                }
            }
            if let (Some(x), Some(y)) = (&a.1, &b.1) {
                let w = if x.tighter(y, false) { y } else { x };
                if k.and_then(|k| k.1.as_ref()).is_none_or(|have| w.tighter(have, false)) {
                    adds.push(normalize(binary(w.op(), term, &w.lit)));
                }
            }
        }
        for f in adds {
            s.insert(f);
        }
        s
    }

    /// The tightest lower and upper bound by a number literal that a fact of Σ states
    /// directly for each term.
    fn bounds(&self) -> FxHashMap<&Expr, (Option<Bound>, Option<Bound>)> {
        let mut out: FxHashMap<&Expr, (Option<Bound>, Option<Bound>)> = FxHashMap::default();
        for f in &self.facts {
            let Some((term, lower, upper)) = bound_of(f) else { continue };
            let e = out.entry(term).or_default();
            for (new, slot, is_lower) in [(lower, &mut e.0, true), (upper, &mut e.1, false)] {
                if let Some(b) = new {
                    if slot.as_ref().is_none_or(|old| b.tighter(old, is_lower)) {
                        *slot = Some(b);
                    }
                }
            }
        }
        out
    }
}

/// A bound by a number literal on some term: `lit <= term` or `lit < term` (a lower
/// bound), `term <= lit` or `term < lit` (an upper one).
#[derive(Clone, Debug)]
struct Bound {
    value: Decimal,
    strict: bool,
    lit: Expr,
}

impl Bound {
    /// Whether this bound says strictly more than `o` (as lower bounds, or upper ones).
    /// Values too large to compare exactly count as not tighter.
    fn tighter(&self, o: &Bound, lower: bool) -> bool {
        match self.value.compare(o.value) {
            Some(std::cmp::Ordering::Equal) => self.strict && !o.strict,
            Some(std::cmp::Ordering::Greater) => lower,
            Some(std::cmp::Ordering::Less) => !lower,
            None => false,
        }
    }

    fn op(&self) -> BinOp {
        if self.strict {
            BinOp::Lt
        } else {
            BinOp::Le
        }
    }
}

/// The term a fact bounds by a number literal, with the lower and upper bound it
/// states (`x == 1` states both).
fn bound_of(f: &Expr) -> Option<(&Expr, Option<Bound>, Option<Bound>)> {
    let ExprKind::Binary(op, a, b) = &f.kind else { return None };
    let strict = match op {
        BinOp::Le | BinOp::Eq => false,
        BinOp::Lt => true,
        _ => return None,
    };
    let (la, lb) = (literal(a), literal(b));
    let bound = |value: Decimal, lit: &Expr| Bound { value, strict, lit: lit.clone() };
    match (la, lb, op) {
        (Some(_), Some(_), _) | (None, None, _) => None,
        (Some(v), None, BinOp::Eq) => Some((b, Some(bound(v, a)), Some(bound(v, a)))),
        (None, Some(v), BinOp::Eq) => Some((a, Some(bound(v, b)), Some(bound(v, b)))),
        (Some(v), None, _) => Some((b, Some(bound(v, a)), None)),
        (None, Some(v), _) => Some((a, None, Some(bound(v, b)))),
    }
}
