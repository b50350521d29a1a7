//! The strongest postcondition of a motion ([T-MOTION] of Table 1 with the Σ section
//! of ARCHITECTURE.md): steps 1-5 of the module documentation of [`super`], syntactic,
//! with one level of snapshots. Every step is an equivalence or a weakening, so Σ after
//! a motion over-approximates the states the motion may end in.

use super::fact_hash;
use super::normal::admissible;
use super::normal::{binary, normalize, var};
use super::{instantiate, invariant, Sigma};
use crate::hir::expr::BinOp;
use crate::hir::expr::{map_vars, mentions};
use crate::hir::*;
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::{BTreeSet, HashSet};

impl Sigma {
    /// The effect of participant `role` running `prim` with `args` (evaluated when it
    /// starts): see the module documentation.
    pub fn apply_motion(&mut self, prog: &Program, role: RoleId, prim: PrimId, args: &[Expr]) {
        self.effect(prog, &[(role, prim, args)]);
    }

    /// The effect of a joint motion `dt<p: a(..), q: b(..)>`: every part's effect at
    /// once (all arguments are evaluated when the motion starts).
    pub fn apply_joint_motion(&mut self, prog: &Program, parts: &[(RoleId, PrimApp)]) {
        let parts: Vec<(RoleId, PrimId, &[Expr])> = parts.iter().map(|(r, a)| (*r, a.prim, &a.args[..])).collect();
        self.effect(prog, &parts);
    }

    fn effect(&mut self, prog: &Program, parts: &[(RoleId, PrimId, &[Expr])]) {
        let movers: Vec<RoleId> = parts.iter().map(|(r, _, _)| *r).collect();
        // Looked up for every variable of every fact: a set, not the list (a wide `dt`).
        let moving: FxHashSet<RoleId> = movers.iter().copied().collect();
        // 1. One level of snapshots: forget the previous one, keeping the bounds by
        //    constants its facts imply for the variables that stay (`min(c, old(x)) <= x`
        //    with `d <= old(x)` keeps `min(c, d) <= x`; `interval.rs`): a loop whose rounds
        //    lower a variable to a bound, which later motions keep, still knows the bound
        //    two motions on. Each kept bound is implied by the facts dropped.
        let old = |v: &Var| matches!(v, Var::Snap(r, _) if moving.contains(r));
        self.bound_before_forgetting(prog, &old);
        self.forget(&old);
        // 2. What was true of the movers' variables is now true of their snapshots.
        let snap = |e: &Expr| {
            map_vars(e, &mut |v, sort| match v {
                Var::Role(r, s) if moving.contains(r) => Some(var(Var::Snap(*r, *s), sort)),
                _ => None,
            })
        };
        let moved = |v: &Var| matches!(v, Var::Role(r, _) if moving.contains(r));
        let before = std::mem::take(&mut self.facts);
        self.set.clear();
        for f in before {
            if mentions(&f, &moved) {
                self.insert(normalize(snap(&f)));
            } else {
                self.insert(f);
            }
        }
        // 3. The postconditions, 4. the invariants.
        for (r, prim, args) in parts {
            let args: Vec<Expr> = args.iter().map(snap).collect();
            self.assume(&instantiate(&prog.prim(*prim).post, *r, &args));
        }
        for r in &movers {
            for e in invariant(prog, *r) {
                self.assume(&e);
            }
        }
        // 5.
        self.simplify();
    }

