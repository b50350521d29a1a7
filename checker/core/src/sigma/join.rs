//! The join of two contexts (ARCHITECTURE.md, "The logical context Σ"): where two
//! paths meet (the branches of a choice, an `if`), Σ is a context implied by each
//! side's, so that it over-approximates the states reachable at the meeting point.
//! Besides the facts both hold literally, it keeps the weaker of two bounds by constants
//! on one term (the interval join), stated or implied (`interval.rs`).

use super::interval::{derive, direct};
use super::Sigma;
use crate::hir::*;

impl Sigma {
    /// A context implied by each of the two (their disjunction, weakened): the facts
    /// both hold literally, and for each term both bound by a constant (`0 <= x`,
    /// `x < 2.5`, `x == 1`, `clear_z <= ze`), the weaker of the two bounds (the interval
    /// join: the lower bound is the smaller, the upper the larger). So `1 <= x` and
    /// `2 <= x` join to `1 <= x`, and `x == 0` and `x == 1` to `0 <= x && x <= 1`, where
    /// keeping only the common facts would lose every fact about `x`. A side's bound on a
    /// variable may be implied rather than stated ([`super::interval::derive`]: `min(c,
    /// old(x)) <= x` with `d <= old(x)` bounds `x` by the smaller of `c` and `d`), so a loop
    /// whose rounds end in a weaker state than the one it starts in keeps the weaker bound
    /// at its head. Constants are ordered by their exact values; where the values do not
    /// order two bounds, neither is kept. Each added bound is implied by a fact of each
    /// side, so the result is implied by each.
    pub fn join(&self, other: &Sigma, prog: &Program) -> Sigma {
        let mut s = self.clone();
        s.retain(|f| other.contains(f));
        if s.len() == self.len() {
            return s;
        }
        let all = |_: &Expr| true;
        let (mut mine, mut theirs) = (direct(prog, &self.facts), direct(prog, &other.facts));
        derive(prog, &self.facts, &mut mine, &all);
        derive(prog, &other.facts, &mut theirs, &all);
        let kept = direct(prog, &s.facts);
        let mut adds = Vec::new();
        // The terms in the order the facts first name them (the result's order is stable).
        let mut terms: Vec<&Expr> = Vec::new();
        let mut seen = rustc_hash::FxHashSet::default();
        for f in &self.facts {
            if let ExprKind::Binary(_, a, b) = &f.kind {
                for t in [&**a, &**b] {
                    if mine.contains_key(t) && seen.insert(t) {
                        terms.push(t);
                    }
                }
            }
        }
        for term in terms {
            let (Some(a), Some(b)) = (mine.get(term), theirs.get(term)) else { continue };
            let k = kept.get(term);
            for (lower, x, y, have) in
                [(true, &a.0, &b.0, k.and_then(|k| k.0.as_ref())), (false, &a.1, &b.1, k.and_then(|k| k.1.as_ref()))]
            {
                let (Some(x), Some(y)) = (x, y) else { continue };
                let w = match x.tighter(y, lower) {
                    Some(true) => y,
                    Some(false) => x,
                    None => continue,
                };
                if have.is_none_or(|have| w.tighter(have, lower) == Some(true)) {
                    adds.push(w.fact(term, lower));
                }
            }
        }
        for f in adds {
            s.insert(f);
        }
        s
    }
}
