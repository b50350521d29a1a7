//! Sessions: which session a frame is a step of, starting one, taking a step (its
//! guard, its fields decoded and checked, its ends bound), the assignments of loops.

use super::automaton::{Automaton, Edge, EndKind, FieldKind, FieldRead, StateKind};
use super::code::{Env, Val};
use super::num::Q;
use super::wire::{self, Scalar};
use super::{report::summary, reset, verdict_fail, Binding, Fail, Kind, Monitor, Outcome, Session};
use crate::mavio::Frame;

impl Monitor {
    /// The frame against protocol `p`: a step of an open session, the start of a new one,
    /// an unexpected message between a session's ends, or `None` (it fits nothing).
    pub(super) fn on_protocol(&mut self, p: usize, f: &Frame, index: u64) -> Option<Outcome> {
        let mut between_ends = None;
        for k in 0..self.open.len() {
            let slot = self.open[k];
            let s = &self.slots[slot];
            if s.proto != p {
                continue;
            }
            let a = &self.protos[p];
            let mut found = false;
            for &e in a.edges_of(s.state) {
                if label_fits(&a.edges[e as usize], f) && ends_fit(a, &a.edges[e as usize], &s.roles, &self.kinds, f) {
                    found = true;
                    break;
                }
            }
            if found {
                return Some(self.step(slot, f, index, 0));
            }
            if a.timeout(s.state).is_some() {
                if let Some((hops, _)) = timeout_chain(a, s.state, &s.roles, &self.kinds, f) {
                    // An act too early for this session may be a late message of a session
                    // its timeout ended, whose sender went on (a first message of the
                    // protocol that opened this session may have been one too).
                    if !self.act_in_time(slot, f, hops) {
                        if let Some(id) = self.late_of_ended(p, f) {
                            self.stats.late += 1;
                            self.stats.passed += 1;
                            return Some(Outcome::Late { session: id });
                        }
                    }
                    return Some(self.step(slot, f, index, hops));
                }
            }
            let t = f.time_us;
            if s.late.iter().any(|(late, until)| {
                t.is_some_and(|t| t <= until)
                    && a.edges_of(late).iter().any(|&e| {
                        label_fits(&a.edges[e as usize], f)
                            && ends_fit(a, &a.edges[e as usize], &s.roles, &self.kinds, f)
                    })
            }) {
                // A message of a branch its receiver abandoned by a timeout, arriving after it
                // and within the late window: real peers ignore it
                // (docs/observed-and-timeouts.md, "Late messages"); not a step, not a
                // violation.
                self.stats.late += 1;
                self.stats.passed += 1;
                return Some(Outcome::Late { session: s.id });
            }
            if between_ends.is_none() && s.roles.iter().any(|b| b.sys == Some(f.sysid) && b.comp == Some(f.compid)) {
                between_ends = Some(slot);
            }
        }
        let a = &self.protos[p];
        let fresh = vec_fresh_check(a, &self.kinds, f);
        if !fresh {
            if let Some(id) = self.late_of_ended(p, f) {
                // A message of a choice that a session abandoned by the timeout that ended
                // it, within the late window: its receiver's session is over and it is no
                // step of any (docs/monitor.md, "Late messages"); not a violation.
                self.stats.late += 1;
                self.stats.passed += 1;
                return Some(Outcome::Late { session: id });
            }
        }
        if fresh {
            // A first message of the protocol starts a session even when it may also be a
            // late message of a session its timeout ended; that session's sender then went on
            // past it, so its next messages are late there too, unless the new session takes
            // them (`late_of_ended` follows the sender).
            self.late_of_ended(p, f);
            let slot = self.start(p, index);
            let o = self.step(slot, f, index, 0);
            if let Outcome::Violation(_) = o {
                // A message that would start a session and breaks its first step starts
                // nothing.
                self.close(slot, false, false);
            }
            return Some(o);
        }
        if let Some(slot) = between_ends {
            let s = &self.slots[slot];
            let state = s.state;
            let v = self.record(
                Some(slot),
                Some(state),
                f,
                index,
                Fail { kind: Kind::Unexpected, edge: None, pred: None, field: None, why: None },
            );
            self.slots[slot].violations += 1;
            return Some(Outcome::Violation(v));
        }
        None
    }

