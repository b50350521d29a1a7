//! The timeout crossing (E0326): at a choice `( p -> R: l_i. G_i + ... + after T ms by R. G_t )`
//! a message of a branch may be on the wire when `R` gives up. `p` then goes on in `G_i`,
//! `R` in `G_t`, and the message reaches `R` late. The untimed checks run the choreography
//! with instant messages (README's model of time), where this run does not exist; this rule
//! makes sure it meets no message a role does not expect (docs/observed-and-timeouts.md,
//! "The timeout crossing").
//!
//! The semantics it is sound for: asynchronous links, one FIFO queue per ordered pair of
//! roles (MAVLink over one link), and a waiting role that, after its timeout, ignores a
//! message of the choice it abandoned that fits no reception of its state (the monitor's
//! "late" messages: real peers drop them). What must hold, for every message branch `i`:
//!
//! 1. **The sender meets `R`'s next message** (the sender's side). After sending `l_i`, `p`
//!    goes on as its projection of `G_i`; `R` sends the first message of `G_t` (E0324: `G_t`
//!    begins with `R -> p`, a choice in which `p` waits for `R`, or `end`). `p` expects it
//!    when `G_i` is `G_t` itself (the same steps, the same jump arguments: then `p`'s
//!    continuation is `p`'s part of `G_t`), or when `G_i` jumps straight back to the choice
//!    with its loop's parameters unchanged, entering no loop with parameters on the way
//!    (`p` is at the choice again, whose timeout
//!    alternative in `p`'s local type, `after T ms by R. T_p`, is `p`'s part of `G_t`; until
//!    it hears from `R`, `p` sends only first messages of the choice).
//! 2. **The late messages are absorbed** (the waiting role's side). The late messages are
//!    `l_i` (first case), or any first message of the choice (second case); FIFO puts all of
//!    them before anything `p` sends after hearing from `R`, so they reach `R` at its first
//!    receptions from `p` in `G_t` (`R`'s own sends, and its own further timeouts, pass
//!    before). At each such reception a late label is either not expected (`R` ignores it:
//!    a late message) or expected by a branch that takes any value (no guard, no refinement
//!    beyond the field's type) and jumps straight back to the same reception, parameters
//!    unchanged (an absorbing loop: `R` takes the late message as one more of a stream it
//!    accepts anyway). Otherwise `R` would read the late message as the answer to its next
//!    request (mavlink/mavlink#950's race), with values its refinements need not admit.
//! 3. **A third role.** When `G_i` is `G_t` or jumps straight back to the choice, `p` and
//!    `R` both go on as `G_t` after the crossing (`p` from `R`'s first message of `G_t` on,
//!    and before it `p` sends `R` only first messages of the choice), so a third role meets
//!    exactly the messages of a run in which the timeout branch was taken: it may take part
//!    in `G_t`. When `R` ended, `p` goes on alone in `G_i`; a third role there would meet
//!    `p`'s branch while `R` took the timeout's: the rule does not decide that case and
//!    rejects it (never a pass).
//!
//! The rule is structural (no solver): it compares global types up to locations (`Loc`s
//! compare equal) with values by binding site, which is exact for what it accepts.

use crate::diag::{Code, Diagnostic};
use crate::hir::*;
use std::collections::HashSet;

/// The timeout crossing (E0326) at every choice of `g` with a timeout branch.
pub fn check(prog: &Program, g: &Global) -> Vec<Diagnostic> {
    let mut c = Crossing { prog, diags: Vec::new(), loops: Vec::new(), tails: Vec::new() };
    c.walk(g);
    c.diags
}

struct Crossing<'a> {
    prog: &'a Program,
    diags: Vec<Diagnostic>,
    /// The loops around the node being walked, innermost last.
    loops: Vec<&'a Global>,
    /// What follows the node being walked in each enclosing sequence, innermost last: a
    /// branch that ends without `end` or a jump goes on after its choice.
    tails: Vec<&'a [Global]>,
}

/// `g`'s steps as one sequence (nested sequences flattened).
fn flatten<'g>(g: &'g Global, out: &mut Vec<&'g Global>) {
    match g {
        Global::Seq(items, _) => items.iter().for_each(|i| flatten(i, out)),
        other => out.push(other),
    }
}

