//! The run-time monitor: refined MAVLink sessions enforced on a stream of frames (DATUM,
//! seed 000 Sec 2 and 4).
//!
//! A verified protocol (a lowered program whose choreography `mochi check` verifies) is
//! compiled once into a flat [`Automaton`]; a [`Monitor`] runs any number of them over one
//! stream of [`Frame`]s. For each frame it answers an [`Outcome`]:
//!
//! - [`Outcome::Passed`]: the message is outside every protocol's alphabet (telemetry);
//! - [`Outcome::Step`]: a session took it (the session and its new state);
//! - [`Outcome::Ended`]: a session took it and reached `end`, conformant;
//! - [`Outcome::Violation`]: it broke a session (or fits none): [`Monitor::violation`]
//!   has the frame, time, protocol state, the guard or refinement that failed with its
//!   source span, the values it read and the local state of each role, and
//!   [`Monitor::describe`] renders it. The session stays where it was: the message is not
//!   delivered to the protocol (a proxy drops it).
//!
//! At the end of the stream, [`Monitor::finish`] reports every session: conformant, or
//! incomplete (ended in a non-final state), with its coverage (states visited, branches
//! taken, predicates evaluated). `docs/monitor.md` explains what is enforced and why.
//!
//! ```
//! use mochi_monitor::monitor::{Automaton, Monitor, Outcome};
//! use mochi_monitor::mavio::Frame;
//! let mut db = mochi_monitor::source::SourceDb::new();
//! let src = "dialect common;
//! system S { participant GCS; participant UAV; }
//! choreography C =
//!   GCS -> UAV: MISSION_CLEAR_ALL(mission_type {mission_type == MAV_MISSION_TYPE_MISSION}).
//!   UAV -> GCS: MISSION_ACK(type {type == MAV_MISSION_ACCEPTED}).
//!   end;";
//! let file = db.add("clear.chor", src);
//! let mut no_imports = |_: &std::path::Path| Err(std::io::Error::other("no imports"));
//! let prog = mochi_verify::driver::prepare(&mut db, file, &mut no_imports, mochi_verify::driver::Stage::Names)
//!     .expect("lowered");
//! let mut m = Monitor::new(vec![Automaton::compile(&prog).expect("compiled")]);
//! let frame = |sysid, compid, msgid, payload: &[u8]| Frame {
//!     time_us: None, version: 2, sysid, compid, msgid, payload: payload.to_vec().leak(),
//!     signed: false, raw: &[],
//! };
//! // MISSION_CLEAR_ALL (45): target 1/1, mission_type 0; MISSION_ACK (47): target 255/190, type 0.
//! assert!(matches!(m.on_frame(&frame(255, 190, 45, &[1, 1, 0])), Outcome::Step { .. }));
//! assert!(matches!(m.on_frame(&frame(1, 1, 0, &[0; 9])), Outcome::Passed)); // a HEARTBEAT
//! assert!(matches!(m.on_frame(&frame(1, 1, 47, &[255, 190, 0, 0])), Outcome::Ended { .. }));
//! // An ACK nobody asked for: in the alphabet, in no session.
//! let Outcome::Violation(v) = m.on_frame(&frame(1, 1, 47, &[255, 190, 0, 0])) else { panic!() };
//! assert!(m.describe(&db, v).contains("outside any session"));
//! ```

pub mod automaton;
pub mod code;
pub mod num;
pub mod wire;

pub use automaton::{Automaton, CompileError, Edge, FieldKind, StateKind};
pub use code::Val;

use crate::mavio::Frame;
use code::{Env, Verdict};
use num::Q;
use wire::Scalar;

/// What the monitor made of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Not in any monitored protocol's alphabet: passed through untouched.
    Passed,
    /// A session took the message; `state` is its state now.
    Step { session: u64, state: u32 },
    /// A session took the message and ended, conformant.
    Ended { session: u64 },
    /// The message breaks a session or fits none: an index for [`Monitor::violation`].
    Violation(usize),
}