    pub(super) fn start(&mut self, p: usize, index: u64) -> usize {
        let a = &self.protos[p];
        let slot = match self.free[p].pop() {
            Some(i) => i,
            None => {
                self.slots.push(Session {
                    id: 0,
                    proto: p,
                    state: 0,
                    regs: Vec::new(),
                    strs: Vec::new(),
                    roles: Vec::new(),
                    first_frame: 0,
                    last_frame: 0,
                    violations: 0,
                    visited: Vec::new(),
                    taken: Vec::new(),
                    evaluated: Vec::new(),
                    entered_us: None,
                    late: Default::default(),
                    idle_from: None,
                    late_from: None,
                });
                self.slots.len() - 1
            }
        };
        let s = &mut self.slots[slot];
        s.id = self.next_id;
        self.next_id += 1;
        s.proto = p;
        s.state = a.start;
        reset(&mut s.regs, a.arena.regs.len(), Val::Unset);
        reset(&mut s.strs, a.arena.str_size as usize, 0);
        reset(&mut s.roles, a.roles.len(), Binding::default());
        reset(&mut s.visited, a.states.len(), false);
        reset(&mut s.taken, a.edges.len(), 0);
        reset(&mut s.evaluated, a.preds, 0);
        s.first_frame = index;
        s.last_frame = index;
        s.violations = 0;
        s.entered_us = None;
        s.late = Default::default();
        s.idle_from = None;
        s.late_from = None;
        self.open.push(slot);
        self.stats.sessions_started += 1;
        // The initial assignments (a protocol that starts with a loop).
        let start = self.slots[slot].state;
        let settled = self.settle(slot, start);
        if let Ok(st) = settled {
            self.slots[slot].state = st;
        }
        slot
    }

    /// Takes the frame in session `slot`: the edge, its checks, the registers, the jumps.
    /// With `hops > 0`, the frame is the waiting role acting after that many timeouts
    /// (`timeout_chain`): each must have passed, in the frames' time, since the state it
    /// leaves was entered; they are taken (their assignments too), then the frame's edge.
    pub(super) fn step(&mut self, slot: usize, f: &Frame, index: u64, hops: u32) -> Outcome {
        let p = self.slots[slot].proto;
        let state = self.slots[slot].state;
        let entered = self.slots[slot].entered_us;
        let late = self.slots[slot].late;
        let (idle_from, late_from) = (self.slots[slot].idle_from, self.slots[slot].late_from);
        self.undo.clear();
        self.undo_strs.clear();
        let fired = if hops > 0 { self.fire(slot, f, hops) } else { Ok(None) };
        let taken = fired.and_then(|fired| self.take(slot, f).map(|(next, e)| (next, e, fired)));
        match taken {
            Ok((next, e, fired)) => {
                let s = &mut self.slots[slot];
                s.state = next;
                s.last_frame = index;
                s.visited[next as usize] = true;
                s.entered_us = f.time_us;
                let a = &self.protos[p];
                if hops == 0 && next == state {
                    // A message of the state's own choice, back at the choice with its
                    // parameters unchanged: when it came at least the timeout's bound after
                    // the state was entered, the waiting role may have given up before it
                    // and ignored it (late). Whether it did, its act says: within the
                    // reaction bound, that act is checked against the entry before it.
                    let bound = a.timeout(state).map(|t| t.ms.saturating_mul(1000));
                    if let (Some(b), Some(e), Some(now)) = (bound, entered, f.time_us) {
                        if now >= e.saturating_add(b) && super::late::params_unchanged(a, &s.regs, &self.undo) {
                            s.idle_from = Some(e);
                            s.late_from = Some(now);
                        }
                    }
                } else {
                    s.idle_from = None;
                    s.late_from = None;
                }
                if fired.is_none() {
                    // Late messages are over once the abandoned choice's sender takes a step
                    // that is none of that choice's messages: FIFO puts every late message
                    // before it, whereas the waiting role's own sends may interleave with late
                    // arrivals (docs/observed-and-timeouts.md, "The timeout crossing").
                    let edge = &a.edges[e as usize];
                    s.late.retain(|(l, _)| {
                        let by = a.timeout(l).map(|t| t.by);
                        let of_choice = a.edges_of(l).iter().any(|&x| label_fits(&a.edges[x as usize], f));
                        !(by.is_some() && by != Some(edge.from) && !of_choice)
                    });
                }
                self.stats.steps += 1;
                if let Some(due) = end_deadline(a, next, s.entered_us) {
                    self.end_due = self.end_due.min(due);
                }
                self.forget_late_of(p, f);
                if matches!(self.protos[p].states[next as usize], StateKind::End) {
                    let s = &self.slots[slot];
                    let id = s.id;
                    if !s.late.is_empty() {
                        self.remember(slot, false);
                    }
                    self.close(slot, true, true);
                    Outcome::Ended { session: id }
                } else {
                    Outcome::Step { session: self.slots[slot].id, state: next }
                }
            }
            Err(fail) => {
                // The strings were saved from the edges of the state the frame was taken
                // in (after the timeouts, if any fired).
                let took_in = self.slots[slot].state;
                let v = self.record(Some(slot), Some(state), f, index, fail);
                // Not delivered: the session stays where it was.
                let s = &mut self.slots[slot];
                s.state = state;
                s.entered_us = entered;
                s.late = late;
                s.idle_from = idle_from;
                s.late_from = late_from;
                while let Some((r, v)) = self.undo.pop() {
                    s.regs[r as usize] = v;
                }
                let a = &self.protos[p];
                let mut at = 0;
                for fr in a.edges_of(took_in).iter().flat_map(|&e| a.edges[e as usize].fields.iter()) {
                    if fr.kind == FieldKind::Str {
                        let info = &a.arena.regs[fr.reg as usize];
                        let (o, n) = (info.str_at as usize, info.str_cap as usize);
                        if at + n <= self.undo_strs.len() {
                            s.strs[o..o + n].copy_from_slice(&self.undo_strs[at..at + n]);
                            at += n;
                        }
                    }
                }
                s.violations += 1;
                s.last_frame = index;
                Outcome::Violation(v)
            }
        }
    }

