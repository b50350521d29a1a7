//! Termination (`mu t(params) decreases E`, E0416/E0417): the measure at each jump.

use super::Contexts;
use crate::hir::expr::{defined_and, BinOp};
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::Sigma;

impl<'a> Contexts<'a> {
    /// Termination (`mu t(params) decreases E`): at the jump `t(a)` (`v`), under Σ there
    /// (the path's messages and guards, the parameters' refinements, the loop invariant),
    /// `E >= 0` (E0416) and `E[a/params] < E` (E0417). E reads only the parameters, values
    /// bound before the loop and constants (lowering), none of which changes between the
    /// loop head and a jump back to it: E here is E of the iteration that jumps.
    pub(super) fn measure(&mut self, var: &str, e: &Expr, params: &[RecParam], v: &RecVar, sigma: &Sigma) {
        let text = print::expr(self.prog, None, e);
        let zero = Expr { kind: ExprKind::Int(0), sort: Sort::Int, loc: e.loc };
        let cmp = |op, a: Expr, b: Expr| Expr {
            kind: ExprKind::Binary(op, Box::new(a), Box::new(b)),
            sort: Sort::Bool,
            loc: e.loc,
        };
        self.obligations.push(Obligation {
            rule: Rule::MeasureBound,
            span: v.loc.0,
            what: format!("the measure `{text}` of `{var}` at the jump `{}`", jump_text(self.prog, v)),
            hyps: sigma.facts().to_vec(),
            goal: Goal::Valid(defined_and(cmp(BinOp::Le, zero, e.clone()))),
        });
        let next = crate::sigma::subst_params(e, params, &v.args);
        self.obligations.push(Obligation {
            rule: Rule::MeasureDecrease,
            span: v.loc.0,
            what: format!(
                "the measure `{text}` of `{var}` must decrease at the jump `{}` (to `{}`)",
                jump_text(self.prog, v),
                print::expr(self.prog, None, &next)
            ),
            hyps: sigma.facts().to_vec(),
            goal: Goal::Valid(defined_and(cmp(BinOp::Lt, next, e.clone()))),
        });
    }
}

/// `t(a, b)`: a jump as written.
fn jump_text(prog: &Program, v: &RecVar) -> String {
    if v.args.is_empty() {
        return v.var.clone();
    }
    let a: Vec<String> = v.args.iter().map(|a| print::expr(prog, None, a)).collect();
    format!("{}({})", v.var, a.join(", "))
}
