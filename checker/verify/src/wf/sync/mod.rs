//! Synchronisability (Sec 4.1) on the happens-before relation of the once-unfolded type.
//!
//! Events are the messages and joint motions of the type with its recursion unfolded
//! once. There is a direct edge `n → n'` when `n` is left and `n'` right of some `.`,
//! and either both are messages and the sender of `n'` takes part in `n` (the usual
//! MPST causality, rule (1)), or one is a motion and they share a participant (rule
//! (2)). Reading rule (2) for two messages too would order `p -> q. p' -> q`, which the
//! paper's Example 4.2 says is unordered; so rule (2) applies when a motion is involved.
//! Happens-before is the transitive closure; the immediate edges its transitive
//! reduction. Neither is materialised (`n²` bits at `n` events): the builder keeps a
//! sparse edge set with the same closure ([`Builder::walk`]) and each check searches it
//! from one motion, through the messages up to the next motions (near-linear on long
//! sequences; a closure-based implementation is the test oracle,
//! `oracle.rs`; the timing checks are in `timing.rs`).
//!
//! - **Unique minimal communication** (E0310): the immediate successors of a motion that
//!   are messages are pairwise exclusive (in different branches of a `+`).
//! - **Sender readiness** (E0311): the sender of such a message runs a non-interruptible
//!   primitive of the motion (several only under joint end, which [AGCOMP] checks: E0401),
//!   or all its primitives are interruptible.
//! - **Total synchronisation** (E0312): between a motion `n` and a later motion `n'`,
//!   every participant of `n` sends or receives a message that happens after `n` and
//!   before `n'`. mochi accepts one exception (ARCHITECTURE.md, "consecutive motions"):
//!   `n = dt<p: a>` with one participant and `a` non-interruptible may be followed by
//!   `n'` with `pt{n'} = {p}`: `p` switches when `a` ends ([NON-INTERRUPT]) and nobody
//!   else waits for it. PGCD's parallel lanes need it.
//!
//! On a synchronisable type, three timing checks close a gap in Sec 4.1 (ARCHITECTURE.md,
//! "Timing"), reading each path of the once-unfolded type as a schedule of instants:
//!
//! - **Common start** (E0317): the participants of a joint motion are released at one
//!   instant, as [AGCOMP] assumes.
//! - **Overlapping motions** (E0318): two motions that may run at the same time are parts
//!   of one dt or on two sides of one `*`, so that some check compares their footprints; a
//!   participant standing still after its primitive ended is compared with nothing once a
//!   part of its dt runs on past the time [AGCOMP] bounds, so that part must keep its own
//!   participant in place.
//! - **Interruptions within D** (E0319): a message ending an interruptible motion comes
//!   when that motion ends, or the primitive is ready at any time (`[0, inf]`, an
//!   assumption free of inputs).

use crate::diag::{Code, Diagnostic};
use crate::hir::print;
use crate::hir::*;
use std::collections::{HashMap, HashSet};

pub fn check(prog: &Program, g: &Global) -> Vec<Diagnostic> {
    let mut b = Builder {
        events: Vec::new(),
        edges: Vec::new(),
        recs: HashMap::new(),
        unfolding: Vec::new(),
        next_node: 0,
        pars: Vec::new(),
        branches: HashMap::new(),
        ends: Vec::new(),
        par_nodes: HashSet::new(),
        first_end: usize::MAX,
    };
    let mut path = Vec::new();
    b.walk(g, &mut path);
    let hb = HappensBefore::new(b.events.len(), &std::mem::take(&mut b.edges));
    let n = b.events.len();
    let mut c = Checker {
        prog,
        ev: &b.events,
        hb: &hb,
        diags: Vec::new(),
        reported: HashSet::new(),
        region: Marks::new(n),
        marks: Marks::new(n),
        stack: Vec::new(),
    };
    c.run();
    // The timing checks rely on the three conditions above (each motion's end is decided
    // by one sender, who is ready): run them only on a synchronisable type.
    if c.diags.is_empty() {
        let layout =
            timing::Layout { branches: &b.branches, ends: &b.ends, pars: &b.par_nodes, first_end: b.first_end };
        c.timing(&layout);
        timing::canonical_order(&mut c.diags);
    }
    c.diags
}