    /// Takes `hops` timeouts from the session's state, after checking that their bounds
    /// passed: the frame's time is at least the state's entry time plus the bounds (µs of
    /// the frames' clock; docs/monitor.md, "Timeouts"). Returns the first state abandoned.
    /// On failure the caller restores the state, its entry time and the registers.
    fn fire(&mut self, slot: usize, f: &Frame, hops: u32) -> Result<Option<u32>, Fail> {
        let s = &self.slots[slot];
        let first = s.state;
        let (due, after_late) = self.act_due(slot, f, hops);
        let mut base = s.entered_us;
        match (f.time_us, due) {
            (Some(t), Some(due)) if t >= due => {}
            (Some(_), Some(_)) if after_late => base = s.idle_from,
            (Some(_), Some(_)) => {
                return Err(Fail {
                    kind: Kind::Early,
                    edge: None,
                    pred: None,
                    field: None,
                    why: Some("its sender acted as after the timeout, but the timeout's bound has not passed since the choice was entered"),
                })
            }
            _ => {
                return Err(Fail {
                    kind: Kind::Undecided,
                    edge: None,
                    pred: None,
                    field: None,
                    why: Some("a timeout branch, and the log has no time to check its bound against"),
                })
            }
        }
        let mut at = first;
        let mut entered = base;
        let now = f.time_us.unwrap_or(0);
        for _ in 0..hops {
            let Some(t) = self.protos[self.slots[slot].proto].timeout(at).copied() else { break };
            // Late messages of the abandoned choice arrive within the timeout's bound of the
            // act: the protocol's timeout exceeds the link's round trip.
            self.slots[slot].late.push(at, now.saturating_add(t.ms.saturating_mul(1000)));
            at = self.settle(slot, t.next)?;
            entered = entered.map(|e| e.saturating_add(t.ms.saturating_mul(1000)));
            self.stats.timeouts += 1;
        }
        let s = &mut self.slots[slot];
        s.state = at;
        s.entered_us = entered;
        Ok(Some(first))
    }

