//! Streams and observed state (docs/observed-and-timeouts.md, "Monitor obligations"): a
//! stream's message is never a step; it is checked against the stream's refinements and, if
//! it holds, becomes the latest reading of its sender's end; a step that reads observed
//! state binds each snapshot to the latest reading its sender has, once, at its arrival.
//!
//! Which obligation is enforced where:
//!
//! 1. classifying a frame: [`Monitor::on_stream`] (a frame is a stream message of a
//!    protocol, whatever state its sessions are in, when its label is a stream's and its
//!    source is the stream's sender; see there how an end no session has bound yet is
//!    classified);
//! 2. checking a stream message: [`Monitor::on_stream`] (wire range, enum, invariant;
//!    a failure is no reading, and a [`Kind::Stream`] violation when its end is bound as the
//!    stream's sender in an open session; from any other end it passes, and the end's
//!    earlier readings are forgotten);
//! 3. the latest value: [`Reading`], one per protocol, stream, sender end and target;
//! 4. taking a snapshot: [`snapshot`], called by the step before its guard;
//! 5. no reading yet: [`snapshot`] fails with [`Kind::NoReading`], the guard and
//!    refinements are not evaluated;
//! 6. what the other end learns: nothing here: the receiver's local type does not read the
//!    sender's snapshot (`project::knows`), and the compilation refuses a predicate that
//!    reads a value its sender does not know;
//! 7. staleness is not checked: a reading is used however old it is.

use super::automaton::{Automaton, StreamDef};
use super::code::{Env, Val};
use super::session::{decode_num, targets_of};
use super::{Binding, Fail, Kind, Monitor, Session, Violation};
use crate::mavio::Frame;

/// The latest accepted message of one stream from one end (to one target: `(0, 0)` when
/// the message has no target or broadcasts), its listed fields in stream field order.
pub(super) struct Reading {
    proto: u32,
    stream: u32,
    from: (u8, u8),
    target: (u8, u8),
    /// The frame index it arrived at: the latest of several readings is the largest.
    at: u64,
    vals: Vec<Val>,
}

/// What a frame is to one protocol's streams.
pub(super) enum Class {
    /// A stream message, accepted: the latest reading of its sender's end.
    Reading,
    /// A stream message breaking the stream's refinements: not a reading.
    Violation(usize),
    /// Not a stream message of this protocol: a candidate step.
    NotStream,
}

/// Whether the frame carries the stream's key (its command, or its name), if it has one.
fn key_fits(st: &StreamDef, f: &Frame) -> bool {
    super::automaton::key_fits(&st.key, f.payload)
}

