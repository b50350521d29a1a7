//! Synchronisability (Sec 4.1) on the happens-before relation of the once-unfolded type.
//!
//! Events are the messages and joint motions of the type with its recursion unfolded
//! once. There is a direct edge `n → n'` when `n` is left and `n'` right of some `.`,
//! and either both are messages and the sender of `n'` takes part in `n` (the usual
//! MPST causality, rule (1)), or one is a motion and they share a participant (rule
//! (2)). Reading rule (2) for two messages too would order `p -> q. p' -> q`, which the
//! paper's Example 4.2 says is unordered; so rule (2) applies when a motion is involved.
//! Happens-before is the transitive closure; the immediate edges its transitive
//! reduction, both computed with petgraph on the event DAG.
//!
//! - **Unique minimal communication** (E0310): the immediate successors of a motion that
//!   are messages are pairwise exclusive (in different branches of a `+`).
//! - **Sender readiness** (E0311): the sender of such a message runs the only
//!   non-interruptible primitive of the motion, or all its primitives are interruptible.
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
use fixedbitset::FixedBitSet;
use petgraph::algo::tred::{dag_to_toposorted_adjacency_list, dag_transitive_reduction_closure};
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::visit::IntoNeighbors;
use std::collections::{HashMap, HashSet};

mod timing;

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
    };
    let mut path = Vec::new();
    b.walk(g, &mut path);
    let hb = HappensBefore::new(&b.events, &b.edges);
    let mut c = Checker { prog, ev: &b.events, hb: &hb, diags: Vec::new(), reported: HashSet::new() };
    c.run();
    // The timing checks rely on the three conditions above (each motion's end is decided
    // by one sender, who is ready): run them only on a synchronisable type.
    if c.diags.is_empty() {
        c.timing(&b.branches, &b.ends);
        super::timing::canonical_order(&mut c.diags);
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
}

impl<'g> Builder<'g> {
    /// Appends the events of `g` (in tree order, which is a topological order of the
    /// edges) and returns the range of their indices.
    fn walk(&mut self, g: &'g Global, path: &mut Vec<(u32, u32, bool)>) -> std::ops::Range<usize> {
        crate::stack::deep(|| self.walk_inner(g, path))
    }

    fn walk_inner(&mut self, g: &'g Global, path: &mut Vec<(u32, u32, bool)>) -> std::ops::Range<usize> {
        let start = self.events.len();
        match g {
            Global::Msg(m) => {
                self.events.push(Event { kind: EventKind::Msg(m), path: path.clone(), pars: self.pars.clone() })
            }
            Global::Motion(m) => {
                self.events.push(Event { kind: EventKind::Motion(m), path: path.clone(), pars: self.pars.clone() })
            }
            Global::Seq(items, _) => {
                let node = self.node();
                // Events of earlier items indexed by participant, for the direct edges.
                let mut seen: HashMap<RoleId, Vec<usize>> = HashMap::new();
                for (i, it) in items.iter().enumerate() {
                    path.push((node, i as u32, false));
                    let range = self.walk(it, path);
                    path.pop();
                    for e in range.clone() {
                        let mut from: Vec<usize> = Vec::new();
                        for r in self.events[e].participants() {
                            if let Some(prev) = seen.get(&r) {
                                from.extend(prev.iter().copied().filter(|&p| direct(&self.events[p], &self.events[e])));
                            }
                        }
                        from.sort_unstable();
                        from.dedup();
                        self.edges.extend(from.into_iter().map(|p| (p, e)));
                    }
                    for e in range {
                        for r in self.events[e].participants() {
                            seen.entry(r).or_default().push(e);
                        }
                    }
                }
            }
            Global::Choice(items, _) | Global::Par(items, _) => {
                let node = self.node();
                let choice = matches!(g, Global::Choice(..));
                if choice {
                    self.branches.insert(node, items.len() as u32);
                }
                for (i, it) in items.iter().enumerate() {
                    path.push((node, i as u32, choice));
                    if !choice {
                        self.pars.push((g as *const Global as usize, i as u32));
                    }
                    self.walk(it, path);
                    if !choice {
                        self.pars.pop();
                    }
                    path.pop();
                }
            }
            Global::Rec { var, body, .. } => {
                self.recs.insert(var, body);
                self.walk(body, path);
            }
            Global::Var(v) => {
                if !self.unfolding.contains(&v.var.as_str()) {
                    if let Some(body) = self.recs.get(v.var.as_str()).copied() {
                        self.unfolding.push(&v.var);
                        self.walk(body, path);
                        self.unfolding.pop();
                    }
                }
            }
            Global::End(_) => self.ends.push(path.clone()),
            Global::After(_) => {}
        }
        start..self.events.len()
    }

