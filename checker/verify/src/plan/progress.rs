//! Progress (E0419, seed 000 Sec 3.1): at a message or a choice, under Σ, some branch
//! has a true guard and a payload its refinements admit; [`enabled`], when a message can
//! be sent.

use super::Contexts;
use crate::hir::expr::{and_all, defined_and, definedness, BinOp};
use crate::hir::*;
use crate::obligation::{Enabled, Goal, Obligation, Rule};
use crate::sigma::Sigma;
use std::collections::HashMap;

impl<'a> Contexts<'a> {
    /// Progress at a choice (E0419): under Σ and the guards' disjunction (whose validity
    /// is total choice's, E0316), some branch has a true guard and a payload its
    /// refinements admit. Asked only when some first message has a refinement: without
    /// one this is total choice itself.
    pub(super) fn progress(&mut self, branches: &[Global], sigma: &Sigma) {
        let firsts: Vec<&Msg> = branches.iter().filter_map(crate::wf::side::first_message).collect();
        if branches.iter().any(|b| b.timeout_head().is_some()) {
            // The timeout branch is always enabled: time passes, and its waiting role takes
            // it when no other branch's message came. The choice cannot get stuck, and no
            // message branch needs to be enabled on its own.
            self.choice_firsts.extend(firsts.iter().map(|m| m.loc.0));
            self.some_message_can_come(&firsts, sigma);
            return;
        }
        if firsts.len() != branches.len() {
            return; // a branch without a first message: E0303, reported by `side`
        }
        self.choice_firsts.extend(firsts.iter().map(|m| m.loc.0));
        let each: Vec<Enabled> = firsts.iter().map(|m| enabled(self.prog, m)).collect();
        if each.iter().all(|e| e.fields.is_empty() && e.refinement.is_true()) {
            return;
        }
        let mut hyps = sigma.clone();
        if let Some(any) = firsts
            .iter()
            .map(|m| m.guard.clone())
            .collect::<Option<Vec<Expr>>>()
            .and_then(|gs| gs.into_iter().reduce(or))
        {
            hyps.assume(&any);
        }
        let m = firsts[0];
        self.obligations.push(Obligation {
            rule: Rule::Progress,
            span: m.loc.0,
            what: format!("the choice by `{}`: some branch can be taken", self.prog.role_name(m.from)),
            hyps: self.exact(hyps.facts()),
            goal: Goal::Progress { branches: each },
        });
    }
}

impl Contexts<'_> {
    /// At a choice with a timeout branch, some message branch can be taken in some state
    /// the choice is reached in (E0410, an error): otherwise the waiting role can only ever
    /// give up, and the choice's messages are dead text. Progress does not ask it (the
    /// timeout is always enabled), and each branch alone is only a dead-branch warning, so
    /// without this a choice whose every message is impossible (`got == want && got > 20`
    /// after `want < 10`) verified with warnings. A satisfiability question: Σ with the
    /// disjunction of the branches' guards and payload refinements (their values free),
    /// each with its definedness, as [`Sigma::assume_message`] assumes a message.
    fn some_message_can_come(&mut self, firsts: &[&Msg], sigma: &Sigma) {
        let Some(m) = firsts.first() else { return };
        let mut can: Vec<Expr> = Vec::new();
        for f in firsts {
            let parts: Vec<Expr> = f
                .guard
                .iter()
                .chain(f.payload.iter().filter_map(|x| x.refinement.as_ref()))
                .map(|e| defined_and(e.clone()))
                .collect();
            let conj = and_all(parts, f.loc);
            if conj.is_true() {
                return; // an unconstrained message can always come
            }
            can.push(conj);
        }
        let Some(any) = can.into_iter().reduce(or) else { return };
        let mut taken = sigma.clone();
        taken.assume(&any);
        let waits = self.prog.role_name(m.to);
        let what = format!("a message of this choice, which `{waits}` otherwise only ever leaves by its timeout");
        // A `float` payload field is a float32, which the satisfiability question assumes as
        // `true` (over the reals): asked again with every value chosen, its format exact.
        let floats = firsts.iter().flat_map(|f| &f.payload).any(|x| self.prog.wire_floats.contains_key(&x.value));
        if floats {
            let facts = self.exact(taken.facts());
            if let Some(ob) = super::streams::float_witness(self.prog, &facts, m.loc, &what) {
                self.obligations.push(ob);
            }
        }
        self.reachable(m.loc.0, what, &taken, vec![sigma.facts().to_vec()], false);
    }
}

fn or(a: Expr, b: Expr) -> Expr {
    let loc = a.loc;
    Expr { kind: ExprKind::Binary(BinOp::Or, Box::new(a), Box::new(b)), sort: Sort::Bool, loc }
}

/// When `m` can be sent: its guard, and some payload satisfying the conjunction of its
/// fields' refinements. A field defined by an equality `f == e` (e of f's sort, reading no
/// field of `m`) is replaced by `e` in the other conjuncts (∃f. f == e ∧ P(f) is P(e)), so
/// that `seq == i` needs no quantifier; the fields still read are left to an existential.
///
/// Both are asked to be defined as well ([`definedness`]): a guard that cannot be evaluated
/// lets no branch be taken, and a payload whose refinement cannot be evaluated is not
/// admitted. The condition is added before a field is replaced by its definition, so that
/// `speed == sqrt(e)` leaves `e >= 0` behind (the encoding alone would let `sqrt` of a
/// negative be any value, and some `speed` would equal it).
pub(super) fn enabled(prog: &Program, m: &Msg) -> Enabled {
    let written = and_all(m.payload.iter().filter_map(|f| f.refinement.clone()), m.loc);
    let mut conj: Vec<Expr> = Vec::new();
    crate::hir::expr::conjuncts(&definedness(&written), &mut conj);
    crate::hir::expr::conjuncts(&written, &mut conj);
    let ids: Vec<ValueId> = m.payload.iter().map(|f| f.value).collect();
    let field = |e: &Expr| match &e.kind {
        ExprKind::Var(Var::Value(id, _)) if ids.contains(id) => Some(*id),
        _ => None,
    };
    let reads_field = |e: &Expr| crate::hir::expr::mentions(e, &|v| matches!(v, Var::Value(id, _) if ids.contains(id)));
    loop {
        let def = conj.iter().enumerate().find_map(|(k, c)| {
            let ExprKind::Binary(BinOp::Eq, a, b) = &c.kind else { return None };
            [(a, b), (b, a)].into_iter().find_map(|(x, e)| {
                let id = field(x)?;
                (!reads_field(e)
                    && (x.sort == e.sort || x.sort == Sort::Real && e.sort == Sort::Int)
                    && crate::lower::float_definition_decided(prog, id, e))
                .then(|| (k, id, (**e).clone()))
            })
        });
        let Some((k, id, e)) = def else { break };
        conj.remove(k);
        let map = HashMap::from([(id, e)]);
        conj = conj.iter().map(|c| crate::hir::expr::subst_values(c, &map)).collect();
    }
    let rest = crate::hir::expr::and_all(conj, m.loc);
    let fields = m
        .payload
        .iter()
        .filter(|f| crate::hir::expr::mentions(&rest, &|v| matches!(v, Var::Value(id, _) if *id == f.value)))
        .map(|f| (f.value, f.name.clone(), f.sort.clone()))
        .collect();
    Enabled {
        what: format!("{} -> {}: {}", prog.role_name(m.from), prog.role_name(m.to), m.label),
        guard: m.guard.clone().map(defined_and),
        fields,
        refinement: rest,
    }
}
