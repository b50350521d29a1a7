//! The cone of influence of a question in a logical context: the facts that share a
//! variable with the question, directly or through other facts kept, and the facts over
//! constants only. Every query slices its hypotheses to this cone (the SMT stage), and the
//! global walk slices the context of a payload value's question (E0243) the same way.
//!
//! Slicing is sound for a proof: fewer hypotheses can only turn "holds" into "fails", and
//! only when the dropped facts contradict each other (the point is unreachable), which the
//! vacuity guard reports rather than hides.

use crate::hir::{Expr, PrimApp, Program, RoleId, Slot, Var};
use std::collections::HashSet;

/// The facts of `hs` in the cone of influence of `seed`'s variables: the slice every query
/// of a goal about `seed` uses.
pub fn cone(prog: &Program, hs: &[Expr], seed: &Expr) -> Vec<Expr> {
    slice(prog, hs, vars_of(prog, [seed]))
}

/// The variables of some expressions (constants excepted).
/// Inputs count as their source's state variable, which they are.
pub fn vars_of<'e>(prog: &Program, es: impl IntoIterator<Item = &'e Expr>) -> HashSet<Var> {
    let mut out = HashSet::new();
    for e in es {
        e.visit_vars(&mut |v, _| {
            if !matches!(v, Var::Const(_)) {
                out.insert(prog.source_of(v));
            }
        });
    }
    out
}

/// What the hypotheses of a motion query may be about: the participants' variables
/// (now and at their latest snapshot), their input sources', and the arguments'.
pub fn seeds_of(prog: &Program, parts: &[(RoleId, PrimApp)]) -> HashSet<Var> {
    let mut out = vars_of(prog, parts.iter().flat_map(|(_, a)| a.args.iter()));
    for (r, _) in parts {
        let mut roles = vec![*r];
        roles.extend(prog.role(*r).input_sources.iter().flatten().copied());
        for role in roles {
            let kind = prog.kind_of(role);
            for i in 0..kind.state.len() {
                out.insert(Var::Role(role, Slot::State(i)));
                out.insert(Var::Snap(role, Slot::State(i)));
            }
            for i in 0..kind.inputs.len() {
                out.insert(prog.source_of(&Var::Role(role, Slot::Input(i))));
            }
        }
    }
    out
}

/// The hypotheses connected to `seeds` through shared variables (the cone of
/// influence). Dropping the others keeps queries small and lets identical questions
/// about different participants share a cache entry. It is sound: fewer hypotheses
/// can only turn "holds" into "fails" — and only when the dropped ones contradict each
/// other, i.e. the point is unreachable, which is reported rather than hidden.
pub fn slice(prog: &Program, hs: &[Expr], mut seeds: HashSet<Var>) -> Vec<Expr> {
    // One visit of each hypothesis per pass, without collecting its variables first: a
    // query of a wide `dt` slices a context of n facts, n times.
    let mut keep = vec![false; hs.len()];
    loop {
        let mut grew = false;
        for (i, h) in hs.iter().enumerate() {
            if keep[i] {
                continue;
            }
            let (mut any, mut hit) = (false, false);
            h.visit_vars(&mut |v, _| {
                if !hit && !matches!(v, Var::Const(_)) {
                    any = true;
                    hit = seeds.contains(&prog.source_of(v));
                }
            });
            if hit || !any {
                keep[i] = true;
                grew = true;
                seeds.extend(vars_of(prog, [h]));
            }
        }
        if !grew {
            break;
        }
    }
    hs.iter().zip(keep).filter(|(_, k)| *k).map(|(h, _)| h.clone()).collect()
}

#[cfg(test)]
mod tests {
    use super::{slice, vars_of};
    use crate::hir::Expr;

    /// The conjuncts of a guard over `A`'s state `x, y, z, w`.
    fn facts(guard: &str) -> (crate::hir::Program, Vec<Expr>) {
        let (prog, g) = crate::testing::first_guard(&format!(
            "robot R {{ state x: real, y: real, z: real, w: real; }} system S {{ participant A: R; participant B: R; }}
             choreography G = A -> B : [{guard}] go. end;"
        ));
        let fs = g.conjuncts().into_iter().cloned().collect();
        (prog, fs)
    }

    fn printed(prog: &crate::hir::Program, es: &[Expr]) -> Vec<String> {
        es.iter().map(|e| crate::hir::print::expr(prog, None, e)).collect()
    }

    #[test]
    fn a_slice_keeps_the_cone_of_influence_and_closed_facts() {
        let (prog, fs) = facts("x >= 0 && y == x + 1 && z == 2 && w <= z && 1 <= 2 && y <= 5");
        // From `x`: the facts linked to it through `y`, and the fact with no variable.
        let kept = slice(&prog, &fs, vars_of(&prog, [&fs[0]]));
        assert_eq!(
            printed(&prog, &kept),
            printed(&prog, &[fs[0].clone(), fs[1].clone(), fs[4].clone(), fs[5].clone()])
        );
        // From `w`: `z` through `w <= z`, whichever comes first.
        let kept = slice(&prog, &fs, vars_of(&prog, [&fs[3]]));
        assert_eq!(printed(&prog, &kept), printed(&prog, &[fs[2].clone(), fs[3].clone(), fs[4].clone()]));
        // No seeds: only the closed fact.
        assert_eq!(slice(&prog, &fs, Default::default()).len(), 1);
    }
}
