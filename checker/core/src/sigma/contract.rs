//! A primitive's contract, a participant's `init` and its kind's invariant, read from
//! the participant's view: the predicates Σ starts from ([T-SESS]) and learns at a
//! motion ([T-MOTION]); see "The logical context Σ" in ARCHITECTURE.md.

use super::normal::var;
use crate::hir::expr::{conjuncts, map_vars};
use crate::hir::*;

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