    /// When the waiting role may act after `hops` timeouts from the session's state: the
    /// entry time plus their bounds (`None` without a time), and whether the act at the
    /// frame's time follows messages of the choice that came after the bound had passed
    /// (`Session::idle_from`: the role gave up before the first of them, they were late, and
    /// it acted within the reaction bound of that first one).
    fn act_due(&self, slot: usize, f: &Frame, hops: u32) -> (Option<u64>, bool) {
        let s = &self.slots[slot];
        let a = &self.protos[s.proto];
        let mut total_ms: u64 = 0;
        let mut at = s.state;
        for _ in 0..hops {
            let Some(t) = a.timeout(at) else { break };
            total_ms = total_ms.saturating_add(t.ms);
            at = a.settle(t.next);
        }
        let total_us = total_ms.saturating_mul(1000);
        let due = s.entered_us.map(|e| e.saturating_add(total_us));
        let after_late = match (s.idle_from, s.late_from, f.time_us) {
            (Some(i), Some(m), Some(t)) => t >= i.saturating_add(total_us) && t <= m.saturating_add(self.reaction_us),
            _ => false,
        };
        (due, after_late)
    }

    /// Whether the waiting role's act after `hops` timeouts comes in time (`act_due`).
    fn act_in_time(&self, slot: usize, f: &Frame, hops: u32) -> bool {
        match (self.act_due(slot, f, hops), f.time_us) {
            ((Some(due), after_late), Some(t)) => t >= due || after_late,
            _ => false,
        }
    }

