//! Total choice (Def 4.4 (1), E0316): under Σ, some guard of a choice holds.

use super::Contexts;
use crate::hir::expr::{defined_and, BinOp};
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::Sigma;

impl<'a> Contexts<'a> {
    /// Def 4.4 (1): under Σ, some guard holds.
    pub(super) fn total_choice(&mut self, branches: &[Global], sigma: &Sigma) {
        let guards: Vec<Option<&Expr>> =
            branches.iter().map(|b| crate::wf::side::first_message(b).and_then(|m| m.guard.as_ref())).collect();
        if guards.iter().any(|g| g.is_none_or(Expr::is_true)) {
            return; // an unguarded branch: the disjunction is trivially valid
        }
        let Some(m) = branches.first().and_then(crate::wf::side::first_message) else { return };
        // A guard that cannot be evaluated does not hold: each disjunct is defined too.
        let mut disj: Option<Expr> = None;
        for g in guards.into_iter().flatten().map(|g| defined_and(g.clone())) {
            disj = Some(match disj {
                None => g,
                Some(d) => {
                    let loc = d.loc;
                    Expr { kind: ExprKind::Binary(BinOp::Or, Box::new(d), Box::new(g)), sort: Sort::Bool, loc }
                }
            });
        }
        if let Some(goal) = disj {
            self.obligations.push(Obligation {
                rule: Rule::TotalChoice,
                span: m.loc.0,
                what: format!("the guards of the choice by `{}`", self.prog.role_name(m.from)),
                hyps: self.exact(sigma.facts()),
                goal: Goal::Valid(goal),
            });
        }
    }
}
