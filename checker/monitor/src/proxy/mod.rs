//! The live proxy: mochi between a ground station and a vehicle (DATUM's enforcement
//! point, seed 000 Sec 2 and 4). Frames are read from both ends, run through the monitor, and
//! forwarded to the other end, byte for byte, unless the monitor finds a violation: then the
//! frame is dropped (or, with `alert_only`, forwarded and reported). Every verdict on a
//! protocol message is an [`Event`] handed to a [`Sink`] (the command line renders each as
//! one JSON line: docs/proxy.md gives the format).
//!
//! Two threads, one per direction, each blocked in a receive on its end (std threads: two
//! blocking reads are the lowest latency there is on a link with two ends, and need no
//! runtime). They share the one monitor under a mutex, since a session's messages flow both
//! ways.
//!
//! What is not forwarded: bytes that belong to no frame whose checksum holds (garbage, bad
//! CRC, truncated frames, and frames of message ids the dialect does not know, whose CRC
//! cannot be checked), and violating frames unless `alert_only`. Signed frames are forwarded
//! as received (the signature is not checked, nor stripped).
//!
//! Memory is bounded whatever the input: the receive buffer is fixed, the frame reassembly
//! buffer holds at most one receive plus one incomplete frame ([`Stream`]), the monitor's
//! record of violations and ended sessions (which it keeps for reports) is cleared after
//! each frame's event is built (`Monitor::clear_reports`: a flood of violations grows
//! nothing and loses no session), and the monitor is rebuilt at [`SESSION_CAP`] open
//! sessions (a flood of session openings): an [`Event::Reset`] says so. A session lost in a
//! reset is not a pass: its next message fits no session and is dropped as outside any
//! session, or starts a new one if it is a first message, as it would have anyway.

pub mod endpoint;
pub mod handoff;
pub mod lines;

pub use endpoint::{Endpoint, Port};

use crate::mavio::parse::{Config, Counts, Item, Stream};
use crate::monitor::{Automaton, EndKind, Kind, Monitor, Outcome};
use crate::source::SourceDb;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Open sessions at which the monitor is rebuilt.
pub const SESSION_CAP: u64 = 1024;
/// The receive buffer: the largest UDP datagram.
pub const RECV_BUF: usize = 65536;

/// What the proxy does with a violating message.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// Drop it (the default): the receiver never sees it.
    #[default]
    Enforce,
    /// Forward it and report it.
    AlertOnly,
}

/// One direction of the link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    GcsToVehicle,
    VehicleToGcs,
}

impl Dir {
    pub fn as_str(self) -> &'static str {
        match self {
            Dir::GcsToVehicle => "gcs->vehicle",
            Dir::VehicleToGcs => "vehicle->gcs",
        }
    }
}

/// The frame a verdict is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct At {
    /// Arrival, microseconds since the Unix epoch.
    pub time_us: u64,
    pub dir: Dir,
    pub msgid: u32,
    pub from: (u8, u8),
    pub signed: bool,
}

/// What the proxy reports.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A session took the message (forwarded); `state` is its state now.
    Step { at: At, session: u64, state: u32 },
    /// The message ended a session (forwarded); `protocol` indexes [`Proxy::protocols`].
    End { at: At, session: u64, protocol: Option<usize>, conformant: bool },
    /// A message of a branch its receiver abandoned by a timeout (`Outcome::Late`): the
    /// static checks assume the receiver ignores it, so it is dropped when enforcing, and
    /// forwarded (`forwarded`) when only alerting.
    Late { at: At, session: u64, forwarded: bool },
    /// The monitor rejects the message: dropped, or forwarded when `forwarded`.
    Violation {
        at: At,
        kind: Kind,
        protocol: Option<usize>,
        session: Option<u64>,
        state: u32,
        field: Option<String>,
        /// The monitor's explanation (`Monitor::describe`), when the sources are known.
        detail: Option<String>,
        forwarded: bool,
    },
    /// Malformed input seen on a direction (cumulative counts).
    Input { time_us: u64, dir: Dir, counts: Counts },
    /// The monitor was rebuilt with sessions open (the module comment says when).
    Reset { time_us: u64, reason: &'static str, open_sessions_lost: u64, resets: u64 },
    /// An end failed (once per distinct error); the proxy goes on.
    Error { dir: Dir, error: String },
}

/// Where events go: called after the frames of one receive were forwarded, with the events
/// of that receive, in order (the forwarding never waits for the report).
pub trait Sink: Sync {
    fn events(&self, events: &[Event]);
}

/// Counters of a run, over both directions.
#[derive(Debug, Default)]
pub struct Totals {
    pub frames: AtomicU64,
    pub forwarded: AtomicU64,
    pub dropped: AtomicU64,
    pub violations: AtomicU64,
    pub resets: AtomicU64,
    /// Bytes received that were not forwarded as part of a frame.
    pub bytes_in: AtomicU64,
}

