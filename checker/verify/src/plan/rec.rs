//! Recursion (`mu t(n: S {R} = e). G` and `t(a)`): the parameters' refinements at entry
//! (E0414) and at each jump (E0415), and the loop invariant's fixpoint (see the module
//! documentation of [`super`]).

use super::Contexts;
use crate::hir::expr::defined_and;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::Sigma;

/// After this many walks of one loop body its candidate invariant is given up for
/// `true` (which is always an invariant), and so once the whole walk has taken
/// [`STEP_BUDGET`] steps: nested loops would otherwise multiply their walks.
const MAX_LOOP_WALKS: usize = 32;
/// For this many walks the candidate is joined with the jumps' contexts by
/// [`Sigma::join`], whose bounds may weaken step by step (`x <= 1`, `x <= 2`, ...);
/// after them only facts every jump holds literally are kept (the widening: a bound
/// that keeps weakening goes to ±∞), so the candidate can only shrink and the
/// fixpoint ends.
pub(super) const WEAKEN_WALKS: usize = 4;
const STEP_BUDGET: usize = 1 << 20;

impl<'a> Contexts<'a> {
    /// `mu t(n: S {R} = e). G`: the refinement `R` must hold of `e` at entry (and of
    /// the arguments at each jump, see `walk`), so the body assumes it; the rest of the
    /// loop invariant is the fixpoint of the module documentation.
    pub(super) fn rec(
        &mut self,
        var: &'a str,
        params: &'a [RecParam],
        measure: Option<&'a Expr>,
        body: &'a Global,
        sigma: Sigma,
    ) -> Option<Sigma> {
        let inits = crate::sigma::initial_values(params);
        for p in params {
            let Some(r) = &p.refinement else { continue };
            self.obligations.push(Obligation {
                rule: Rule::RecInit,
                span: p.init.loc.0,
                what: format!(
                    "the refinement `{}` of parameter `{}` of `{var}` holds of its initial value `{}`",
                    print::expr(self.prog, None, r),
                    p.name,
                    print::expr(self.prog, None, &p.init)
                ),
                hyps: sigma.facts().to_vec(),
                goal: Goal::Valid(defined_and(crate::sigma::subst_params(r, params, &inits))),
            });
        }
        let ids: Vec<ValueId> = params.iter().map(|p| p.value).collect();
        let mut candidate = sigma;
        candidate.forget_values(&ids);
        let marks = (self.obligations.len(), self.runs.len(), self.jumps.len());
        let depth = self.loops.len();
        let mut walks = 0;
        loop {
            walks += 1;
            let mut start = candidate.clone();
            for r in params.iter().filter_map(|p| p.refinement.as_ref()) {
                start.assume(r);
            }
            self.loops.push((var, params, measure));
            let out = self.walk(body, start);
            self.loops.pop();
            let reached: Vec<&Sigma> =
                self.jumps[marks.2..].iter().filter(|(i, _)| *i == depth).map(|(_, s)| s).collect();
            // The next candidate: implied by the current one and by every jump's context.
            let next = if walks <= WEAKEN_WALKS {
                reached.iter().fold(candidate.clone(), |c, s| c.join(s, self.prog))
            } else {
                let mut c = candidate.clone();
                c.retain(|f| reached.iter().all(|s| s.contains(f)));
                c
            };
            if next == candidate {
                // Stable: every jump implies the candidate. This walk's obligations
                // stand. Jumps to this loop are used up; jumps to enclosing loops stay
                // for them.
                let mut k = 0;
                self.jumps.retain(|(i, _)| {
                    k += 1;
                    k <= marks.2 || *i != depth
                });
                return out;
            }
            candidate = if walks >= MAX_LOOP_WALKS || self.steps > STEP_BUDGET { Sigma::new() } else { next };
            self.obligations.truncate(marks.0);
            self.runs.truncate(marks.1);
            self.jumps.truncate(marks.2);
        }
    }

    /// A jump `t(a)` (`v`) under Σ (`sigma`): the measure, the parameters' refinements of
    /// the arguments, and the context kept for the loop invariant.
    pub(super) fn jump(&mut self, v: &RecVar, mut sigma: Sigma) {
        if let Some(i) = self.loops.iter().rposition(|(n, _, _)| *n == v.var) {
            let (_, params, measure) = self.loops[i];
            if let (Some(e), true) = (measure, params.len() == v.args.len()) {
                self.measure(&v.var, e, params, v, &sigma);
            }
            // The next iteration assumes the refinements of the arguments.
            if params.len() == v.args.len() {
                for p in params {
                    let Some(r) = &p.refinement else { continue };
                    self.obligations.push(Obligation {
                        rule: Rule::RecJump,
                        span: v.loc.0,
                        what: format!(
                            "the refinement `{}` of parameter `{}` of `{}` must hold of the argument{}",
                            print::expr(self.prog, None, r),
                            p.name,
                            v.var,
                            args_text(self.prog, &v.args)
                        ),
                        hyps: sigma.facts().to_vec(),
                        goal: Goal::Valid(defined_and(crate::sigma::subst_params(r, params, &v.args))),
                    });
                }
            }
            // The arguments are the parameters' new values.
            let ids: Vec<ValueId> = params.iter().map(|p| p.value).collect();
            sigma.forget_values(&ids);
            self.jumps.push((i, sigma));
        }
    }
}

/// "s `a, b`": the arguments of a jump as written, for messages.
fn args_text(prog: &Program, args: &[Expr]) -> String {
    let v: Vec<String> = args.iter().map(|a| print::expr(prog, None, a)).collect();
    format!("s `{}`", v.join(", "))
}