    /// Adds the bounds by constants that the facts mentioning a variable `hit` selects imply
    /// for the other variables ([`super::interval::derive`]), where they are tighter than
    /// the bounds Σ states: the facts are about to be forgotten.
    fn bound_before_forgetting(&mut self, prog: &Program, hit: &dyn Fn(&Var) -> bool) {
        if !self.facts.iter().any(|f| mentions(f, hit)) {
            return;
        }
        let facts = self.facts.clone();
        let stated = super::interval::direct(prog, &facts);
        let mut known = stated.clone();
        super::interval::derive(prog, &facts, &mut known, &|f| mentions(f, hit));
        let mut adds = Vec::new();
        for f in &facts {
            let ExprKind::Binary(_, a, b) = &f.kind else { continue };
            for t in [&**a, &**b] {
                if mentions(t, hit) {
                    continue;
                }
                let Some((lo, hi)) = known.get(t) else { continue };
                let was = stated.get(t);
                for (lower, new, have) in
                    [(true, lo, was.and_then(|w| w.0.as_ref())), (false, hi, was.and_then(|w| w.1.as_ref()))]
                {
                    let Some(new) = new else { continue };
                    if have.is_none_or(|have| new.tighter(have, lower) == Some(true)) {
                        adds.push(new.fact(t, lower));
                    }
                }
            }
        }
        for f in adds {
            self.insert(f);
        }
    }

    /// Eliminates snapshots defined by equalities and simplifies `min`/`max`, until
    /// nothing changes (a few rounds at most).
    fn simplify(&mut self) {
        for _ in 0..8 {
            let a = self.eliminate_snapshots();
            let b = self.simplify_min_max();
            if !(a || b) {
                break;
            }
        }
        self.drop_unlinked_snapshots();
    }

    /// Drops the facts that speak only of snapshots (and constants) that no chain of
    /// facts links to a current variable or a value: they constrain the past alone, so
    /// they say nothing about the present (`∃ old(r.x). F` is implied by what remains,
    /// up to satisfiability, and dropping facts only weakens Σ).
    fn drop_unlinked_snapshots(&mut self) {
        let snaps = |f: &Expr| {
            let mut out: Vec<Var> = Vec::new();
            let mut present = false;
            f.visit_vars(&mut |v, _| match v {
                Var::Snap(..) if !out.contains(v) => out.push(v.clone()),
                Var::Role(..) | Var::Value(..) => present = true,
                _ => {}
            });
            (out, present)
        };
        let info: Vec<(Vec<Var>, bool)> = self.facts.iter().map(snaps).collect();
        if info.iter().all(|(s, present)| s.is_empty() || *present) {
            return;
        }
        let mut linked: HashSet<Var> = HashSet::new();
        let mut keep: Vec<bool> = info.iter().map(|(s, present)| s.is_empty() || *present).collect();
        loop {
            let mut grew = false;
            for (i, (s, _)) in info.iter().enumerate() {
                if keep[i] || s.iter().any(|v| linked.contains(v)) {
                    keep[i] = true;
                    for v in s {
                        grew |= linked.insert(v.clone());
                    }
                }
            }
            if !grew {
                break;
            }
        }
        let mut i = 0;
        self.retain(|_| {
            i += 1;
            keep[i - 1]
        });
    }

