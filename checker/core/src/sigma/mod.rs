//! The logical context Σ (ARCHITECTURE.md, "The logical context Σ"): what is known about
//! the state at a point of a choreography or of a process, as a set of conjuncts. Process
//! typing (Table 1, `typeck/`) threads one per participant; the well-scopedness walk
//! (`wf/scope.rs`) threads one over the global type and hands it to the [AGCOMP],
//! total-choice and separation obligations.
//!
//! Facts speak about participants' variables ([`Var::Role`]), value variables (payload
//! fields, received values, recursion parameters) and constants. A motion makes time
//! pass, so what held before it must be re-read afterwards. [`Sigma::apply_motion`] computes the
//! strongest postcondition of a motion, syntactically, with one level of snapshots:
//!
//! 1. facts that mention an older snapshot of a moving participant `r` ([`Var::Snap`]) are
//!    dropped, so only one snapshot per variable ever exists (contexts stay small and
//!    canonical, and loops over them converge); the bounds by constants they imply for
//!    the variables that stay are kept first (`interval.rs`);
//! 2. every fact about `r`'s variables is renamed to speak about the snapshot: `r.x`
//!    becomes `old(r.x)`, the value when this motion started;
//! 3. the postcondition is added with the kind's variables as `r.x`, `old(x)` as the
//!    snapshot `old(r.x)` and parameters as the arguments, which were evaluated when the
//!    motion started (so their `r.x` is `old(r.x)` too);
//! 4. the kind's invariant is added for `r`;
//! 5. snapshots are eliminated where an equality defines them (`old(r.x) == e` lets
//!    every other fact read `e`), `min`/`max` are simplified where Σ orders their
//!    arguments, and facts over constants only, or over snapshots that no fact links
//!    to the current state, are dropped.
//!
//! Every step is an equivalence (eliminating a snapshot is `∃ old(r.x)`), except the
//! drops, which only weaken Σ. So Σ over-approximates the states reachable at its point.
//! Facts mentioning `clock`, footprint points or a contract's own variables never enter
//! Σ: they do not describe one state.
//!
//! Comparisons are stored in one orientation (`a >= b` as `b <= a`, `a > b` as `b < a`,
//! a participant's variable on the left of `==`), and sums, differences and products of
//! number literals are computed exactly (`0 + 0.5 - 0.5` is `0`), so that the syntactic
//! comparisons of the loop handling see equal facts as equal.
//!
//! The files: this one holds the set of facts and the operations that add, keep and
//! restrict them; `join.rs` the weakening join of two contexts (the interval join of
//! bounds by constants); `interval.rs` those bounds, stated or implied through
//! `min`/`max`; `motion.rs` the strongest postcondition of a motion (steps 1-5
//! above); `normal.rs` the canonical form of a fact (orientation, exact literal
//! arithmetic); `contract.rs` a primitive's predicates, `init` and invariants from a
//! participant's view.

pub mod cone;
mod contract;
mod interval;
mod join;
mod motion;
mod normal;

pub use contract::{init, initial_values, instantiate, invariant, participants, subst_params};
use normal::{admissible, normalize};

use crate::hir::expr::{conjuncts, mentions};
use crate::hir::*;
use rustc_hash::{FxHashSet, FxHasher};
use std::collections::HashMap;
use std::hash::{Hash, Hasher};

/// The logical context: a set of conjuncts, kept in the order they were learnt.
#[derive(Clone, Debug, Default)]
pub struct Sigma {
    facts: Vec<Expr>,
    set: FxHashSet<Expr>,
}

/// Two contexts are equal when they hold the same facts, in whatever order.
impl PartialEq for Sigma {
    fn eq(&self, other: &Sigma) -> bool {
        self.facts.len() == other.facts.len() && self.facts.iter().all(|f| other.set.contains(f))
    }
}

/// A hash of a fact for ordering and sets, as equality sees it (without locations).
/// FxHash (`rustc-hash`): much faster than the default SipHash on the many small terms a
/// context hashes, and contexts need no protection against adversarial collisions.
pub fn fact_hash(e: &Expr) -> u64 {
    let mut h = FxHasher::default();
    e.hash(&mut h);
    h.finish()
}

impl Sigma {
    /// The empty context (`true`).
    pub fn new() -> Sigma {
        Sigma::default()
    }