    /// The checks of a step, writing registers (old values in the undo log).
    pub(super) fn take(&mut self, slot: usize, f: &Frame) -> Result<(u32, u32), Fail> {
        let s = &mut self.slots[slot];
        let a = &self.protos[s.proto];
        // Strings of every field of the state's edges are saved once, in edge order (the
        // restore walks the same order).
        for fr in a.edges_of(s.state).iter().flat_map(|&e| a.edges[e as usize].fields.iter()) {
            if fr.kind == FieldKind::Str {
                let info = &a.arena.regs[fr.reg as usize];
                let (o, n) = (info.str_at as usize, info.str_cap as usize);
                self.undo_strs.extend_from_slice(&s.strs[o..o + n]);
            }
        }
        self.inferred.clear();
        let mut first_fail: Option<Fail> = None;
        let mut chosen = None;
        for &e in a.edges_of(s.state) {
            let edge = &a.edges[e as usize];
            if !label_fits(edge, f) || !ends_fit(a, edge, &s.roles, &self.kinds, f) {
                continue;
            }
            if !edge.observed.is_empty() {
                self.inferred.clear();
                let bound = super::stream::snapshot(a, &self.readings, s, e, f, &mut self.undo, &mut self.inferred);
                if let Err(fail) = bound {
                    first_fail.get_or_insert(fail);
                    continue;
                }
            }
            if let Some(g) = &edge.guard {
                s.evaluated[g.id as usize] += 1;
                let env = Env { regs: &s.regs, strs: &s.strs, arena: &a.arena, prog: &a.prog };
                match env.holds(g, &mut self.stats.fallbacks) {
                    Ok(true) => {}
                    Ok(false) => {
                        first_fail.get_or_insert(Fail {
                            kind: Kind::Guard,
                            edge: Some(e),
                            pred: Some(g.id),
                            field: None,
                            why: None,
                        });
                        continue;
                    }
                    Err(v) => {
                        first_fail.get_or_insert(verdict_fail(v, Some(e), g.id, None));
                        continue;
                    }
                }
            }
            chosen = Some(e);
            break;
        }
        let Some(e) = chosen else {
            return Err(first_fail.unwrap_or(Fail {
                kind: Kind::Unexpected,
                edge: None,
                pred: None,
                field: None,
                why: None,
            }));
        };
        let edge = &a.edges[e as usize];
        // Decode the listed fields into their registers.
        for (i, fr) in edge.fields.iter().enumerate() {
            let old = s.regs[fr.reg as usize];
            self.undo.push((fr.reg, old));
            let v = match fr.kind {
                FieldKind::Int | FieldKind::Float => match decode_num(fr, f.payload) {
                    Some(v) => v,
                    None => {
                        return Err(Fail {
                            kind: Kind::NonFinite,
                            edge: Some(e),
                            pred: None,
                            field: Some(i as u16),
                            why: None,
                        })
                    }
                },
                FieldKind::Str => {
                    let info = &a.arena.regs[fr.reg as usize];
                    let (o, n) = (info.str_at as usize, info.str_cap as usize);
                    let src = wire::read_str(f.payload, fr.slot);
                    let dst = &mut s.strs[o..o + n];
                    dst.fill(0);
                    dst[..src.len().min(n)].copy_from_slice(&src[..src.len().min(n)]);
                    Val::Str(fr.reg)
                }
            };
            s.regs[fr.reg as usize] = v;
        }
        s.taken[e as usize] += 1;
        let env = Env { regs: &s.regs, strs: &s.strs, arena: &a.arena, prog: &a.prog };
        for (i, fr) in edge.fields.iter().enumerate() {
            if let Some((c, _)) = &fr.entry {
                s.evaluated[c.id as usize] += 1;
                match env.holds(c, &mut self.stats.fallbacks) {
                    Ok(true) => {}
                    Ok(false) => {
                        return Err(Fail {
                            kind: Kind::Entry,
                            edge: Some(e),
                            pred: Some(c.id),
                            field: Some(i as u16),
                            why: None,
                        })
                    }
                    Err(v) => return Err(verdict_fail(v, Some(e), c.id, Some(i as u16))),
                }
            }
            if let Some(c) = &fr.refinement {
                s.evaluated[c.id as usize] += 1;
                match env.holds(c, &mut self.stats.fallbacks) {
                    Ok(true) => {}
                    Ok(false) => {
                        return Err(Fail {
                            kind: Kind::Refinement,
                            edge: Some(e),
                            pred: Some(c.id),
                            field: Some(i as u16),
                            why: None,
                        })
                    }
                    Err(v) => return Err(verdict_fail(v, Some(e), c.id, Some(i as u16))),
                }
            }
        }
        // Bind the ends: the sender fully, the receiver as far as the targets say.
        let (from, to) = (edge.from.idx(), edge.to.idx());
        s.roles[from] = Binding { sys: Some(f.sysid), comp: Some(f.compid) };
        let (ts, tc) = targets(edge, f);
        if let Some(t) = ts.filter(|&t| t != 0) {
            s.roles[to].sys.get_or_insert(t);
            if let Some(c) = tc.filter(|&c| c != 0) {
                s.roles[to].comp.get_or_insert(c);
            }
        }
        // The ends a snapshot read the stream from, when the session did not know them:
        // the role is the end whose state its sender decided on.
        for &(role, (sys, comp)) in &self.inferred {
            let taken =
                s.roles.iter().enumerate().any(|(k, b)| k != role && b.sys == Some(sys) && b.comp == Some(comp));
            let b = &mut s.roles[role];
            if !taken && b.sys.is_none_or(|x| x == sys) && b.comp.is_none_or(|x| x == comp) {
                *b = Binding { sys: Some(sys), comp: Some(comp) };
            }
        }
        let target = edge.target_state;
        let next = self.settle(slot, target).map_err(|mut fail| {
            fail.edge = Some(e);
            fail
        })?;
        Ok((next, e))
    }

    /// Follows the assignments from `s` to the branch or end they lead to.
    pub(super) fn settle(&mut self, slot: usize, mut at: u32) -> Result<u32, Fail> {
        let sess = &mut self.slots[slot];
        let a = &self.protos[sess.proto];
        for _ in 0..=a.states.len() {
            sess.visited[at as usize] = true;
            let StateKind::Assign { assigns, checks, next, .. } = &a.states[at as usize] else { return Ok(at) };
            self.args.clear();
            {
                let env = Env { regs: &sess.regs, strs: &sess.strs, arena: &a.arena, prog: &a.prog };
                for (_, c) in assigns {
                    match env.value(c, &mut self.stats.fallbacks) {
                        Ok(v) => self.args.push(v),
                        Err(v) => return Err(verdict_fail(v, None, c.id, None)),
                    }
                }
            }
            for ((r, _), v) in assigns.iter().zip(&self.args) {
                self.undo.push((*r, sess.regs[*r as usize]));
                sess.regs[*r as usize] = *v;
            }
            let env = Env { regs: &sess.regs, strs: &sess.strs, arena: &a.arena, prog: &a.prog };
            for (_, c) in checks {
                sess.evaluated[c.id as usize] += 1;
                match env.holds(c, &mut self.stats.fallbacks) {
                    Ok(true) => {}
                    Ok(false) => {
                        return Err(Fail {
                            kind: Kind::Invariant,
                            edge: None,
                            pred: Some(c.id),
                            field: None,
                            why: None,
                        })
                    }
                    Err(v) => return Err(verdict_fail(v, None, c.id, None)),
                }
            }
            at = *next;
        }
        Ok(at)
    }

