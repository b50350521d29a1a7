//! [T-REC] and [T-VAR] of Table 1: process loops are checked coinductively against the
//! local type's (a loop body met again with the same type node and context is assumed
//! well typed, with widening to the invariant after [`super::WIDEN_AFTER`] contexts),
//! and loop parameters (DATUM) satisfy their refinements (E0712, E0713) and follow the
//! type's parameters (E0714).

use super::{hash_of, Checker, State, WIDEN_AFTER};
use crate::hir::expr::{mentions, subst_values, value_expr};
use crate::hir::node::NodeRef;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::{self, Sigma};
use std::collections::HashMap;

impl<'a> Checker<'a> {
    /// The process's loop parameters get `values` (process terms, evaluated now), at
    /// entry (`jump` false) or at a jump back: [T-REC]/[T-VAR] with parameters.
    /// - Their refinements must hold of the values (E0712 at entry, E0713 at a jump),
    ///   and the loop body assumes them of the (fresh) parameters.
    /// - When the local type enters or repeats a loop with as many parameters at the
    ///   same step (`ty`: its parameters, whose new values are in `vals` already), the
    ///   process's parameters stand for the type's: each value must equal the type's
    ///   (E0714), and afterwards the type's parameter is the process's in `vals`.
    pub(super) fn loop_params(
        &mut self,
        params: &[RecParam],
        values: &[Expr],
        locs: Vec<Loc>,
        ty: Option<Vec<RecParam>>,
        st: &mut State,
        jump: bool,
    ) {
        let (rule, when) = if jump { (Rule::TRecJump, "the argument") } else { (Rule::TRecInit, "the initial value") };
        for ((p, v), loc) in params.iter().zip(values).zip(&locs) {
            if let Some(r) = &p.refinement {
                self.obligations.push(Obligation {
                    rule,
                    span: loc.0,
                    what: format!(
                        "the refinement `{}` of `{}`'s loop parameter `{}` holds of {when} `{}`",
                        print::expr(self.prog, None, r),
                        self.name(),
                        p.name,
                        print::expr(self.prog, None, v)
                    ),
                    hyps: st.sigma.facts().to_vec(),
                    // Held and defined of the values (`hir::expr::definedness`).
                    goal: Goal::Valid(crate::hir::expr::defined_and(sigma::subst_params(r, params, values))),
                });
            }
        }
        if let Some(tp) = &ty {
            for (((p, v), t), loc) in params.iter().zip(values).zip(tp).zip(&locs) {
                let Some(want) = st.vals.get(&t.value) else { continue };
                let goal = Expr {
                    kind: ExprKind::Binary(crate::hir::expr::BinOp::Eq, Box::new(v.clone()), Box::new(want.clone())),
                    sort: Sort::Bool,
                    loc: *loc,
                };
                self.obligations.push(Obligation {
                    rule: Rule::TRecArgs,
                    span: loc.0,
                    what: format!(
                        "{when} `{}` of `{}`'s loop parameter `{}` equals the local type's `{}` for its parameter `{}`",
                        print::expr(self.prog, None, v),
                        self.name(),
                        p.name,
                        print::expr(self.prog, None, want),
                        t.name
                    ),
                    hyps: st.sigma.facts().to_vec(),
                    goal: Goal::Valid(crate::hir::expr::defined_and(goal)),
                });
            }
        }
        let ids: Vec<ValueId> = params.iter().map(|p| p.value).collect();
        st.forget(&ids);
        for r in params.iter().filter_map(|p| p.refinement.as_ref()) {
            st.assume(r.clone());
        }
        if let Some(tp) = ty {
            for (p, t) in params.iter().zip(tp) {
                st.vals.insert(t.value, value_expr(p.value, &p.name, &p.sort));
                if t.refinement.is_some() {
                    self.stands_for.insert(p.value, (p.clone(), t.clone()));
                }
            }
        }
    }

    /// Advice for a failed obligation `goal` of this process: where it reads a loop
    /// parameter that stands for a refined parameter of the type's loop and the
    /// process's loop does not keep that refinement (conjunct by conjunct), the fix is to
    /// add the type's refinement, in the process's names, to the process's parameter
    /// (the body then assumes it, and E0712/E0713 check it at entry and at each jump).
    pub(super) fn loop_hint(&self, goal: &Expr) -> Option<String> {
        let mut missing = Vec::new();
        let mut ids: Vec<&ValueId> = self.stands_for.keys().collect();
        ids.sort();
        for id in ids {
            let (p, t) = &self.stands_for[id];
            if !mentions(goal, &|v| matches!(v, Var::Value(x, _) if x == id)) {
                continue;
            }
            let Some(r) = &t.refinement else { continue };
            let map = HashMap::from([(t.value, value_expr(p.value, &p.name, &p.sort))]);
            let want = subst_values(r, &map);
            let kept: Vec<&Expr> = p.refinement.iter().flat_map(|e| e.conjuncts()).collect();
            if want.conjuncts().iter().all(|c| kept.contains(c)) {
                continue;
            }
            missing.push(format!(
                "add `{{{}}}` to the process's loop parameter `{}` (it stands for the local type's `{}`, \
                 whose loop keeps that refinement; the process's loop then assumes it, and it is \
                 checked at entry and at each jump)",
                print::expr(self.prog, None, &want),
                p.name,
                t.name
            ));
        }
        (!missing.is_empty()).then(|| missing.join("; "))
    }

    /// Coinduction for process loops: whether `body` still needs checking against `t`
    /// under the current context. Widens the context after [`WIDEN_AFTER`] variants.
    pub(super) fn enter(&mut self, body: &'a Process, t: &LocalArc, st: &mut State) -> bool {
        let pair = (NodeRef::new(body), NodeRef::from(t));
        let n = self.contexts.get(&pair).copied().unwrap_or(0);
        if n >= WIDEN_AFTER {
            st.sigma = Sigma::from_facts(&self.invariant);
            st.vals.clear();
        }
        let mut sigma = st.sigma.facts().to_vec();
        sigma.sort_by_key(hash_of);
        let mut vals: Vec<(ValueId, Expr)> = st.vals.iter().map(|(k, v)| (*k, v.clone())).collect();
        vals.sort_by_key(|a| a.0);
        if !self.assumed.insert((pair.0.clone(), pair.1.clone(), sigma, vals)) {
            return false;
        }
        self.contexts.insert(pair, n + 1);
        true
    }
}