fn steps_of(g: &Global) -> Vec<&Global> {
    let mut out = Vec::new();
    flatten(g, &mut out);
    out
}

/// The loop `var` among `loops` (innermost first) and the loops met inside the walked part.
fn find_loop<'g>(loops: &[&'g Global], var: &str) -> Option<&'g Global> {
    loops.iter().rev().copied().find(|l| matches!(l, Global::Rec { var: v, .. } if v == var))
}

/// The first step of a loop's body (through sequences and nested `mu`s without
/// parameters). Entering a nested loop with parameters sets them to their initial values:
/// that is a step of its own, so a jump through it does not come straight back to the
/// choice (the sender would be there with the inner loop's parameters restarted, the
/// waiting role with its own).
fn first_step(g: &Global) -> Option<&Global> {
    match g {
        Global::Seq(items, _) => items.first().and_then(first_step),
        Global::Rec { body, params, .. } if params.is_empty() => first_step(body),
        other => Some(other),
    }
}

/// Whether `steps` is a jump straight back to `node` (the first step of the jump's loop's
/// body), its loop's parameters unchanged (each argument is its parameter).
fn loops_back(steps: &[&Global], node: &Global, loops: &[&Global]) -> bool {
    let [Global::Var(v)] = steps else { return false };
    let Some(Global::Rec { params, body, .. }) = find_loop(loops, &v.var) else { return false };
    let same_node = first_step(body).is_some_and(|f| std::ptr::eq(f, node));
    let unchanged = params.len() == v.args.len()
        && params
            .iter()
            .zip(&v.args)
            .all(|(p, a)| matches!(&a.kind, ExprKind::Var(Var::Value(id, _)) if *id == p.value));
    same_node && unchanged
}

/// Whether `m` takes any value: no guard, and no refinement beyond its fields' types.
fn takes_anything(m: &Msg) -> bool {
    m.guard.is_none()
        && m.payload.iter().all(|f| match &f.mav {
            Some(mav) => !mav.user,
            None => f.refinement.as_ref().is_none_or(Expr::is_true),
        })
}

/// Where `R` would read a late message as a step (the reception expecting its label), or
/// a step the rule does not follow (a `*`).
struct Taken {
    at: Loc,
    label: String,
    why: &'static str,
}

impl<'a> Crossing<'a> {
    fn walk(&mut self, g: &'a Global) {
        crate::stack::deep(|| self.walk_inner(g))
    }

    fn walk_inner(&mut self, g: &'a Global) {
        match g {
            Global::Seq(items, _) => {
                for (k, it) in items.iter().enumerate() {
                    self.tails.push(&items[k + 1..]);
                    self.walk(it);
                    self.tails.pop();
                }
            }
            Global::Choice(branches, _) => {
                if branches.iter().any(|b| b.timeout_head().is_some()) {
                    self.choice(g, branches);
                }
                for b in branches {
                    self.walk(b);
                }
            }
            Global::Par(sides, _) => {
                // A side of `*` does not go on after the `*`.
                let saved = std::mem::take(&mut self.tails);
                for s in sides {
                    self.walk(s);
                }
                self.tails = saved;
            }
            Global::Rec { body, .. } => {
                self.loops.push(g);
                let saved = std::mem::take(&mut self.tails);
                self.walk(body);
                self.tails = saved;
                self.loops.pop();
            }
            Global::Msg(_) | Global::Motion(_) | Global::Var(_) | Global::End(_) | Global::After(_) => {}
        }
    }

