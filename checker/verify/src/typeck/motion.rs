//! [T-MOTION] of Table 1 with [SUB-MOTION] (Fig 5): the process's primitive refines the
//! type's (Def 3.4, corrected direction; E0705 when interruptibility differs), the
//! context implies the precondition, and Σ becomes the strongest postcondition.

use super::{Checker, State};
use crate::hir::expr::{and_all, conjuncts, mentions, subst_values};
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::instantiate;
use crate::subtype::refinement;

impl Checker<'_> {
    /// [T-MOTION] with [SUB-MOTION]: refinement, `Σ ⇒ Pre`, then Σ := Post.
    pub(super) fn motion(&mut self, a: &PrimApp, loc: Loc, prims: &[PrimApp], tloc: Loc, st: &mut State) -> bool {
        let abstract_: Vec<PrimApp> = prims
            .iter()
            .map(|b| PrimApp {
                prim: b.prim,
                args: b.args.iter().map(|e| subst_values(e, &st.vals)).collect(),
                loc: b.loc,
            })
            .collect();
        match refinement(self.prog, self.role, std::slice::from_ref(a), loc, &abstract_, tloc) {
            Err(d) => {
                self.diags.push(d);
                return false;
            }
            // Refinement (Def 3.4) constrains whole trajectories, not the state the
            // motion starts in, so it gets no hypotheses from Σ.
            Ok(Some(ob)) => self.obligations.push(ob),
            Ok(None) => {}
        }
        let prim = self.prog.prim(a.prim);
        // Received values in the arguments take the sorts of their payload fields.
        let args: Vec<Expr> = a.args.iter().map(|e| subst_values(e, &st.vals)).collect();
        // The arguments can be evaluated, and the precondition holds of them (and can be
        // evaluated too): an argument `1 / p` with `p == 0` is no value to start with.
        let mut pre = Vec::new();
        for a in &args {
            conjuncts(&crate::hir::expr::definedness(a), &mut pre);
        }
        conjuncts(&crate::hir::expr::defined_and(instantiate(&prim.pre, self.role, &args)), &mut pre);
        if !pre.is_empty() {
            let goal = and_all(pre, loc);
            if let Some(hint) = self.loop_hint(&goal) {
                self.hints.insert((Rule::TMotion, loc.0), hint);
            }
            self.obligations.push(Obligation {
                rule: Rule::TMotion,
                span: loc.0,
                what: format!(
                    "the precondition of `{}` holds when `{}` starts it",
                    print::prim_app(self.prog, a),
                    self.name()
                ),
                hyps: st.sigma.facts().to_vec(),
                goal: Goal::Valid(goal),
            });
        }
        // Σ := the strongest postcondition; the others moved meanwhile.
        st.sigma.apply_motion(self.prog, self.role, a.prim, &args);
        let me = self.role;
        st.sigma.forget(&|v| matches!(v, Var::Role(r, _) | Var::Snap(r, _) if *r != me));
        st.vals.retain(|_, e| !mentions(e, &is_physical));
        st.actions += 1;
        true
    }
}

/// Variables whose value changes when time passes.
pub(super) fn is_physical(v: &Var) -> bool {
    matches!(v, Var::Role(..) | Var::Snap(..) | Var::Own(_) | Var::Old(_) | Var::Clock | Var::Point(_))
}