/// One message or joint motion of the once-unfolded tree.
struct Event<'g> {
    kind: EventKind<'g>,
    /// Internal nodes from the root: (node id, child index, is a choice).
    path: Vec<(u32, u32, bool)>,
    /// The `*` nodes above the event, as (address of the syntactic node, side): an
    /// unfolded copy of a `*` is the same node, whose separation obligation covers it.
    pars: Vec<(usize, u32)>,
}

enum EventKind<'g> {
    Msg(&'g Msg),
    Motion(&'g Motion),
}

impl Event<'_> {
    fn participants(&self) -> Vec<RoleId> {
        match self.kind {
            EventKind::Msg(m) => vec![m.from, m.to],
            EventKind::Motion(m) => m.parts.iter().map(|(r, _)| *r).collect(),
        }
    }
    fn loc(&self) -> Loc {
        match self.kind {
            EventKind::Msg(m) => m.loc,
            EventKind::Motion(m) => m.loc,
        }
    }
    fn is_motion(&self) -> bool {
        matches!(self.kind, EventKind::Motion(_))
    }
}

/// Whether two events lie in different branches of some choice.
fn exclusive(a: &Event, b: &Event) -> bool {
    for (x, y) in a.path.iter().zip(&b.path) {
        if x.0 != y.0 {
            return false;
        }
        if x.1 != y.1 {
            return x.2;
        }
    }
    false
}

/// Whether rule (1)/(2) puts a direct edge from `a` to `b` when `a` is left of `b`.
fn direct(a: &Event, b: &Event) -> bool {
    match (&a.kind, &b.kind) {
        (EventKind::Msg(m1), EventKind::Msg(m2)) => m2.from == m1.from || m2.from == m1.to,
        _ => {
            let pa = a.participants();
            b.participants().iter().any(|r| pa.contains(r))
        }
    }
}

/// Per participant, the events of the items walked so far that a later item's event may
/// have a direct edge from: `msgs` the messages with that participant, `motions` the
/// motions with it. Only events not already known to happen before another kept one are
/// kept (see [`Builder::walk`]), which keeps the edge list near-linear.
#[derive(Default)]
struct Exits {
    msgs: Vec<usize>,
    motions: Vec<usize>,
}

type Frontier = HashMap<RoleId, Exits>;

fn merge(into: &mut Frontier, from: Frontier) {
    for (r, x) in from {
        let e = into.entry(r).or_default();
        e.msgs.extend(x.msgs);
        e.motions.extend(x.motions);
    }
}

struct Builder<'g> {
    events: Vec<Event<'g>>,
    edges: Vec<(usize, usize)>,
    recs: HashMap<&'g str, &'g Global>,
    unfolding: Vec<&'g str>,
    next_node: u32,
    /// The enclosing `*` nodes and sides (see [`Event::pars`]).
    pars: Vec<(usize, u32)>,
    /// Number of branches of each choice node.
    branches: HashMap<u32, u32>,
    /// The internal nodes above each `end` (as [`Event::path`]).
    ends: Vec<Vec<(u32, u32, bool)>>,
    /// The `*` nodes (as in [`Event::path`]).
    par_nodes: HashSet<u32>,
    /// How many events precede the first `end` in tree order (`usize::MAX` if none).
    first_end: usize,
}

