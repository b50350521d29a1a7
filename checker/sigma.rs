//! The logical context Σ: what is known about the state at a point of a choreography or
//! of a process, as a set of conjuncts. Process typing (Table 1, `typeck.rs`) threads one
//! per participant; the well-scopedness walk (`wf/scope.rs`) threads one over the global
//! type and hands it to the [AGCOMP], total-choice and separation obligations.
//!
//! Facts speak about participants' variables ([`Var::Role`]), value variables (payload
//! fields, received values, recursion parameters) and constants. A motion makes time
//! pass, so what held before it must be re-read afterwards. [`Sigma::run`] computes the
//! strongest postcondition of a motion, syntactically, with one level of snapshots:
//!
//! 1. facts that mention an older snapshot of a moving participant `r` ([`Var::Snap`]) are
//!    dropped, so only one snapshot per variable ever exists (contexts stay small and
//!    canonical, and loops over them converge);
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

use crate::hir::expr::BinOp;
use crate::hir::*;
use crate::subtype::{conjuncts, map_vars, mentions};
use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hash, Hasher};

/// The logical context: a set of conjuncts, kept in the order they were learnt.
#[derive(Clone, Debug, Default)]
pub struct Sigma {
    facts: Vec<Expr>,
    set: HashSet<Expr, BuildHasherDefault<FxHasher>>,
}

