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

// ---------------------------------------------------------------------------------------
// Timing: motions that overlap in time (E0317, E0318) and interruptions outside the
// interrupted primitive's duration (E0319). See ARCHITECTURE.md, "Timing".
//
// Each path of the once-unfolded tree (one branch per choice) is read as a schedule.
// Time is named by *instants*: the start (time 0), the end of each motion `n` (its
// non-interruptible primitive's end, or the moment its unique minimal sender sends, Sec
// 4.1), and the moment of a message whose two parties become ready at instants that
// nothing orders. Communication takes no time and happens as soon as both parties are
// ready (Fig 3: time passes only by [M-PAR], with every process in a motion), so a
// message happens at the later of: its sender's readiness (its previous message, or the
// end of the motion it was running) and its receiver's (its previous message, or the
// start of the interruptible motion it is running). A participant starts a motion at its
// previous message, or where its previous (non-interruptible, lone) motion ends. Instants
// are ordered by a DAG whose edges say "not later than"; the same instant is one node.

/// Past this many paths through choices the timing checks give up with an error.
const MAX_PATHS: usize = 4096;

/// A path: its events in tree order, and the branch taken at each choice node.
type SchedulePath = (Vec<usize>, HashMap<u32, u32>);

/// The paths of the once-unfolded tree: for each, the events on it in tree order and the
/// branch it takes at each choice it meets.
/// `None` if there are more than [`MAX_PATHS`].
fn paths(ev: &[Event], branches: &HashMap<u32, u32>) -> Option<Vec<SchedulePath>> {
    let mut done: Vec<SchedulePath> = Vec::new();
    let mut work: Vec<(HashMap<u32, u32>, Vec<usize>, usize)> = vec![(HashMap::new(), Vec::new(), 0)];
    while let Some((mut assign, mut list, mut i)) = work.pop() {
        'ev: while i < ev.len() {
            for &(node, b, choice) in &ev[i].path {
                if !choice {
                    continue;
                }
                let taken = match assign.get(&node) {
                    Some(&x) => x,
                    None => {
                        let n = branches.get(&node).copied().unwrap_or(1);
                        if done.len() + work.len() + n as usize > MAX_PATHS {
                            return None;
                        }
                        for k in 1..n {
                            let mut a = assign.clone();
                            a.insert(node, k);
                            work.push((a, list.clone(), i));
                        }
                        assign.insert(node, 0);
                        0
                    }
                };
                if taken != b {
                    i += 1;
                    continue 'ev;
                }
            }
            list.push(i);
            i += 1;
        }
        done.push((list, assign));
    }
    Some(done)
}

/// Instants and the order "not later than" between them; node 0 is the start.
struct Instants {
    /// `below[i]`: the instants not later than `i` (other than `i`).
    below: Vec<FixedBitSet>,
    cap: usize,
    /// What the durations say about the distance between instants.
    off: super::clock::Offsets,
}

impl Instants {
    fn new(cap: usize) -> Instants {
        Instants { below: vec![FixedBitSet::with_capacity(cap)], cap, off: super::clock::Offsets::new() }
    }
    /// A new instant not earlier than each of `after`.
    fn add(&mut self, after: &[usize]) -> usize {
        let mut set = FixedBitSet::with_capacity(self.cap);
        for &a in after {
            set.union_with(&self.below[a]);
            set.insert(a);
        }
        self.below.push(set);
        self.below.len() - 1
    }
    fn le(&self, a: usize, b: usize) -> bool {
        a == b || self.below[b].contains(a) || self.off.le(a, b)
    }
    /// Whether `a` and `b` are the same time: one instant, or two the durations prove equal.
    fn same(&self, a: usize, b: usize) -> bool {
        a == b || (self.le(a, b) && self.le(b, a))
    }
    /// The later of two instants: one of them when they are ordered, else a new one.
    fn max(&mut self, a: usize, b: usize) -> usize {
        if self.le(a, b) {
            b
        } else if self.le(b, a) {
            a
        } else {
            self.off.later_of(a, b);
            self.add(&[a, b])
        }
    }
}

/// The `*` sides enclosing an event (see [`Event::pars`]).
type Sides<'e> = &'e [(usize, u32)];