    fn node(&mut self) -> u32 {
        self.next_node += 1;
        self.next_node
    }
}

/// Happens-before and its immediate edges.
struct HappensBefore {
    /// `after[n]`: every event that happens after `n`.
    after: Vec<FixedBitSet>,
    /// Immediate successors (transitive reduction).
    next: Vec<Vec<usize>>,
}

impl HappensBefore {
    fn new(events: &[Event], edges: &[(usize, usize)]) -> HappensBefore {
        let n = events.len();
        let mut g: DiGraph<(), ()> = DiGraph::with_capacity(n, edges.len());
        let nodes: Vec<NodeIndex> = (0..n).map(|_| g.add_node(())).collect();
        for &(a, b) in edges {
            g.add_edge(nodes[a], nodes[b], ());
        }
        // Tree order is topological: every edge goes from an earlier to a later event.
        let (list, _) = dag_to_toposorted_adjacency_list::<_, u32>(&g, &nodes);
        let (tred, tclos) = dag_transitive_reduction_closure(&list);
        let mut after = vec![FixedBitSet::with_capacity(n); n];
        let mut next = vec![Vec::new(); n];
        for (i, set) in after.iter_mut().enumerate() {
            for j in (&tclos).neighbors(i as u32) {
                set.insert(j as usize);
            }
            next[i] = (&tred).neighbors(i as u32).map(|j| j as usize).collect();
        }
        HappensBefore { after, next }
    }

    fn before(&self, a: usize, b: usize) -> bool {
        self.after[a].contains(b)
    }
}

struct Checker<'a, 'g> {
    prog: &'a Program,
    ev: &'a [Event<'g>],
    hb: &'a HappensBefore,
    diags: Vec<Diagnostic>,
    /// An unfolded copy repeats the original's events: report each problem once.
    reported: HashSet<(Code, u32, u32, String)>,
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
        let msgs: Vec<usize> = self.hb.next[n].iter().copied().filter(|&m| !self.ev[m].is_motion()).collect();
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

    fn total_synchronisation(&mut self, n: usize) {
        let EventKind::Motion(motion) = self.ev[n].kind else { return };
        // Motions after n with no motion in between.
        let later: Vec<usize> = self.hb.after[n].ones().filter(|&m| self.ev[m].is_motion()).collect();
        let mut beyond = FixedBitSet::with_capacity(self.ev.len());
        for &m in &later {
            beyond.union_with(&self.hb.after[m]);
        }
        for n2 in later.into_iter().filter(|&m| !beyond.contains(m)) {
            let EventKind::Motion(next) = self.ev[n2].kind else { continue };
            if let [(p, a)] = motion.parts.as_slice() {
                let lone_next = next.parts.len() == 1 && next.parts[0].0 == *p;
                if lone_next && !self.prog.prim(a.prim).interruptible {
                    continue; // the documented consecutive-motion exception
                }
            }
            for (p, a) in &motion.parts {
                let told = self.hb.after[n]
                    .ones()
                    .any(|m| !self.ev[m].is_motion() && self.ev[m].participants().contains(p) && self.hb.before(m, n2));
                if told {
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
