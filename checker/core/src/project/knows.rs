//! What a receiver may assume of a payload whose refinement reads values it never holds.
//!
//! E0305 lets a refinement read only what its *sender* knows, so `A -> B: batt(b). B -> C:
//! now(n {n == b})` is a protocol: B promises C that `n` is the battery level A told it.
//! C never holds `b`, so C's local type cannot name it. What C learns is the refinement
//! with the values it does not hold bound existentially, `exists b. b >= 0 && n == b`,
//! which is `n >= 0`. The language has no quantifiers, so the projection computes what it
//! can of that existential without a solver and drops the rest:
//!
//! 1. A conjunct `x == e` (or `e == x`) that defines a value `x` C does not hold by an
//!    expression `e` it can read eliminates `x` exactly: `exists x. x == e && P(x)` is
//!    `P(e)`. `P` ranges over the other conjuncts and `x`'s own refinement (its sender
//!    guaranteed it when `x` was sent). Each conjunct `e` entered carries `e`'s
//!    definedness ([`defined_and`]): the sender proved `x == e` with `e` defined.
//! 2. A conjunct that still reads a value C does not hold is dropped. C then assumes less
//!    than its sender promised, which is sound for C's typing (a weaker hypothesis) and
//!    what a monitor of C alone can check (every conjunct it keeps reads only C's values).
//!
//! The receiver's local type therefore never names a value it does not hold, so
//! `mochi project --role` prints a type whose every name is bound and that parses as a
//! `local` item.

use crate::hir::expr::{conjuncts, defined_and, mentions, subst_values, BinOp};
use crate::hir::*;
use std::collections::{HashMap, HashSet};

impl super::Projector<'_> {
    /// The payload of a message as its receiver sees it: each refinement with the values
    /// the receiver does not hold eliminated or dropped (see the module docs).
    pub(super) fn receiver_payload(&self, payload: &[Field]) -> Vec<Field> {
        payload
            .iter()
            .map(|f| {
                let mut f = f.clone();
                let Some(r) = f.refinement.take() else { return f };
                // A MAVLink field's refinement is `implicit && user` (`hir::MavField`): the
                // implicit part (wire range, enum, fixed command) reads no value, and only
                // the user's part is reduced; when none of it is left, the field has no user
                // refinement any more, so that it prints (and reads back) as such.
                if let Some(mav) = f.mav.as_mut().filter(|m| m.user) {
                    let (implicit, user) = match (&r.kind, mav.implicit) {
                        (ExprKind::Binary(BinOp::And, i, u), true) => (Some((**i).clone()), (**u).clone()),
                        (_, false) => (None, r.clone()),
                        _ => {
                            f.refinement = self.what_receiver_learns(&r);
                            return f;
                        }
                    };
                    let learned = self.what_receiver_learns(&user);
                    mav.user = learned.is_some();
                    f.refinement = match (implicit, learned) {
                        (Some(i), Some(u)) => Some(Expr { loc: r.loc, ..Expr::and(i, u) }),
                        (i, u) => i.or(u),
                    };
                    return f;
                }
                f.refinement = self.what_receiver_learns(&r);
                f
            })
            .collect()
    }

    /// Whether the role being projected never holds value `id`: a payload field of a
    /// message between two other participants.
    fn foreign(&self, v: &Var) -> bool {
        match v {
            Var::Value(id, _) => self.prog.value(*id).origin.unheld_by(self.role),
            _ => false,
        }
    }

    fn what_receiver_learns(&self, r: &Expr) -> Option<Expr> {
        let foreign = |v: &Var| self.foreign(v);
        if !mentions(r, &foreign) {
            return Some(r.clone());
        }
        let mut conj = Vec::new();
        conjuncts(r, &mut conj);
        // Each value eliminated at most once, so this ends; a bound keeps a pathological
        // chain of definitions linear.
        let mut eliminated: Vec<ValueId> = Vec::new();
        while let Some((i, x, e)) = conj
            .iter()
            .enumerate()
            .find_map(|(i, c)| definition(c, &foreign).filter(|(x, _)| !eliminated.contains(x)).map(|(x, e)| (i, x, e)))
        {
            conj.remove(i);
            eliminated.push(x);
            let mut more = Vec::new();
            if let Some(own) = self.occurs.field(x).and_then(|f| f.refinement.as_ref()) {
                conjuncts(own, &mut more);
            }
            let map = HashMap::from([(x, e)]);
            let hit = |v: &Var| matches!(v, Var::Value(id, _) if *id == x);
            conj = conj
                .into_iter()
                .chain(more)
                .map(|c| if mentions(&c, &hit) { defined_and(subst_values(&c, &map)) } else { c })
                .collect();
        }
        let kept: Vec<Expr> = conj.into_iter().filter(|c| !mentions(c, &foreign)).collect();
        let loc = r.loc;
        kept.into_iter().reduce(Expr::and).map(|e| Expr { loc, ..e })
    }
}