impl Monitor {
    /// Whether the frame is a message of one of protocol `p`'s streams.
    ///
    /// Only a source of the kind the stream's sending role asks (`EndKind::admits`, as for a
    /// step) sends the stream: a ground station's HEARTBEAT is not a vehicle's. A frame whose
    /// label is a stream's is then that stream's message when its source is bound
    /// to the stream's sender in an open session of the protocol, or when the protocol has no
    /// step with that label. When it has one (a ground station sends HEARTBEAT as a step, the
    /// vehicle streams it), a source bound to another role in an open session
    /// sends a step; a source no session has bound is classified by the payload: the stream's
    /// message if the stream's refinements hold, otherwise a candidate step (which may start
    /// a session, or be a violation as any step). A reading from an end that is not the
    /// session's stream sender is never used by the session (readings are kept per end).
    /// A message breaking the stream's refinements is a violation only from an end bound as
    /// the stream's sender in an open session; from another end it is not this stream's (it
    /// passes unless a step takes it), and it erases that end's readings of the stream.
    pub(super) fn on_stream(&mut self, p: usize, f: &Frame, index: u64) -> Class {
        let src = (f.sysid, f.compid);
        for si in 0..self.protos[p].streams.len() {
            let a = &self.protos[p];
            let st = &a.streams[si];
            if st.msgid != f.msgid || !key_fits(st, f) {
                continue;
            }
            // As for a step (`session::kinds_fit`), the source must be an end of the kind the
            // stream's sending role asks: a ground station's own HEARTBEAT is no reading of a
            // vehicle's HEARTBEAT stream (nor a violation of its invariant).
            if !a.role_kinds[st.from.idx()].admits(super::session::kind_of(&self.kinds, src)) {
                continue;
            }
            let (mut as_sender, mut as_other) = (false, false);
            for &slot in &self.open {
                let s = &self.slots[slot];
                if s.proto != p {
                    continue;
                }
                for (k, b) in s.roles.iter().enumerate() {
                    if b.sys == Some(src.0) && b.comp == Some(src.1) {
                        if k == st.from.idx() {
                            as_sender = true;
                        } else {
                            as_other = true;
                        }
                    }
                }
            }
            let could_step = a.edges_with(f.msgid).iter().any(|&e| super::session::label_fits(&a.edges[e as usize], f));
            if could_step && as_other && !as_sender {
                continue;
            }
            let checked = check(a, st, f, &mut self.scratch, &mut self.stats.fallbacks);
            match checked {
                // From an end no session has bound, a frame that is a valid reading and
                // also a valid first step of a session is ambiguous: taken as a reading,
                // the session it starts would go unmonitored, and every later step of it
                // would be checked (if at all) as the start of another session. It starts
                // the session: a missed start could hide a violation, a spurious one
                // cannot (the stream's invariant tells the two apart where the protocol
                // writes one).
                Ok(()) if could_step && !as_sender && self.starts_cleanly(p, f, index) => return Class::NotStream,
                Ok(()) => {
                    let st = &self.protos[p].streams[si];
                    let target = match targets_of(st.target, f) {
                        (Some(s), Some(c)) => (s, c),
                        (Some(s), None) => (s, 0),
                        _ => (0, 0),
                    };
                    let vals = st.fields.iter().map(|fr| self.scratch[fr.reg as usize]);
                    match self
                        .readings
                        .iter_mut()
                        .find(|r| r.proto == p as u32 && r.stream == si as u32 && r.from == src && r.target == target)
                    {
                        Some(r) => {
                            r.at = index;
                            for (slot, v) in r.vals.iter_mut().zip(vals) {
                                *slot = v;
                            }
                        }
                        None => self.readings.push(Reading {
                            proto: p as u32,
                            stream: si as u32,
                            from: src,
                            target,
                            at: index,
                            vals: vals.collect(),
                        }),
                    }
                    self.stats.readings += 1;
                    return Class::Reading;
                }
                Err(fail) if as_sender => {
                    let st = &self.protos[p].streams[si];
                    self.stats.violations += 1;
                    let field = fail.field.and_then(|i| st.fields.get(i as usize)).map(|fr| fr.name.clone());
                    self.violations.push(Violation {
                        frame: index,
                        time_us: f.time_us,
                        kind: fail.kind,
                        protocol: Some(p),
                        session: None,
                        state: 0,
                        edge: None,
                        pred: fail.pred,
                        field,
                        why: fail.why,
                        msgid: f.msgid,
                        from: src,
                        regs: self.scratch.clone(),
                        strs: Vec::new(),
                        roles: Vec::new(),
                    });
                    return Class::Violation(self.taken_violations + self.violations.len() - 1);
                }
                // From an end no open session binds as the stream's sender, a message breaking
                // the stream's refinements is no reading: its end is none that plays the
                // sending role (a PX4 autopilot's, a camera's or a gimbal's HEARTBEAT, to a
                // protocol for ArduPilot quadrotors). Nor is it a violation: it is no step
                // (passed, unless a step takes it). But it is that end's latest message: an
                // earlier reading of it is forgotten, so no step reads a value older than its
                // sender's latest message (docs/monitor.md, "Streams and observed state").
                Err(_) => {
                    let (p, si) = (p as u32, si as u32);
                    self.readings.retain(|r| !(r.proto == p && r.stream == si && r.from == src));
                }
            }
        }
        Class::NotStream
    }

    /// Whether the frame would start a session of protocol `p` whose first step it passes
    /// (label, ends, guard, refinements), tried on a session that is then discarded: no
    /// session, violation or statistic is left of the trial.
    fn starts_cleanly(&mut self, p: usize, f: &Frame, index: u64) -> bool {
        if !super::session::vec_fresh_check(&self.protos[p], &self.kinds, f) {
            return false;
        }
        let (id, started) = (self.next_id, self.stats.sessions_started);
        let slot = self.start(p, index);
        self.undo.clear();
        self.undo_strs.clear();
        let ok = self.take(slot, f).is_ok();
        self.close(slot, false, false);
        self.next_id = id;
        self.stats.sessions_started = started;
        ok
    }
}