/// What kind of rule a message broke.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The guard of the branch the message's label picks is false.
    Guard,
    /// A listed field's refinement is false.
    Refinement,
    /// A listed field of an enum type holds no entry (or a bitmask a bit no flag has).
    Entry,
    /// A listed `float`/`double` field is NaN or infinite (outside the static model).
    NonFinite,
    /// A guard, refinement or recursion argument applies a partial operator outside its
    /// domain (a division by zero).
    Undefined,
    /// Exact evaluation could not decide a predicate (never passed).
    Undecided,
    /// A recursion parameter's refinement fails after a jump.
    Invariant,
    /// The message is between the ends of a session that does not expect it here.
    Unexpected,
    /// The message is in a protocol's alphabet, fits no open session and cannot start one.
    OutsideSession,
}

impl Kind {
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Guard => "guard",
            Kind::Refinement => "refinement",
            Kind::Entry => "enum entry",
            Kind::NonFinite => "non-finite float",
            Kind::Undefined => "undefined",
            Kind::Undecided => "undecided",
            Kind::Invariant => "loop invariant",
            Kind::Unexpected => "unexpected message",
            Kind::OutsideSession => "outside any session",
        }
    }
}

/// How a role is bound to a MAVLink end: system and component ids, each once known.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Binding {
    pub sys: Option<u8>,
    pub comp: Option<u8>,
}

/// A violation, with what is needed to explain it (rendered by [`Monitor::describe`]).
#[derive(Clone, Debug)]
pub struct Violation {
    pub frame: u64,
    pub time_us: Option<u64>,
    pub kind: Kind,
    /// The protocol (index in the monitor), when the message fits one's ends.
    pub protocol: Option<usize>,
    pub session: Option<u64>,
    /// The protocol state the session was in.
    pub state: u32,
    pub edge: Option<u32>,
    /// The failed predicate's index among the protocol's predicates, and which field.
    pub pred: Option<u32>,
    pub field: Option<String>,
    pub why: Option<&'static str>,
    pub msgid: u32,
    pub from: (u8, u8),
    /// The registers and string area at the check (the message's fields written).
    pub regs: Vec<Val>,
    pub strs: Vec<u8>,
    pub roles: Vec<Binding>,
}

/// What a session did, at its end or at the end of the stream.
#[derive(Clone, Debug)]
pub struct SessionSummary {
    pub session: u64,
    pub protocol: usize,
    /// `true`: reached `end`; `false`: incomplete (the stream ended or it was abandoned).
    pub conformant: bool,
    pub state: u32,
    pub first_frame: u64,
    pub last_frame: u64,
    pub violations: u32,
    pub roles: Vec<Binding>,
    /// States visited, edges taken (times each), predicates evaluated (times each).
    pub visited: Vec<bool>,
    pub taken: Vec<u32>,
    pub evaluated: Vec<u32>,
}

/// Counters over the whole stream.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    pub frames: u64,
    pub passed: u64,
    pub steps: u64,
    pub violations: u64,
    pub sessions_started: u64,
    pub sessions_ended: u64,
    /// Predicates evaluated over big rationals because the fixed width did not suffice.
    pub fallbacks: u64,
}

struct Session {
    id: u64,
    proto: usize,
    state: u32,
    regs: Vec<Val>,
    strs: Vec<u8>,
    roles: Vec<Binding>,
    first_frame: u64,
    last_frame: u64,
    violations: u32,
    visited: Vec<bool>,
    taken: Vec<u32>,
    evaluated: Vec<u32>,
}

/// The monitor: protocols, their open sessions, and what it found.
pub struct Monitor {
    protos: Vec<Automaton>,
    /// Session slots; `open` lists those in use, `free` per protocol those to reuse (their
    /// buffers, sized for that protocol, kept: a new session allocates nothing once a slot
    /// of its protocol exists).
    slots: Vec<Session>,
    open: Vec<usize>,
    free: Vec<Vec<usize>>,
    next_id: u64,
    undo: Vec<(u16, Val)>,
    undo_strs: Vec<u8>,
    args: Vec<Val>,
    violations: Vec<Violation>,
    summaries: Vec<SessionSummary>,
    pub stats: Stats,
}

