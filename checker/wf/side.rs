//! The side conditions of Def 4.1: `p != q` (E0301), distinct labels in a choice
//! (E0302), every branch of a choice starting with a message from the same sender to
//! the same receiver (E0303), guarded recursion (E0304), guards and refinements reading
//! only what the sender knows, `fv(P) ⊆ p.X ∪ p.W` extended with the values the sender
//! has sent or received (E0305), distinct participants in a joint motion (E0306), and
//! recursion, its variables and `end` closing a sequence (E0314, the shape
//! `G ::= g.G | t | mu t.G`).

use crate::diag::{Code, Diagnostic};
use crate::hir::*;
use std::collections::HashSet;

pub fn check(prog: &Program, g: &Global) -> Vec<Diagnostic> {
    let mut c = Side { prog, diags: Vec::new() };
    c.walk(g, true, false);
    c.diags
}

struct Side<'a> {
    prog: &'a Program,
    diags: Vec<Diagnostic>,
}

/// The first message of a branch, if it starts with one.
pub fn first_message(g: &Global) -> Option<&Msg> {
    match g {
        Global::Msg(m) => Some(m),
        Global::Seq(items, _) => items.first().and_then(first_message),
        _ => None,
    }
}

impl Side<'_> {
    fn walk(&mut self, g: &Global, tail: bool, in_par: bool) {
        crate::stack::deep(|| self.walk_inner(g, tail, in_par))
    }

    fn walk_inner(&mut self, g: &Global, tail: bool, in_par: bool) {
        match g {
            Global::Msg(m) => self.msg(m),
            Global::Motion(m) => self.motion(m),
            Global::Seq(items, _) => {
                for (i, it) in items.iter().enumerate() {
                    self.walk(it, tail && i + 1 == items.len(), in_par);
                }
            }
            Global::Choice(branches, loc) => {
                self.choice(branches, *loc);
                for b in branches {
                    self.walk(b, tail, in_par);
                }
            }
            Global::Par(sides, _) => {
                for s in sides {
                    self.walk(s, false, true);
                }
            }
            Global::Rec { var, body, loc, params, decreases } => {
                self.closes(tail, *loc, &format!("`mu {var}`"));
                // Every participant of the loop reads its parameters' refinements (each
                // tests them in its guards): a value is known when each of them sent or
                // received it.
                let pt = body.participant_list();
                for p in params {
                    if let Some(r) = &p.refinement {
                        self.knows_all(r, &pt, "the refinement of a recursion parameter");
                    }
                }
                if let (Some(m), false) = (decreases, has_exit(body, var)) {
                    self.diags.push(
                        Diagnostic::error(
                            Code::MeasureNoExit,
                            m.loc.0,
                            format!("`mu {var}` claims to terminate, but no path of its body leaves the loop"),
                        )
                        .with_label(loc.0, "every path of this loop jumps back to it")
                        .with_note("a loop with `decreases` must have a path to `end` or to an enclosing loop")
                        .with_help("add the branch that leaves the loop (for example an acknowledgement followed by `end`), or drop `decreases` for a loop meant to run forever"),
                    );
                }
                if unguarded(body).contains(var.as_str()) {
                    self.diags.push(
                        Diagnostic::error(
                            Code::UnguardedRecursion,
                            loc.0,
                            format!("recursion `mu {var}` is not guarded"),
                        )
                        .with_note(
                            "Def 4.1: a recursion variable must be preceded by a message or a motion in its body",
                        )
                        .with_help(format!("put a message or a motion between `mu {var}.` and `{var}`")),
                    );
                }
                self.walk(body, true, false);
            }
            // Inside a side of `*` a variable is judged by well-scopedness (E0308), which
            // is what the paper's once-unfolded labelling reports for it.
            Global::Var(v) if !in_par => self.closes(tail, v.loc, &format!("`{}`", v.var)),
            Global::Var(_) => {}
            Global::End(loc) => self.closes(tail, *loc, "`end`"),
        }
    }

    fn closes(&mut self, tail: bool, loc: Loc, what: &str) {
        if !tail {
            self.diags.push(
                Diagnostic::error(Code::NotTailPosition, loc.0, format!("{what} must end its sequence"))
                    .with_note("Def 4.1: G ::= g.G | t | mu t.G — recursion, recursion variables and `end` close a type, and the sides of `*` are prefixes")
                    .with_help("move what follows into the recursion body, or the recursion out of the `*`"),
            );
        }
    }

    fn msg(&mut self, m: &Msg) {
        if m.from == m.to {
            self.diags.push(
                Diagnostic::error(
                    Code::SelfMessage,
                    m.loc.0,
                    format!("`{}` sends a message to itself", self.prog.role_name(m.from)),
                )
                .with_note("Def 4.1 requires p != q in p -> q")
                .with_help("send to another participant, or drop the message"),
            );
        }
        if let Some(g) = &m.guard {
            self.knows(g, Some(m.from), "the guard");
        }
        for f in &m.payload {
            if let Some(r) = &f.refinement {
                self.knows(r, Some(m.from), "the refinement");
            }
        }
    }

    fn motion(&mut self, m: &Motion) {
        let mut seen: Vec<(RoleId, Loc)> = Vec::new();
        for (r, app) in &m.parts {
            if let Some((_, first)) = seen.iter().find(|(q, _)| q == r) {
                self.diags.push(
                    Diagnostic::error(
                        Code::DuplicateMotionParticipant,
                        app.loc.0,
                        format!("`{}` is given two primitives in one joint motion", self.prog.role_name(*r)),
                    )
                    .with_label(first.0, "first primitive here")
                    .with_help("a robot runs one primitive at a time; keep one"),
                );
            } else {
                seen.push((*r, app.loc));
            }
            for a in &app.args {
                self.knows(a, Some(*r), "a motion argument");
            }
        }
    }

    fn choice(&mut self, branches: &[Global], loc: Loc) {
        let firsts: Vec<Option<&Msg>> = branches.iter().map(first_message).collect();
        let Some(head) = firsts.iter().flatten().next().copied() else {
            self.diags.push(
                Diagnostic::error(Code::ChoiceMismatch, loc.0, "no branch of this choice starts with a message")
                    .with_note(
                        "Def 4.1: every branch of `+` starts with a message p -> q that tells q which branch was taken",
                    )
                    .with_help("start each branch with a message from the deciding participant"),
            );
            return;
        };
        let mut labels: Vec<(&str, Loc)> = Vec::new();
        for (b, first) in branches.iter().zip(&firsts) {
            let Some(m) = first else {
                self.diags.push(
                    Diagnostic::error(
                        Code::ChoiceMismatch,
                        b.loc().0,
                        "this branch of a choice does not start with a message",
                    )
                    .with_label(head.loc.0, "the first branch starts here")
                    .with_note(
                        "Def 4.1: every branch of `+` starts with a message from the same sender to the same receiver",
                    )
                    .with_help(format!(
                        "start it with `{} -> {} : label`",
                        self.prog.role_name(head.from),
                        self.prog.role_name(head.to)
                    )),
                );
                continue;
            };
            let shape_ok = m.from == head.from && m.to == head.to;
            if !shape_ok {
                self.diags.push(
                    Diagnostic::error(
                        Code::ChoiceMismatch,
                        m.loc.0,
                        format!(
                            "this branch starts with `{} -> {}`, the first with `{} -> {}`",
                            self.prog.role_name(m.from),
                            self.prog.role_name(m.to),
                            self.prog.role_name(head.from),
                            self.prog.role_name(head.to)
                        ),
                    )
                    .with_label(head.loc.0, "the first branch starts here")
                    .with_note("Def 4.1: the branches of a choice start with messages from the same sender to the same receiver")
                    .with_help(format!(
                        "send the deciding message to `{}` in every branch (with distinct labels) and inform the others in a second message",
                        self.prog.role_name(head.to)
                    )),
                );
            }
            if !shape_ok {
                continue; // labels only distinguish branches of the same shape
            }
            if let Some((l, first)) = labels.iter().find(|(l, _)| crate::hir::labels_overlap(l, &m.label)) {
                let message = if *l == m.label {
                    format!("label `{}` is used by two branches", m.label)
                } else {
                    format!(
                        "labels `{l}` and `{}` are one MAVLink message: the one without a fixed command may carry the other's",
                        m.label
                    )
                };
                self.diags.push(
                    Diagnostic::error(Code::DuplicateLabel, m.label_loc.0, message)
                        .with_label(first.0, "first used here")
                        .with_note(
                            "Def 4.1: labels of a choice are distinct so the receiver can tell the branches apart",
                        )
                        .with_help("rename one of the labels"),
                );
            } else {
                labels.push((&m.label, m.label_loc));
            }
        }
    }

    /// E0305: `e` may read only what `viewer` knows.
    /// [`Self::knows`] for each of `viewers` (no participant: what every participant
    /// knows, constants and parameters).
    fn knows_all(&mut self, e: &Expr, viewers: &[RoleId], what: &str) {
        if viewers.is_empty() {
            return self.knows(e, None, what);
        }
        let before = self.diags.len();
        for w in viewers {
            self.knows(e, Some(*w), what);
            if self.diags.len() > before {
                return; // one report: the first participant that does not know
            }
        }
    }

    fn knows(&mut self, e: &Expr, viewer: Option<RoleId>, what: &str) {
        let prog = self.prog;
        let mut bad: Vec<(String, Loc, String)> = Vec::new();
        e.visit_vars(&mut |v, loc| match v {
            Var::Role(r, slot) if Some(*r) != viewer => {
                let name = format!("{}.{}", prog.role_name(*r), prog.slot_name(prog.role(*r).kind, *slot));
                bad.push((name, loc, format!("it belongs to `{}`", prog.role_name(*r))));
            }
            Var::Value(id, name) => {
                if let ValueOrigin::Message { from, to } = &prog.value(*id).origin {
                    // With no viewer (a recursion parameter's refinement) every participant
                    // must know the value: so only when the sender and the receiver are all
                    // of them (a protocol between two, as MAVLink's GCS and UAV).
                    let known = match viewer {
                        Some(w) => w == *from || w == *to,
                        None => prog.role_ids().all(|r| r == *from || r == *to),
                    };
                    if !known {
                        bad.push((
                            name.clone(),
                            loc,
                            format!("it was sent by `{}` to `{}`", prog.role_name(*from), prog.role_name(*to)),
                        ));
                    }
                }
            }
            _ => {}
        });
        for (name, loc, why) in bad {
            let who = viewer.map(|w| format!("`{}`", prog.role_name(w))).unwrap_or_else(|| "every participant".into());
            self.diags.push(
                Diagnostic::error(
                    Code::GuardNotLocal,
                    loc.0,
                    format!("{what} reads `{name}`, which {who} does not know"),
                )
                .with_note(format!("{why}; Def 4.1: fv(P) ⊆ p.X ∪ p.W for the sender p"))
                .with_help("send the value to this participant first, or test it where it is known"),
            );
        }
    }
}

