//! Obligation planning for the global type: the walk [`Contexts`] threads the logical
//! context Σ ([`Sigma`]) through the type (not unfolded: loops get an invariant instead)
//! and makes every predicate met on the way an obligation, with the Σ of its point as
//! hypotheses. Nothing is decided here (the SMT stage decides). One file a rule:
//! [T-SESS]'s `init` (`initial.rs`, E0410/E0411), the streams' invariants (`streams.rs`,
//! E0410), [AGCOMP] of each joint motion (`motion.rs`), total choice (`total_choice.rs`,
//! Def 4.4 (1)), enum entries (`enum_entry.rs`, E0243), progress (`progress.rs`, E0419),
//! termination measures (`measure.rs`, E0416/E0417), recursion parameters and loop
//! invariants (`rec.rs`, E0414/E0415), full separation of `*` (`par.rs`); this file walks
//! and dispatches, and holds the vacuity guard of a step (`reachable`).
//!
//! How Σ evolves:
//!
//! - the root starts from every participant's `init` and its kind's invariant ([T-SESS]);
//! - after `p -> q : [P] l(v: S {P'})`, Σ ∧ P ∧ P' (payload fields are value variables;
//!   a field of the same name bound earlier is forgotten first);
//! - each branch of a choice starts from Σ ∧ its first message's guard, and after the
//!   choice Σ is the join of the branches that continue (what they agree on, with
//!   literal bounds weakened to cover every branch);
//! - a joint motion `dt<p: a, q: b>` applies the effect of every part
//!   ([`Sigma::apply_joint_motion`]: strongest postcondition, one level of snapshots);
//! - `g1 * g2`: each side starts from the facts of Σ over its own participants (and over
//!   values and constants only), and afterwards Σ is the conjunction of the sides' ends;
//! - `mu t(n: S {R} = e). G`: R must hold of `e` at entry (E0414) and of the arguments
//!   at each `t(a)` (E0415); the body assumes it. The rest of the loop invariant is a
//!   fixpoint: the candidate is Σ at entry; the body is walked under it (and R), and the
//!   next candidate is its join ([`Sigma::join`]: common facts, and the weaker of two
//!   literal bounds on a term) with the context at every `t` reached, until it is the
//!   candidate again. After [`rec::WEAKEN_WALKS`] walks only facts every `t` holds literally
//!   are kept (widening), so the candidate shrinks and this ends. Only the last walk's
//!   obligations are kept. Recursion parameters are forgotten at entry and at each `t`.
//!
//! Every step only keeps or weakens what holds, so every obligation's hypotheses hold
//! whenever the choreography reaches its point.

pub mod crossing;
mod enum_entry;
mod initial;
mod measure;
mod motion;
mod par;
mod progress;
mod rec;
mod streams;
mod total_choice;

use crate::hir::expr::defined_and;
use crate::hir::*;
use crate::obligation::{Goal, Obligation, RoleMotion, Rule};
use crate::sigma::Sigma;
use std::collections::HashMap;

/// The obligations of the global type `g` (its predicates, with their contexts), in the
/// order of the type.
pub fn obligations(prog: &Program, g: &Global) -> Vec<Obligation> {
    let mut c = Contexts {
        prog,
        obligations: Vec::new(),
        loops: Vec::new(),
        jumps: Vec::new(),
        runs: Vec::new(),
        in_par: 0,
        steps: 0,
        choice_firsts: Default::default(),
        enum_of: Default::default(),
        exact_entry: Default::default(),
    };
    let start = c.initial();
    c.streams();
    c.walk(g, start);
    c.obligations
}