/// Two contexts are equal when they hold the same facts, in whatever order.
impl PartialEq for Sigma {
    fn eq(&self, other: &Sigma) -> bool {
        self.facts.len() == other.facts.len() && self.facts.iter().all(|f| other.set.contains(f))
    }
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
        if let Some(g) = &m.guard {
            self.assume(g);
        }
        let ids: Vec<ValueId> = m.payload.iter().map(|f| f.value).collect();
        self.forget_values(&ids);
        for f in &m.payload {
            if let Some(r) = &f.refinement {
                self.assume(r);
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
        let mut seen: HashSet<&Expr, BuildHasherDefault<FxHasher>> = HashSet::default();
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
    fn bounds(&self) -> HashMap<&Expr, (Option<Bound>, Option<Bound>), BuildHasherDefault<FxHasher>> {
        let mut out: HashMap<&Expr, (Option<Bound>, Option<Bound>), BuildHasherDefault<FxHasher>> = HashMap::default();
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

    /// The effect of participant `role` running `prim` with `args` (evaluated when it
    /// starts): see the module documentation.
    pub fn run(&mut self, prog: &Program, role: RoleId, prim: PrimId, args: &[Expr]) {
        self.effect(prog, &[(role, prim, args)]);
    }

    /// The effect of a joint motion `dt<p: a(..), q: b(..)>`: every part's effect at
    /// once (all arguments are evaluated when the motion starts).
    pub fn run_joint(&mut self, prog: &Program, parts: &[(RoleId, PrimApp)]) {
        let parts: Vec<(RoleId, PrimId, &[Expr])> = parts.iter().map(|(r, a)| (*r, a.prim, &a.args[..])).collect();
        self.effect(prog, &parts);
    }

    fn effect(&mut self, prog: &Program, parts: &[(RoleId, PrimId, &[Expr])]) {
        let movers: Vec<RoleId> = parts.iter().map(|(r, _, _)| *r).collect();
        // 1. One level of snapshots: forget the previous one.
        self.forget(&|v| matches!(v, Var::Snap(r, _) if movers.contains(r)));
        // 2. What was true of the movers' variables is now true of their snapshots.
        let snap = |e: &Expr| {
            map_vars(e, &mut |v, sort| match v {
                Var::Role(r, s) if movers.contains(r) => Some(var(Var::Snap(*r, *s), sort)),
                _ => None,
            })
        };
        let moved = |v: &Var| matches!(v, Var::Role(r, _) if movers.contains(r));
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
    fn eliminate_snapshots(&mut self) -> bool {
        let mut changed = false;
        while let Some((i, v, def)) = self.definition(true).or_else(|| self.definition(false)) {
            changed = true;
            let facts = std::mem::take(&mut self.facts);
            self.set.clear();
            for (j, f) in facts.into_iter().enumerate() {
                if j == i {
                    continue;
                }
                if !mentions(&f, &|w| *w == v) {
                    self.insert(f);
                    continue;
                }
                let g = map_vars(&f, &mut |w, _| if *w == v { Some(def.clone()) } else { None });
                self.insert(normalize(g));
            }
        }
        changed
    }

    /// The first fact `old(r.x) == e` (either way round) with `e` free of `old(r.x)`;
    /// with `ground`, `e` must be free of every snapshot.
    fn definition(&self, ground: bool) -> Option<(usize, Var, Expr)> {
        let is_snap = |v: &Var| matches!(v, Var::Snap(..));
        self.facts.iter().enumerate().find_map(|(i, f)| {
            let ExprKind::Binary(BinOp::Eq, a, b) = &f.kind else { return None };
            [(a, b), (b, a)].into_iter().find_map(|(x, e)| {
                let ExprKind::Var(v @ Var::Snap(..)) = &x.kind else { return None };
                let free = if ground { !mentions(e, &is_snap) } else { !mentions(e, &|w| w == v) };
                free.then(|| (i, v.clone(), (**e).clone()))
            })
        })
    }

    /// Rewrites `min(a, b)` to `a` (and `max(a, b)` to `b`) when Σ holds `a <= b`,
    /// `a < b` or `a == b`, and symmetrically.
    fn simplify_min_max(&mut self) -> bool {
        let has_min_max = |e: &Expr| {
            let mut found = false;
            visit(e, &mut |x| found |= matches!(x.kind, ExprKind::Call(Builtin::Min | Builtin::Max, _)));
            found
        };
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

    fn rewrite_min_max(&self, e: &Expr) -> Expr {
        stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || self.rewrite_min_max_inner(e))
    }

    fn rewrite_min_max_inner(&self, e: &Expr) -> Expr {
        let kind = match &e.kind {
            ExprKind::Call(f @ (Builtin::Min | Builtin::Max), args) if args.len() == 2 => {
                let a = self.rewrite_min_max(&args[0]);
                let b = self.rewrite_min_max(&args[1]);
                let (lo, hi) = if self.known_le(&a, &b) {
                    (a, b)
                } else if self.known_le(&b, &a) {
                    (b, a)
                } else {
                    return Expr { kind: ExprKind::Call(*f, vec![a, b]), sort: e.sort.clone(), loc: e.loc };
                };
                let pick = if *f == Builtin::Min { lo } else { hi };
                return Expr { loc: e.loc, ..pick };
            }
            ExprKind::Call(f, args) => ExprKind::Call(*f, args.iter().map(|a| self.rewrite_min_max(a)).collect()),
            ExprKind::Unary(op, a) => ExprKind::Unary(*op, Box::new(self.rewrite_min_max(a))),
            ExprKind::Component(a, i) => ExprKind::Component(Box::new(self.rewrite_min_max(a)), *i),
            ExprKind::Binary(op, a, b) => {
                ExprKind::Binary(*op, Box::new(self.rewrite_min_max(a)), Box::new(self.rewrite_min_max(b)))
            }
            ExprKind::If(a, b, c) => ExprKind::If(
                Box::new(self.rewrite_min_max(a)),
                Box::new(self.rewrite_min_max(b)),
                Box::new(self.rewrite_min_max(c)),
            ),
            ExprKind::Tuple(xs) => ExprKind::Tuple(xs.iter().map(|a| self.rewrite_min_max(a)).collect()),
            ExprKind::Int(_) | ExprKind::Real(_) | ExprKind::Bool(_) | ExprKind::Var(_) => return e.clone(),
        };
        Expr { kind, sort: e.sort.clone(), loc: e.loc }
    }

    /// Whether Σ literally orders `a <= b`.
    fn known_le(&self, a: &Expr, b: &Expr) -> bool {
        a == b
            || [BinOp::Le, BinOp::Lt, BinOp::Eq].into_iter().any(|op| self.set.contains(&binary(op, a, b)))
            || self.set.contains(&binary(BinOp::Eq, b, a))
    }
}

/// A primitive's predicate from participant `role`'s view: its own variables become
/// `role`'s ([`Var::Role`]), `old(x)` the snapshot ([`Var::Snap`]), parameters the
/// arguments.
pub fn instantiate(e: &Expr, role: RoleId, args: &[Expr]) -> Expr {
    map_vars(e, &mut |v, sort| match v {
        Var::Own(slot) => Some(var(Var::Role(role, *slot), sort)),
        Var::Old(i) => Some(var(Var::Snap(role, Slot::State(*i)), sort)),
        Var::Param(i) => args.get(*i).cloned(),
        _ => None,
    })
}

/// `e` with each recursion parameter of `params` replaced by the value at the same
/// position of `values` (simultaneously: the values are not substituted again).
/// Parameters are matched by `Var` equality with their binding.
pub fn subst_params(e: &Expr, params: &[RecParam], values: &[Expr]) -> Expr {
    let vars: Vec<Var> = params.iter().map(|p| Var::Value(p.value, p.name.clone())).collect();
    map_vars(e, &mut |v, _| vars.iter().position(|w| w == v).and_then(|i| values.get(i).cloned()))
}

/// The parameters' values when their loop is entered: each initial value, which may
/// read the parameters before it, with those replaced by their own initial values.
pub fn initial_values(params: &[RecParam]) -> Vec<Expr> {
    let mut out: Vec<Expr> = Vec::with_capacity(params.len());
    for (i, p) in params.iter().enumerate() {
        let v = subst_params(&p.init, &params[..i], &out);
        out.push(v);
    }
    out
}

/// The conjuncts of the invariant of `role`'s kind, over `role`'s variables.
pub fn invariant(prog: &Program, role: RoleId) -> Vec<Expr> {
    let mut out = Vec::new();
    if let Some(inv) = &prog.kind_of(role).invariant {
        conjuncts(&instantiate(inv, role, &[]), &mut out);
    }
    out
}

/// The conjuncts of `role`'s `init` predicate.
pub fn init(prog: &Program, role: RoleId) -> Vec<Expr> {
    let mut out = Vec::new();
    if let Some(e) = &prog.role(role).init {
        conjuncts(e, &mut out);
    }
    out
}

/// The participants a fact speaks about (through their variables or snapshots).
pub fn participants(e: &Expr) -> Vec<RoleId> {
    let mut out: Vec<RoleId> = Vec::new();
    e.visit_vars(&mut |v, _| {
        if let Var::Role(r, _) | Var::Snap(r, _) = v {
            if !out.contains(r) {
                out.push(*r);
            }
        }
    });
    out
}

/// Whether a conjunct may be stored: it describes one state (no `clock`, no footprint
/// point, no contract variable left uninstantiated), mentions some variable, and is
/// not literally reflexive (`e == e`, `e <= e`).
fn admissible(e: &Expr) -> bool {
    let mut state = false;
    let mut foreign = false;
    e.visit_vars(&mut |v, _| match v {
        Var::Role(..) | Var::Snap(..) | Var::Value(..) => state = true,
        Var::Const(_) => {}
        Var::Own(_) | Var::Old(_) | Var::Param(_) | Var::Point(_) | Var::Clock => foreign = true,
    });
    let reflexive = matches!(&e.kind, ExprKind::Binary(BinOp::Eq | BinOp::Le | BinOp::Ge, a, b) if a == b);
    state && !foreign && !reflexive && !e.is_true()
}

/// One orientation per comparison: `a >= b` is `b <= a`, `a > b` is `b < a`, and `==`,
/// `!=` put a participant's variable (else a value variable) on the left.
fn normalize(e: Expr) -> Expr {
    let e = if needs_fold(&e) { fold(&e) } else { e };
    let rank = |x: &Expr| match &x.kind {
        ExprKind::Var(Var::Role(..) | Var::Snap(..)) => 2,
        ExprKind::Var(Var::Value(..)) => 1,
        _ => 0,
    };
    match e.kind {
        ExprKind::Binary(BinOp::Ge, a, b) => Expr { kind: ExprKind::Binary(BinOp::Le, b, a), ..e },
        ExprKind::Binary(BinOp::Gt, a, b) => Expr { kind: ExprKind::Binary(BinOp::Lt, b, a), ..e },
        ExprKind::Binary(op @ (BinOp::Eq | BinOp::Ne), a, b) if rank(&b) > rank(&a) => {
            Expr { kind: ExprKind::Binary(op, b, a), ..e }
        }
        kind => Expr { kind, ..e },
    }
}

/// Computes `+`, `-` and `*` (and unary `-`) of number literals exactly, bottom-up.
/// Results are written as the parser would read them: an integer as an `int` literal, a
/// negative number as `-` applied to a literal. What would overflow is left as it is.
fn fold(e: &Expr) -> Expr {
    stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || {
        let kind = match &e.kind {
            ExprKind::Binary(op, a, b) => {
                let (a, b) = (fold(a), fold(b));
                let value = match (literal(&a), literal(&b), op) {
                    (Some(x), Some(y), BinOp::Add) => x.add(y),
                    (Some(x), Some(y), BinOp::Sub) => y.neg().and_then(|n| x.add(n)),
                    (Some(x), Some(y), BinOp::Mul) => x.mul(y),
                    _ => None,
                };
                if let Some(v) = value.and_then(|v| v.expr(e.loc)) {
                    return v;
                }
                ExprKind::Binary(*op, Box::new(a), Box::new(b))
            }
            ExprKind::Unary(op, a) => ExprKind::Unary(*op, Box::new(fold(a))),
            ExprKind::Component(a, i) => ExprKind::Component(Box::new(fold(a)), *i),
            ExprKind::If(a, b, c) => ExprKind::If(Box::new(fold(a)), Box::new(fold(b)), Box::new(fold(c))),
            ExprKind::Call(f, xs) => ExprKind::Call(*f, xs.iter().map(fold).collect()),
            ExprKind::Tuple(xs) => ExprKind::Tuple(xs.iter().map(fold).collect()),
            ExprKind::Int(_) | ExprKind::Real(_) | ExprKind::Bool(_) | ExprKind::Var(_) => return e.clone(),
        };
        Expr { kind, sort: e.sort.clone(), loc: e.loc }
    })
}

/// Whether [`fold`] would change `e`: some `+`, `-` or `*` has number literals (or
/// arithmetic on them) on both sides.
fn needs_fold(e: &Expr) -> bool {
    fn constant(e: &Expr) -> bool {
        match &e.kind {
            ExprKind::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, a, b) => constant(a) && constant(b),
            _ => literal(e).is_some(),
        }
    }
    let mut found = false;
    visit(e, &mut |x| {
        found |= matches!(&x.kind, ExprKind::Binary(BinOp::Add | BinOp::Sub | BinOp::Mul, a, b) if constant(a) && constant(b))
    });
    found
}

/// A decimal number `num / 10^scale`, exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Decimal {
    num: i128,
    scale: u32,
}

/// The most decimal places kept: enough for any literal a user writes, far from
/// overflowing `i128`.
const MAX_SCALE: u32 = 18;

impl Decimal {
    fn parse(lit: &str) -> Option<Decimal> {
        let (mant, exp) = match lit.split_once(['e', 'E']) {
            Some((m, e)) => (m, e.parse::<i32>().ok()?),
            None => (lit, 0),
        };
        let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
        let digits: i128 = format!("{int}{frac}").parse().ok()?;
        let scale = i32::try_from(frac.len()).ok()?.checked_sub(exp)?;
        if scale >= 0 {
            Decimal { num: digits, scale: scale as u32 }.reduced()
        } else {
            Decimal { num: digits.checked_mul(10i128.checked_pow((-scale) as u32)?)?, scale: 0 }.reduced()
        }
    }