/// Whether some path of `g`, the body of `mu var`, leaves the loop: reaches `end` or a jump
/// to an enclosing loop (a variable not bound inside `g`, other than `var`). Syntactic:
/// each node of a global type is on some path (E0314 rejects what follows a jump).
fn has_exit(g: &Global, var: &str) -> bool {
    fn go<'g>(g: &'g Global, var: &str, inner: &mut Vec<&'g str>) -> bool {
        match g {
            Global::End(_) => true,
            Global::Var(v) => v.var != var && !inner.contains(&v.var.as_str()),
            Global::Msg(_) | Global::Motion(_) => false,
            Global::Seq(gs, _) | Global::Choice(gs, _) | Global::Par(gs, _) => {
                gs.iter().any(|g| crate::stack::deep(|| go(g, var, inner)))
            }
            Global::Rec { var: v, body, .. } => {
                inner.push(v);
                let out = crate::stack::deep(|| go(body, var, inner));
                inner.pop();
                out
            }
        }
    }
    go(g, var, &mut Vec::new())
}

/// Recursion variables reachable from the start of `g` without a message or motion.
fn unguarded(g: &Global) -> HashSet<&str> {
    match g {
        Global::Msg(_) | Global::Motion(_) | Global::End(_) => HashSet::new(),
        Global::Var(v) => HashSet::from([v.var.as_str()]),
        Global::Seq(items, _) => items.first().map(unguarded).unwrap_or_default(),
        Global::Choice(bs, _) | Global::Par(bs, _) => bs.iter().flat_map(unguarded).collect(),
        Global::Rec { var, body, .. } => {
            let mut s = unguarded(body);
            s.remove(var.as_str());
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::diag::Code;
    use crate::lower::tests::{lower_src, HEADER};

    fn codes(chor: &str) -> Vec<Code> {
        let (p, d) = lower_src(&format!("{HEADER} choreography G = {chor};"));
        assert!(d.is_empty(), "{d:?}");
        let c = p.choreography.as_ref().expect("choreography");
        super::check(&p, &c.body).into_iter().map(|d| d.code).collect()
    }

    #[test]
    fn accepts_a_plain_loop() {
        assert_eq!(codes("mu t. C -> A : go. dt<C: idle, A: work>. A -> C : ok. t"), vec![]);
    }

    #[test]
    fn each_side_condition_has_its_code() {
        assert_eq!(codes("C -> C : go. end"), vec![Code::SelfMessage]);
        assert_eq!(codes("C -> A : go. end + C -> A : go. end"), vec![Code::DuplicateLabel]);
        assert_eq!(codes("C -> A : go. end + A -> C : no. end"), vec![Code::ChoiceMismatch]);
        assert_eq!(codes("C -> A : go. end + dt<C: idle, A: work>. end"), vec![Code::ChoiceMismatch]);
        assert_eq!(codes("mu t. t"), vec![Code::UnguardedRecursion]);
        assert_eq!(codes("mu t. (t + C -> A: a. t)"), vec![Code::UnguardedRecursion, Code::ChoiceMismatch]);
        assert_eq!(codes("dt<C: idle, C: idle>. end"), vec![Code::DuplicateMotionParticipant]);
        assert_eq!(codes("end. C -> A : go. end"), vec![Code::NotTailPosition]);
        assert_eq!(codes("(C -> A : go. end) * dt<A: work>"), vec![Code::NotTailPosition]);
    }

    #[test]
    fn guards_read_only_what_the_sender_knows() {
        assert_eq!(codes("C -> A : [A.h > 0] go. end"), vec![Code::GuardNotLocal]);
        assert_eq!(codes("C -> A : [x > 0] go(n: real { n > A.h }). end"), vec![Code::GuardNotLocal]);
        // A received `n` from C, so A may test it; C may too.
        assert_eq!(codes("C -> A : go(n: real). A -> C : [n > h] back. C -> A : [n > x] again. end"), vec![]);
        // But a third party may not: here the guard of A's message reads C's variable.
        assert_eq!(codes("C -> A : go(n: real). A -> C : [C.x > n] back. end"), vec![Code::GuardNotLocal]);
    }
}