/// The walk that threads Σ through the type and makes the predicate obligations (see
/// the module documentation).
struct Contexts<'a> {
    prog: &'a Program,
    obligations: Vec<Obligation>,
    /// Enclosing recursions, innermost last: the variable, its parameters and its
    /// termination measure.
    loops: Vec<(&'a str, &'a [RecParam], Option<&'a Expr>)>,
    /// The contexts reached at recursion variables: (index into `loops`, Σ there).
    jumps: Vec<(usize, Sigma)>,
    /// The primitives run inside some `*`, in walk order, with the context each starts
    /// in; each side of a `*` takes the ones logged while it was walked.
    runs: Vec<RoleMotion>,
    /// How many `*` enclose the current point.
    in_par: usize,
    steps: usize,
    /// The first messages of the choices met: their progress is the choice's.
    choice_firsts: std::collections::HashSet<crate::source::Span>,
    /// The enum of each enum-typed payload value met so far (E0243's shortcut for `x == y`
    /// with `y` of the same enum).
    enum_of: HashMap<ValueId, (String, crate::dialect::Wire)>,
    /// The exact entry predicate of each enum-typed payload value that Σ assumes by a
    /// weaker fact (`lower::approximate_entries`): added to the hypotheses of total choice
    /// and progress ([`Contexts::exact`]), whose counterexamples must be values of the
    /// fields' types.
    exact_entry: HashMap<ValueId, Expr>,
}

impl<'a> Contexts<'a> {
    /// Walks `g` from context `sigma`; the context at its end, or `None` when no path
    /// goes past it (it loops back or ends).
    fn walk(&mut self, g: &'a Global, sigma: Sigma) -> Option<Sigma> {
        crate::stack::deep(|| self.walk_inner(g, sigma))
    }

    fn walk_inner(&mut self, g: &'a Global, mut sigma: Sigma) -> Option<Sigma> {
        self.steps += 1;
        match g {
            Global::Msg(m) => {
                // Progress (E0419): in every state of Σ, the guard holds and some payload
                // satisfies the refinements (the first message of a choice: the
                // choice's). A message no value fits is stuck, not unreachable: nothing
                // but the protocol itself is there to establish it (a program may have no
                // processes at all).
                if !self.choice_firsts.contains(&m.loc.0) {
                    observe(&mut sigma, &m.observed);
                    let e = progress::enabled(self.prog, m);
                    if e.guard.is_some() || !e.refinement.is_true() {
                        self.obligations.push(Obligation {
                            rule: Rule::Progress,
                            span: m.loc.0,
                            what: format!("the message {}: some payload satisfies its refinements", e.what),
                            hyps: self.exact(sigma.facts()),
                            goal: Goal::Progress { branches: vec![e] },
                        });
                    }
                }
                // Σ assumes a costly entry predicate (MAV_CMD's fifty runs) by its hull; the
                // message's own checks read the exact one (`lower::approximate_entries`).
                let assumed = crate::lower::approximate_entries(self.prog.dialect, m);
                if let Some(a) = &assumed {
                    for (f, g) in m.payload.iter().zip(&a.payload) {
                        let Some(check) = f.mav.as_ref().and_then(|mav| mav.entry.as_ref()) else { continue };
                        if f.refinement != g.refinement {
                            let x = crate::hir::expr::value_expr(f.value, &f.name, &f.sort);
                            let (entry, _) = crate::lower::entry_predicate(self.prog.dialect, check, &x);
                            self.exact_entry.insert(f.value, entry);
                        }
                    }
                }
                let asked = self.enum_fields(m);
                if !asked.is_empty() {
                    self.enum_entries(m, assumed.as_ref().unwrap_or(m), &asked, &sigma);
                }
                sigma.assume_message(assumed.as_ref().unwrap_or(m));
                Some(sigma)
            }
            Global::Motion(m) => {
                self.motion(m, &mut sigma);
                Some(sigma)
            }
            Global::Seq(items, _) => {
                let mut cur = Some(sigma);
                for it in items {
                    // What follows a `t` or `end` is unreachable (E0314): `true` will do.
                    cur = self.walk(it, cur.unwrap_or_default());
                }
                cur
            }
            Global::Choice(branches, _) => {
                // The deciding participant's snapshot, shared by the branches' first messages.
                let mut snap: Vec<Observed> = Vec::new();
                for m in branches.iter().filter_map(crate::wf::side::first_message) {
                    for o in &m.observed {
                        if !snap.iter().any(|x| x.value == o.value) {
                            snap.push(o.clone());
                        }
                    }
                }
                observe(&mut sigma, &snap);
                self.total_choice(branches, &sigma);
                self.progress(branches, &sigma);
                let mut out: Option<Sigma> = None;
                for b in branches {
                    let mut s = sigma.clone();
                    let first = crate::wf::side::first_message(b);
                    if let Some(guard) = first.and_then(|m| m.guard.as_ref()) {
                        s.assume(&defined_and(guard.clone()));
                    }
                    if let (Some(m), true) = (first, branches.len() > 1) {
                        // A dead branch: its guard, or its guard and its payload's
                        // refinements together (no value fits), contradict Σ.
                        let mut taken = sigma.clone();
                        taken.assume_message(m);
                        if taken.facts() != sigma.facts() {
                            let what = format!(
                                "the guard and payload of branch `{}` ({} -> {})",
                                m.label,
                                self.prog.role_name(m.from),
                                self.prog.role_name(m.to)
                            );
                            self.reachable(m.loc.0, what, &taken, vec![sigma.facts().to_vec()], true);
                        }
                    }
                    if let Some(end) = self.walk(b, s) {
                        out = Some(match out {
                            None => end,
                            Some(o) => o.join(&end, self.prog),
                        });
                    }
                }
                out
            }
            Global::Par(sides, loc) => self.par(sides, *loc, sigma),
            Global::Rec { var, params, decreases, body, .. } => self.rec(var, params, decreases.as_ref(), body, sigma),
            Global::Var(v) => {
                self.jump(v, sigma);
                None
            }
            Global::End(_) => None,
            // A timeout teaches nothing about values (docs/observed-and-timeouts.md): Σ
            // after it is Σ at the choice.
            Global::After(_) => Some(sigma),
        }
    }