    /// Without trailing zeros, within [`MAX_SCALE`].
    fn reduced(mut self) -> Option<Decimal> {
        while self.scale > 0 && self.num % 10 == 0 {
            self.num /= 10;
            self.scale -= 1;
        }
        (self.scale <= MAX_SCALE && self.num.unsigned_abs() < 1u128 << 100).then_some(self)
    }

    fn at_scale(self, scale: u32) -> Option<i128> {
        self.num.checked_mul(10i128.checked_pow(scale - self.scale)?)
    }

    fn add(self, o: Decimal) -> Option<Decimal> {
        let scale = self.scale.max(o.scale);
        Decimal { num: self.at_scale(scale)?.checked_add(o.at_scale(scale)?)?, scale }.reduced()
    }

    fn compare(self, o: Decimal) -> Option<std::cmp::Ordering> {
        let scale = self.scale.max(o.scale);
        Some(self.at_scale(scale)?.cmp(&o.at_scale(scale)?))
    }

    fn neg(self) -> Option<Decimal> {
        Some(Decimal { num: self.num.checked_neg()?, scale: self.scale })
    }

    fn mul(self, o: Decimal) -> Option<Decimal> {
        Decimal { num: self.num.checked_mul(o.num)?, scale: self.scale + o.scale }.reduced()
    }

