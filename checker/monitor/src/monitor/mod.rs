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
mod late;
pub mod num;
mod order;
mod report;
mod session;
mod stream;
pub mod wire;

pub use automaton::{Automaton, CompileError, Edge, EndKind, FieldKind, ObservedRead, StateKind, StreamDef};
pub use code::Val;

use crate::mavio::Frame;
use code::Verdict;
use report::summary;
use stream::Reading;

/// What the monitor made of one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Not in any monitored protocol's alphabet: passed through untouched.
    Passed,
    /// A session took the message; `state` is its state now.
    Step { session: u64, state: u32 },
    /// A session took the message and ended, conformant.
    Ended { session: u64 },
    /// A message of a branch its receiver abandoned by a timeout, arriving after it: the
    /// static checks assume the receiver ignores it (docs/observed-and-timeouts.md, "Late
    /// messages"), so it is no step and no violation, and a proxy that enforces drops it
    /// (a real vehicle might act on a late command).
    Late { session: u64 },
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
    /// A stream's message whose field breaks the stream's refinement (wire range, enum,
    /// invariant): not a reading.
    Stream,
    /// A step whose guard or refinements read an observed value of which its sender has no
    /// reading yet (or readings from several ends, none of them the session's).
    NoReading,
    /// The waiting role acted as after a timeout before the timeout's bound had passed
    /// since the choice was entered (a re-request too early).
    Early,
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
            Kind::Stream => "stream refinement",
            Kind::NoReading => "no reading",
            Kind::Early => "before its timeout",
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
    /// Stream messages accepted as readings (each also counted in `passed`).
    pub readings: u64,
    /// Predicates evaluated over big rationals because the fixed width did not suffice.
    pub fallbacks: u64,
    /// Timeout branches taken.
    pub timeouts: u64,
    /// Late messages: a first message of a branch its receiver abandoned by a timeout,
    /// ignored (each also counted in `passed`).
    pub late: u64,
    /// Sessions closed by time while the stream went on (each also in `sessions_ended`).
    pub ended_by_time: u64,
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
    /// When the current state was entered (the time of the frame that reached it, or, after
    /// a timeout, the earliest instant the timeout could fire), in µs of the frames' time.
    entered_us: Option<u64>,
    /// The states whose timeouts its waiting roles took, while late messages of their
    /// abandoned branches are ignored: until the other end's first step after the timeout
    /// that is none of the abandoned choice's messages, and at most until the end of each
    /// one's window in time, the waiting role's act plus the bound of the timeout it took
    /// (`session::fire`; docs/monitor.md, "Late messages").
    late: late::LateSet,
    /// A message of the current state's own choice that re-entered it (parameters
    /// unchanged) at least the timeout's bound after it was entered may have reached a
    /// waiting role that had given up: `late_from` is its arrival (the latest such gap's),
    /// `idle_from` the entry before it. The waiting role's act within the reaction bound of
    /// `late_from` is checked against `idle_from` (`session::fire`): the messages since
    /// were late. A late message never restarts a timeout.
    idle_from: Option<u64>,
    late_from: Option<u64>,
}

