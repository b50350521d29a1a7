//! Timing: motions that overlap in time (E0317, E0318) and interruptions outside the
//! interrupted primitive's duration (E0319). See ARCHITECTURE.md, "Timing".
//!
//! Each path of the once-unfolded tree (one branch per choice) is read as a schedule.
//! Time is named by *instants*: the start (time 0), the end of each motion `n` (its
//! non-interruptible primitive's end, or the moment its unique minimal sender sends, Sec
//! 4.1), and the moment of a message whose two parties become ready at instants that
//! nothing orders. Communication takes no time and happens as soon as both parties are
//! ready (Fig 3: time passes only by [M-PAR], with every process in a motion), so a
//! message happens at the later of: its sender's readiness (its previous message, or the
//! end of the motion it was running) and its receiver's (its previous message, or the
//! start of the interruptible motion it is running). A participant starts a motion at its
//! previous message, or where its previous (non-interruptible, lone) motion ends. Instants
//! are ordered by a DAG whose edges say "not later than"; the same instant is one node. The
//! durations of non-interruptible parts order more of them, and may prove two nodes the same
//! time (`clock.rs`). Sequences of choices are read segment by segment between
//! synchronisation points ([`Checker::timing`]).

use super::*;

mod overlap;
mod paths;

pub(super) use paths::Layout;
#[cfg(test)]
pub(super) use paths::STEPS;
use paths::*;

/// The state at a *synchronisation point* of a path: every participant that has an event
/// so far last took part in a message at one instant, and every part has been left. Each
/// participant's last message (for the labels of E0317), by participant.
type Seed = Vec<(RoleId, usize)>;

/// Sorts the timing diagnostics by place, code and text: the paths (or the segments of
/// paths) are read in an order that says nothing to the user.
pub(super) fn canonical_order(diags: &mut [Diagnostic]) {
    diags.sort_by(|a, b| {
        (a.span.file.0, a.span.start, a.code.as_str(), &a.message).cmp(&(
            b.span.file.0,
            b.span.start,
            b.code.as_str(),
            &b.message,
        ))
    });
}

/// Instants and the order "not later than" between them; node 0 is the start.
///
/// An instant is only ever below instants created after it, and tree order puts the
/// instants of one stretch of the schedule next to each other, so each down-set is kept
/// as a short list of index ranges (one range on a sequence) rather than a bit set per
/// instant (`n²` bits on a path of `n` motions).
struct Instants {
    /// `below[i]`: the instants not later than `i` (other than `i`), as sorted, disjoint,
    /// non-adjacent half-open ranges.
    below: Vec<Vec<(usize, usize)>>,
    /// What the durations say about the distance between instants.
    off: clock::Offsets,
}

