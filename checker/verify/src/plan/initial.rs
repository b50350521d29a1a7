//! [T-SESS]'s assumption, checked: each participant's `init` admits a state within its
//! kind's invariant (E0411, or E0410 without an invariant), and the `init`s are jointly
//! satisfiable; the initial context Σ.

use super::Contexts;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, Rule};
use crate::sigma::Sigma;
use std::collections::HashMap;

impl<'a> Contexts<'a> {
    /// [T-SESS]'s assumption, checked: each participant's `init` is satisfiable and
    /// implies its kind's invariant, and all of them are jointly satisfiable. The
    /// initial context Σ (every `init` and invariant) is returned.
    pub(super) fn initial(&mut self) -> Sigma {
        let prog = self.prog;
        let mut each = Vec::new();
        for r in prog.role_ids() {
            let init = crate::sigma::init(prog, r);
            let span = prog.role(r).init.as_ref().map(|e| e.loc.0).unwrap_or(prog.role(r).span);
            let name = prog.role_name(r);
            // The robot's first state satisfies `init` and, as every state of the kind,
            // the invariant: `init` need not repeat the invariant, but must allow a
            // state within it (E0411). One query when it does; when it does not, an
            // `init` no state satisfies at all is E0410 instead.
            let both = Sigma::initial(prog, [r]).into_facts();
            if crate::sigma::invariant(prog, r).is_empty() {
                if !init.is_empty() {
                    let what = format!("the initial state of `{name}`");
                    self.reachable(span, what, &Sigma::from_facts(&init), Vec::new(), false);
                }
            } else {
                self.obligations.push(Obligation {
                    rule: Rule::InitInvariant,
                    span,
                    what: format!("the `init` of `{name}`"),
                    hyps: both.clone(),
                    goal: Goal::Reachable { before: vec![init], dead_branch: false },
                });
            }
            each.push(both);
        }
        let all = Sigma::initial(prog, prog.role_ids());
        // Contexts over disjoint variables (each participant's own, an input being its
        // source's) are jointly satisfiable when each is: ask only when some share.
        let mut owner: HashMap<Var, usize> = HashMap::new();
        let mut shared = false;
        for (i, facts) in each.iter().enumerate() {
            for f in facts {
                f.visit_vars(&mut |v, _| {
                    if !matches!(v, Var::Const(_)) {
                        shared |= *owner.entry(prog.source_of(v)).or_insert(i) != i;
                    }
                });
            }
        }
        if shared && !all.is_empty() {
            let span = prog.system.as_ref().map(|(_, s)| *s).unwrap_or_default();
            let what = "the conjunction of the participants' initial states".to_string();
            self.reachable(span, what, &all, each, false);
        }
        all
    }
}
