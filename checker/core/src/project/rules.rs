//! The rules of projection, Def 4.8: messages and choices (1)-(3), joint motions,
//! recursion (4) (a role that does not occur in the loop gets `end`), sequences, and
//! separation `*` (7). The merge of (3) is in `merge.rs`.

use super::Projector;
use crate::diag::{Code, Diagnostic};
use crate::hir::*;
use std::sync::Arc;

impl Projector<'_> {
    pub(super) fn project(&self, g: &Global, tail: LocalArc) -> Result<LocalArc, Diagnostic> {
        crate::stack::deep(|| self.project_inner(g, tail))
    }

    pub(super) fn project_inner(&self, g: &Global, tail: LocalArc) -> Result<LocalArc, Diagnostic> {
        match g {
            Global::Msg(m) => self.choice(std::slice::from_ref(g), m.loc, tail),
            Global::Choice(branches, loc) => self.choice(branches, *loc, tail),
            Global::Motion(m) => Ok(match m.parts.iter().find(|(r, _)| *r == self.role) {
                Some((_, a)) => Arc::new(Local::Motion { prims: vec![a.clone()], cont: tail, loc: a.loc }),
                None => tail,
            }),
            Global::Seq(items, _) => {
                let mut t = tail;
                for item in items.iter().rev() {
                    t = self.project(item, t)?;
                }
                Ok(t)
            }
            Global::Par(sides, loc) => {
                let mine: Vec<&Global> = match self.occurs.sides(g) {
                    Some(side_of) => {
                        side_of.get(&self.role).into_iter().flatten().filter_map(|&i| sides.get(i)).collect()
                    }
                    None => sides.iter().filter(|s| self.occurs_in(s)).collect(),
                };
                match mine.as_slice() {
                    [] => Ok(tail),
                    [side] => self.project(side, tail),
                    [..] => Err(Diagnostic::error(
                        Code::SeparationOverlap,
                        loc.0,
                        format!("`{}` occurs on more than one side of `*`", self.name()),
                    )
                    .with_note("projection (Def 4.8 (7)) needs the sides of `*` to have disjoint participants")
                    .with_help("move the participant's actions out of all sides but one")),
                }
            }
            Global::Rec { var, params, body, loc, .. } => {
                if !self.occurs_in(body) {
                    // Def 4.8 (4) is undefined here; the role has left the protocol.
                    return Ok(Arc::new(Local::End(*loc)));
                }
                let body = self.project(body, tail)?;
                if matches!(&*body, Local::Var { var: v, .. } if v == var) {
                    // `mu t. t` would be unguarded: the role never acts in the loop.
                    return Ok(Arc::new(Local::End(*loc)));
                }
                Ok(Arc::new(Local::Rec { var: var.clone(), params: params.clone(), body, loc: *loc }))
            }
            Global::Var(v) => Ok(Arc::new(Local::Var { var: v.var.clone(), args: v.args.clone(), loc: v.loc })),
            Global::End(loc) => Ok(Arc::new(Local::End(*loc))),
            // Lowering admits `after` only at the head of a branch of a choice, which
            // `choice` splits off; anywhere else it is E0321, reported already.
            Global::After(a) => {
                Err(Diagnostic::error(Code::TimeoutNotInChoice, a.loc.0, "`after` does not start a branch of a choice"))
            }
        }
    }

    pub(super) fn name(&self) -> &str {
        self.prog.role_name(self.role)
    }

    pub(super) fn occurs_in(&self, g: &Global) -> bool {
        self.occurs.contains(g, self.role)
    }

    /// Projects the items of a sequence, right to left, in front of `tail`.
    pub(super) fn seq(&self, items: &[&Global], tail: LocalArc) -> Result<LocalArc, Diagnostic> {
        let mut t = tail;
        for item in items.iter().rev() {
            t = self.project(item, t)?;
        }
        Ok(t)
    }

    /// Def 4.8 (1)-(3): a choice whose branches each start with a message `p -> q`.
    pub(super) fn choice(&self, branches: &[Global], loc: Loc, tail: LocalArc) -> Result<LocalArc, Diagnostic> {
        let mut split: Vec<(&Msg, Vec<&Global>)> = Vec::new();
        // The timeout branch `after T ms by R. G`: its head and what follows it.
        let mut timeout: Option<(&After, Vec<&Global>)> = None;
        for b in branches {
            let mut items = Vec::new();
            flatten_seq(b, &mut items);
            if let Some((Global::After(a), rest)) = items.split_first() {
                if timeout.is_some() {
                    return Err(Diagnostic::error(
                        Code::TwoTimeouts,
                        a.loc.0,
                        "a second timeout branch in this choice",
                    ));
                }
                timeout = Some((a, rest.to_vec()));
                continue;
            }
            split_branch(b, &[], &mut split).map_err(not_a_choice)?;
        }
        let Some(&(first, _)) = split.first() else {
            return Err(not_a_choice(loc));
        };
        if let Some((m, _)) = split.iter().find(|(m, _)| m.from != first.from || m.to != first.to) {
            return Err(not_a_choice(m.loc));
        }
        if let Some((a, _)) = &timeout {
            if a.by != first.to {
                return Err(Diagnostic::error(
                    Code::TimeoutNotWaiting,
                    a.loc.0,
                    "the timeout is taken by a participant that does not wait in this choice",
                ));
            }
        }
        // The role's part of the timeout branch: `G` followed by what follows the choice.
        let timeout = match timeout {
            Some((a, rest)) => Some(Timeout { after: a.clone(), cont: self.seq(&rest, tail.clone())? }),
            None => None,
        };
        if self.role == first.from {
            let mut out = Vec::new();
            for (m, rest) in &split {
                out.push(SendBranch {
                    observed: m.observed.clone(),
                    guard: m.guard.clone(),
                    to: m.to,
                    label: m.label.clone(),
                    payload: m.payload.clone(),
                    cont: self.seq(rest, tail.clone())?,
                    loc: m.loc,
                });
            }
            return Ok(Arc::new(Local::Send { branches: out, timeout, loc: first.loc }));
        }
        if self.role == first.to {
            let mut out = Vec::new();
            for (m, rest) in &split {
                out.push(RecvBranch {
                    from: m.from,
                    label: m.label.clone(),
                    payload: self.receiver_payload(&m.payload),
                    cont: self.seq(rest, tail.clone())?,
                    loc: m.loc,
                });
            }
            return Ok(Arc::new(Local::Recv { branches: out, default: None, timeout, loc: first.loc }));
        }
        // Def 4.8 (3) with the merge of Def 4.7; the timeout branch's part is merged like
        // any other branch's (the role takes no part in the choice, so it learns which
        // branch was taken only from a later message).
        let mut acc: Option<(LocalArc, Vec<&str>)> = timeout.map(|t| (t.cont, vec!["after"]));
        for (m, rest) in &split {
            let t = self.seq(rest, tail.clone())?;
            acc = Some(match acc {
                None => (t, vec![m.label.as_str()]),
                Some((prev, mut labels)) => match self.merge(&prev, &t) {
                    Ok(merged) => {
                        labels.push(&m.label);
                        (merged, labels)
                    }
                    Err(clash) => {
                        let left = format!("`{}`", labels.join("`/`"));
                        let right = format!("`{}`", m.label);
                        return Err(self.unmergeable(first, (&left, &prev), (&right, &t), clash));
                    }
                },
            });
        }
        Ok(acc.map(|(t, _)| t).unwrap_or(tail))
    }
}

