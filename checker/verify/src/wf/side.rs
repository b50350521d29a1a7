//! The side conditions of Def 4.1: `p != q` (E0301), distinct labels in a choice
//! (E0302), every branch of a choice starting with a message from the same sender to
//! the same receiver (E0303), guarded recursion (E0304), guards and refinements reading
//! only what the sender knows, `fv(P) ⊆ p.X ∪ p.W` extended with the values the sender
//! has sent or received (E0305), distinct participants in a joint motion (E0306), and
//! recursion, its variables and `end` closing a sequence (E0314, the shape
//! `G ::= g.G | t | mu t.G`).

use crate::diag::{Code, Diagnostic};
use crate::hir::*;
use std::collections::{HashMap, HashSet};

pub fn check(prog: &Program, g: &Global) -> Vec<Diagnostic> {
    let mut c = Side { prog, diags: Vec::new(), loops: Vec::new(), bodies: Vec::new(), holders: HashMap::new() };
    c.walk(g, true, false);
    c.diags
}

struct Side<'a> {
    prog: &'a Program,
    diags: Vec<Diagnostic>,
    /// The loops around the node being walked, innermost last: each one's variable, its
    /// parameters and its participants.
    loops: Vec<(&'a str, &'a [RecParam], Vec<RoleId>)>,
    /// Who holds each recursion parameter in scope: the participants of its loop's body.
    /// Each of them carries the parameters in its projection (`mu t(n = e)` in every local
    /// type of the loop), so each must know the initial value and every jump argument:
    /// then each knows the parameter, and a guard of theirs may read it.
    holders: HashMap<ValueId, Vec<RoleId>>,
    /// The bodies of the loops around the node being walked, innermost last: where a
    /// timeout branch's jump goes (E0324).
    bodies: Vec<(&'a str, &'a Global)>,
}

/// The first message of a branch, if it starts with one.
pub fn first_message(g: &Global) -> Option<&Msg> {
    match g {
        Global::Msg(m) => Some(m),
        Global::Seq(items, _) => items.first().and_then(first_message),
        _ => None,
    }
}

impl<'a> Side<'a> {
    fn walk(&mut self, g: &'a Global, tail: bool, in_par: bool) {
        crate::stack::deep(|| self.walk_inner(g, tail, in_par))
    }

    fn walk_inner(&mut self, g: &'a Global, tail: bool, in_par: bool) {
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
                // Every participant of the loop holds its parameters (each local type of
                // the loop binds them) and assumes their refinements: each must know every
                // value a parameter is given (its initial value here, the arguments of every
                // jump below) and every value its refinement reads.
                let pt = body.participant_list();
                for p in params {
                    let what = format!("the initial value of recursion parameter `{}`", p.name);
                    self.holds(&p.init, &pt, &what, &format!("`mu {var}` is entered with `{} = ", p.name));
                }
                for p in params {
                    self.holders.insert(p.value, pt.clone());
                }
                for p in params {
                    if let Some(r) = &p.refinement {
                        self.knows_all(r, &pt, "the refinement of a recursion parameter");
                    }
                }
                self.loops.push((var.as_str(), params.as_slice(), pt));
                self.bodies.push((var.as_str(), body));
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
                self.loops.pop();
                self.bodies.pop();
            }
            Global::Var(v) => {
                self.jump(v);
                // Inside a side of `*` a variable is judged by well-scopedness (E0308),
                // which is what the paper's once-unfolded labelling reports for it.
                if !in_par {
                    self.closes(tail, v.loc, &format!("`{}`", v.var))
                }
            }
            Global::End(loc) => self.closes(tail, *loc, "`end`"),
            // Checked with its choice (`timeouts`); lowering placed it (E0321).
            Global::After(_) => {}
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