/// Decodes the stream's fields into the template registers of `regs` and checks them: the
/// enum membership, then the refinement (wire range, float format, invariant) of each.
fn check(a: &Automaton, st: &StreamDef, f: &Frame, regs: &mut [Val], fallbacks: &mut u64) -> Result<(), Fail> {
    for (i, fr) in st.fields.iter().enumerate() {
        match decode_num(fr, f.payload) {
            Some(v) => regs[fr.reg as usize] = v,
            None => {
                return Err(Fail { kind: Kind::NonFinite, edge: None, pred: None, field: Some(i as u16), why: None })
            }
        }
    }
    let env = Env { regs, strs: &[], arena: &a.arena, prog: &a.prog };
    for (i, fr) in st.fields.iter().enumerate() {
        for c in fr.entry.iter().map(|(c, _)| c).chain(fr.refinement.iter()) {
            match env.holds(c, fallbacks) {
                Ok(true) => {}
                Ok(false) => {
                    return Err(Fail {
                        kind: Kind::Stream,
                        edge: None,
                        pred: Some(c.id),
                        field: Some(i as u16),
                        why: None,
                    })
                }
                Err(v) => {
                    let mut fail = super::verdict_fail(v, None, c.id, Some(i as u16));
                    fail.why = fail.why.or(Some("the stream's refinement"));
                    return Err(fail);
                }
            }
        }
    }
    Ok(())
}

/// Binds the snapshots edge `e` reads to the latest readings its sender has (obligations 4
/// and 5), writing their registers (old values in `undo`). The stream sender's end is the
/// session's binding of the stream's sender role; when the session does not know it yet,
/// the frame's target (the stream's sender is the message's receiver), or else the one end
/// that has sent readings of the stream (not the frame's source, not an end bound to
/// another role); that end is pushed to `inferred`, to be bound if the step is taken.
/// Several such ends, or none, is no reading.
pub(super) fn snapshot(
    a: &Automaton,
    readings: &[Reading],
    s: &mut Session,
    e: u32,
    f: &Frame,
    undo: &mut Vec<(u16, Val)>,
    inferred: &mut Vec<(usize, (u8, u8))>,
) -> Result<(), Fail> {
    let edge = &a.edges[e as usize];
    let reader = (f.sysid, f.compid);
    let p = s.proto as u32;
    let no = |why: &'static str| Fail { kind: Kind::NoReading, edge: Some(e), pred: None, field: None, why: Some(why) };
    for o in &edge.observed {
        let st = &a.streams[o.stream as usize];
        let role = st.from.idx();
        let end = if st.from == edge.from {
            reader
        } else {
            let b = s.roles[role];
            match (b.sys, b.comp) {
                (Some(x), Some(y)) => (x, y),
                _ => {
                    let (ts, tc) = if st.from == edge.to { targets_of(edge.target, f) } else { (None, None) };
                    let want =
                        Binding { sys: b.sys.or(ts.filter(|&t| t != 0)), comp: b.comp.or(tc.filter(|&c| c != 0)) };
                    let mut found: Option<(u8, u8)> = None;
                    for r in readings.iter().filter(|r| r.proto == p && r.stream == o.stream) {
                        let other = s
                            .roles
                            .iter()
                            .enumerate()
                            .any(|(k, b)| k != role && b.sys == Some(r.from.0) && b.comp == Some(r.from.1));
                        if r.from == reader
                            || other
                            || want.sys.is_some_and(|x| x != r.from.0)
                            || want.comp.is_some_and(|x| x != r.from.1)
                        {
                            continue;
                        }
                        match found {
                            Some(end) if end != r.from => {
                                return Err(no(
                                    "readings of the stream from several ends, none of them bound to the session",
                                ))
                            }
                            _ => found = Some(r.from),
                        }
                    }
                    let Some(end) = found else { return Err(no("no reading of the stream yet")) };
                    inferred.push((role, end));
                    end
                }
            }
        };
        // The latest reading the sender has: its own, or one addressed to it (or broadcast).
        let own = st.from == edge.from;
        let latest = readings
            .iter()
            .filter(|r| {
                r.proto == p
                    && r.stream == o.stream
                    && r.from == end
                    && (own
                        || r.target.0 == 0
                        || (r.target.0 == reader.0 && (r.target.1 == 0 || r.target.1 == reader.1)))
            })
            .max_by_key(|r| r.at);
        let Some(r) = latest else { return Err(no("no reading of the stream yet")) };
        let Some(&v) = r.vals.get(o.field as usize) else { return Err(no("no reading of the stream yet")) };
        undo.push((o.reg, s.regs[o.reg as usize]));
        s.regs[o.reg as usize] = v;
    }
    Ok(())
}