/// What [`Monitor::take_reports`] hands over: the recorded violations and the summaries of
/// the sessions that ended, each drained from the monitor.
pub struct Reports<'a> {
    pub violations: std::vec::Drain<'a, Violation>,
    pub summaries: std::vec::Drain<'a, SessionSummary>,
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
    /// How many violations [`Monitor::take_reports`] took: the first index in `violations`.
    taken_violations: usize,
    summaries: Vec<SessionSummary>,
    /// The latest reading of each stream from each end (`stream.rs`), a register file to
    /// check a stream message in, and the ends a step's snapshots bound a role to.
    readings: Vec<Reading>,
    scratch: Vec<Val>,
    inferred: Vec<(usize, (u8, u8))>,
    /// The latest frame time seen (the log's or the proxy's clock).
    clock: Option<u64>,
    /// Each end's kind, as its latest HEARTBEAT declared it (`session::kinds_fit`).
    kinds: Vec<session::EndOf>,
    /// Whether some protocol has a timeout branch (sessions may end by time).
    timed: bool,
    /// Sessions that ended by a timeout, whose abandoned choices' messages may still arrive
    /// within their late window (`late::Ghost`), oldest first, at most
    /// [`late::GHOSTS`].
    ghosts: Vec<late::Ghost>,
    /// How long after a waiting role's timeout fired its act may reach the log (µs):
    /// [`REACTION_US`] unless [`Monitor::set_reaction_bound`] says otherwise.
    reaction_us: u64,
    /// No open session ends by time before this instant (µs of the frames' clock): a lower
    /// bound of their deadlines (`session::end_deadline`), lowered by every step that sets
    /// one and recomputed by the scan it triggers, so that a frame before it scans nothing.
    end_due: u64,
    /// The ends whose kind [`Monitor::pin_end_kind`] fixed (HEARTBEATs do not change it).
    pinned: Vec<(u8, u8)>,
    pinned_kinds: bool,
    /// A bit per message id below [`SPOKEN_IDS`]: set when some protocol's alphabet or
    /// streams hold it. A frame whose bit is clear is outside every protocol: it passes
    /// without a look at any protocol (most of a real stream is such telemetry).
    spoken: Vec<u64>,
    /// For each message id some protocol speaks (sorted): the range of `id_protos` that
    /// lists the protocols whose alphabet or streams hold it, in protocol order. A frame
    /// visits only those.
    by_id: Vec<(u32, u32, u32)>,
    id_protos: Vec<u32>,
    pub stats: Stats,
}

/// The reaction bound's default: a waiting role acts (sends the first message of its
/// timeout branch) within 20 ms of its timeout firing, as the log sees it. A message of the
/// abandoned choice that the log shows before that act is late only if it came at most this
/// long before it (docs/monitor.md, "Late messages").
pub const REACTION_US: u64 = 20_000;

/// The message ids [`Monitor`]'s `spoken` bitmap covers (MAVLink 2 ids are 24 bits; the
/// common and ArduPilot dialects stay below this). A frame with a larger id takes the
/// protocols' own lookups.
const SPOKEN_IDS: u32 = 1 << 16;

