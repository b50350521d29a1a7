//! Projection of a global type onto a participant (Def 4.8) and the merge operator of
//! Def 4.7, with Def 4.8 (3) read as the merge `⊓` (seeds README, known error 3).
//!
//! Projection is continuation-passing: [`project`] takes the local type `tail` that
//! follows `g` and pushes it into every branch of a choice. Tails are [`Arc`]-shared,
//! so a sequence of choices costs linear space, and the result is in the prefix form of
//! Def 4.6 (`dt<a>.T`, `⊕{..}`, `&{..}`, `&{..} & dt<a>.T`, `mu t.T`, `t`, `end`).
//!
//! The rules, for a role `r`:
//! - `p -> q : {[P_i] l_i(F_i).G_i}`: the sender gets `⊕{[P_i] q!l_i(F_i).T_i}`, the
//!   receiver `&{p?l_i(F_i).T_i}`, anybody else the merge `⊓_i T_i` (a single message
//!   is a choice with one branch);
//! - `dt<(p_i : a_i)>.T` is `dt<a_j>.T` for `r = p_j` and `T` otherwise;
//! - `g1 * g2` is the projection of the side that contains `r` (and `T` if none does);
//! - sequences fold from the right; `t` and `end` ignore the tail;
//! - `mu t.G` is `mu t.T'` when `r ∈ pt{G}`. Def 4.8 (4) leaves the projection
//!   undefined otherwise; we follow the usual MPST convention that `r` has left the
//!   protocol and project to `end`.
//!
//! Equality of local types ([`equal`]) ignores source locations, compares the branches
//! of a choice as a set, and is alpha-equivalence: payload fields and recursion
//! parameters (binders) correspond by position, and a value is its binding site, never
//! its name (see `Differ`). The merge reads one branch's continuation in terms of the
//! other's binders of a shared message before merging the two (`rename_local`).
//!
//! The files: `rules.rs` holds the rules of Def 4.8, `merge.rs` the merge of Def 4.7,
//! `equal.rs` the equality of local types up to renaming that the merge and E0602 use,
//! `occurs.rs` who occurs in which node of the global type, `knows.rs` what a receiver
//! learns from a refinement that reads values only others hold. The printing helpers for
//! local types in diagnostics are in `hir/print.rs`.

mod equal;
mod knows;
mod merge;
mod occurs;
mod rules;

pub use equal::{alpha_equal, equal, first_difference};
pub use knows::unheld_reads;

use crate::diag::{Code, Diagnostic};
use crate::hir::print::print_bounded;
use crate::hir::*;
use occurs::Occurs;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Projects the choreography onto every participant of the system. A participant whose
/// projection fails is missing from the map and has a diagnostic (E0601) instead.
pub fn project_all(prog: &Program) -> (BTreeMap<RoleId, LocalArc>, Vec<Diagnostic>) {
    let mut out = BTreeMap::new();
    let mut diags = Vec::new();
    let Some(chor) = &prog.choreography else {
        return (out, diags);
    };
    let tail: LocalArc = Arc::new(Local::End(Loc(chor.span)));
    // Who occurs where, computed once for all roles: projecting n roles must not walk
    // the whole type n times to find each role's side of every `*`.
    let occurs = Occurs::new(prog, &chor.body);
    for role in prog.role_ids() {
        match (Projector { prog, role, occurs: &occurs }).project(&chor.body, tail.clone()) {
            Ok(t) => {
                out.insert(role, t);
            }
            Err(d) => diags.push(d),
        }
    }
    (out, diags)
}

/// Checks every `local R = T;` item against the projection onto `R` (E0602). Roles
/// whose projection failed are skipped: their error is already reported.
pub fn check_declared(prog: &Program, projections: &BTreeMap<RoleId, LocalArc>) -> Vec<Diagnostic> {
    let mut diags = Vec::new();
    for def in &prog.locals {
        let Some(proj) = projections.get(&def.role) else {
            continue;
        };
        let Some((declared, projected)) = first_difference(&def.body, proj) else {
            continue;
        };
        let name = prog.role_name(def.role);
        diags.push(
            Diagnostic::error(
                Code::LocalMismatch,
                def.span,
                format!("the declared local type of `{name}` differs from the projection of the choreography"),
            )
            .with_label(declared.0, "the declared type says this")
            .with_label(projected.0, "where the choreography says this")
            .with_note(format!("the projection onto `{name}` is:\n{}", print_bounded(prog, proj, 20_000)))
            .with_help(format!(
                "use `mochi project FILE --role {name}` to print the projection and paste it, or change the choreography"
            )),
        );
    }
    diags
}

/// The projection of `g` onto `role`, followed by `tail` (Def 4.8).
pub fn project(prog: &Program, g: &Global, role: RoleId, tail: LocalArc) -> Result<LocalArc, Diagnostic> {
    let occurs = Occurs::new(prog, g);
    Projector { prog, role, occurs: &occurs }.project(g, tail)
}

struct Projector<'a> {
    prog: &'a Program,
    role: RoleId,
    occurs: &'a Occurs<'a>,
}

#[cfg(test)]
pub(crate) mod tests;
