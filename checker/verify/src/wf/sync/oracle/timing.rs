//! The oracle's timing checks (E0317-E0319): every path of the once-unfolded type enumerated
//! at once, instants as bit sets.

use super::*;

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
    off: crate::wf::sync::clock::Offsets,
}

impl Instants {
    fn new(cap: usize) -> Instants {
        Instants { below: vec![FixedBitSet::with_capacity(cap)], cap, off: crate::wf::sync::clock::Offsets::new() }
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
struct MotionPart<'g> {
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
    MotionPart(usize),
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
    pub(super) fn timing(&mut self, branches: &HashMap<u32, u32>, ends: &[Vec<(u32, u32, bool)>]) {
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

    fn part_name(&self, p: &MotionPart) -> String {
        format!("{}: {}", self.prog.role_name(p.role), self.prog.prim(p.app.prim).name)
    }

    fn timing_path(&mut self, path: &[usize], ends_here: bool) {
        let ev = self.ev;
        let mut inst = Instants::new(path.len() + 1);
        let mut parts: Vec<MotionPart<'g>> = Vec::new();
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
                            Some(Last::MotionPart(x)) => (*r, parts[*x].end_of_motion, Some(parts[*x].ev)),
                        })
                        .collect();
                    if starts.iter().any(|s| !inst.same(s.1, starts[0].1)) {
                        self.unsynchronised_start(e, &starts, &inst);
                        return;
                    }
                    let start = starts.first().map(|s| s.1).unwrap_or(0);
                    for (r, _) in &m.parts {
                        if let Some(Last::MotionPart(x)) = last.get(r) {
                            let x = *x;
                            parts[x].left = Some(start);
                        }
                    }
                    inst.off.after(start, &crate::wf::sync::clock::motion_window(self.prog, m));
                    let end = inst.add(&[start]);
                    for (r, app) in &m.parts {
                        parts.push(MotionPart { ev: e, role: *r, app, start, end_of_motion: end, left: None });
                        last.insert(*r, Last::MotionPart(parts.len() - 1));
                    }
                }
                EventKind::Msg(msg) => {
                    let ready = |who: RoleId, sender: bool, parts: &[MotionPart]| match last.get(&who) {
                        None => 0,
                        Some(Last::Msg(i, _)) => *i,
                        Some(Last::MotionPart(x)) => {
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
                        if let Some(Last::MotionPart(x)) = last.get(&who) {
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

    fn never_interrupted(&mut self, p: &MotionPart) {
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

    fn interrupted_untied(&mut self, msg: usize, p: &MotionPart) {
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
    fn overlaps(&mut self, parts: &[MotionPart], inst: &Instants, ends_here: bool) {
        // Parts of one dt are compared by [AGCOMP] while all of them run (its query bounds
        // the time by every part's duration and assumes every guarantee). Two interruptible
        // parts that run on after the motion ends (left later, or never before `end`) are
        // not compared after that when a third part bounds the query.
        let overruns = |p: &MotionPart| {
            self.prog.prim(p.app.prim).interruptible
                && match p.left {
                    Some(l) => !inst.same(l, p.end_of_motion),
                    None => ends_here,
                }
        };
        // A part bounds the query in time when its duration has an upper bound or its
        // guarantee reads the clock (its other variables are its own, fresh at each time).
        let bounds_time = |p: &MotionPart| {
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
                        && (!overruns(p) || crate::wf::sync::timing::stationary(self.prog, self.prog.prim(p.app.prim)))
                })
            };
            if !overruns(y)
                || crate::wf::sync::timing::stays_in_place(
                    self.prog,
                    y.role,
                    self.prog.prim(y.app.prim),
                    &carrier_still,
                )
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
                    && !crate::wf::sync::timing::attached(self.prog, x.role, y.role)
                {
                    let d = crate::wf::sync::timing::stands_still(
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
        let before = |x: &MotionPart, y: &MotionPart| x.left.is_some_and(|l| inst.le(l, y.start));
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