impl<'g> Builder<'g> {
    /// Appends the events of `g` (in tree order, which is a topological order of the
    /// edges) and returns the range of their indices and their [`Frontier`].
    ///
    /// Edges: a Seq puts rule (1)/(2)'s direct edge from each event of an earlier item to
    /// each event of a later one when [`direct`] holds. A later message `s -> t` has one
    /// from every earlier message with `s` and every earlier motion with `s` or `t`; a
    /// later motion from every earlier event sharing a participant. Not all of these are
    /// materialised (a flat sequence of `n` messages would have `n²/2`): only those from
    /// the [`Frontier`] of the items so far. After an item containing a message sent by
    /// `r` or a motion with `r`, the earlier messages with `r` are dropped from it: each
    /// has a direct edge to that event `x`, and every later event that would take an
    /// edge from them (a message sent by `r`, a motion with `r`) takes one from `x` too
    /// (or from the kept event `x` happens before, by induction), so the edge is implied.
    /// After an item containing a motion with `r`, the earlier motions with `r` are
    /// dropped likewise (a later message *to* `r` takes edges from motions with `r`
    /// only, hence only a motion may stand in for a motion). The happens-before relation
    /// (the transitive closure) is therefore the same as with every edge, and so is its
    /// transitive reduction, which every generating edge set contains.
    fn walk(&mut self, g: &'g Global, path: &mut Vec<(u32, u32, bool)>) -> (std::ops::Range<usize>, Frontier) {
        crate::stack::deep(|| self.walk_inner(g, path))
    }

    fn walk_inner(&mut self, g: &'g Global, path: &mut Vec<(u32, u32, bool)>) -> (std::ops::Range<usize>, Frontier) {
        let start = self.events.len();
        let mut front = Frontier::new();
        match g {
            Global::Msg(m) => {
                self.events.push(Event { kind: EventKind::Msg(m), path: path.clone(), pars: self.pars.clone() });
                for r in [m.from, m.to] {
                    front.entry(r).or_default().msgs.push(start);
                }
            }
            Global::Motion(m) => {
                self.events.push(Event { kind: EventKind::Motion(m), path: path.clone(), pars: self.pars.clone() });
                for (r, _) in &m.parts {
                    front.entry(*r).or_default().motions.push(start);
                }
            }
            Global::Seq(items, _) => {
                let node = self.node();
                let empty = Exits::default();
                for (i, it) in items.iter().enumerate() {
                    path.push((node, i as u32, false));
                    let (range, exits) = self.walk(it, path);
                    path.pop();
                    // Roles whose earlier messages (resp. motions) this item supersedes.
                    let mut drop_msgs: Vec<RoleId> = Vec::new();
                    let mut drop_motions: Vec<RoleId> = Vec::new();
                    let mut from: Vec<usize> = Vec::new();
                    for e in range {
                        from.clear();
                        let seen = |r: &RoleId| front.get(r).unwrap_or(&empty);
                        match self.events[e].kind {
                            EventKind::Msg(m) => {
                                from.extend(&seen(&m.from).msgs);
                                from.extend(&seen(&m.from).motions);
                                from.extend(&seen(&m.to).motions);
                                drop_msgs.push(m.from);
                            }
                            EventKind::Motion(m) => {
                                for (r, _) in &m.parts {
                                    from.extend(&seen(r).msgs);
                                    from.extend(&seen(r).motions);
                                    drop_msgs.push(*r);
                                    drop_motions.push(*r);
                                }
                            }
                        }
                        from.sort_unstable();
                        from.dedup();
                        debug_assert!(from.iter().all(|&p| direct(&self.events[p], &self.events[e])));
                        self.edges.extend(from.iter().map(|&p| (p, e)));
                    }
                    for r in drop_msgs {
                        if let Some(x) = front.get_mut(&r) {
                            x.msgs.clear();
                        }
                    }
                    for r in drop_motions {
                        if let Some(x) = front.get_mut(&r) {
                            x.motions.clear();
                        }
                    }
                    merge(&mut front, exits);
                }
            }
            Global::Choice(items, _) | Global::Par(items, _) => {
                let node = self.node();
                let choice = matches!(g, Global::Choice(..));
                if choice {
                    self.branches.insert(node, items.len() as u32);
                } else {
                    self.par_nodes.insert(node);
                }
                for (i, it) in items.iter().enumerate() {
                    path.push((node, i as u32, choice));
                    if !choice {
                        self.pars.push((g as *const Global as usize, i as u32));
                    }
                    let (_, exits) = self.walk(it, path);
                    merge(&mut front, exits);
                    if !choice {
                        self.pars.pop();
                    }
                    path.pop();
                }
            }
            Global::Rec { var, body, .. } => {
                self.recs.insert(var, body);
                front = self.walk(body, path).1;
            }
            Global::Var(v) => {
                if !self.unfolding.contains(&v.var.as_str()) {
                    if let Some(body) = self.recs.get(v.var.as_str()).copied() {
                        self.unfolding.push(&v.var);
                        front = self.walk(body, path).1;
                        self.unfolding.pop();
                    }
                }
            }
            // A timeout head is no event: the waiting role's next message, the first of the
            // branch, is ordered after what came before the choice.
            Global::After(_) => {}
            Global::End(_) => {
                self.first_end = self.first_end.min(self.events.len());
                self.ends.push(path.clone());
            }
        }
        (start..self.events.len(), front)
    }