/// A failure inside a step, before it is recorded.
struct Fail {
    kind: Kind,
    edge: Option<u32>,
    pred: Option<u32>,
    field: Option<u16>,
    why: Option<&'static str>,
}

impl Monitor {
    /// A monitor of these protocols.
    pub fn new(protos: Vec<Automaton>) -> Monitor {
        let undo = protos.iter().map(|a| a.arena.regs.len()).max().unwrap_or(0);
        let strs = protos.iter().map(|a| a.arena.str_size as usize).max().unwrap_or(0);
        let n = protos.len();
        Monitor {
            protos,
            slots: Vec::new(),
            open: Vec::with_capacity(16),
            free: (0..n).map(|_| Vec::with_capacity(16)).collect(),
            next_id: 0,
            undo: Vec::with_capacity(undo * 2 + 8),
            undo_strs: Vec::with_capacity(strs),
            args: Vec::with_capacity(undo + 8),
            violations: Vec::new(),
            summaries: Vec::new(),
            stats: Stats::default(),
        }
    }

    pub fn protocols(&self) -> &[Automaton] {
        &self.protos
    }

    pub fn violation(&self, i: usize) -> Option<&Violation> {
        self.violations.get(i)
    }

    pub fn violations(&self) -> &[Violation] {
        &self.violations
    }

    /// The sessions that ended so far (and, after [`Monitor::finish`], every session).
    pub fn summaries(&self) -> &[SessionSummary] {
        &self.summaries
    }

    /// Monitors one frame (the hot path: no allocation unless a session starts in a new
    /// slot, ends, or a violation is recorded).
    pub fn on_frame(&mut self, f: &Frame) -> Outcome {
        let index = self.stats.frames;
        self.stats.frames += 1;
        let mut result = None;
        let mut in_alphabet = false;
        for p in 0..self.protos.len() {
            if !self.protos[p].in_alphabet(f.msgid) {
                continue;
            }
            in_alphabet = true;
            if let Some(o) = self.on_protocol(p, f, index) {
                // With several protocols, a violation wins over a step.
                result = match (result, o) {
                    (Some(Outcome::Violation(v)), _) => Some(Outcome::Violation(v)),
                    _ => Some(o),
                };
            }
        }
        match result {
            Some(o) => o,
            None if in_alphabet => {
                let v = self.record(
                    None,
                    None,
                    f,
                    index,
                    Fail { kind: Kind::OutsideSession, edge: None, pred: None, field: None, why: None },
                );
                Outcome::Violation(v)
            }
            None => {
                self.stats.passed += 1;
                Outcome::Passed
            }
        }
    }