    /// A context assuming each of `facts`.
    pub fn from_facts<'e>(facts: impl IntoIterator<Item = &'e Expr>) -> Sigma {
        let mut s = Sigma::new();
        for f in facts {
            s.assume(f);
        }
        s
    }

    /// [T-SESS]'s initial context: each participant's `init` and its kind's invariant.
    pub fn initial(prog: &Program, roles: impl IntoIterator<Item = RoleId>) -> Sigma {
        let mut s = Sigma::new();
        for r in roles {
            for e in init(prog, r).iter().chain(&invariant(prog, r)) {
                s.assume(e);
            }
        }
        s
    }

    pub fn facts(&self) -> &[Expr] {
        &self.facts
    }

    pub fn into_facts(self) -> Vec<Expr> {
        self.facts
    }

    pub fn len(&self) -> usize {
        self.facts.len()
    }

    pub fn is_empty(&self) -> bool {
        self.facts.is_empty()
    }

    pub fn contains(&self, e: &Expr) -> bool {
        self.set.contains(e)
    }

    /// Adds `e`, split into conjuncts, each stored once. Conjuncts over constants only
    /// and conjuncts that do not describe one state (`clock`, footprint points, a
    /// contract's own variables) are left out.
    pub fn assume(&mut self, e: &Expr) {
        let mut cs = Vec::new();
        conjuncts(e, &mut cs);
        for c in cs {
            self.insert(normalize(c));
        }
    }

    fn insert(&mut self, c: Expr) {
        if !admissible(&c) || self.set.contains(&c) {
            return;
        }
        self.set.insert(c.clone());
        self.facts.push(c);
    }

    /// What holds after the message `p -> q : [P] l(v: S {P'})`: its guard `P` (about
    /// the values before it), then, the fields now holding new values (a binding site
    /// met again in a loop rebinds its value), the refinements `P'`.
    pub fn assume_message(&mut self, m: &Msg) {
        // With their definedness (`hir::expr::definedness`): a message that was sent had a
        // guard and refinements that could be evaluated, so this is true and says more than
        // the predicates alone (whose undefined parts the encoder leaves arbitrary).
        if let Some(g) = &m.guard {
            self.assume(&crate::hir::expr::defined_and(g.clone()));
        }
        let ids: Vec<ValueId> = m.payload.iter().map(|f| f.value).collect();
        self.forget_values(&ids);
        for f in &m.payload {
            if let Some(r) = &f.refinement {
                self.assume(&crate::hir::expr::defined_and(r.clone()));
            }
        }
    }

    /// Keeps the facts for which `keep` answers true.
    pub fn retain(&mut self, mut keep: impl FnMut(&Expr) -> bool) {
        let set = &mut self.set;
        self.facts.retain(|f| {
            let k = keep(f);
            if !k {
                set.remove(f);
            }
            k
        });
    }

    /// Forgets every fact that mentions a variable for which `hit` answers true.
    pub fn forget(&mut self, hit: &dyn Fn(&Var) -> bool) {
        self.retain(|e| !mentions(e, hit));
    }

    /// Forgets what is known about the value variables `ids` (they get new values).
    /// By binding site, not by name: another value of the same name is another variable.
    pub fn forget_values(&mut self, ids: &[ValueId]) {
        if ids.is_empty() {
            return;
        }
        self.forget(&|v| matches!(v, Var::Value(id, _) if ids.contains(id)));
    }

    /// The conjunction of two contexts: every fact of either.
    pub fn meet(&mut self, other: Sigma) {
        for f in other.facts {
            self.insert(f);
        }
    }

    /// Whether every fact of `other` is among these.
    pub fn contains_all(&self, other: &Sigma) -> bool {
        other.facts.iter().all(|f| self.set.contains(f))
    }

    /// The facts over the participants `roles` only (and over values and constants).
    pub fn restrict(&self, roles: &[RoleId]) -> Sigma {
        let mut s = self.clone();
        s.retain(|f| participants(f).iter().all(|r| roles.contains(r)));
        s
    }

    /// [`Sigma::restrict`] to each group of `groups` at once, in time linear in the size
    /// of Σ plus what is copied (the sides of a wide `*`).
    pub fn split(&self, groups: &[Vec<RoleId>]) -> Vec<Sigma> {
        let mut owner: HashMap<RoleId, usize> = HashMap::new();
        for (i, g) in groups.iter().enumerate() {
            for r in g {
                owner.entry(*r).or_insert(i);
            }
        }
        let mut out = vec![Sigma::new(); groups.len()];
        for f in &self.facts {
            let rs = participants(f);
            let Some(first) = rs.first() else {
                out.iter_mut().for_each(|s| s.insert(f.clone()));
                continue;
            };
            let Some(&i) = owner.get(first) else { continue };
            if rs.iter().all(|r| owner.get(r) == Some(&i)) {
                out[i].insert(f.clone());
            }
        }
        out
    }
}

#[cfg(test)]
mod tests;