    fn node(&mut self) -> u32 {
        self.next_node += 1;
        self.next_node
    }
}

/// The happens-before relation, kept as the (sparse) edges of [`Builder::walk`] and
/// queried by bounded searches rather than materialised (a closure of `n` events takes
/// `n²` bits: 1.2 GB at 10^5).
struct HappensBefore {
    succ: Vec<Vec<usize>>,
    pred: Vec<Vec<usize>>,
}

impl HappensBefore {
    fn new(n: usize, edges: &[(usize, usize)]) -> HappensBefore {
        let mut succ = vec![Vec::new(); n];
        let mut pred = vec![Vec::new(); n];
        for &(a, b) in edges {
            succ[a].push(b);
            pred[b].push(a);
        }
        for v in succ.iter_mut().chain(pred.iter_mut()) {
            v.sort_unstable();
            v.dedup();
        }
        HappensBefore { succ, pred }
    }
}

/// Visited marks for the searches, reset in O(1) by bumping the epoch.
struct Marks {
    stamp: Vec<u32>,
    epoch: u32,
}

impl Marks {
    fn new(n: usize) -> Marks {
        Marks { stamp: vec![0; n], epoch: 0 }
    }
    fn clear(&mut self) {
        self.epoch += 1;
        if self.epoch == u32::MAX {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.epoch = 1;
        }
    }
    fn has(&self, i: usize) -> bool {
        self.stamp[i] == self.epoch
    }
    /// Marks `i`; whether it was unmarked.
    fn set(&mut self, i: usize) -> bool {
        let fresh = self.stamp[i] != self.epoch;
        self.stamp[i] = self.epoch;
        fresh
    }
}

/// The elements of `set` (ascending) that no other element of it happens before: the
/// immediate ones when `set` is the direct successors of an event. Searches only events
/// up to the last of `set` (a path to it runs through earlier events in tree order).
fn minimal(hb: &HappensBefore, set: &[usize], marks: &mut Marks, stack: &mut Vec<usize>) -> Vec<usize> {
    let Some(&hi) = set.last() else { return Vec::new() };
    marks.clear();
    let mut out = Vec::new();
    for &s in set {
        if marks.has(s) {
            continue;
        }
        out.push(s);
        stack.push(s);
        while let Some(x) = stack.pop() {
            for &y in &hb.succ[x] {
                if y > hi {
                    break;
                }
                if marks.set(y) {
                    stack.push(y);
                }
            }
        }
    }
    out
}

struct Checker<'a, 'g> {
    prog: &'a Program,
    ev: &'a [Event<'g>],
    hb: &'a HappensBefore,
    diags: Vec<Diagnostic>,
    /// An unfolded copy repeats the original's events: report each problem once.
    reported: HashSet<(Code, u32, u32, String)>,
    /// The messages after the motion being checked with no motion in between.
    region: Marks,
    /// Scratch marks and stack for the other searches.
    marks: Marks,
    stack: Vec<usize>,
}