    /// The frame against protocol `p`: a step of an open session, the start of a new one,
    /// an unexpected message between a session's ends, or `None` (it fits nothing).
    fn on_protocol(&mut self, p: usize, f: &Frame, index: u64) -> Option<Outcome> {
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
                if label_fits(&a.edges[e as usize], f) && ends_fit(&a.edges[e as usize], &s.roles, f) {
                    found = true;
                    break;
                }
            }
            if found {
                return Some(self.step(slot, f, index));
            }
            if between_ends.is_none() && s.roles.iter().any(|b| b.sys == Some(f.sysid) && b.comp == Some(f.compid)) {
                between_ends = Some(slot);
            }
        }
        let a = &self.protos[p];
        let fresh = vec_fresh_check(a, f);
        if fresh {
            let slot = self.start(p, index);
            let o = self.step(slot, f, index);
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

    fn start(&mut self, p: usize, index: u64) -> usize {
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
    fn step(&mut self, slot: usize, f: &Frame, index: u64) -> Outcome {
        let p = self.slots[slot].proto;
        let state = self.slots[slot].state;
        self.undo.clear();
        self.undo_strs.clear();
        match self.take(slot, f) {
            Ok(next) => {
                let s = &mut self.slots[slot];
                s.state = next;
                s.last_frame = index;
                s.visited[next as usize] = true;
                self.stats.steps += 1;
                if matches!(self.protos[p].states[next as usize], StateKind::End) {
                    let id = s.id;
                    self.close(slot, true, true);
                    Outcome::Ended { session: id }
                } else {
                    Outcome::Step { session: self.slots[slot].id, state: next }
                }
            }
            Err(fail) => {
                let v = self.record(Some(slot), Some(state), f, index, fail);
                // Not delivered: the session stays where it was.
                let s = &mut self.slots[slot];
                while let Some((r, v)) = self.undo.pop() {
                    s.regs[r as usize] = v;
                }
                let a = &self.protos[p];
                let mut at = 0;
                for fr in a.edges_of(state).iter().flat_map(|&e| a.edges[e as usize].fields.iter()) {
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

    /// The checks of a step, writing registers (old values in the undo log).
    fn take(&mut self, slot: usize, f: &Frame) -> Result<u32, Fail> {
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
        let mut first_fail: Option<Fail> = None;
        let mut chosen = None;
        for &e in a.edges_of(s.state) {
            let edge = &a.edges[e as usize];
            if !label_fits(edge, f) || !ends_fit(edge, &s.roles, f) {
                continue;
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
                        first_fail.get_or_insert(verdict_fail(v, e, g.id, None));
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
                FieldKind::Int => match wire::read(f.payload, fr.slot, 0) {
                    Scalar::Int(i) => Val::Num(Q::int(i)),
                    _ => Val::Unset,
                },
                FieldKind::Float => {
                    let x = match wire::read(f.payload, fr.slot, 0) {
                        Scalar::F32(x) => f64::from(x),
                        Scalar::F64(x) => x,
                        Scalar::Int(i) => i as f64,
                    };
                    if !x.is_finite() {
                        return Err(Fail {
                            kind: Kind::NonFinite,
                            edge: Some(e),
                            pred: None,
                            field: Some(i as u16),
                            why: None,
                        });
                    }
                    match Q::from_f64(x) {
                        Some(q) => Val::Num(q),
                        None => Val::Wide(x),
                    }
                }
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
                    Err(v) => return Err(verdict_fail(v, e, c.id, Some(i as u16))),
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
                    Err(v) => return Err(verdict_fail(v, e, c.id, Some(i as u16))),
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
        let target = edge.target_state;
        self.settle(slot, target).map_err(|mut fail| {
            fail.edge = Some(e);
            fail
        })
    }

    /// Follows the assignments from `s` to the branch or end they lead to.
    fn settle(&mut self, slot: usize, mut at: u32) -> Result<u32, Fail> {
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
                        Err(Verdict::Undefined(why)) => {
                            return Err(Fail {
                                kind: Kind::Undefined,
                                edge: None,
                                pred: Some(c.id),
                                field: None,
                                why: Some(why),
                            })
                        }
                        Err(Verdict::Undecided) => {
                            return Err(Fail {
                                kind: Kind::Undecided,
                                edge: None,
                                pred: Some(c.id),
                                field: None,
                                why: None,
                            })
                        }
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
                    Err(Verdict::Undefined(why)) => {
                        return Err(Fail {
                            kind: Kind::Undefined,
                            edge: None,
                            pred: Some(c.id),
                            field: None,
                            why: Some(why),
                        })
                    }
                    Err(Verdict::Undecided) => {
                        return Err(Fail {
                            kind: Kind::Undecided,
                            edge: None,
                            pred: Some(c.id),
                            field: None,
                            why: None,
                        })
                    }
                }
            }
            at = *next;
        }
        Ok(at)
    }

    fn record(&mut self, slot: Option<usize>, state: Option<u32>, f: &Frame, index: u64, fail: Fail) -> usize {
        self.stats.violations += 1;
        let s = slot.map(|i| &self.slots[i]);
        let field = match (s, fail.edge, fail.field) {
            (Some(s), Some(e), Some(i)) => {
                self.protos[s.proto].edges[e as usize].fields.get(i as usize).map(|fr| fr.name.clone())
            }
            _ => None,
        };
        self.violations.push(Violation {
            frame: index,
            time_us: f.time_us,
            kind: fail.kind,
            protocol: s.map(|s| s.proto),
            session: s.map(|s| s.id),
            state: state.unwrap_or(0),
            edge: fail.edge,
            pred: fail.pred,
            field,
            why: fail.why,
            msgid: f.msgid,
            from: (f.sysid, f.compid),
            regs: s.map(|s| s.regs.clone()).unwrap_or_default(),
            strs: s.map(|s| s.strs.clone()).unwrap_or_default(),
            roles: s.map(|s| s.roles.clone()).unwrap_or_default(),
        });
        self.violations.len() - 1
    }

    fn close(&mut self, slot: usize, conformant: bool, keep: bool) {
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

    /// Ends the stream: every open session is reported incomplete. Returns all summaries.
    pub fn finish(&mut self) -> &[SessionSummary] {
        let mut open = std::mem::take(&mut self.open);
        open.sort_by_key(|&i| self.slots[i].id);
        for slot in open {
            self.summaries.push(summary(&self.slots[slot], false));
            self.free[self.slots[slot].proto].push(slot);
        }
        &self.summaries
    }

    /// A violation in words: what broke, where in the source, the values involved, and each
    /// role's local state (its binding and the values it knows).
    pub fn describe(&self, db: &crate::source::SourceDb, i: usize) -> String {
        let Some(v) = self.violations.get(i) else { return String::new() };
        let mut out = format!("frame {}", v.frame);
        if let Some(t) = v.time_us {
            out += &format!(" (t = {t} us)");
        }
        out += &format!(": message {} from {}/{}: {}", v.msgid, v.from.0, v.from.1, v.kind.as_str());
        let Some(p) = v.protocol else {
            return out;
        };
        let a = &self.protos[p];
        out += &format!(" in `{}` (session {}, state {})", a.name, v.session.unwrap_or(0), v.state);
        if let Some(e) = v.edge.and_then(|e| a.edges.get(e as usize)) {
            out += &format!(", at `{} -> {} : {}`", a.roles[e.from.idx()], a.roles[e.to.idx()], e.label);
        }
        if let Some(f) = &v.field {
            out += &format!(", field `{f}`");
        }
        if let Some(why) = v.why {
            out += &format!(": {why}");
        }
        if let Some(code) = v.pred.and_then(|id| find_code(a, id)) {
            let (file, line, col) = db.location(code.expr.loc.0);
            let text = crate::hir::print::expr(&a.prog, None, &code.expr);
            out += &format!("\n  {file}:{line}:{col}: `{text}`");
            let mut names = Vec::new();
            code.expr.visit_vars(&mut |var, _| {
                if let crate::hir::Var::Value(id, name) = var {
                    if let Some(r) = a.arena.reg_of.get(id) {
                        if !names.iter().any(|(n, _): &(String, u16)| n == name) {
                            names.push((name.clone(), *r));
                        }
                    }
                }
            });
            for (n, r) in names {
                out += &format!("\n  {n} = {}", show(a, &v.regs, &v.strs, r));
            }
        }
        for (k, role) in a.roles.iter().enumerate() {
            let b = v.roles.get(k).copied().unwrap_or_default();
            let end = |x: Option<u8>| x.map_or("?".to_string(), |x| x.to_string());
            out += &format!("\n  role {role} ({}/{}) knows:", end(b.sys), end(b.comp));
            for (r, info) in a.arena.regs.iter().enumerate() {
                if info.knowers >> k & 1 == 1 && !matches!(v.regs.get(r), None | Some(Val::Unset)) {
                    out += &format!(" {} = {};", info.name, show(a, &v.regs, &v.strs, r as u16));
                }
            }
        }
        out
    }
}

fn find_code(a: &Automaton, id: u32) -> Option<&code::Code> {
    for e in &a.edges {
        for c in e
            .guard
            .iter()
            .chain(e.fields.iter().flat_map(|f| f.refinement.iter().chain(f.entry.iter().map(|(c, _)| c))))
        {
            if c.id == id {
                return Some(c);
            }
        }
    }
    for s in &a.states {
        if let StateKind::Assign { assigns, checks, .. } = s {
            for (_, c) in assigns.iter().chain(checks) {
                if c.id == id {
                    return Some(c);
                }
            }
        }
    }
    None
}

fn show(a: &Automaton, regs: &[Val], strs: &[u8], r: u16) -> String {
    match regs.get(r as usize).copied().unwrap_or(Val::Unset) {
        Val::Unset => "(not set)".into(),
        Val::Bool(b) => b.to_string(),
        Val::Num(q) => crate::exact::decimal(&code::q_to_rat(q)),
        Val::Wide(x) => format!("{x:e}"),
        Val::Lit(c) => format!("{:?}", a.prog.strings.get(c as usize).map_or("", String::as_str)),
        Val::Str(reg) => {
            let info = &a.arena.regs[reg as usize];
            let bytes = strs.get(info.str_at as usize..info.str_at as usize + info.str_cap as usize).unwrap_or(&[]);
            format!("{:?}", String::from_utf8_lossy(code::cut(bytes)))
        }
    }
}

fn summary(s: &Session, conformant: bool) -> SessionSummary {
    SessionSummary {
        session: s.id,
        protocol: s.proto,
        conformant,
        state: s.state,
        first_frame: s.first_frame,
        last_frame: s.last_frame,
        violations: s.violations,
        roles: s.roles.clone(),
        visited: s.visited.clone(),
        taken: s.taken.clone(),
        evaluated: s.evaluated.clone(),
    }
}

fn verdict_fail(v: Verdict, e: u32, pred: u32, field: Option<u16>) -> Fail {
    match v {
        Verdict::Undefined(why) => {
            Fail { kind: Kind::Undefined, edge: Some(e), pred: Some(pred), field, why: Some(why) }
        }
        Verdict::Undecided => Fail { kind: Kind::Undecided, edge: Some(e), pred: Some(pred), field, why: None },
    }
}

/// Resizes `v` to `n` copies of `x` (no allocation once its capacity suffices).
fn reset<T: Clone>(v: &mut Vec<T>, n: usize, x: T) {
    v.clear();
    v.resize(n, x);
}

/// Whether the frame is the edge's message (and command, for `COMMAND_LONG[MAV_CMD_X]`).
#[inline]
fn label_fits(e: &Edge, f: &Frame) -> bool {
    e.msgid == f.msgid
        && match e.command {
            Some((slot, cmd)) => wire::read(f.payload, slot, 0) == Scalar::Int(cmd),
            None => true,
        }
}

/// The frame's `target_system` and `target_component`, when the message has them.
fn targets(e: &Edge, f: &Frame) -> (Option<u8>, Option<u8>) {
    let get = |s: Option<wire::Slot>| {
        s.map(|s| match wire::read(f.payload, s, 0) {
            Scalar::Int(i) => i as u8,
            _ => 0,
        })
    };
    (get(e.target.0), get(e.target.1))
}

/// Whether the frame's ends fit the session's bindings: the sender is the edge's sender
/// role (or that role is unbound and the sender plays no other role), and the targets, when
/// the message has them and they are not broadcast (0), are the receiver role's.
#[inline]
fn ends_fit(e: &Edge, roles: &[Binding], f: &Frame) -> bool {
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
fn vec_fresh_check(a: &Automaton, f: &Frame) -> bool {
    let none = [Binding::default(); 64];
    let roles = &none[..a.roles.len().min(64)];
    a.edges_of(a.settle(a.start))
        .iter()
        .any(|&e| label_fits(&a.edges[e as usize], f) && ends_fit(&a.edges[e as usize], roles, f))
}

#[cfg(test)]
mod tests;