    pub(super) fn close(&mut self, slot: usize, conformant: bool, keep: bool) {
        if let Some(k) = self.open.iter().position(|&i| i == slot) {
            self.open.swap_remove(k);
        }
        if keep {
            self.stats.sessions_ended += 1;
            let s = &self.slots[slot];
            self.summaries.push(summary(s, conformant));
        } else {
            self.stats.sessions_started -= 1;
        }
        self.free[self.slots[slot].proto].push(slot);
    }
}

/// Whether the frame is a first message after timeouts from `state`: the number of
/// timeouts taken in a row (each the waiting role giving up on the state it leaves) and
/// their bounds' sum in milliseconds, when an edge of the state they lead to fits the frame.
pub(super) fn timeout_chain(
    a: &Automaton,
    state: u32,
    roles: &[Binding],
    kinds: &[EndOf],
    f: &Frame,
) -> Option<(u32, u64)> {
    let mut at = state;
    let mut ms: u64 = 0;
    for hop in 1..=a.states.len() as u32 {
        let t = a.timeout(at)?;
        ms = ms.saturating_add(t.ms);
        at = a.settle(t.next);
        let fits = a
            .edges_of(at)
            .iter()
            .any(|&e| label_fits(&a.edges[e as usize], f) && ends_fit(a, &a.edges[e as usize], roles, kinds, f));
        if fits {
            return Some((hop, ms));
        }
    }
    None
}

/// Whether a session in `state`, entered at `entered`, ended by time before `clock`: a
/// chain of timeouts from `state` reaches `end`, and their bounds' sum passed.
pub(super) fn ends_by_time(a: &Automaton, state: u32, entered: Option<u64>, clock: Option<u64>) -> bool {
    match (end_deadline(a, state, entered), clock) {
        (Some(due), Some(clock)) => clock >= due,
        _ => false,
    }
}

/// The instant (µs of the frames' clock) from which a session in `state`, entered at
/// `entered`, has ended by time: when a chain of timeouts from `state` reaches `end`, the
/// entry time plus their bounds' sum.
pub(super) fn end_deadline(a: &Automaton, state: u32, entered: Option<u64>) -> Option<u64> {
    let entered = entered?;
    let mut at = state;
    let mut ms: u64 = 0;
    for _ in 0..a.states.len() {
        let t = a.timeout(at)?;
        ms = ms.saturating_add(t.ms);
        at = a.settle(t.next);
        if matches!(a.states[at as usize], StateKind::End) {
            return Some(entered.saturating_add(ms.saturating_mul(1000)));
        }
    }
    None
}

/// Whether the frame is the edge's message (and key, for `COMMAND_LONG[MAV_CMD_X]` and
/// `PARAM_VALUE["MC_PITCH_P"]`).
#[inline]
pub(super) fn label_fits(e: &Edge, f: &Frame) -> bool {
    e.msgid == f.msgid && super::automaton::key_fits(&e.key, f.payload)
}

/// The frame's `target_system` and `target_component`, when the message has them.
pub(super) fn targets(e: &Edge, f: &Frame) -> (Option<u8>, Option<u8>) {
    targets_of(e.target, f)
}

/// The values at these target slots of the frame's payload.
pub(super) fn targets_of(slots: (Option<wire::Slot>, Option<wire::Slot>), f: &Frame) -> (Option<u8>, Option<u8>) {
    let get = |s: Option<wire::Slot>| {
        s.map(|s| match wire::read(f.payload, s, 0) {
            Scalar::Int(i) => i as u8,
            _ => 0,
        })
    };
    (get(slots.0), get(slots.1))
}