/// `x == e` or `e == x` with `x` a value `foreign` says the receiver does not hold and `e`
/// an expression without any such value.
fn definition(c: &Expr, foreign: &dyn Fn(&Var) -> bool) -> Option<(ValueId, Expr)> {
    let ExprKind::Binary(BinOp::Eq, a, b) = &c.kind else { return None };
    for (x, e) in [(a, b), (b, a)] {
        if let ExprKind::Var(v @ Var::Value(id, _)) = &x.kind {
            if foreign(v) && !mentions(e, foreign) {
                return Some((*id, (**e).clone()));
            }
        }
    }
    None
}

/// The names of the values `t` reads that `role` never holds (payload fields of messages
/// between two other participants), in order of first reading. Empty for every
/// projection (see the module docs); the tests hold the corpus to it.
pub fn unheld_reads(prog: &Program, role: RoleId, t: &Local) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut read = |e: &Expr| {
        e.visit_vars(&mut |v, _| {
            if let Var::Value(id, name) = v {
                let unheld = prog.value(*id).origin.unheld_by(role);
                if unheld && !out.contains(name) {
                    out.push(name.clone());
                }
            }
        })
    };
    visit_local_exprs(t, &mut read, &mut HashSet::new());
    out
}

/// Every expression of a local type: guards, refinements, motion arguments, recursion
/// parameters' refinements and initial values, jump arguments. A node shared by several
/// branches (projection pushes one tail into every branch of a choice) is visited once.
fn visit_local_exprs(t: &Local, f: &mut dyn FnMut(&Expr), seen: &mut HashSet<*const Local>) {
    if !seen.insert(t as *const Local) {
        return;
    }
    if let Local::Send { timeout: Some(to), .. } | Local::Recv { timeout: Some(to), .. } = t {
        visit_local_exprs(&to.cont, f, seen);
    }
    crate::stack::deep(|| match t {
        Local::Send { branches, .. } => {
            for b in branches {
                b.guard.iter().for_each(&mut *f);
                b.payload.iter().filter_map(|p| p.refinement.as_ref()).for_each(&mut *f);
                visit_local_exprs(&b.cont, f, seen);
            }
        }
        Local::Recv { branches, default, .. } => {
            for b in branches {
                b.payload.iter().filter_map(|p| p.refinement.as_ref()).for_each(&mut *f);
                visit_local_exprs(&b.cont, f, seen);
            }
            if let Some((prims, cont)) = default {
                prims.iter().flat_map(|p| &p.args).for_each(&mut *f);
                visit_local_exprs(cont, f, seen);
            }
        }
        Local::Motion { prims, cont, .. } => {
            prims.iter().flat_map(|p| &p.args).for_each(&mut *f);
            visit_local_exprs(cont, f, seen);
        }
        Local::Rec { params, body, .. } => {
            for p in params {
                p.refinement.iter().for_each(&mut *f);
                f(&p.init);
            }
            visit_local_exprs(body, f, seen);
        }
        Local::Var { args, .. } => args.iter().for_each(f),
        Local::End(_) => {}
    })
}