    /// As an expression: an `int` literal when whole, else a real literal; `-` in front
    /// when negative.
    fn expr(self, loc: Loc) -> Option<Expr> {
        let abs = self.num.unsigned_abs();
        let lit = if self.scale == 0 {
            Expr { kind: ExprKind::Int(i64::try_from(abs).ok()?), sort: Sort::Int, loc }
        } else {
            let digits = format!("{abs:0>width$}", width = self.scale as usize + 1);
            let (int, frac) = digits.split_at(digits.len() - self.scale as usize);
            Expr { kind: ExprKind::Real(format!("{int}.{frac}")), sort: Sort::Real, loc }
        };
        Some(if self.num < 0 {
            let sort = lit.sort.clone();
            Expr { kind: ExprKind::Unary(crate::hir::expr::UnOp::Neg, Box::new(lit)), sort, loc }
        } else {
            lit
        })
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

/// The value of a number literal, or of `-` applied to one.
fn literal(e: &Expr) -> Option<Decimal> {
    match &e.kind {
        ExprKind::Int(n) => Some(Decimal { num: *n as i128, scale: 0 }),
        ExprKind::Real(r) => Decimal::parse(r),
        ExprKind::Unary(crate::hir::expr::UnOp::Neg, a) => literal(a)?.neg(),
        _ => None,
    }
}

fn var(v: Var, sort: &Sort) -> Expr {
    Expr { kind: ExprKind::Var(v), sort: sort.clone(), loc: Loc::default() }
}

fn binary(op: BinOp, a: &Expr, b: &Expr) -> Expr {
    Expr { kind: ExprKind::Binary(op, Box::new(a.clone()), Box::new(b.clone())), sort: Sort::Bool, loc: Loc::default() }
}

/// A hash of a fact for ordering and sets, as equality sees it (without locations).
pub(crate) fn fact_hash(e: &Expr) -> u64 {
    let mut h = FxHasher::default();
    e.hash(&mut h);
    h.finish()
}

/// rustc's FxHash: much faster than the default SipHash on the many small terms a
/// context hashes, and contexts need no protection against adversarial collisions.
#[derive(Clone, Copy, Default)]
pub(crate) struct FxHasher(u64);

impl FxHasher {
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            let mut w = [0u8; 8];
            w.copy_from_slice(c);
            self.add(u64::from_le_bytes(w));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut w = [0u8; 8];
            w[..rest.len()].copy_from_slice(rest);
            self.add(u64::from_le_bytes(w));
        }
    }
    fn write_u8(&mut self, i: u8) {
        self.add(u64::from(i));
    }
    fn write_u32(&mut self, i: u32) {
        self.add(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

/// Calls `f` on every subterm of `e`.
fn visit(e: &Expr, f: &mut dyn FnMut(&Expr)) {
    stacker::maybe_grow(64 * 1024, 4 * 1024 * 1024, || visit_inner(e, f))
}

fn visit_inner(e: &Expr, f: &mut dyn FnMut(&Expr)) {
    f(e);
    match &e.kind {
        ExprKind::Int(_) | ExprKind::Real(_) | ExprKind::Bool(_) | ExprKind::Var(_) => {}
        ExprKind::Unary(_, a) | ExprKind::Component(a, _) => visit(a, f),
        ExprKind::Binary(_, a, b) => {
            visit(a, f);
            visit(b, f);
        }
        ExprKind::If(a, b, c) => {
            visit(a, f);
            visit(b, f);
            visit(c, f);
        }
        ExprKind::Call(_, xs) | ExprKind::Tuple(xs) => xs.iter().for_each(|a| visit(a, f)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lower::tests::lower_src;

    /// A cart `C` and an arm `A`; `x`'s invariant is `-10 <= x <= 10`, `ze`'s `0 <= ze <= 1`.
    const SRC: &str = "
        const gx: real = 1.6;
        const cz: real = 0.2;
        robot Cart { state x: real, v: real; invariant: -10 <= x <= 10; }
        robot Arm { state ze: real; invariant: 0 <= ze <= 1; }
        motion Cart.idle { interruptible: true; post: x == old(x) && v == 0; }
        motion Cart.move(xf: real) { interruptible: false; pre: xf > x; post: x == xf && v == 0; }
        motion Cart.step(d: real) { interruptible: false; post: x == old(x) + d; }
        motion Arm.work { interruptible: true; post: min(cz, old(ze)) <= ze && ze <= max(cz, old(ze)); }
        system S { participant C: Cart { init: x == 0 && v == 0; } participant A: Arm { init: ze >= cz; } }
    ";

    /// Lowers SRC with a choreography whose messages carry `preds` as guards, in order;
    /// `C:` or `A:` in front says who sends (and whose variables are unqualified). The
    /// first message binds the value `n`, which later guards may read.
    fn setup(preds: &[&str]) -> (Program, Vec<Expr>) {
        let mut msgs = vec!["C -> A : first(n: real)".to_string()];
        for (i, p) in preds.iter().enumerate() {
            let (who, g) = p.split_at(2);
            let (from, to) = if who == "C:" { ("C", "A") } else { ("A", "C") };
            msgs.push(format!("{from} -> {to} : [{g}] m{i}"));
        }
        let (prog, d) = lower_src(&format!("{SRC} choreography G = {}. end;", msgs.join(". ")));
        assert!(d.is_empty(), "{d:?}");
        let Some(Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("a sequence")
        };
        let guards = items
            .iter()
            .filter_map(|g| match g {
                Global::Msg(m) => m.guard.clone(),
                _ => None,
            })
            .collect();
        (prog, guards)
    }

    fn shown(prog: &Program, s: &Sigma) -> Vec<String> {
        s.facts().iter().map(|e| print::expr(prog, None, e)).collect()
    }

    fn role(prog: &Program, name: &str) -> RoleId {
        prog.role_by_name(name).expect("role")
    }

    fn prim(prog: &Program, name: &str) -> PrimId {
        PrimId(prog.prims.iter().position(|p| p.name == name).expect("primitive") as u32)
    }

    fn constant(prog: &Program, name: &str) -> Expr {
        let i = prog.consts.iter().position(|c| c.name == name).expect("constant");
        var(Var::Const(ConstId(i as u32)), &Sort::Real)
    }

    #[test]
    fn assume_splits_orients_and_dedupes() {
        let (prog, g) = setup(&["C: x >= 0 && v == 0 && 0 <= x", "C: gx > 1", "C: 0 == v && n > x"]);
        let s = Sigma::from_facts(&g);
        // `0 == v` is `C.v == 0` again; `gx > 1` speaks of constants only.
        assert_eq!(shown(&prog, &s), vec!["0 <= C.x", "C.v == 0", "C.x < n"]);
        let clock = Expr { kind: ExprKind::Var(Var::Clock), sort: Sort::Real, loc: Loc::default() };
        let mut t = s.clone();
        t.assume(&binary(BinOp::Le, &clock, &g[1]));
        assert_eq!(t, s, "facts about clock describe no single state");
    }

    #[test]
    fn forgetting_values_by_binding_site() {
        let (prog, g) = setup(&["C: n > x && v == 0"]);
        let mut s = Sigma::from_facts(&g);
        let n = ValueId(prog.values.iter().position(|v| v.name == "n").expect("n") as u32);
        s.forget_values(&[n]);
        assert_eq!(shown(&prog, &s), vec!["C.v == 0"]);
    }

    /// The refinements `n == 0` of two payload fields that are both named `n`.
    fn two_values_named_n() -> (Program, Expr, Expr, ValueId, ValueId) {
        let (prog, d) = lower_src(&format!(
            "{SRC} choreography G = C -> A : first(n: real {{n == 0}}). A -> C : second(n: real {{n == 0}}). end;"
        ));
        assert!(d.is_empty(), "{d:?}");
        let Some(Global::Seq(items, _)) = prog.choreography.as_ref().map(|c| c.body.clone()) else {
            panic!("a sequence")
        };
        let fields: Vec<Field> = items
            .iter()
            .filter_map(|g| match g {
                Global::Msg(m) => m.payload.first().cloned(),
                _ => None,
            })
            .collect();
        let [a, b] = &fields[..] else { panic!("two messages") };
        let r = |f: &Field| f.refinement.clone().expect("refinement");
        (prog, r(a), r(b), a.value, b.value)
    }

    /// Shadowing: a fact about one `n` is no fact about another `n`. The loop fixpoint
    /// keeps a candidate fact only if every `t` reached `contains` it, the `*` conjoins
    /// the sides' facts, and the join keeps the shared ones: all by identity. (Before,
    /// values compared by name and the second `n == 0` "re-established" the first.)
    #[test]
    fn same_named_values_are_different_facts() {
        let (prog, first, second, n1, n2) = two_values_named_n();
        assert_ne!(n1, n2);
        assert_ne!(first, second, "equal by name, different by binding site");
        let s = Sigma::from_facts([&first]);
        assert!(!s.contains(&second));
        assert!(s.join(&Sigma::from_facts([&second])).is_empty());
        let mut both = s.clone();
        both.meet(Sigma::from_facts([&second]));
        assert_eq!(both.len(), 2);
        // Forgetting the second `n` (it is rebound) keeps what is known of the first.
        both.forget_values(&[n2]);
        assert_eq!(both, s);
        assert_eq!(shown(&prog, &both), vec!["n == 0"]);
    }

    #[test]
    fn initial_context_is_init_and_invariant() {
        let (prog, _) = setup(&[]);
        let s = Sigma::initial(&prog, prog.role_ids());
        assert_eq!(
            shown(&prog, &s),
            vec!["C.x == 0", "C.v == 0", "-10 <= C.x", "C.x <= 10", "cz <= A.ze", "0 <= A.ze", "A.ze <= 1"]
        );
    }

    #[test]
    fn a_post_with_old_keeps_what_was_known() {
        // Sec 3.5's m_idle: `x == old(x)`. Before, the cart is at gx.
        let (prog, g) = setup(&["C: x == gx && v == 0 && n > x"]);
        let c = role(&prog, "C");
        let mut s = Sigma::from_facts(&g);
        s.run(&prog, c, prim(&prog, "idle"), &[]);
        assert_eq!(shown(&prog, &s), vec!["gx < n", "C.x == gx", "C.v == 0", "-10 <= C.x", "C.x <= 10"]);
    }

    #[test]
    fn a_move_replaces_the_position_and_keeps_facts_about_values() {
        let (prog, _) = setup(&["C: n > x"]);
        let c = role(&prog, "C");
        let mut s = Sigma::initial(&prog, [c]);
        let (_, g) = setup(&["C: n > x"]);
        s.assume(&g[0]);
        s.run(&prog, c, prim(&prog, "move"), &[constant(&prog, "gx")]);
        // `old(C.x) == 0` defines the snapshot: `C.x < n` before is `0 < n` now.
        assert_eq!(shown(&prog, &s), vec!["0 < n", "C.x == gx", "C.v == 0", "-10 <= C.x", "C.x <= 10"]);
    }

    #[test]
    fn one_level_of_snapshots() {
        // Nothing defines the snapshot: facts about it stay, until the next motion.
        let (prog, g) = setup(&["C: x >= 1"]);
        let c = role(&prog, "C");
        let mut s = Sigma::from_facts(&g);
        let one = Expr { kind: ExprKind::Int(1), sort: Sort::Int, loc: Loc::default() };
        s.run(&prog, c, prim(&prog, "step"), std::slice::from_ref(&one));
        assert_eq!(shown(&prog, &s), vec!["1 <= old(C.x)", "C.x == old(C.x) + 1", "-10 <= C.x", "C.x <= 10"]);
        s.run(&prog, c, prim(&prog, "step"), std::slice::from_ref(&one));
        // The first snapshot is gone with every fact about it.
        assert_eq!(
            shown(&prog, &s),
            vec!["-10 <= old(C.x)", "old(C.x) <= 10", "C.x == old(C.x) + 1", "-10 <= C.x", "C.x <= 10"]
        );
        let again = {
            let mut t = s.clone();
            t.run(&prog, c, prim(&prog, "step"), std::slice::from_ref(&one));
            t
        };
        assert_eq!(again, s, "a loop of steps reaches a fixpoint");
    }

    #[test]
    fn arguments_are_evaluated_when_the_motion_starts() {
        // `dt<C: step(x)>`: the argument reads the state before the motion.
        let (prog, g) = setup(&["C: x == 2"]);
        let c = role(&prog, "C");
        let x = var(Var::Role(c, Slot::State(0)), &Sort::Real);
        let mut s = Sigma::from_facts(&g);
        s.run(&prog, c, prim(&prog, "step"), &[x]);
        assert_eq!(shown(&prog, &s), vec!["C.x == 4", "-10 <= C.x", "C.x <= 10"]);
    }

    #[test]
    fn number_literals_are_computed_exactly() {
        let (prog, g) = setup(&[
            "C: x == 0 + 0.5 - 0.5",
            "C: v == 0.1 + 0.2",
            "C: x <= 1 - 2.5",
            "C: n == 1.5 * 2 + 1e-3",
            "C: x == n * (2 + 1)",
            "C: v < 9223372036854775807 + 1",
            "C: v <= 1e-2147483648 + 1",
        ]);
        let s = Sigma::from_facts(&g);
        assert_eq!(
            shown(&prog, &s),
            vec![
                "C.x == 0",
                "C.v == 0.3",
                "C.x <= -1.5",
                "n == 3.001",
                "C.x == n * 3",
                "C.v < 9223372036854775807 + 1",
                "C.v <= 1e-2147483648 + 1"
            ]
        );
        // PGCD's lanes: forward half a metre and back again is where the cart started.
        let c = role(&prog, "C");
        let mut s = Sigma::from_facts(&g[..1]);
        let half = |neg: bool| {
            let lit = Expr { kind: ExprKind::Real("0.5".into()), sort: Sort::Real, loc: Loc::default() };
            if neg {
                Expr {
                    kind: ExprKind::Unary(crate::hir::expr::UnOp::Neg, Box::new(lit)),
                    sort: Sort::Real,
                    loc: Loc::default(),
                }
            } else {
                lit
            }
        };
        let start = {
            let mut t = s.clone();
            t.run(&prog, c, prim(&prog, "step"), &[half(true)]);
            t.run(&prog, c, prim(&prog, "step"), &[half(false)]);
            t
        };
        s.run(&prog, c, prim(&prog, "step"), &[half(false)]);
        assert_eq!(shown(&prog, &s), vec!["C.x == 0.5", "-10 <= C.x", "C.x <= 10"]);
        s.run(&prog, c, prim(&prog, "step"), &[half(true)]);
        assert_eq!(shown(&prog, &s), vec!["C.x == 0", "-10 <= C.x", "C.x <= 10"]);
        assert_eq!(s, start);
    }

    #[test]
    fn min_and_max_simplify_where_the_context_orders_them() {
        let (prog, _) = setup(&[]);
        let a = role(&prog, "A");
        let mut s = Sigma::initial(&prog, [a]);
        s.run(&prog, a, prim(&prog, "work"), &[]);
        // `cz <= old(A.ze)` makes `min(cz, old(A.ze))` just `cz`.
        assert_eq!(
            shown(&prog, &s),
            vec![
                "cz <= old(A.ze)",
                "0 <= old(A.ze)",
                "old(A.ze) <= 1",
                "cz <= A.ze",
                "A.ze <= old(A.ze)",
                "0 <= A.ze",
                "A.ze <= 1"
            ]
        );
        // A second motion forgets `cz <= old(A.ze)` but `cz <= A.ze` survived, as `cz <= old(A.ze)`.
        s.run(&prog, a, prim(&prog, "work"), &[]);
        assert!(shown(&prog, &s).contains(&"cz <= A.ze".to_string()), "{:?}", shown(&prog, &s));
    }

    #[test]
    fn joint_motions_move_every_part() {
        let (prog, _) = setup(&[]);
        let (c, a) = (role(&prog, "C"), role(&prog, "A"));
        let mut s = Sigma::initial(&prog, prog.role_ids());
        let idle = PrimApp { prim: prim(&prog, "idle"), args: vec![], loc: Loc::default() };
        let work = PrimApp { prim: prim(&prog, "work"), args: vec![], loc: Loc::default() };
        s.run_joint(&prog, &[(c, idle), (a, work)]);
        let facts = shown(&prog, &s);
        for f in ["C.x == 0", "C.v == 0", "cz <= A.ze"] {
            assert!(facts.contains(&f.to_string()), "{f} in {facts:?}");
        }
    }

    #[test]
    fn restriction_to_participants() {
        let (prog, g) = setup(&["C: x == 0 && n > 0", "A: ze >= C.x", "A: ze <= 1"]);
        let s = Sigma::from_facts(&g);
        let (c, a) = (role(&prog, "C"), role(&prog, "A"));
        assert_eq!(shown(&prog, &s.restrict(&[c])), vec!["C.x == 0", "0 < n"]);
        assert_eq!(shown(&prog, &s.restrict(&[a])), vec!["0 < n", "A.ze <= 1"]);
        assert_eq!(shown(&prog, &s.restrict(&[a, c])), shown(&prog, &s));
        let parts = s.split(&[vec![c], vec![a]]);
        assert_eq!(parts[0], s.restrict(&[c]));
        assert_eq!(parts[1], s.restrict(&[a]));
    }

    #[test]
    fn meet_join_and_containment() {
        let (prog, g) = setup(&["C: x == 0", "C: v == 0", "C: n > 0"]);
        let ab = Sigma::from_facts(&g[..2]);
        let bc = Sigma::from_facts(&g[1..]);
        assert_eq!(shown(&prog, &ab.join(&bc)), vec!["C.v == 0"]);
        let mut all = ab.clone();
        all.meet(bc.clone());
        assert_eq!(all, Sigma::from_facts(&g));
        assert!(all.contains_all(&ab) && all.contains_all(&bc) && !ab.contains_all(&all));
    }

    #[test]
    fn join_weakens_bounds_by_literals() {
        let (prog, g) = setup(&["C: x == 0", "C: x == 1.5", "C: 1 <= x", "C: x > 2", "C: v < 1 && x <= n"]);
        let one = |i: usize| Sigma::from_facts(&g[i..=i]);
        // Two positions: the interval between them.
        assert_eq!(shown(&prog, &one(0).join(&one(1))), vec!["0 <= C.x", "C.x <= 1.5"]);
        assert_eq!(shown(&prog, &one(1).join(&one(0))), vec!["0 <= C.x", "C.x <= 1.5"]);
        // The weaker lower bound, strictness included; a bound on one side only goes.
        assert_eq!(shown(&prog, &one(2).join(&one(3))), vec!["1 <= C.x"]);
        assert_eq!(shown(&prog, &one(3).join(&one(2))), vec!["1 <= C.x"]);
        assert_eq!(shown(&prog, &one(3).join(&one(4))), Vec::<String>::new());
        // What is common is kept as it is; nothing weaker is added beside it.
        let mut a = one(2);
        a.assume(&g[1]);
        assert_eq!(shown(&prog, &a.join(&one(2))), vec!["1 <= C.x"]);
    }
}

/// The probe: with Σ threaded through, the predicate obligations of the bundled
/// examples hold (they failed while [T-MOTION] forgot the positions a post with
/// `old(x)` keeps).
#[cfg(test)]
mod probe {
    use crate::hir::{print, Program};
    use crate::obligation::{Goal, Obligation};
    use crate::smt::{check_valid, SmtConfig, Verdict};
    use crate::source::SourceDb;
    use std::path::Path;

    /// The obligations of well-formedness and typing for a bundled example.
    fn example_obligations(path: &str) -> (Program, Vec<Obligation>) {
        let mut db = SourceDb::new();
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
        let root = crate::syntax::load_root(&mut db, &file).expect("example readable");
        let (parsed, d) = crate::syntax::parse_with_imports(&mut db, root, &mut |p| std::fs::read_to_string(p));
        assert!(d.is_empty(), "{d:?}");
        let (prog, d) = crate::lower::lower(&parsed);
        assert!(d.is_empty(), "{d:?}");
        let body = prog.choreography.as_ref().map(|c| c.body.clone()).expect("a choreography");
        let (d, mut obs) = crate::wf::scope::check(&prog, &body);
        assert!(d.is_empty(), "{d:?}");
        let (locals, d) = crate::project::project_all(&prog);
        assert!(d.is_empty(), "{d:?}");
        let (d, typing) = crate::typeck::check_processes(&prog, &locals);
        assert!(d.is_empty(), "{d:?}");
        obs.extend(typing);
        (prog, obs)
    }

    /// Decides every `Goal::Valid` obligation; returns one line per obligation.
    fn decide(path: &str) -> Vec<(String, Verdict)> {
        let (prog, obs) = example_obligations(path);
        obs.iter()
            .filter_map(|ob| match &ob.goal {
                Goal::Valid(goal) => {
                    let v = check_valid(&prog, &ob.hyps, goal, &SmtConfig::default());
                    let hyps: Vec<String> = ob.hyps.iter().map(|h| print::expr(&prog, None, h)).collect();
                    let line = format!(
                        "{} {}: {}  [{}]",
                        ob.rule.name(),
                        ob.what,
                        print::expr(&prog, None, goal),
                        hyps.join(", ")
                    );
                    Some((line, v))
                }
                _ => None,
            })
            .collect()
    }

    fn all_hold(path: &str, expected: usize) {
        let results = decide(path);
        for (line, v) in &results {
            eprintln!("{path}: {v:?}: {line}");
        }
        let failed: Vec<&(String, Verdict)> = results.iter().filter(|(_, v)| *v != Verdict::Holds).collect();
        assert!(failed.is_empty(), "{path}: {failed:#?}");
        assert_eq!(results.len(), expected, "{path}: the number of predicate obligations");
    }

    #[test]
    fn cart_and_arms_obligations_hold() {
        all_hold("choreographies/cart-and-arms.chor", 10);
    }

    #[test]
    fn sorting_obligations_hold() {
        all_hold("choreographies/sorting.chor", 14);
    }
}