/// Whether the frame's ends fit the session's bindings: the sender is the edge's sender
/// role (or that role is unbound and the sender plays no other role), and the targets, when
/// the message has them and they are not broadcast (0), are the receiver role's; and the
/// ends are of the kinds the roles ask ([`kinds_fit`]).
#[inline]
pub(super) fn ends_fit(a: &Automaton, e: &Edge, roles: &[Binding], kinds: &[EndOf], f: &Frame) -> bool {
    if !kinds_fit(a, e, kinds, f) {
        return false;
    }
    let from = roles[e.from.idx()];
    let sender_ok = match (from.sys, from.comp) {
        (Some(s), Some(c)) => s == f.sysid && c == f.compid,
        (s, c) => {
            s.is_none_or(|s| s == f.sysid)
                && c.is_none_or(|c| c == f.compid)
                && !roles
                    .iter()
                    .enumerate()
                    .any(|(k, b)| k != e.from.idx() && b.sys == Some(f.sysid) && b.comp == Some(f.compid))
        }
    };
    if !sender_ok {
        return false;
    }
    let to = roles[e.to.idx()];
    let (ts, tc) = targets(e, f);
    match ts {
        None | Some(0) => true,
        Some(t) => {
            to.sys.is_none_or(|s| s == t)
                && match tc {
                    None | Some(0) => true,
                    Some(c) => to.comp.is_none_or(|x| x == c),
                }
        }
    }
}

/// Whether the frame can start a session of `a`: a first edge of its start state fits it
/// with no role bound.
pub(super) fn vec_fresh_check(a: &Automaton, kinds: &[EndOf], f: &Frame) -> bool {
    let none = [Binding::default(); 64];
    let roles = &none[..a.roles.len().min(64)];
    a.edges_of(a.settle(a.start))
        .iter()
        .any(|&e| label_fits(&a.edges[e as usize], f) && ends_fit(a, &a.edges[e as usize], roles, kinds, f))
}

/// An end's kind, as its latest HEARTBEAT declared it.
pub(super) type EndOf = ((u8, u8), EndKind);

/// The kind of end `(sys, comp)` (unknown when it sent no HEARTBEAT).
#[inline]
pub(super) fn kind_of(kinds: &[EndOf], end: (u8, u8)) -> EndKind {
    kinds.iter().find(|(e, _)| *e == end).map_or(EndKind::Unknown, |(_, k)| *k)
}

/// Whether the frame's ends may play the edge's roles by their kinds: the source's kind is
/// admitted by the sender role's, and the target's (when the message names one end, system
/// and component, neither broadcast) by the receiver role's. A vehicle's MISSION_COUNT
/// (the answer of a download) is no upload's first message when the upload's `GCS` must be
/// a ground station.
#[inline]
pub(super) fn kinds_fit(a: &Automaton, e: &Edge, kinds: &[EndOf], f: &Frame) -> bool {
    if kinds.is_empty() {
        return true;
    }
    let (from, to) = (a.role_kinds[e.from.idx()], a.role_kinds[e.to.idx()]);
    if !from.admits(kind_of(kinds, (f.sysid, f.compid))) {
        return false;
    }
    match targets(e, f) {
        (Some(s), Some(c)) if s != 0 && c != 0 => to.admits(kind_of(kinds, (s, c))),
        _ => true,
    }
}

/// A numeric field's value: an integer, or a float as the exact rational it is (`None`: NaN
/// or infinite, outside the static model).
pub(super) fn decode_num(fr: &FieldRead, payload: &[u8]) -> Option<Val> {
    match fr.kind {
        FieldKind::Int => Some(match wire::read(payload, fr.slot, 0) {
            Scalar::Int(i) => Val::Num(Q::int(i)),
            _ => Val::Unset,
        }),
        FieldKind::Float => {
            let x = match wire::read(payload, fr.slot, 0) {
                Scalar::F32(x) => f64::from(x),
                Scalar::F64(x) => x,
                Scalar::Int(i) => i as f64,
            };
            if !x.is_finite() {
                return None;
            }
            Some(match Q::from_f64(x) {
                Some(q) => Val::Num(q),
                None => Val::Wide(x),
            })
        }
        FieldKind::Str => None,
    }
}