fn not_a_choice(loc: Loc) -> Diagnostic {
    Diagnostic::error(Code::ChoiceMismatch, loc.0, "this branch of a choice does not start with the choosing message")
        .with_note("Def 4.1: every branch of `+` starts with a message from the same sender to the same receiver")
        .with_help("start every branch with `p -> q : label` for the same `p` and `q`")
}

/// Splits a branch of a choice, followed by `rest`, into its choosing message and
/// what follows it. A nested choice at the front is distributed over the rest,
/// `(g1 + g2).g = g1.g + g2.g`, as Sec 4.1 writes choices. Fails with the location of
/// a branch that does not start with a message.
fn split_branch<'g>(b: &'g Global, rest: &[&'g Global], out: &mut Vec<(&'g Msg, Vec<&'g Global>)>) -> Result<(), Loc> {
    crate::stack::deep(|| {
        let mut items = Vec::new();
        flatten_seq(b, &mut items);
        items.extend_from_slice(rest);
        match items.split_first() {
            Some((Global::Msg(m), tail)) => {
                out.push((m, tail.to_vec()));
                Ok(())
            }
            Some((Global::Choice(inner, _), tail)) => inner.iter().try_for_each(|i| split_branch(i, tail, out)),
            _ => Err(b.loc()),
        }
    })
}

/// The items of a (possibly nested) sequence, in order.
fn flatten_seq<'g>(g: &'g Global, out: &mut Vec<&'g Global>) {
    match g {
        Global::Seq(items, _) => items.iter().for_each(|i| flatten_seq(i, out)),
        other => out.push(other),
    }
}