    /// While some fact is `old(r.x) == e` with `e` free of `old(r.x)`, drops it and
    /// replaces `old(r.x)` by `e` everywhere else. Definitions free of any snapshot are
    /// used first, so the result speaks of the current state where it can.
    ///
    /// The result is that of the plain loop (take the first definition in the order of
    /// the facts, rewrite every fact, keep the first of equal facts), computed with an
    /// index from each snapshot to the facts that mention it: each elimination touches
    /// only those facts, not all of Σ (a wide `dt` of n participants eliminates about 2n
    /// snapshots from a context of about 5n facts; the plain loop was quadratic).
    pub(super) fn eliminate_snapshots(&mut self) -> bool {
        // Positions are those of the facts at entry; a dropped fact leaves `None`, so the
        // order of the facts is the order of their positions.
        let mut ground: BTreeSet<usize> = BTreeSet::new();
        let mut any: BTreeSet<usize> = BTreeSet::new();
        for (i, f) in self.facts.iter().enumerate() {
            classify(f, i, &mut ground, &mut any);
        }
        if any.is_empty() {
            return false;
        }
        let mut facts: Vec<Option<Expr>> = std::mem::take(&mut self.facts).into_iter().map(Some).collect();
        self.set.clear();
        // Each fact's position by its hash (equal facts hash equally), and the facts
        // that mention each snapshot (entries may be stale: checked when used).
        let mut by_hash: FxHashMap<u64, Vec<usize>> = FxHashMap::default();
        let mut uses: FxHashMap<Var, Vec<usize>> = FxHashMap::default();
        for (i, f) in facts.iter().enumerate() {
            let Some(f) = f else { continue };
            by_hash.entry(fact_hash(f)).or_default().push(i);
            index_snapshots(f, i, &mut uses);
        }
        let unlink = |by_hash: &mut FxHashMap<u64, Vec<usize>>, f: &Expr, i: usize| {
            if let Some(b) = by_hash.get_mut(&fact_hash(f)) {
                b.retain(|k| *k != i);
            }
        };
        while let Some((i, is_ground)) = ground.first().map(|i| (*i, true)).or_else(|| any.first().map(|i| (*i, false)))
        {
            ground.remove(&i);
            any.remove(&i);
            let Some(f) = facts[i].take() else { continue };
            unlink(&mut by_hash, &f, i);
            let Some((v, def)) = definition_of(&f, is_ground) else { continue };
            // The facts that mention `v`, taken out in order, then rewritten and put back
            // in order: a rewritten fact equal to an earlier fact is dropped; equal to a
            // later one, it takes that one's place (the first of equal facts stays).
            let mut hit: Vec<usize> = uses.remove(&v).unwrap_or_default();
            hit.sort_unstable();
            hit.dedup();
            let mut taken = Vec::with_capacity(hit.len());
            for j in hit {
                let Some(g) = facts[j].take_if(|g| mentions(g, &|w| *w == v)) else { continue };
                unlink(&mut by_hash, &g, j);
                ground.remove(&j);
                any.remove(&j);
                taken.push((j, g));
            }
            for (j, g) in taken {
                let g = normalize(map_vars(&g, &mut |w, _| if *w == v { Some(def.clone()) } else { None }));
                if !admissible(&g) {
                    continue;
                }
                let h = fact_hash(&g);
                let same = by_hash.get(&h).and_then(|b| b.iter().copied().find(|k| facts[*k].as_ref() == Some(&g)));
                match same {
                    Some(k) if k < j => continue,
                    Some(k) => {
                        if let Some(old) = facts[k].take() {
                            unlink(&mut by_hash, &old, k);
                        }
                        ground.remove(&k);
                        any.remove(&k);
                    }
                    None => {}
                }
                by_hash.entry(h).or_default().push(j);
                index_snapshots(&g, j, &mut uses);
                classify(&g, j, &mut ground, &mut any);
                facts[j] = Some(g);
            }
        }
        for f in facts.into_iter().flatten() {
            self.insert(f);
        }
        true
    }

    /// Rewrites `min(a, b)` to `a` (and `max(a, b)` to `b`) when Σ holds `a <= b`,
    /// `a < b` or `a == b`, and symmetrically.
    fn simplify_min_max(&mut self) -> bool {
        let has_min_max = |e: &Expr| e.any(|x| matches!(x.kind, ExprKind::Call(Builtin::Min | Builtin::Max, _)));
        if !self.facts.iter().any(has_min_max) {
            return false;
        }
        let mut changed = false;
        let mut out = Vec::with_capacity(self.facts.len());
        for f in &self.facts {
            if !has_min_max(f) {
                out.push(f.clone());
                continue;
            }
            let g = self.rewrite_min_max(f);
            changed |= g != *f;
            out.push(normalize(g));
        }
        if changed {
            self.facts.clear();
            self.set.clear();
            for f in out {
                self.insert(f);
            }
        }
        changed
    }

    /// `min`/`max` of two arguments that Σ orders, replaced by the argument it picks,
    /// bottom-up (the arguments are rewritten first).
    fn rewrite_min_max(&self, e: &Expr) -> Expr {
        e.map(&mut |n| match &n.kind {
            ExprKind::Call(f @ (Builtin::Min | Builtin::Max), args) if args.len() == 2 => {
                let (a, b) = (&args[0], &args[1]);
                let (lo, hi) = if self.known_le(a, b) {
                    (a, b)
                } else if self.known_le(b, a) {
                    (b, a)
                } else {
                    return n;
                };
                let pick = if *f == Builtin::Min { lo } else { hi };
                Expr { loc: n.loc, ..pick.clone() }
            }
            _ => n,
        })
    }