    /// The vacuity guard at a step: Σ after it (`sigma`) is satisfiable, or the step is
    /// where the protocol gets stuck (when every context in `before` is satisfiable).
    fn reachable(
        &mut self,
        span: crate::source::Span,
        what: String,
        sigma: &Sigma,
        before: Vec<Vec<Expr>>,
        dead_branch: bool,
    ) {
        self.obligations.push(Obligation {
            rule: Rule::Reachable,
            span,
            what,
            hyps: sigma.facts().to_vec(),
            goal: Goal::Reachable { before, dead_branch },
        });
    }

    /// `facts` with the exact entry predicate of every payload value they mention whose
    /// entry predicate Σ assumes by a weaker fact (MAV_CMD's hull): total choice and
    /// progress then decide over the field's type (a counterexample is an entry, and a
    /// split at a gap of the entries is total), while the other checks keep Σ's cheaper
    /// fact. Sound: the predicate mentions the value alone and holds of every value the
    /// field carried (it is the field's type), whichever binding a fact is about.
    fn exact(&self, facts: &[Expr]) -> Vec<Expr> {
        let mut out = facts.to_vec();
        if self.exact_entry.is_empty() {
            return out;
        }
        let mut seen = std::collections::BTreeSet::new();
        for f in facts {
            f.visit_vars(&mut |v, _| {
                if let Var::Value(id, _) = v {
                    if self.exact_entry.contains_key(id) {
                        seen.insert(*id);
                    }
                }
            });
        }
        out.extend(seen.into_iter().filter_map(|id| self.exact_entry.get(&id).cloned()));
        out
    }
}

/// A snapshot of observed values is taken (LANGUAGE.md, "Observed state"): each is a new
/// value (what was known of the same binding site, an earlier round's snapshot, is
/// forgotten) of which only its refinement is known: the field's wire range and float
/// model and the stream's invariant. Nothing relates it to any other step's snapshot.
fn observe(sigma: &mut Sigma, snap: &[Observed]) {
    if snap.is_empty() {
        return;
    }
    let ids: Vec<ValueId> = snap.iter().map(|o| o.value).collect();
    sigma.forget_values(&ids);
    for r in snap.iter().filter_map(|o| o.refinement.as_ref()) {
        sigma.assume(&defined_and(r.clone()));
    }
}

#[cfg(test)]
mod tests;