/// The proxy's settings.
pub struct Proxy<'a> {
    /// The verified protocols, compiled; none: forward every well-formed frame unmonitored.
    pub protocols: Vec<Automaton>,
    /// The sources of the protocols, for the violations' explanations (file:line:col).
    pub db: Option<&'a SourceDb>,
    pub mode: Mode,
    /// How frames are checked (dialect; a signing key is not used by the proxy).
    pub config: Config,
    /// Events on every protocol message (`true`), or only violations, resets, input counts
    /// and errors.
    pub steps: bool,
}

struct Shared {
    monitor: Monitor,
    /// Open sessions and record sizes are read from the monitor; these add up across resets.
    resets: u64,
}

/// Microseconds since the Unix epoch.
fn now_us() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_micros() as u64)
}

impl Proxy<'_> {
    /// Runs until `stop` is set: frames from `gcs` go to `vehicle` and back; events go to
    /// `out`. Returns when both directions have stopped; an error of one end is reported and
    /// the proxy goes on (a link that fails is retried, as a ground station does).
    ///
    /// The protocols move into the one monitor (not copied: a copy of each compiled protocol
    /// and its program would double the proxy's largest memory), hence `self` by value.
    pub fn run(mut self, gcs: &dyn Port, vehicle: &dyn Port, out: &dyn Sink, stop: &AtomicBool, totals: &Totals) {
        let protocols = std::mem::take(&mut self.protocols);
        let shared = if protocols.is_empty() {
            None
        } else {
            Some(Mutex::new(Shared { monitor: Monitor::new(protocols), resets: 0 }))
        };
        let this = &self;
        std::thread::scope(|scope| {
            let shared = shared.as_ref();
            scope.spawn(move || this.direction(Dir::GcsToVehicle, gcs, vehicle, shared, out, stop, totals));
            scope.spawn(move || this.direction(Dir::VehicleToGcs, vehicle, gcs, shared, out, stop, totals));
        });
    }

    #[allow(clippy::too_many_arguments)]
    fn direction(
        &self,
        dir: Dir,
        from: &dyn Port,
        to: &dyn Port,
        shared: Option<&Mutex<Shared>>,
        out: &dyn Sink,
        stop: &AtomicBool,
        totals: &Totals,
    ) {
        let mut buf = vec![0u8; RECV_BUF];
        let mut stream = Stream::new(self.config);
        let mut fwd: Vec<u8> = Vec::with_capacity(RECV_BUF + crate::mavio::parse::MAX_FRAME);
        let mut events: Vec<Event> = Vec::with_capacity(64);
        let mut last_counts = Counts::default();
        let mut last_report = Instant::now();
        let mut last_error: Option<String> = None;
        while !stop.load(Ordering::Relaxed) {
            let n = match from.recv(&mut buf) {
                Ok(n) => n,
                Err(e) => {
                    let msg = e.to_string();
                    if last_error.as_deref() != Some(&msg) {
                        out.events(&[Event::Error { dir, error: msg.clone() }]);
                        last_error = Some(msg);
                    }
                    std::thread::sleep(endpoint::POLL);
                    continue;
                }
            };
            if n == 0 {
                self.report_counts(dir, &stream, &mut last_counts, &mut last_report, out, true);
                continue;
            }
            let t = now_us();
            stream.push(&buf[..n], Some(t));
            totals.bytes_in.fetch_add(n as u64, Ordering::Relaxed);
            fwd.clear();
            events.clear();
            while let Some(item) = stream.next_item() {
                let f = match item {
                    // A message the dialect does not know is outside every protocol's
                    // alphabet: forwarded whole, unchecked (its CRC_EXTRA is unknown), as
                    // mavlink-router does; the receiver checks its checksum.
                    Item::Unknown(raw) => {
                        fwd.extend_from_slice(raw);
                        totals.forwarded.fetch_add(1, Ordering::Relaxed);
                        continue;
                    }
                    Item::Frame(f) => f,
                };
                totals.frames.fetch_add(1, Ordering::Relaxed);
                let forward = match shared {
                    None => true,
                    Some(sh) => {
                        let Ok(mut g) = sh.lock() else {
                            // A poisoned monitor (a panic in another thread) cannot judge:
                            // nothing is forwarded unjudged.
                            continue;
                        };
                        self.judge(dir, &mut g, &f, &mut events, totals)
                    }
                };
                if forward {
                    fwd.extend_from_slice(f.raw);
                    totals.forwarded.fetch_add(1, Ordering::Relaxed);
                } else {
                    totals.dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
            if !fwd.is_empty() {
                if let Err(e) = to.send(&fwd) {
                    events.push(Event::Error { dir, error: format!("cannot forward: {e}") });
                }
            }
            if !events.is_empty() {
                out.events(&events);
            }
            self.report_counts(dir, &stream, &mut last_counts, &mut last_report, out, false);
        }
        out.events(&[Event::Input { time_us: now_us(), dir, counts: stream.counts() }]);
    }

    /// One frame through the monitor: whether to forward it, with its event added to
    /// `events`.
    fn judge(
        &self,
        dir: Dir,
        g: &mut Shared,
        f: &crate::mavio::Frame<'_>,
        events: &mut Vec<Event>,
        totals: &Totals,
    ) -> bool {
        // The side a frame comes from says what its end is; a HEARTBEAT only claims it. Were
        // the claim believed, a ground station announcing itself as an autopilot would take
        // its upload out of every upload protocol's reach, and the upload would pass unjudged.
        if !g.monitor.is_pinned(f.sysid, f.compid) {
            let kind = match dir {
                Dir::GcsToVehicle => EndKind::GroundStation,
                Dir::VehicleToGcs => EndKind::Vehicle,
            };
            g.monitor.pin_end_kind(f.sysid, f.compid, kind);
        }
        let outcome = g.monitor.on_frame(f);
        let at =
            At { time_us: f.time_us.unwrap_or(0), dir, msgid: f.msgid, from: (f.sysid, f.compid), signed: f.signed };
        let forward = match outcome {
            Outcome::Passed => true,
            Outcome::Step { session, state } => {
                if self.steps {
                    events.push(Event::Step { at, session, state });
                }
                true
            }
            Outcome::Ended { session } => {
                if self.steps {
                    let s = g.monitor.summaries().iter().rev().find(|s| s.session == session);
                    events.push(Event::End {
                        at,
                        session,
                        protocol: s.map(|s| s.protocol),
                        conformant: s.is_some_and(|s| s.conformant),
                    });
                }
                true
            }
            Outcome::Late { session } => {
                let forwarded = self.mode == Mode::AlertOnly;
                events.push(Event::Late { at, session, forwarded });
                forwarded
            }
            Outcome::Violation(i) => {
                totals.violations.fetch_add(1, Ordering::Relaxed);
                let forwarded = self.mode == Mode::AlertOnly;
                let detail = self.db.map(|db| g.monitor.describe(db, i));
                let e = match g.monitor.violation(i) {
                    Some(v) => Event::Violation {
                        at,
                        kind: v.kind,
                        protocol: v.protocol,
                        session: v.session,
                        state: v.state,
                        field: v.field.clone(),
                        detail,
                        forwarded,
                    },
                    None => Event::Violation {
                        at,
                        kind: Kind::OutsideSession,
                        protocol: None,
                        session: None,
                        state: 0,
                        field: None,
                        detail,
                        forwarded,
                    },
                };
                events.push(e);
                forwarded
            }
        };
        // The event holds all it needs: the record is not kept (it would grow with every
        // violation and ended session).
        g.monitor.clear_reports();
        self.bound(g, events, totals);
        forward
    }

    /// Keeps the monitor's memory bounded (the module comment says how).
    fn bound(&self, g: &mut Shared, events: &mut Vec<Event>, totals: &Totals) {
        let m = &g.monitor;
        let open = m.stats.sessions_started.saturating_sub(m.stats.sessions_ended);
        if open < SESSION_CAP {
            return;
        }
        g.resets += 1;
        totals.resets.fetch_add(1, Ordering::Relaxed);
        events.push(Event::Reset {
            time_us: now_us(),
            reason: "too many open sessions",
            open_sessions_lost: open,
            resets: g.resets,
        });
        let old = std::mem::replace(&mut g.monitor, Monitor::new(Vec::new()));
        g.monitor = Monitor::new(old.into_protocols());
    }

    /// At most once a second, an event with the input counts of a direction when something
    /// malformed was seen since the last one (a flood of garbage is reported, not echoed).
    fn report_counts(
        &self,
        dir: Dir,
        stream: &Stream,
        last: &mut Counts,
        at: &mut Instant,
        out: &dyn Sink,
        idle: bool,
    ) {
        if !idle && at.elapsed() < Duration::from_secs(1) {
            return;
        }
        let c = stream.counts();
        let bad = |c: &Counts| c.bad_crc + c.bad_signature + c.bad_flags + c.unknown_id + c.garbage_bytes;
        if bad(&c) != bad(last) && at.elapsed() >= Duration::from_secs(1) {
            out.events(&[Event::Input { time_us: now_us(), dir, counts: c }]);
            *last = c;
            *at = Instant::now();
        }
    }
}

#[cfg(test)]
mod tests;