    /// Whether Σ literally orders `a <= b`.
    fn known_le(&self, a: &Expr, b: &Expr) -> bool {
        a == b
            || [BinOp::Le, BinOp::Lt, BinOp::Eq].into_iter().any(|op| self.set.contains(&binary(op, a, b)))
            || self.set.contains(&binary(BinOp::Eq, b, a))
    }
}

/// `f` as a definition `old(r.x) == e` (either way round, left first) with `e` free of
/// `old(r.x)`; with `ground`, `e` must be free of every snapshot.
fn definition_of(f: &Expr, ground: bool) -> Option<(Var, Expr)> {
    let is_snap = |v: &Var| matches!(v, Var::Snap(..));
    let ExprKind::Binary(BinOp::Eq, a, b) = &f.kind else { return None };
    [(a, b), (b, a)].into_iter().find_map(|(x, e)| {
        let ExprKind::Var(v @ Var::Snap(..)) = &x.kind else { return None };
        let free = if ground { !mentions(e, &is_snap) } else { !mentions(e, &|w| w == v) };
        free.then(|| (v.clone(), (**e).clone()))
    })
}

/// Files the fact at position `i` among the definitions it is (of either kind).
fn classify(f: &Expr, i: usize, ground: &mut BTreeSet<usize>, any: &mut BTreeSet<usize>) {
    if definition_of(f, false).is_some() {
        any.insert(i);
        if definition_of(f, true).is_some() {
            ground.insert(i);
        }
    }
}

/// Records position `i` under each snapshot the fact mentions.
fn index_snapshots(f: &Expr, i: usize, uses: &mut FxHashMap<Var, Vec<usize>>) {
    f.visit_vars(&mut |v, _| {
        if matches!(v, Var::Snap(..)) {
            let at = uses.entry(v.clone()).or_default();
            if at.last() != Some(&i) {
                at.push(i);
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(i: u32, name: &str) -> Expr {
        var(Var::Value(ValueId(i), name.to_string()), &Sort::Real)
    }

    fn call(f: Builtin, a: Expr, b: Expr) -> Expr {
        Expr { kind: ExprKind::Call(f, vec![a, b]), sort: Sort::Real, loc: Loc::default() }
    }

    /// The rewrite goes bottom-up: an inner `min` is settled first, and the outer call then
    /// sees the picked argument; a call whose arguments Σ does not order is left alone.
    #[test]
    fn nested_min_max_are_rewritten_bottom_up() {
        let (a, b, c) = (value(0, "a"), value(1, "b"), value(2, "c"));
        let s = Sigma::from_facts(&[binary(BinOp::Le, &a, &b), binary(BinOp::Lt, &a, &c)]);
        // min(a, b) is a; max(a, c) is c.
        let e = call(Builtin::Max, call(Builtin::Min, a.clone(), b.clone()), c.clone());
        assert_eq!(s.rewrite_min_max(&e), c);
        // b and c are not ordered: max(min(a, b), ...) keeps its shape around the rewritten part.
        let e = call(Builtin::Max, call(Builtin::Max, b.clone(), a.clone()), c.clone());
        assert_eq!(s.rewrite_min_max(&e), call(Builtin::Max, b.clone(), c.clone()));
        // Under another operator, and the argument keeps the call's location.
        let at = Loc(crate::source::Span::new(crate::source::FileId(0), 3, 9));
        let inner = Expr { loc: at, ..call(Builtin::Min, b.clone(), a.clone()) };
        let e = Expr { kind: ExprKind::Unary(crate::hir::expr::UnOp::Neg, Box::new(inner)), sort: Sort::Real, loc: at };
        let ExprKind::Unary(_, out) = s.rewrite_min_max(&e).kind else { panic!("still a negation") };
        assert_eq!((out.kind.clone(), out.loc), (a.kind.clone(), at));
    }
}