impl Checker<'_, '_> {
    fn push(&mut self, d: Diagnostic) {
        if self.reported.insert((d.code, d.span.file.0, d.span.start, d.message.clone())) {
            self.diags.push(d);
        }
    }

    fn describe(&self, e: usize) -> String {
        match self.ev[e].kind {
            EventKind::Msg(m) => {
                format!("`{} -> {} : {}`", self.prog.role_name(m.from), self.prog.role_name(m.to), m.label)
            }
            EventKind::Motion(m) => {
                let parts: Vec<String> = m
                    .parts
                    .iter()
                    .map(|(r, a)| format!("{}: {}", self.prog.role_name(*r), self.prog.prim(a.prim).name))
                    .collect();
                format!("`dt<{}>`", parts.join(", "))
            }
        }
    }

    fn run(&mut self) {
        let motions: Vec<usize> = (0..self.ev.len()).filter(|&i| self.ev[i].is_motion()).collect();
        for &n in &motions {
            self.unique_minimal_and_readiness(n);
            self.total_synchronisation(n);
        }
    }

    fn unique_minimal_and_readiness(&mut self, n: usize) {
        let EventKind::Motion(motion) = self.ev[n].kind else { return };
        let next = minimal(self.hb, &self.hb.succ[n], &mut self.marks, &mut self.stack);
        let msgs: Vec<usize> = next.into_iter().filter(|&m| !self.ev[m].is_motion()).collect();
        for (i, &a) in msgs.iter().enumerate() {
            for &b in &msgs[..i] {
                if !exclusive(&self.ev[a], &self.ev[b]) {
                    let d = Diagnostic::error(
                        Code::NotUniqueMinimal,
                        self.ev[n].loc().0,
                        format!("after this motion, {} and {} can both come first", self.describe(b), self.describe(a)),
                    )
                    .with_label(self.ev[b].loc().0, "one possible first message")
                    .with_label(self.ev[a].loc().0, "another")
                    .with_note("Sec 4.1, unique minimal communication: every motion has a unique immediate happens-before edge to a message")
                    .with_help("order the messages: let the sender of the second take part in the first");
                    self.push(d);
                }
            }
        }
        for &m in &msgs {
            let EventKind::Msg(msg) = self.ev[m].kind else { continue };
            // Joint end: a sender that runs a non-interruptible part ends when every
            // other non-interruptible part does ([AGCOMP]'s joint-end part, E0401, checks
            // that their durations force it), so only an interruptible or absent sender
            // can be blocked by one.
            let non = |r: &RoleId, a: &PrimApp| *r != msg.from && !self.prog.prim(a.prim).interruptible;
            let sender_ends = motion.parts.iter().any(|(r, a)| *r == msg.from && !self.prog.prim(a.prim).interruptible);
            let blocking: Vec<&(RoleId, PrimApp)> =
                if sender_ends { Vec::new() } else { motion.parts.iter().filter(|(r, a)| non(r, a)).collect() };
            if let Some((r, a)) = blocking.first() {
                let sender = self.prog.role_name(msg.from);
                let in_motion = motion.parts.iter().any(|(q, _)| *q == msg.from);
                let why = if in_motion {
                    format!(
                        "`{sender}` sends the message that ends it, but `{}` runs `{}`, which cannot be interrupted",
                        self.prog.role_name(*r),
                        self.prog.prim(a.prim).name
                    )
                } else {
                    format!(
                        "`{sender}` is not in this motion, so all its primitives must be interruptible; `{}` runs `{}`",
                        self.prog.role_name(*r),
                        self.prog.prim(a.prim).name
                    )
                };
                let d = Diagnostic::error(Code::SenderNotReady, self.ev[m].loc().0, format!("this message may be sent while the motion before it cannot be interrupted: {why}"))
                    .with_label(self.ev[n].loc().0, "the motion this message ends")
                    .with_label(a.loc.0, "non-interruptible primitive")
                    .with_note("Sec 4.1, sender readiness: the sender runs the unique non-interruptible primitive, or every primitive is interruptible")
                    .with_help(format!("let `{}` send this message, or make `{}` interruptible", self.prog.role_name(*r), self.prog.prim(a.prim).name));
                self.push(d);
            }
        }
    }