/// A failure inside a step, before it is recorded.
pub(crate) struct Fail {
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
        let timed = protos.iter().any(|a| a.timeouts.iter().any(Option::is_some));
        let mut spoken = vec![0u64; (SPOKEN_IDS / 64) as usize];
        for id in protos.iter().flat_map(|a| a.alphabet.iter().chain(&a.stream_alphabet)) {
            if *id < SPOKEN_IDS {
                spoken[(*id / 64) as usize] |= 1 << (*id % 64);
            }
        }
        let mut ids: Vec<u32> =
            protos.iter().flat_map(|a| a.alphabet.iter().chain(&a.stream_alphabet)).copied().collect();
        ids.sort_unstable();
        ids.dedup();
        let (mut by_id, mut id_protos) = (Vec::with_capacity(ids.len()), Vec::new());
        for id in ids {
            let start = id_protos.len() as u32;
            id_protos.extend(
                (0..protos.len()).filter(|&p| protos[p].in_alphabet(id) || protos[p].in_streams(id)).map(|p| p as u32),
            );
            by_id.push((id, start, id_protos.len() as u32));
        }
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
            taken_violations: 0,
            summaries: Vec::new(),
            readings: Vec::with_capacity(16),
            scratch: vec![Val::Unset; undo],
            inferred: Vec::with_capacity(8),
            clock: None,
            kinds: Vec::with_capacity(16),
            timed,
            ghosts: Vec::new(),
            reaction_us: REACTION_US,
            end_due: 0,
            pinned: Vec::new(),
            pinned_kinds: false,
            spoken,
            by_id,
            id_protos,
            stats: Stats::default(),
        }
    }

    pub fn protocols(&self) -> &[Automaton] {
        &self.protos
    }

    /// The compiled protocols, given back (to rebuild a monitor from them without a copy).
    pub fn into_protocols(self) -> Vec<Automaton> {
        self.protos
    }

    /// Violation `i` (the index an [`Outcome::Violation`] carries), unless it was taken.
    pub fn violation(&self, i: usize) -> Option<&Violation> {
        i.checked_sub(self.taken_violations).and_then(|k| self.violations.get(k))
    }

    /// The violations recorded and not yet taken ([`Monitor::take_reports`]).
    pub fn violations(&self) -> &[Violation] {
        &self.violations
    }

    /// Takes the violations and session summaries recorded so far, oldest first, leaving
    /// the monitor's buffers empty with their capacity (no allocation: the caller iterates
    /// the drains). A long-running user (a proxy) calls it after reporting, so that the
    /// record does not grow with the stream. Violation indices stay unique: one taken is no
    /// longer found by [`Monitor::violation`], later ones keep counting.
    pub fn take_reports(&mut self) -> Reports<'_> {
        self.taken_violations += self.violations.len();
        Reports { violations: self.violations.drain(..), summaries: self.summaries.drain(..) }
    }

    /// The sessions that ended so far (and, after [`Monitor::finish`], every session).
    pub fn summaries(&self) -> &[SessionSummary] {
        &self.summaries
    }

    /// Forgets the violations and session summaries recorded so far (the indices of earlier
    /// outcomes no longer name them); sessions, readings and statistics are kept. For a
    /// caller that reports each outcome as it comes (the proxy), so that the record does not
    /// grow with the stream. No allocation: the record keeps its capacity.
    pub fn clear_reports(&mut self) {
        self.violations.clear();
        self.summaries.clear();
    }

    /// Monitors one frame (the hot path: no allocation unless a session starts in a new
    /// slot, ends, or a violation is recorded).
    pub fn on_frame(&mut self, f: &Frame) -> Outcome {
        let index = self.stats.frames;
        self.stats.frames += 1;
        if let Some(t) = f.time_us {
            self.clock = Some(self.clock.map_or(t, |c| c.max(t)));
            if self.timed {
                self.end_by_time();
            }
        }
        if f.msgid == HEARTBEAT {
            self.heard(f);
        }
        // Outside every protocol's alphabet and streams: what the loop below concludes for
        // such a frame, without it.
        if f.msgid < SPOKEN_IDS && self.spoken[(f.msgid / 64) as usize] & (1 << (f.msgid % 64)) == 0 {
            self.stats.passed += 1;
            return Outcome::Passed;
        }
        let mut result = None;
        let mut in_alphabet = false;
        let (from, to) = match self.by_id.binary_search_by_key(&f.msgid, |&(id, _, _)| id) {
            Ok(k) => (self.by_id[k].1 as usize, self.by_id[k].2 as usize),
            Err(_) => (0, 0),
        };
        for k in from..to {
            let p = self.id_protos[k] as usize;
            if self.protos[p].in_streams(f.msgid) {
                match self.on_stream(p, f, index) {
                    stream::Class::Reading => continue,
                    stream::Class::Violation(v) => {
                        result = Some(Outcome::Violation(v));
                        continue;
                    }
                    stream::Class::NotStream => {}
                }
            }
            if !self.protos[p].in_alphabet(f.msgid) {
                continue;
            }
            // A `COMMAND_LONG` of a command no edge fixes is not this protocol's message, nor
            // is a message whose ends are of kinds no edge of its label admits (a vehicle's
            // MISSION_COUNT to an upload whose `GCS` sends it).
            let a = &self.protos[p];
            if !a.edges_with(f.msgid).iter().any(|&e| {
                let e = &a.edges[e as usize];
                session::label_fits(e, f) && session::kinds_fit(a, e, &self.kinds, f)
            }) {
                continue;
            }
            in_alphabet = true;
            if let Some(o) = self.on_protocol(p, f, index) {
                // With several protocols, a violation wins over a step, and a step over a late
                // message (another protocol's step must be delivered).
                result = match (result, o) {
                    (Some(Outcome::Violation(v)), _) => Some(Outcome::Violation(v)),
                    (
                        Some(prev @ (Outcome::Step { .. } | Outcome::Ended { .. })),
                        Outcome::Late { .. } | Outcome::Passed,
                    ) => Some(prev),
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

    /// Closes, conformant, every open session that ended by time before the stream's clock:
    /// its state reaches `end` by timeouts alone and their bounds passed since it was
    /// entered (`session::ends_by_time`). Nothing says so on the link (a ground station that
    /// gave up sends nothing), so the next frame with a time is when the monitor learns it;
    /// a later message of that session is then in no session.
    fn end_by_time(&mut self) {
        let Some(clock) = self.clock else { return };
        if clock < self.end_due {
            return;
        }
        let mut due = u64::MAX;
        let mut k = 0;
        while k < self.open.len() {
            let slot = self.open[k];
            let s = &self.slots[slot];
            match session::end_deadline(&self.protos[s.proto], s.state, s.entered_us) {
                Some(d) if clock >= d => {
                    self.stats.ended_by_time += 1;
                    self.remember(slot, true);
                    // `close` moves the last open session to position `k`.
                    self.close(slot, true, true);
                }
                d => {
                    due = due.min(d.unwrap_or(u64::MAX));
                    k += 1;
                }
            }
        }
        self.end_due = due;
    }

    /// The kind of end `(sys, comp)`, as its latest HEARTBEAT declared it.
    pub fn end_kind(&self, sys: u8, comp: u8) -> EndKind {
        session::kind_of(&self.kinds, (sys, comp))
    }

    /// Fixes the kind of end `(sys, comp)`, whatever its HEARTBEATs say from now on: a
    /// proxy knows which side a frame came from (`--gcs` or `--vehicle`), which a HEARTBEAT
    /// only claims.
    pub fn pin_end_kind(&mut self, sys: u8, comp: u8, kind: EndKind) {
        self.pinned_kinds = true;
        match self.kinds.iter_mut().find(|(e, _)| *e == (sys, comp)) {
            Some(k) => k.1 = kind,
            None => self.kinds.push(((sys, comp), kind)),
        }
        if !self.pinned.contains(&(sys, comp)) {
            self.pinned.push((sys, comp));
        }
    }

    /// Sets the reaction bound (µs, default [`REACTION_US`]): how long after its timeout
    /// fired a waiting role's act may appear in the log. A message of the abandoned choice
    /// logged before the act is read as late (not restarting the timeout) only within it.
    pub fn set_reaction_bound(&mut self, us: u64) {
        self.reaction_us = us;
    }

    /// Whether [`Monitor::pin_end_kind`] fixed the kind of end `(sys, comp)`.
    pub fn is_pinned(&self, sys: u8, comp: u8) -> bool {
        self.pinned.contains(&(sys, comp))
    }

    /// A HEARTBEAT: its sender's kind, kept (in place once the end is known), unless pinned.
    fn heard(&mut self, f: &Frame) {
        let kind = EndKind::of_heartbeat(f.payload);
        let end = (f.sysid, f.compid);
        if self.pinned_kinds && self.pinned.contains(&end) {
            return;
        }
        match self.kinds.iter_mut().find(|(e, _)| *e == end) {
            Some(k) => k.1 = kind,
            None => self.kinds.push((end, kind)),
        }
    }

    /// Ends the stream: every open session is reported incomplete, unless its state can
    /// end by timeouts alone and their bounds passed before the stream's last time (then it
    /// ended by time, conformant). Returns all summaries.
    pub fn finish(&mut self) -> &[SessionSummary] {
        let mut open = std::mem::take(&mut self.open);
        open.sort_by_key(|&i| self.slots[i].id);
        for slot in open {
            let s = &self.slots[slot];
            let timed_out = session::ends_by_time(&self.protos[s.proto], s.state, s.entered_us, self.clock);
            if timed_out {
                self.stats.sessions_ended += 1;
            }
            self.summaries.push(summary(&self.slots[slot], timed_out));
            self.free[self.slots[slot].proto].push(slot);
        }
        &self.summaries
    }
}

/// HEARTBEAT's message id.
const HEARTBEAT: u32 = 0;

/// The failure an undefined or undecided predicate is (`edge` is `None` at an assignment).
fn verdict_fail(v: Verdict, edge: Option<u32>, pred: u32, field: Option<u16>) -> Fail {
    match v {
        Verdict::Undefined(why) => Fail { kind: Kind::Undefined, edge, pred: Some(pred), field, why: Some(why) },
        Verdict::Undecided => Fail { kind: Kind::Undecided, edge, pred: Some(pred), field, why: None },
    }
}

/// Resizes `v` to `n` copies of `x` (no allocation once its capacity suffices).
fn reset<T: Clone>(v: &mut Vec<T>, n: usize, x: T) {
    v.clear();
    v.resize(n, x);
}

#[cfg(test)]
mod code_tests;
#[cfg(test)]
mod tests;