/// One participant's part of a joint motion on a path.
struct Part<'g> {
    /// The motion's event.
    ev: usize,
    role: RoleId,
    app: &'g PrimApp,
    start: usize,
    /// The motion's end (see the module comment).
    end_of_motion: usize,
    /// When this participant leaves it; `None` if it never does on this path.
    left: Option<usize>,
}

/// A participant's last event on the path so far.
#[derive(Clone, Copy)]
enum Last {
    /// A message: its instant and its event.
    Msg(usize, usize),
    /// A part of a motion (index into the parts).
    Part(usize),
}

fn names(prog: &Program, rs: &[RoleId]) -> String {
    let v: Vec<_> = rs.iter().map(|r| format!("`{}`", prog.role_name(*r))).collect();
    match v.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => v.join(""),
    }
}

/// Whether a primitive may be interrupted at any time after it starts, with an assumption
/// that does not depend on the other participants: `D = [0, inf]` (a literal bound `<= 0`)
/// and no input read by `A`.
fn open_ended(prim: &Primitive) -> bool {
    let lo_zero = match &prim.duration.lo.kind {
        crate::hir::expr::ExprKind::Int(i) => *i <= 0,
        crate::hir::expr::ExprKind::Real(r) => r.parse::<f64>().is_ok_and(|v| v <= 0.0),
        _ => false,
    };
    lo_zero && prim.duration.hi.is_none() && !reads_input(prim)
}

/// Whether the assumption of `prim` reads an input (a partner's guarantee discharges it).
fn reads_input(prim: &Primitive) -> bool {
    let mut reads = false;
    prim.assume.visit_vars(&mut |v, _| reads |= matches!(v, Var::Own(Slot::Input(_))));
    reads
}