    /// The timeout branches of a choice whose first message is `head` (`p -> R`): at most
    /// one (E0322), taken by `R`, the role that waits (E0323), and `p` learns of it
    /// (E0324): the branch goes on with a message from `R` to `p`, or ends. A jump goes on
    /// as its loop's body begins.
    fn timeouts(&mut self, timeouts: &[&'a Global], head: &Msg) {
        let (p, r) = (self.prog.role_name(head.from), self.prog.role_name(head.to));
        for (i, b) in timeouts.iter().enumerate() {
            let Some(a) = b.timeout_head() else { continue };
            if i > 0 {
                let first = timeouts[0].loc();
                self.diags.push(
                    Diagnostic::error(Code::TwoTimeouts, a.loc.0, "a second timeout branch in this choice")
                        .with_label(first.0, "the first timeout branch")
                        .with_note("when no message came in time, the waiting role must know which branch to take")
                        .with_help("keep one `after T ms by R` branch per choice"),
                );
                continue;
            }
            if a.by != head.to {
                self.diags.push(
                    Diagnostic::error(
                        Code::TimeoutNotWaiting,
                        a.loc.0,
                        format!("`{}` times out in a choice where `{r}` waits for `{p}`", self.prog.role_name(a.by)),
                    )
                    .with_label(head.loc.0, format!("`{r}` receives the choice's messages"))
                    .with_note("only the receiver of a choice can decide by silence that no message came")
                    .with_help(format!("write `after {} ms by {r}`", a.ms)),
                );
                continue;
            }
            let mut items = Vec::new();
            flatten(b, &mut items);
            let rest = &items[1..];
            if let Some(own) = self.own_clock(rest, head.from, 0) {
                self.diags.push(
                    Diagnostic::error(
                        Code::TimeoutUnheard,
                        own.0,
                        format!("`{p}` times out here before it is told that `{r}` timed out: only `end` may follow"),
                    )
                    .with_label(a.loc.0, format!("`{r}` gives up waiting here"))
                    .with_note(format!(
                        "`{p}` cannot observe `{r}`'s clock, so its own wait here has no start it shares with \
                         `{r}`: it may run out while `{r}` still waits for the choice's messages, and what `{p}` \
                         sends then reaches `{r}` where it expects something else"
                    ))
                    .with_help(format!(
                        "end `{p}`'s timeout branch here with `end`, or let `{r}` speak first (`{r} -> {p}`) \
                         before `{p}` may time out"
                    )),
                );
            } else if !self.heard(rest, head.to, head.from, 0) {
                let at = rest.first().map(|g| g.loc()).unwrap_or(a.loc);
                self.diags.push(
                    Diagnostic::error(
                        Code::TimeoutUnheard,
                        at.0,
                        format!(
                            "after `{r}` times out, `{p}` is not told: the branch must go on with `{r} -> {p}` or end"
                        ),
                    )
                    .with_label(a.loc.0, format!("`{r}` gives up waiting here"))
                    .with_note(format!(
                        "`{p}` cannot observe `{r}`'s clock: it learns of the timeout only from `{r}`'s next message"
                    ))
                    .with_help(format!(
                        "start the branch with a message `{r} -> {p}` (a re-request, an error), or end it with `end`"
                    )),
                );
            }
        }
    }

    /// Where `p`, after `r` timed out and before it hears from `r`, may take a timeout of its
    /// own that is not followed by `end`: a nested choice in which `p` waits for `r` (as
    /// [`Self::heard`] accepts) whose `after T ms by p` branch goes on. Through sequences, the
    /// nested choices' message branches are `r`'s and tell `p`; a jump is followed into its
    /// loop's body as `heard` follows it.
    fn own_clock(&self, items: &[&'a Global], p: RoleId, depth: usize) -> Option<Loc> {
        let first = items.first()?;
        match first {
            Global::Seq(..) => {
                let mut inner = Vec::new();
                flatten(first, &mut inner);
                inner.extend_from_slice(&items[1..]);
                self.own_clock(&inner, p, depth)
            }
            Global::Choice(bs, _) => bs.iter().find_map(|b| {
                let a = b.timeout_head()?;
                if a.by != p {
                    return None;
                }
                let mut inner = Vec::new();
                flatten(b, &mut inner);
                inner.extend_from_slice(&items[1..]);
                (!matches!(inner.get(1), Some(Global::End(_)))).then_some(a.loc)
            }),
            Global::Rec { body, .. } => self.own_clock(&[&**body], p, depth),
            Global::Var(v) if depth < 8 => match self.bodies.iter().rev().find(|(n, _)| *n == v.var) {
                Some((_, body)) => self.own_clock(&[*body], p, depth + 1),
                None => None,
            },
            _ => None,
        }
    }

    /// Whether every path of `items` (a sequence) starts with a message from `r` to `p`,
    /// or is `end`. A jump is followed into its loop's body once (`depth`).
    fn heard(&self, items: &[&'a Global], r: RoleId, p: RoleId, depth: usize) -> bool {
        let Some(first) = items.first() else { return false };
        match first {
            Global::Msg(m) => m.from == r && m.to == p,
            Global::End(_) => true,
            Global::Seq(..) => {
                let mut inner = Vec::new();
                flatten(first, &mut inner);
                inner.extend_from_slice(&items[1..]);
                self.heard(&inner, r, p, depth)
            }
            // A nested choice in which `p` waits for `r` (its timeout branch, if any, is
            // `p`'s: E0323 holds it to the nested choice's receiver) tells `p` either way.
            Global::Choice(bs, _) => bs.iter().all(|b| {
                if b.timeout_head().is_some() {
                    return true;
                }
                let mut inner = Vec::new();
                flatten(b, &mut inner);
                inner.extend_from_slice(&items[1..]);
                self.heard(&inner, r, p, depth)
            }),
            Global::Rec { body, .. } => self.heard(&[&**body], r, p, depth),
            Global::Var(v) if depth < 8 => match self.bodies.iter().rev().find(|(n, _)| *n == v.var) {
                Some((_, body)) => self.heard(&[*body], r, p, depth + 1),
                None => false,
            },
            _ => false,
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

    fn choice(&mut self, branches: &'a [Global], loc: Loc) {
        // The timeout branch (LANGUAGE.md, Timeouts) starts with no message; its own rules
        // are checked once the choice's sender and receiver are known.
        let timeouts: Vec<&'a Global> = branches.iter().filter(|b| b.timeout_head().is_some()).collect();
        let branches: Vec<&'a Global> = branches.iter().filter(|b| b.timeout_head().is_none()).collect();
        let firsts: Vec<Option<&Msg>> = branches.iter().map(|b| first_message(b)).collect();
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
        self.timeouts(&timeouts, head);
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

    /// The jump `t(a)`: each argument is the next value of a parameter of `t`, which every
    /// participant of `t`'s loop holds, so each of them must know it (E0305). A jump to a
    /// variable no loop binds, or with the wrong number of arguments, is reported by lowering.
    fn jump(&mut self, v: &RecVar) {
        let Some((_, params, pt)) = self.loops.iter().rev().find(|(n, _, _)| *n == v.var) else { return };
        let (params, pt) = (*params, pt.clone());
        for (p, a) in params.iter().zip(&v.args) {
            let what = format!("the argument for recursion parameter `{}` of the jump `{}(..)`", p.name, v.var);
            self.holds(a, &pt, &what, &format!("the jump `{}` gives `{} = ", v.var, p.name));
        }
    }

    /// [`Self::knows_all`] for a value a recursion parameter is given (`e`, described by
    /// `what`), each report with a note naming the leak: `given` followed by `e`.
    fn holds(&mut self, e: &Expr, pt: &[RoleId], what: &str, given: &str) {
        let before = self.diags.len();
        self.knows_all(e, pt, what);
        let names: Vec<&str> = pt.iter().map(|r| self.prog.role_name(*r)).collect();
        let note = format!(
            "{given}{}`, and every participant of the loop (`{}`) holds the parameter: each must know the value",
            crate::hir::print::expr(self.prog, None, e),
            names.join("`, `")
        );
        for d in &mut self.diags[before..] {
            d.notes.push(note.clone());
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
        let (prog, holders) = (self.prog, &self.holders);
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
                } else if let ValueOrigin::Observed { reader, stream } = &prog.value(*id).origin {
                    // A snapshot: the value its reader saw when it decided, held by it alone
                    // (lowering binds a snapshot only for a reader that sees the stream).
                    let sees = prog.streams.get(*stream as usize).is_some_and(|s| s.seen_by(*reader));
                    if viewer != Some(*reader) || !sees {
                        bad.push((
                            name.clone(),
                            loc,
                            format!("it is `{}`'s reading of a stream", prog.role_name(*reader)),
                        ));
                    }
                } else if matches!(prog.value(*id).origin, ValueOrigin::Stream { .. }) {
                    bad.push((name.clone(), loc, "it is a stream's field as declared, read by no step".to_string()));
                } else if let Some(pt) = holders.get(id) {
                    // A recursion parameter: known to the participants of its loop (each
                    // knows every value it is given, checked at its entry and jumps).
                    let known = match viewer {
                        Some(w) => pt.contains(&w),
                        None => prog.role_ids().all(|r| pt.contains(&r)),
                    };
                    if !known {
                        let names: Vec<&str> = pt.iter().map(|r| prog.role_name(*r)).collect();
                        bad.push((
                            name.clone(),
                            loc,
                            format!("it is a parameter of a loop whose participants are `{}`", names.join("`, `")),
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

/// The items of a (possibly nested) sequence, in order.
fn flatten<'g>(g: &'g Global, out: &mut Vec<&'g Global>) {
    match g {
        Global::Seq(items, _) => items.iter().for_each(|i| flatten(i, out)),
        other => out.push(other),
    }
}

/// Whether some path of `g`, the body of `mu var`, leaves the loop: reaches `end` or a jump
/// to an enclosing loop (a variable not bound inside `g`, other than `var`). Syntactic:
/// each node of a global type is on some path (E0314 rejects what follows a jump).
fn has_exit(g: &Global, var: &str) -> bool {
    fn go<'g>(g: &'g Global, var: &str, inner: &mut Vec<&'g str>) -> bool {
        match g {
            Global::End(_) => true,
            Global::After(_) => false,
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
        Global::Msg(_) | Global::Motion(_) | Global::End(_) | Global::After(_) => HashSet::new(),
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

    /// The timeout rules (LANGUAGE.md, Timeouts): one per choice (E0322), taken by the
    /// choice's receiver (E0323), after which the sender is told first or the session ends
    /// (E0324); a jump is followed into its loop.
    #[test]
    fn timeout_branches_have_their_codes() {
        assert_eq!(codes("C -> A: go. end + after 10 ms by A. end"), vec![]);
        assert_eq!(codes("C -> A: go. end + after 10 ms by A. A -> C: again. end"), vec![]);
        assert_eq!(codes("C -> A: go. end + after 10 ms by A. end + after 20 ms by A. end"), vec![Code::TwoTimeouts]);
        assert_eq!(codes("C -> A: go. end + after 10 ms by C. end"), vec![Code::TimeoutNotWaiting]);
        assert_eq!(codes("C -> A: go. end + after 10 ms by A. C -> A: late. end"), vec![Code::TimeoutUnheard]);
        assert_eq!(codes("C -> A: go. end + after 10 ms by A. dt<C: idle, A: work>. end"), vec![Code::TimeoutUnheard]);
        assert_eq!(codes("mu t. A -> C: ask. (C -> A: go. end + after 10 ms by A. t)"), vec![]);
        assert_eq!(codes("mu t. C -> A: ask. (C -> A: go. end + after 10 ms by A. t)"), vec![Code::TimeoutUnheard]);
        // The sender waits in a nested choice, with its own timeout: told either way.
        assert_eq!(codes("C -> A: go. end + after 10 ms by A. (A -> C: again. end + after 30 ms by C. end)"), vec![]);
        // ... but its own timeout there may only end: it cannot tell when A gave up, so its
        // clock may run out while A still waits for `go`, and `late` would reach A there.
        let own = "C -> A: go. end + after 10 ms by A. (A -> C: again. end + after 30 ms by C. C -> A: late. end)";
        assert_eq!(codes(own), vec![Code::TimeoutUnheard]);
        let looped =
            "mu t. (C -> A: go. t + after 10 ms by A. (A -> C: x. C -> A: y. end + after 5 ms by C. C -> A: y. end))";
        assert_eq!(codes(looped), vec![Code::TimeoutUnheard]);
        assert_eq!(codes("(after 10 ms by A. end + after 20 ms by A. end)"), vec![Code::ChoiceMismatch]);
    }

    /// [`HEADER`] with a third participant, `B`, an arm like `A`.
    fn codes3(chor: &str) -> Vec<(Code, usize)> {
        let header = HEADER.replace(
            "participant A: Arm { at: pose(2, 1, 0); }",
            "participant A: Arm { at: pose(2, 1, 0); } participant B: Arm { at: pose(4, 1, 0); }",
        );
        let src = format!("{header} choreography G = {chor};");
        let (p, d) = lower_src(&src);
        assert!(d.is_empty(), "{d:?}");
        let c = p.choreography.as_ref().expect("choreography");
        super::check(&p, &c.body)
            .into_iter()
            .map(|d| (d.code, d.span.start as usize - src.find("choreography G").unwrap_or(0)))
            .collect()
    }

    #[test]
    fn every_participant_of_a_loop_knows_the_values_of_its_parameters() {
        // `n` went from C to A; B's guard reads `k`, which holds `n`: the initial value leaks.
        let leak = "C -> A : go(n: real). mu t(k: real = n). B -> A : [k > 0] a. A -> C : b. A -> B : c. t(k)";
        let at = |s: &str, w: &str| s.find(w).expect("in the text") + "choreography G = ".len();
        assert_eq!(codes3(leak), vec![(Code::GuardNotLocal, at(leak, "n). B"))]);
        // The jump argument `m` went from A to C, and B holds the parameter too.
        let jump = "mu t(k: real = 0). B -> A : [k > 0] a. A -> C : r(m: real). A -> B : c. t(m)";
        assert_eq!(codes3(jump), vec![(Code::GuardNotLocal, at(jump, "m)"))]);
        // Values every participant of the loop knows: constants, the parameters, and a value
        // sent between the two participants of a two-party loop.
        assert_eq!(codes3("mu t(k: real = 0). B -> A : [k > 0] a. A -> C : b. A -> B : c. t(k + 1)"), vec![]);
        assert_eq!(codes3("C -> A : go(n: real). mu t(k: real = n). A -> C : [k > 0] a(m: real). t(m)"), vec![]);
        // A parameter of an inner loop of A and C given to the outer loop, which B is part of.
        let inner =
            "mu t(k: real = 0). B -> A : [k > 0] a. A -> B : f. mu s(j: real = 1). A -> C : d. C -> A : e. t(j)";
        assert_eq!(codes3(inner), vec![(Code::GuardNotLocal, at(inner, "j)"))]);
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