    /// The steps after the choice being walked, in order.
    fn after_choice(&self) -> Vec<&'a Global> {
        let mut out = Vec::new();
        for t in self.tails.iter().rev() {
            for g in t.iter() {
                flatten(g, &mut out);
            }
        }
        out
    }

    fn choice(&mut self, node: &'a Global, branches: &'a [Global]) {
        let Some(timeout) = branches.iter().find(|b| b.timeout_head().is_some()) else { return };
        let Some(after) = timeout.timeout_head() else { return };
        let firsts: Vec<&'a Msg> = branches.iter().filter_map(crate::wf::side::first_message).collect();
        let Some(head) = firsts.first() else { return };
        let (p, r) = (head.from, head.to);
        let (pn, rn) = (self.prog.role_name(p), self.prog.role_name(r));
        let t_steps: Vec<&'a Global> = steps_of(timeout)[1..].to_vec();
        let tail = self.after_choice();
        for b in branches.iter().filter(|b| b.timeout_head().is_none()) {
            let Some(m) = crate::wf::side::first_message(b) else { continue };
            let cont: Vec<&'a Global> = steps_of(b)[1..].to_vec();
            // 1. The sender meets R's next message.
            let mut path: Vec<&'a Global> = t_steps.clone();
            path.extend(&tail);
            let late: Vec<&str> = if cont == t_steps {
                vec![m.label.as_str()]
            } else if loops_back(&cont, node, &self.loops) {
                firsts.iter().map(|f| f.label.as_str()).collect()
            } else if matches!(path.as_slice(), [Global::End(_)]) {
                // R's session is over: nothing reaches R as a step any more, and p goes on
                // alone; it must never wait for R without a timeout of its own.
                // 3. Here only p and R may take part until the branch jumps or ends.
                let mut roles = Vec::new();
                for g in cont.iter().chain(&t_steps) {
                    g.participants(&mut roles);
                }
                if let Some(&q) = roles.iter().find(|&&q| q != p && q != r) {
                    let qn = self.prog.role_name(q);
                    self.diags.push(
                        Diagnostic::error(
                            Code::TimeoutCrossing,
                            m.loc.0,
                            format!(
                                "`{pn}`'s `{}` may cross `{rn}`'s timeout, and `{qn}` takes part in what follows",
                                m.label
                            ),
                        )
                        .with_label(after.loc.0, format!("`{rn}` may give up here while `{}` is on the wire", m.label))
                        .with_note(format!(
                            "after a crossing `{pn}` goes on in this branch and `{rn}` in the timeout branch; which \
                             messages `{qn}` then gets depends on the crossing, which mochi does not decide"
                        ))
                        .with_help(format!(
                            "let `{pn}` and `{rn}` agree first (end both branches, or jump back to the choice) and \
                             involve `{qn}` after"
                        )),
                    );
                    continue;
                }
                let mut seen = HashSet::new();
                let mut loops = self.loops.clone();
                if let Some(at) = self.waits_for_ever(&cont, p, r, &mut loops, &mut seen) {
                    self.diags.push(
                        Diagnostic::error(
                            Code::TimeoutCrossing,
                            m.loc.0,
                            format!(
                                "`{pn}`'s `{}` may cross `{rn}`'s timeout, after which `{rn}` has ended and \
                                 `{pn}` waits for it for ever",
                                m.label
                            ),
                        )
                        .with_label(after.loc.0, format!("`{rn}` may give up here while `{}` is on the wire", m.label))
                        .with_label(at.0, format!("`{pn}` waits for `{rn}` here, with no timeout of its own"))
                        .with_note(format!(
                            "on a real link `{pn}` may send `{}` just as `{rn}` gives up and ends its session; \
                             `{pn}` then goes on in this branch with no one to answer it",
                            m.label
                        ))
                        .with_help(format!(
                            "give every wait of `{pn}` for `{rn}` in this branch a timeout of its own \
                             (`after T ms by {pn}`), or end the branch as the timeout branch does"
                        )),
                    );
                }
                continue;
            } else {
                let at = cont.first().map(|g| g.loc()).unwrap_or(m.loc);
                self.diags.push(
                    Diagnostic::error(
                        Code::TimeoutCrossing,
                        m.loc.0,
                        format!(
                            "`{pn}`'s `{}` may cross `{rn}`'s timeout: `{pn}` then goes on here, `{rn}` in the timeout branch",
                            m.label
                        ),
                    )
                    .with_label(after.loc.0, format!("`{rn}` may give up here while `{}` is on the wire", m.label))
                    .with_label(at.0, format!("`{pn}`'s next step after `{}`, which the timeout branch does not have", m.label))
                    .with_note(format!(
                        "on a real link a message takes time: `{pn}` may send `{}` just as `{rn}` gives up, and \
                         then `{pn}` meets `{rn}`'s first message of the timeout branch where its own branch \
                         expects something else",
                        m.label
                    ))
                    .with_help(format!(
                        "make the branch go on exactly as the timeout branch does, or jump straight back to \
                         the choice (so `{pn}` still accepts `{rn}`'s message after the timeout)"
                    )),
                );
                continue;
            };
            // 2. The late messages are absorbed where R next receives from p.
            let mut seen = HashSet::new();
            let mut loops = self.loops.clone();
            if let Some(t) = self.late_taken(&path, p, r, &late, &mut loops, &mut seen) {
                self.diags.push(
                    Diagnostic::error(
                        Code::TimeoutCrossing,
                        m.loc.0,
                        format!(
                            "`{pn}`'s `{}` may cross `{rn}`'s timeout and reach `{rn}` late, where it is read as `{}`",
                            m.label, t.label
                        ),
                    )
                    .with_label(after.loc.0, format!("`{rn}` may give up here while `{}` is on the wire", m.label))
                    .with_label(t.at.0, format!("`{rn}` would take the late message as this step ({})", t.why))
                    .with_note(format!(
                        "a message sent before `{pn}` learns of the timeout reaches `{rn}` before anything \
                         `{pn}` sends after; here `{rn}` cannot tell it from the answer it waits for \
                         (mavlink/mavlink#950's race)"
                    ))
                    .with_help(format!(
                        "accept the late message where `{rn}` next waits: a branch with no guard and no \
                         refinement that jumps straight back to that choice (`mu w. ( {pn} -> {rn}: {}. w + \
                         after T ms by {rn}. ... )`), or use another message there",
                        t.label
                    )),
                );
            }
        }
    }

    /// After `R` ended its session, where `p`, following `steps`, may wait for `R` with
    /// no timeout of its own (a reception from `R`, or a choice `R` decides without an
    /// `after T ms by p` branch), or meets a step it cannot take without `R` (a joint motion
    /// with `R`, or a `*`, not followed). A jump is followed into its loop once.
    fn waits_for_ever(
        &self,
        steps: &[&'a Global],
        p: RoleId,
        r: RoleId,
        loops: &mut Vec<&'a Global>,
        seen: &mut HashSet<String>,
    ) -> Option<Loc> {
        crate::stack::deep(|| self.waits_for_ever_inner(steps, p, r, loops, seen))
    }

    fn waits_for_ever_inner(
        &self,
        steps: &[&'a Global],
        p: RoleId,
        r: RoleId,
        loops: &mut Vec<&'a Global>,
        seen: &mut HashSet<String>,
    ) -> Option<Loc> {
        let (first, rest) = steps.split_first()?;
        match first {
            Global::Msg(m) if m.from == r && m.to == p => Some(m.loc),
            Global::Motion(mo) if mo.parts.iter().any(|(q, _)| *q == r) => Some(mo.loc),
            Global::Par(_, loc) => Some(*loc),
            Global::Msg(_) | Global::Motion(_) | Global::After(_) => self.waits_for_ever(rest, p, r, loops, seen),
            Global::Seq(..) => {
                let mut inner = Vec::new();
                flatten(first, &mut inner);
                inner.extend_from_slice(rest);
                self.waits_for_ever(&inner, p, r, loops, seen)
            }
            Global::Choice(bs, loc) => {
                let decided_by_r =
                    bs.iter().filter_map(crate::wf::side::first_message).any(|m| m.from == r && m.to == p);
                let own_timeout = bs.iter().any(|b| b.timeout_head().is_some_and(|a| a.by == p));
                if decided_by_r && !own_timeout {
                    return Some(*loc);
                }
                // A branch of p's with no guard and no refinement is always enabled: p never
                // has to wait for R's timeout at this choice (its part of R's timeout branch
                // is reached only by a message from R, who sends nothing any more).
                let p_always_sends = bs
                    .iter()
                    .filter_map(crate::wf::side::first_message)
                    .any(|m| m.from == p && m.to == r && takes_anything(m));
                for b in bs {
                    if crate::wf::side::first_message(b).is_some_and(|m| m.from == r) {
                        continue; // never taken: R sends nothing any more
                    }
                    if p_always_sends && b.timeout_head().is_some_and(|a| a.by == r) {
                        continue;
                    }
                    // R's timeout branch is walked too: unless it ends, p waits there for R's
                    // message (E0324), which a p with every branch's guard false needs. When it
                    // ends, p's part is `end`: p learns nothing from that timeout, and its wait
                    // there is bounded by time, not by R (docs/observed-and-timeouts.md, "A wait
                    // that the ended role's timeout ends is not a wait for ever").
                    let mut path = steps_of(b);
                    path.extend_from_slice(rest);
                    if let Some(at) = self.waits_for_ever(&path, p, r, loops, seen) {
                        return Some(at);
                    }
                }
                None
            }
            Global::Rec { body, .. } => {
                loops.push(first);
                let t = self.waits_for_ever(&[&**body], p, r, loops, seen);
                loops.pop();
                t
            }
            Global::Var(v) => {
                if !seen.insert(v.var.clone()) {
                    return None;
                }
                let Some(Global::Rec { body, .. }) = find_loop(loops, &v.var) else { return None };
                self.waits_for_ever(&[&**body], p, r, loops, seen)
            }
            Global::End(_) => None,
        }
    }

    /// Follows `R`'s paths through `steps` up to its first receptions from `p`, and returns
    /// one that would take a late message (a label of `late`) as a step, unless it absorbs
    /// it. `R`'s own sends and timeouts pass; a jump is followed into its loop once.
    #[allow(clippy::too_many_arguments)]
    fn late_taken(
        &self,
        steps: &[&'a Global],
        p: RoleId,
        r: RoleId,
        late: &[&str],
        loops: &mut Vec<&'a Global>,
        seen: &mut HashSet<String>,
    ) -> Option<Taken> {
        crate::stack::deep(|| self.late_taken_inner(steps, p, r, late, loops, seen))
    }

    #[allow(clippy::too_many_arguments)]
    fn late_taken_inner(
        &self,
        steps: &[&'a Global],
        p: RoleId,
        r: RoleId,
        late: &[&str],
        loops: &mut Vec<&'a Global>,
        seen: &mut HashSet<String>,
    ) -> Option<Taken> {
        let (first, rest) = steps.split_first()?;
        let is_late = |m: &Msg| late.iter().any(|l| labels_overlap(l, &m.label));
        match first {
            Global::Msg(m) if m.from == p && m.to == r => {
                // A lone reception: absorbing only if it jumps straight back to itself.
                if !is_late(m) {
                    return None;
                }
                let absorbs = takes_anything(m) && loops_back(rest, first, loops);
                (!absorbs).then(|| Taken { at: m.loc, label: m.label.clone(), why: "it expects this label here" })
            }
            Global::Msg(_) | Global::Motion(_) | Global::After(_) => self.late_taken(rest, p, r, late, loops, seen),
            Global::Seq(..) => {
                let mut inner = Vec::new();
                flatten(first, &mut inner);
                inner.extend_from_slice(rest);
                self.late_taken(&inner, p, r, late, loops, seen)
            }
            Global::Choice(bs, _) => {
                for b in bs {
                    let bsteps = steps_of(b);
                    match crate::wf::side::first_message(b) {
                        Some(m) if m.from == p && m.to == r => {
                            if !is_late(m) {
                                continue;
                            }
                            let absorbs = takes_anything(m) && loops_back(&bsteps[1..], first, loops);
                            if !absorbs {
                                let why = if takes_anything(m) {
                                    "its branch does not jump straight back to this choice"
                                } else {
                                    "its branch has a guard or a refinement the late message need not meet"
                                };
                                return Some(Taken { at: m.loc, label: m.label.clone(), why });
                            }
                        }
                        _ => {
                            // R's own send, R's own timeout, or p's timeout (after which p
                            // speaks first: E0324): R has not received from p yet.
                            let mut path = bsteps;
                            path.extend_from_slice(rest);
                            if let Some(t) = self.late_taken(&path, p, r, late, loops, seen) {
                                return Some(t);
                            }
                        }
                    }
                }
                None
            }
            Global::Rec { body, .. } => {
                loops.push(first);
                let t = self.late_taken(&[&**body], p, r, late, loops, seen);
                loops.pop();
                t
            }
            Global::Var(v) => {
                if !seen.insert(v.var.clone()) {
                    return None; // this loop's receptions are being or were looked at
                }
                let l = find_loop(loops, &v.var)?;
                let Global::Rec { body, .. } = l else { return None };
                self.late_taken(&[&**body], p, r, late, loops, seen)
            }
            // Not followed: a `*` before `R` hears from `p` again is rejected, never passed.
            Global::Par(_, loc) => Some(Taken {
                at: *loc,
                label: "a parallel composition".into(),
                why: "the rule does not follow a `*` here",
            }),
            Global::End(_) => None,
        }
    }
}