    /// The motions after `n` with no motion in between (ascending), and marks in
    /// `self.region` the messages after `n` with no motion in between.
    ///
    /// Every motion after `n` is reached by a path whose first motion is one of `first`
    /// (the motions reached through messages only), so the next motions are the elements
    /// of `first` that no other one happens before.
    fn next_motions(&mut self, n: usize) -> Vec<usize> {
        self.region.clear();
        let mut first: Vec<usize> = Vec::new();
        self.stack.push(n);
        while let Some(x) = self.stack.pop() {
            for &y in &self.hb.succ[x] {
                if self.ev[y].is_motion() {
                    first.push(y);
                } else if self.region.set(y) {
                    self.stack.push(y);
                }
            }
        }
        first.sort_unstable();
        first.dedup();
        minimal(self.hb, &first, &mut self.marks, &mut self.stack)
    }

    /// The participants of the messages between `n` and its next motion `n2`: those
    /// marked in `self.region` from which `n2` is reached. (A message between the two
    /// lies there and reaches `n2` through messages only: a motion on either side of it
    /// would come between `n` and `n2`.)
    fn told_between(&mut self, n2: usize) -> HashSet<RoleId> {
        let mut told = HashSet::new();
        self.marks.clear();
        self.stack.push(n2);
        while let Some(x) = self.stack.pop() {
            for &y in &self.hb.pred[x] {
                if self.region.has(y) && self.marks.set(y) {
                    told.extend(self.ev[y].participants());
                    self.stack.push(y);
                }
            }
        }
        told
    }

    fn total_synchronisation(&mut self, n: usize) {
        let EventKind::Motion(motion) = self.ev[n].kind else { return };
        for n2 in self.next_motions(n) {
            let EventKind::Motion(next) = self.ev[n2].kind else { continue };
            if let [(p, a)] = motion.parts.as_slice() {
                let lone_next = next.parts.len() == 1 && next.parts[0].0 == *p;
                if lone_next && !self.prog.prim(a.prim).interruptible {
                    continue; // the documented consecutive-motion exception
                }
            }
            let told = self.told_between(n2);
            for (p, a) in &motion.parts {
                if told.contains(p) {
                    continue;
                }
                let next_prim =
                    next.parts.iter().find(|(q, _)| q == p).map(|(_, b)| self.prog.prim(b.prim).name.clone());
                let what = match next_prim {
                    Some(b) => format!("from `{}` to `{b}`", self.prog.prim(a.prim).name),
                    None => format!("out of `{}`", self.prog.prim(a.prim).name),
                };
                let d = Diagnostic::error(
                    Code::NotTotallySynchronised,
                    self.ev[n2].loc().0,
                    format!("`{}` switches {what} without sending or receiving a message in between", self.prog.role_name(*p)),
                )
                .with_label(self.ev[n].loc().0, "the earlier motion")
                .with_note("Sec 4.1, total synchronisation: between two motions every participant of the first must be told (Example 4.2)")
                .with_help(format!("send `{}` a message between the two motions", self.prog.role_name(*p)));
                self.push(d);
            }
        }
    }
}

mod clock;
mod timing;

/// A second implementation (happens-before as a materialised transitive closure and
/// reduction, instants as bit sets): quadratic, simple, the oracle of
/// [`tests::same_as_the_oracle`].
#[cfg(test)]
mod oracle;

#[cfg(test)]
mod tests;