impl<'g> Checker<'_, 'g> {
    fn timing(&mut self, branches: &HashMap<u32, u32>, ends: &[Vec<(u32, u32, bool)>]) {
        // Without a motion there is nothing to time.
        if !self.ev.iter().any(Event::is_motion) {
            return;
        }
        let Some(paths) = paths(self.ev, branches) else {
            let loc = self.ev.first().map(Event::loc).unwrap_or_default();
            self.push(
                Diagnostic::error(
                    Code::UncheckedOverlap,
                    loc.0,
                    format!("more than {MAX_PATHS} paths through the choices: mochi cannot check which motions overlap in time"),
                )
                .with_note("the timing checks read each path of the once-unfolded type separately")
                .with_help("split the choreography, or reduce the nesting of choices"),
            );
            return;
        };
        for (path, assign) in &paths {
            // Whether the path reaches an `end` (rather than only a recursion variable,
            // whose next round the unfolded copy already shows).
            let ends_here =
                ends.iter().any(|e| e.iter().filter(|n| n.2).all(|(node, b, _)| assign.get(node) == Some(b)));
            self.timing_path(path, ends_here);
        }
    }

    fn part_name(&self, p: &Part) -> String {
        format!("{}: {}", self.prog.role_name(p.role), self.prog.prim(p.app.prim).name)
    }

    fn timing_path(&mut self, path: &[usize], ends_here: bool) {
        let ev = self.ev;
        let mut inst = Instants::new(path.len() + 1);
        let mut parts: Vec<Part<'g>> = Vec::new();
        let mut last: HashMap<RoleId, Last> = HashMap::new();
        for &e in path {
            match ev[e].kind {
                EventKind::Motion(m) => {
                    // Where each participant starts (E0317: all at once).
                    let starts: Vec<(RoleId, usize, Option<usize>)> = m
                        .parts
                        .iter()
                        .map(|(r, _)| match last.get(r) {
                            None => (*r, 0, None),
                            Some(Last::Msg(i, by)) => (*r, *i, Some(*by)),
                            Some(Last::Part(x)) => (*r, parts[*x].end_of_motion, Some(parts[*x].ev)),
                        })
                        .collect();
                    if starts.iter().any(|s| !inst.same(s.1, starts[0].1)) {
                        self.unsynchronised_start(e, &starts, &inst);
                        return;
                    }
                    let start = starts.first().map(|s| s.1).unwrap_or(0);
                    for (r, _) in &m.parts {
                        if let Some(Last::Part(x)) = last.get(r) {
                            let x = *x;
                            parts[x].left = Some(start);
                        }
                    }
                    inst.off.after(start, &super::clock::motion_window(self.prog, m));
                    let end = inst.add(&[start]);
                    for (r, app) in &m.parts {
                        parts.push(Part { ev: e, role: *r, app, start, end_of_motion: end, left: None });
                        last.insert(*r, Last::Part(parts.len() - 1));
                    }
                }
                EventKind::Msg(msg) => {
                    let ready = |who: RoleId, sender: bool, parts: &[Part]| match last.get(&who) {
                        None => 0,
                        Some(Last::Msg(i, _)) => *i,
                        Some(Last::Part(x)) => {
                            let p = &parts[*x];
                            if !sender && self.prog.prim(p.app.prim).interruptible {
                                p.start
                            } else {
                                p.end_of_motion
                            }
                        }
                    };
                    let s = ready(msg.from, true, &parts);
                    let r = ready(msg.to, false, &parts);
                    let at = inst.max(s, r);
                    for who in [msg.from, msg.to] {
                        if let Some(Last::Part(x)) = last.get(&who) {
                            let x = *x;
                            let interruptible = self.prog.prim(parts[x].app.prim).interruptible;
                            parts[x].left = Some(if interruptible { at } else { parts[x].end_of_motion });
                            let prim = self.prog.prim(parts[x].app.prim);
                            if interruptible && !inst.same(at, parts[x].end_of_motion) && !open_ended(prim) {
                                self.interrupted_untied(e, &parts[x]);
                            }
                        }
                        last.insert(who, Last::Msg(at, e));
                    }
                }
            }
        }
        if ends_here {
            // An interruptible motion that nothing interrupts runs on after `end`.
            // It needs `hi = inf`, and if its assumption reads inputs, partners that keep
            // guaranteeing: every other part of its dt left running too ([AGCOMP] checked
            // the assumption at every time from their guarantees).
            for p in parts.iter().filter(|p| p.left.is_none()) {
                let prim = self.prog.prim(p.app.prim);
                let partners_left = parts.iter().any(|q| q.ev == p.ev && q.left.is_some());
                if prim.interruptible && (prim.duration.hi.is_some() || (reads_input(prim) && partners_left)) {
                    self.never_interrupted(p);
                }
            }
        }
        self.overlaps(&parts, &inst, ends_here);
    }

    fn never_interrupted(&mut self, p: &Part) {
        let prim = self.prog.prim(p.app.prim);
        let (lo, hi) = self.duration_text(prim);
        let d = Diagnostic::error(
            Code::InterruptOutsideDuration,
            p.app.loc.0,
            format!(
                "nothing interrupts `{}` before `end`, so it runs on past its duration [{lo}, {hi}]",
                self.part_name(p)
            ),
        )
        .with_note("Fig 3 [INTERRUPT] and Def 4.11 (5): an interruptible motion is consumed only while t ∈ D; its contract (and every check of its footprint) says nothing after D. Sec 4.1 reads `end` as idling forever")
        .with_help(format!(
            "end with a primitive whose duration has no upper bound (and whose assumption reads no input, if its partners stop first), or interrupt `{}` with a message before `end`",
            self.prog.role_name(p.role)
        ));
        self.push(d);
    }

    fn duration_text(&self, prim: &Primitive) -> (String, String) {
        let lo = print::expr(self.prog, None, &prim.duration.lo);
        let hi = prim.duration.hi.as_ref().map(|h| print::expr(self.prog, None, h)).unwrap_or_else(|| "inf".into());
        (lo, hi)
    }

    fn unsynchronised_start(&mut self, e: usize, starts: &[(RoleId, usize, Option<usize>)], inst: &Instants) {
        let first = starts[0].1;
        let (same, other): (Vec<_>, Vec<_>) = starts.iter().partition(|s| inst.same(s.1, first));
        let who = |v: &[&(RoleId, usize, Option<usize>)]| names(self.prog, &v.iter().map(|s| s.0).collect::<Vec<_>>());
        let mut d = Diagnostic::error(
            Code::UnsynchronisedStart,
            self.ev[e].loc().0,
            format!(
                "{} may start this joint motion at another time than {}: nothing ties the moments they are released",
                who(&same),
                who(&other)
            ),
        );
        let mut bys: Vec<usize> = starts.iter().filter_map(|s| s.2).collect();
        bys.sort_unstable();
        bys.dedup();
        for by in bys {
            let rs: Vec<RoleId> = starts.iter().filter(|s| s.2 == Some(by)).map(|s| s.0).collect();
            let what = if self.ev[by].is_motion() { "when this motion ends" } else { "this message" };
            d = d.with_label(self.ev[by].loc().0, format!("{} start(s) after {what}", names(self.prog, &rs)));
        }
        d = d
            .with_note("[AGCOMP] composes the primitives of a dt from a common start (Sec 3.4), and Def 4.11 (6) consumes a joint motion at one time for all; after `*` the sides run at independent times (Sec 4.1)")
            .with_help("release all its participants from the same instant: end the other sides in interruptible motions and let one side's last sender tell each of them (as in Example 4.2 (4)), or keep the motion on one side of the `*`");
        self.push(d);
    }

    fn interrupted_untied(&mut self, msg: usize, p: &Part) {
        let prim = self.prog.prim(p.app.prim);
        let (lo, hi) = self.duration_text(prim);
        let d = Diagnostic::error(
            Code::InterruptOutsideDuration,
            self.ev[msg].loc().0,
            format!(
                "{} may interrupt `{}` at any time, not only within its duration [{lo}, {hi}]: its timing is not tied to the end of that motion",
                self.describe(msg),
                self.part_name(p)
            ),
        )
        .with_label(p.app.loc.0, "the interrupted primitive")
        .with_note("Fig 3 [INTERRUPT] and Def 4.11 (5), (8b): an interruptible motion is consumed only while t ∈ D; its contract (and every check of its footprint) says nothing after D")
        .with_help(format!(
            "send the message in the burst that ends `{}`'s own motion, or give `{}` the duration [0, inf] and an assumption that reads no input",
            self.prog.role_name(p.role),
            prim.name
        ));
        self.push(d);
    }

    /// E0318: two parts of different participants that may run at the same time and that
    /// neither [AGCOMP] (one dt) nor a separation obligation (two sides of one `*`) covers.
    fn overlaps(&mut self, parts: &[Part], inst: &Instants, ends_here: bool) {
        // Parts of one dt are compared by [AGCOMP] while all of them run (its query bounds
        // the time by every part's duration and assumes every guarantee). Two interruptible
        // parts that run on after the motion ends (left later, or never before `end`) are
        // not compared after that when a third part bounds the query.
        let overruns = |p: &Part| {
            self.prog.prim(p.app.prim).interruptible
                && match p.left {
                    Some(l) => !inst.same(l, p.end_of_motion),
                    None => ends_here,
                }
        };
        // A part bounds the query in time when its duration has an upper bound or its
        // guarantee reads the clock (its other variables are its own, fresh at each time).
        let bounds_time = |p: &Part| {
            let prim = self.prog.prim(p.app.prim);
            let mut clock = false;
            prim.guarantee.visit_vars(&mut |v, _| clock |= matches!(v, Var::Clock));
            prim.duration.hi.is_some() || clock
        };
        let mut together: std::collections::BTreeMap<usize, Vec<String>> = std::collections::BTreeMap::new();
        for (i, x) in parts.iter().enumerate() {
            if !overruns(x) {
                continue;
            }
            for (j, y) in parts.iter().enumerate().skip(i + 1).filter(|(_, y)| y.ev == x.ev && overruns(y)) {
                let bounded = parts.iter().enumerate().any(|(k, q)| q.ev == x.ev && k != i && k != j && bounds_time(q));
                if bounded {
                    together.entry(x.ev).or_default().push(format!(
                        "`{}` with `{}`",
                        self.part_name(x),
                        self.part_name(y)
                    ));
                }
            }
        }
        for (e, pairs) in together {
            let d = Diagnostic::error(
                Code::UncheckedOverlap,
                self.ev[e].loc().0,
                format!(
                    "some primitives of this motion may run on together after the others stop, and no check compares them then: {}",
                    pairs.join(", ")
                ),
            )
            .with_note("they are interrupted later than the motion ends (or not before `end`); [AGCOMP] compares the footprints of a dt only while all its primitives run")
            .with_help("interrupt them in the burst of messages that ends the motion, or give them a dt (or `*` sides) of their own");
            self.push(d);
        }

        // A participant standing still after its part ended, and a part of the same dt
        // running on past the time [AGCOMP] compared them (no third part needed: the
        // standing part itself may bound the time).
        for (j, y) in parts.iter().enumerate() {
            let carrier_still = |c: RoleId| {
                parts.iter().any(|p| {
                    p.ev == y.ev
                        && p.role == c
                        && (!overruns(p) || super::timing::stationary(self.prog, self.prog.prim(p.app.prim)))
                })
            };
            if !overruns(y)
                || super::timing::stays_in_place(self.prog, y.role, self.prog.prim(y.app.prim), &carrier_still)
            {
                continue;
            }
            let bounded = parts.iter().enumerate().any(|(k, q)| q.ev == y.ev && k != j && bounds_time(q));
            if !bounded {
                continue;
            }
            for (i, x) in parts.iter().enumerate() {
                if x.ev == y.ev
                    && i != j
                    && !overruns(x)
                    && x.role != y.role
                    && !super::timing::attached(self.prog, x.role, y.role)
                {
                    let d = super::timing::stands_still(
                        self.ev[y.ev].loc().0,
                        &self.part_name(y),
                        self.prog.role_name(x.role),
                    );
                    self.push(d);
                }
            }
        }

        // Group by enclosing `*` sides: whether a pair is covered depends only on them.
        let mut groups: Vec<(Sides, Vec<usize>)> = Vec::new();
        let mut index: HashMap<&[(usize, u32)], usize> = HashMap::new();
        for (i, p) in parts.iter().enumerate() {
            let sig: &[(usize, u32)] = &self.ev[p.ev].pars;
            let g = *index.entry(sig).or_insert_with(|| {
                groups.push((sig, Vec::new()));
                groups.len() - 1
            });
            groups[g].1.push(i);
        }
        let covered =
            |a: &[(usize, u32)], b: &[(usize, u32)]| a.iter().any(|(n, s)| b.iter().any(|(m, t)| n == m && s != t));
        let before = |x: &Part, y: &Part| x.left.is_some_and(|l| inst.le(l, y.start));
        // Per pair of motions (earlier, later), the pairs of parts that may overlap.
        type Pairs = Vec<(String, String, RoleId, RoleId)>;
        let mut found: std::collections::BTreeMap<(usize, usize), Pairs> = std::collections::BTreeMap::new();
        for gi in 0..groups.len() {
            for gj in gi..groups.len() {
                if covered(groups[gi].0, groups[gj].0) {
                    continue;
                }
                for (k, &a) in groups[gi].1.iter().enumerate() {
                    let from = if gi == gj { k + 1 } else { 0 };
                    for &b in &groups[gj].1[from..] {
                        let (x, y) = (&parts[a], &parts[b]);
                        if x.role == y.role || x.ev == y.ev || before(x, y) || before(y, x) {
                            continue;
                        }
                        let (x, y) = if x.ev < y.ev { (x, y) } else { (y, x) };
                        found.entry((x.ev, y.ev)).or_default().push((
                            self.part_name(x),
                            self.part_name(y),
                            x.role,
                            y.role,
                        ));
                    }
                }
            }
        }
        for ((xe, ye), pairs) in found {
            let list: Vec<String> = pairs.iter().map(|(a, b, _, _)| format!("`{b}` with `{a}`")).collect();
            let (_, _, xr, yr) = pairs[0];
            let d = Diagnostic::error(
                Code::UncheckedOverlap,
                self.ev[ye].loc().0,
                format!(
                    "this motion may start while {} is still running, and no check compares them: {}",
                    self.describe(xe),
                    list.join(", ")
                ),
            )
            .with_label(self.ev[xe].loc().0, "may still be running")
            .with_note("nothing orders the two in time, and they are neither one dt ([AGCOMP]) nor the two sides of one `*` (full separation, Sec 4.1), so their footprints are never compared")
            .with_help(format!(
                "order them with a message (e.g. let `{}` tell `{}` when it is done), or put them on the two sides of one `*`",
                self.prog.role_name(xr),
                self.prog.role_name(yr)
            ));
            self.push(d);
        }
    }
}