impl Instants {
    fn new() -> Instants {
        Instants { below: vec![Vec::new()], off: clock::Offsets::new() }
    }
    /// A new instant not earlier than each of `after` (its place in [`clock::Offsets`] is
    /// the caller's to register).
    fn add(&mut self, after: &[usize]) -> usize {
        let mut ranges: Vec<(usize, usize)> = Vec::new();
        for &a in after {
            ranges.extend_from_slice(&self.below[a]);
            ranges.push((a, a + 1));
        }
        ranges.sort_unstable();
        let mut set: Vec<(usize, usize)> = Vec::with_capacity(ranges.len());
        for (lo, hi) in ranges {
            match set.last_mut() {
                Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
                _ => set.push((lo, hi)),
            }
        }
        self.below.push(set);
        self.below.len() - 1
    }
    /// The end of a motion that starts at `start` and ends within `w` of it.
    fn end(&mut self, start: usize, w: &clock::Window) -> usize {
        self.off.after(start, w);
        self.add(&[start])
    }
    /// Whether `a` is not later than `b`: by the events, or by the durations.
    fn le(&self, a: usize, b: usize) -> bool {
        if a == b {
            return true;
        }
        let set = &self.below[b];
        // The last range starting at or before `a`.
        let k = set.partition_point(|r| r.0 <= a);
        (k > 0 && a < set[k - 1].1) || self.off.le(a, b)
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

/// Whether two events' enclosing `*` sides put them on two sides of one `*` (so that a
/// separation obligation compares them).
fn covered(a: &[(usize, u32)], b: &[(usize, u32)]) -> bool {
    a.iter().any(|(n, s)| b.iter().any(|(m, t)| n == m && s != t))
}

/// For the `*` sides of a part, the participants of a path with a motion on sides not
/// covering them: the only ones whose parts the pair search may pair with it.
struct Relevant<'e> {
    /// Each participant of the path with a motion, and the distinct sides of its motions.
    sides: Vec<(RoleId, Vec<Sides<'e>>)>,
    cache: HashMap<&'e [(usize, u32)], Vec<RoleId>>,
}

impl<'e> Relevant<'e> {
    fn new(ev: &'e [Event], path: &[usize]) -> Relevant<'e> {
        let mut by_role: HashMap<RoleId, Vec<&'e [(usize, u32)]>> = HashMap::new();
        for &e in path.iter().filter(|&&e| ev[e].is_motion()) {
            for r in ev[e].participants() {
                let v = by_role.entry(r).or_default();
                if !v.contains(&ev[e].pars.as_slice()) {
                    v.push(&ev[e].pars);
                }
            }
        }
        let mut sides: Vec<_> = by_role.into_iter().collect();
        sides.sort_unstable_by_key(|(r, _)| *r);
        Relevant { sides, cache: HashMap::new() }
    }

    fn of(&mut self, sig: &'e [(usize, u32)]) -> &[RoleId] {
        let sides = &self.sides;
        self.cache.entry(sig).or_insert_with(|| {
            sides.iter().filter(|(_, ss)| ss.iter().any(|s| !covered(sig, s))).map(|(r, _)| *r).collect()
        })
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
    /// Every part from this index on starts after this one is left (see
    /// [`Checker::retire`]); `usize::MAX` if not known.
    retired: usize,
}

/// How a path of a segment ends (see [`Checker::timing`]).
enum PathEnd {
    /// At an E0317: the path is read no further.
    Stopped,
    /// At a synchronisation point, from which the next segment is read.
    Synchronised(Seed),
    /// With a part still running or participants at different instants.
    Running,
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

/// E0318 for a participant left standing still (its primitive ended) while `running`, a
/// part of the same dt, runs on past the time [AGCOMP] compared them.
pub(super) fn stands_still(span: crate::source::Span, running: &str, standing: &str) -> Diagnostic {
    Diagnostic::error(
        Code::UncheckedOverlap,
        span,
        format!(
            "`{running}` may run on after this motion ends, while `{standing}` stands still where its primitive left it, and no check compares them then"
        ),
    )
    .with_note("a participant whose primitive has ended waits outside any motion, its body where the primitive left it; [AGCOMP] compares the footprints of a dt only while all its primitives run, and the primitive running on is interrupted later (or not before `end`)")
    .with_help(format!("interrupt `{running}` in the burst of messages that ends the motion, give it a guarantee that keeps its participant in place (`x == old(x)` for every state variable), or move `{standing}` on with a primitive of its own"))
}

/// Whether a primitive keeps its participant where it started, with a footprint that
/// depends on nothing but that state: its guarantee has a conjunct `x == old(x)` (either
/// way round) for every state variable of its kind, and neither its footprint predicate
/// nor the poses of its geometric footprint read the clock or an input. Its footprint is
/// then the same at every time. A footprint written `false` (a participant with no body,
/// such as an environment) occupies nothing at any time and counts as well.
pub(super) fn stationary(prog: &Program, prim: &Primitive) -> bool {
    use crate::hir::expr::{BinOp, ExprKind};
    use crate::hir::Footprint;
    let n = prog.kind(prim.kind).state.len();
    let mut kept = vec![false; n];
    for c in prim.guarantee.conjuncts() {
        if let ExprKind::Binary(BinOp::Eq, a, b) = &c.kind {
            if let (ExprKind::Var(u), ExprKind::Var(v)) = (&a.kind, &b.kind) {
                for (x, y) in [(u, v), (v, u)] {
                    if let (Var::Own(Slot::State(i)), Var::Old(k)) = (x, y) {
                        if i == k && *i < n {
                            kept[*i] = true;
                        }
                    }
                }
            }
        }
    }
    let moving = |v: &Var| matches!(v, Var::Clock | Var::Own(Slot::Input(_)));
    let pred_moves = prim.footprint.predicate().is_some_and(|f| crate::hir::expr::mentions(&f.pred, &moving));
    let body_moves = prim.footprint.body().is_some_and(|b| {
        b.parts.iter().any(|p| {
            p.place.as_ref().is_some_and(|pose| pose.args.iter().any(|e| crate::hir::expr::mentions(e, &moving)))
        })
    });
    let occupies_nothing =
        matches!(&prim.footprint, Footprint::Predicate(f) if matches!(f.pred.kind, ExprKind::Bool(false)));
    occupies_nothing || (kept.iter().all(|k| *k) && !pred_moves && !body_moves)
}

/// Whether the part `y` (of `role`, running `prim`) stays where it is after its motion ends:
/// it is [`stationary`], and so is every carrier it rides on (`on:`), which must be a part
/// of the same motion that stops with it or is itself stationary (`carrier_still`).
pub(super) fn stays_in_place(
    prog: &Program,
    role: RoleId,
    prim: &Primitive,
    carrier_still: &dyn Fn(RoleId) -> bool,
) -> bool {
    stationary(prog, prim) && prog.carriers(role).iter().all(|m| carrier_still(m.carrier))
}

/// Whether one of `a`, `b` rides (directly or through other carriers) on the other: they
/// are attached at the mount, and their mutual clearance is not a question of the protocol.
pub(super) fn attached(prog: &Program, a: RoleId, b: RoleId) -> bool {
    prog.carriers(a).iter().any(|m| m.carrier == b) || prog.carriers(b).iter().any(|m| m.carrier == a)
}

/// Whether the assumption of `prim` reads an input (a partner's guarantee discharges it).
fn reads_input(prim: &Primitive) -> bool {
    let mut reads = false;
    prim.assume.visit_vars(&mut |v, _| reads |= matches!(v, Var::Own(Slot::Input(_))));
    reads
}

impl<'g> Checker<'_, 'g> {
    /// Reads every path of the once-unfolded tree as a schedule (module comment).
    ///
    /// The paths through a sequence of `k` choices are `2^k`; they are read *segment by
    /// segment*. The events are cut before each choice that only sequences enclose
    /// ([`cut_points`]); a segment's paths are read from each state a path of the segments
    /// before may reach the cut in, when that is a synchronisation point ([`Seed`]): every
    /// participant's last event a message at one instant `X`, every part left. What comes
    /// after such a point depends on what came before only through the messages each
    /// participant last took part in: every earlier part was left at an instant not later
    /// than `X`, every later part starts at `X` or later, so no earlier part is compared
    /// with a later one (E0318), no later message interrupts an earlier part (E0319) and
    /// later starts are compared with `X` or later instants only (E0317); `X` is then the
    /// start (instant 0) of the next segment's reading. Where some path does not reach a
    /// synchronisation point, the segment runs on to the next cut (what it reported is
    /// dropped and the longer segment read again), so the paths are then read whole, as
    /// without cuts. Only a segment with more than [`MAX_PATHS`] paths (times the states it
    /// starts from) is beyond the check: an error, never a pass.
    pub(super) fn timing(&mut self, layout: &Layout) {
        let ev = self.ev;
        // Without a motion there is nothing to time.
        if !ev.iter().any(Event::is_motion) {
            return;
        }
        let everyone: HashSet<RoleId> = ev.iter().flat_map(Event::participants).collect();
        let cuts = cut_points(ev, layout);
        let mut seeds: Vec<Seed> = vec![Vec::new()];
        let mut lo = 0;
        let mut k = 0;
        while lo < ev.len() && !seeds.is_empty() {
            let hi = cuts.get(k).copied().unwrap_or(ev.len());
            let last = hi == ev.len();
            let mark = (self.diags.len(), self.reported.clone());
            let mut next: Vec<Seed> = Vec::new();
            let mut synchronised = true;
            let mut within = true;
            let limit = MAX_PATHS / seeds.len();
            for seed in &seeds {
                within &= paths(ev, lo..hi, layout.branches, limit, |path, assign| {
                    // Whether the path reaches an `end` (rather than only a recursion
                    // variable, whose next round the unfolded copy already shows); every
                    // `end` lies in the last segment.
                    let ends_here = last
                        && layout
                            .ends
                            .iter()
                            .any(|e| e.iter().filter(|n| n.2).all(|(node, b, _)| assign.get(node) == Some(b)));
                    match self.timing_path(path, seed, ends_here, &everyone) {
                        PathEnd::Stopped => {}
                        PathEnd::Synchronised(s) => next.push(s),
                        PathEnd::Running => synchronised = false,
                    }
                });
                if !within {
                    break;
                }
            }
            if !within {
                self.diags.truncate(mark.0);
                self.reported = mark.1;
                let loc = ev.get(lo).map(Event::loc).unwrap_or_default();
                self.push(
                    Diagnostic::error(
                        Code::UncheckedOverlap,
                        loc.0,
                        format!("more than {MAX_PATHS} paths through the choices from here: mochi cannot check which motions overlap in time"),
                    )
                    .with_note("the timing checks read each path through the choices as a schedule; a sequence of choices is read one choice at a time only where every participant is synchronised between them (each last took part in a message at one instant, no primitive still running)")
                    .with_help("synchronise the participants between the choices: end each branch with a burst of messages after its last motion (its non-interruptible participant telling every other one), so that no motion runs on into the next choice; or split the choreography"),
                );
                return;
            }
            if last || synchronised {
                next.sort_unstable();
                next.dedup();
                seeds = next;
                lo = hi;
                k += 1;
            } else {
                // Some path runs on into the next segment: read the longer one instead.
                self.diags.truncate(mark.0);
                self.reported = mark.1;
                k += 1;
            }
        }
    }

    fn part_name(&self, p: &MotionPart) -> String {
        format!("{}: {}", self.prog.role_name(p.role), self.prog.prim(p.app.prim).name)
    }

    /// Reads one path (of a segment, from the state `seed`: see [`Checker::timing`]).
    fn timing_path(&mut self, path: &[usize], seed: &Seed, ends_here: bool, everyone: &HashSet<RoleId>) -> PathEnd {
        let ev = self.ev;
        let mut inst = Instants::new();
        let mut parts: Vec<MotionPart<'g>> = Vec::new();
        let mut last: HashMap<RoleId, Last> = seed.iter().map(|&(r, by)| (r, Last::Msg(0, by))).collect();
        let mut relevant = Relevant::new(ev, path);
        let mut live: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
        for &e in path {
            match ev[e].kind {
                EventKind::Motion(m) => {
                    Self::retire(ev, &mut parts, &mut live, &last, &inst, &mut relevant);
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
                        return PathEnd::Stopped;
                    }
                    let start = starts.first().map(|s| s.1).unwrap_or(0);
                    for (r, _) in &m.parts {
                        if let Some(Last::MotionPart(x)) = last.get(r) {
                            let x = *x;
                            parts[x].left = Some(start);
                        }
                    }
                    let end = inst.end(start, &clock::motion_window(self.prog, m));
                    for (r, app) in &m.parts {
                        parts.push(MotionPart {
                            ev: e,
                            role: *r,
                            app,
                            start,
                            end_of_motion: end,
                            left: None,
                            retired: usize::MAX,
                        });
                        last.insert(*r, Last::MotionPart(parts.len() - 1));
                        live.push_back(parts.len() - 1);
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
            // The motions some part of which was left (one pass: a wide dt has many parts).
            let left: std::collections::HashSet<usize> =
                parts.iter().filter(|q| q.left.is_some()).map(|q| q.ev).collect();
            for p in parts.iter().filter(|p| p.left.is_none()) {
                let prim = self.prog.prim(p.app.prim);
                let partners_left = left.contains(&p.ev);
                if prim.interruptible && (prim.duration.hi.is_some() || (reads_input(prim) && partners_left)) {
                    self.never_interrupted(p);
                }
            }
        }
        self.overlaps(&parts, &inst, ends_here);
        // A synchronisation point: every part left, every participant's last event a
        // message at one instant (0 too for those yet to appear, unless all have).
        let mut at: Option<usize> = None;
        let mut seed: Seed = Vec::with_capacity(last.len());
        for (r, l) in &last {
            let Last::Msg(i, by) = *l else { return PathEnd::Running };
            if at.is_some_and(|x| x != i) {
                return PathEnd::Running;
            }
            at = Some(i);
            seed.push((*r, by));
        }
        let everyone_here = everyone.iter().all(|r| last.contains_key(r));
        if parts.iter().any(|p| p.left.is_none()) || (at.is_some_and(|x| x != 0) && !everyone_here) {
            return PathEnd::Running;
        }
        seed.sort_unstable();
        PathEnd::Synchronised(seed)
    }

    /// Marks the oldest parts that every later part they could be paired with starts
    /// after as retired from the E0318 pair search (so that a long sequence compares each
    /// part with its few neighbours only, not with every other part).
    ///
    /// A participant's later parts start no earlier than its current floor: the instant
    /// of its last message, or the start of its current part (a part starts at its
    /// participant's last message or at the end of its previous motion, and a message
    /// comes no earlier than each party is ready); one yet to appear starts no earlier
    /// than 0. The pair search only pairs parts whose enclosing `*` sides do not cover
    /// each other, so only the participants with an event on such sides count (see
    /// [`Relevant`]). So if a part was left at an instant not later than each of their
    /// floors, it is before every later part it could be paired with. The oldest parts
    /// are tried first, up to the first that fails: a cheap, sound under-approximation (a
    /// part kept is only compared exactly).
    fn retire<'e>(
        ev: &'e [Event],
        parts: &mut [MotionPart],
        live: &mut std::collections::VecDeque<usize>,
        last: &HashMap<RoleId, Last>,
        inst: &Instants,
        relevant: &mut Relevant<'e>,
    ) {
        while let Some(&x) = live.front() {
            let Some(left) = parts[x].left else { break };
            let floor = |r: &RoleId| match last.get(r) {
                None => 0,
                Some(Last::Msg(i, _)) => *i,
                Some(Last::MotionPart(p)) => parts[*p].start,
            };
            if !relevant.of(&ev[parts[x].ev].pars).iter().all(|r| inst.le(left, floor(r))) {
                break;
            }
            parts[x].retired = parts.len();
            live.pop_front();
        }
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
}
