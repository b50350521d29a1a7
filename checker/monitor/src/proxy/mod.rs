//! The live proxy: mochi between a ground station and a vehicle (DATUM's enforcement
//! point, seed 000 Sec 2 and 4). Frames are read from both ends, run through the monitor, and
//! forwarded to the other end, byte for byte, unless the monitor finds a violation: then the
//! frame is dropped (or, with `alert_only`, forwarded and reported). Every verdict on a
//! protocol message is one JSON line on the output (docs/proxy.md gives the format).
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
//! buffer holds at most one receive plus one incomplete frame ([`Stream`]), and the
//! monitor's record of violations and ended sessions (which it keeps for its reports) is
//! cleared by rebuilding the monitor once it holds [`REPORT_CAP`] entries and no session is
//! open, or, whatever is open, at [`HARD_CAP`] entries or [`SESSION_CAP`] open sessions (a
//! flood of session openings): a `reset` line says so. A session lost in a reset is not a
//! pass: its next message fits no session and is dropped as outside any session, or starts a
//! new one if it is a first message, as it would have anyway.

pub mod endpoint;

pub use endpoint::{Endpoint, Port};

use crate::mavio::parse::{Config, Counts, Stream};
use crate::monitor::{Automaton, Monitor, Outcome};
use crate::source::SourceDb;
use std::fmt::Write as _;
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Recorded violations and session summaries kept before the monitor is rebuilt (when no
/// session is open).
pub const REPORT_CAP: usize = 1024;
/// Recorded entries at which the monitor is rebuilt even with sessions open.
pub const HARD_CAP: usize = 8 * REPORT_CAP;
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
    /// Verdict lines on every protocol message (`true`), or only violations, resets and errors.
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

/// A string as a JSON string literal.
fn json_str(out: &mut String, s: &str) {
    match serde_json::to_string(s) {
        Ok(q) => out.push_str(&q),
        Err(_) => out.push_str("\"\""),
    }
}

impl Proxy<'_> {
    /// Runs until `stop` is set: frames from `gcs` go to `vehicle` and back. Verdict lines go
    /// to `out` (written and flushed after the frames of one receive were forwarded). Returns
    /// when both directions have stopped; an error of one end is reported on `out` and the
    /// proxy goes on (a link that fails is retried, as a ground station does).
    pub fn run(
        &self,
        gcs: &dyn Port,
        vehicle: &dyn Port,
        out: &Mutex<Box<dyn Write + Send>>,
        stop: &AtomicBool,
        totals: &Totals,
    ) {
        let shared = if self.protocols.is_empty() {
            None
        } else {
            Some(Mutex::new(Shared { monitor: Monitor::new(self.protocols.clone()), resets: 0 }))
        };
        std::thread::scope(|scope| {
            let shared = shared.as_ref();
            scope.spawn(move || self.direction(Dir::GcsToVehicle, gcs, vehicle, shared, out, stop, totals));
            scope.spawn(move || self.direction(Dir::VehicleToGcs, vehicle, gcs, shared, out, stop, totals));
        });
    }

    #[allow(clippy::too_many_arguments)]
    fn direction(
        &self,
        dir: Dir,
        from: &dyn Port,
        to: &dyn Port,
        shared: Option<&Mutex<Shared>>,
        out: &Mutex<Box<dyn Write + Send>>,
        stop: &AtomicBool,
        totals: &Totals,
    ) {
        let mut buf = vec![0u8; RECV_BUF];
        let mut stream = Stream::new(self.config);
        let mut fwd: Vec<u8> = Vec::with_capacity(RECV_BUF + crate::mavio::parse::MAX_FRAME);
        let mut lines = String::with_capacity(4096);
        let mut last_counts = Counts::default();
        let mut last_report = Instant::now();
        let mut last_error: Option<String> = None;
        while !stop.load(Ordering::Relaxed) {
            let n = match from.recv(&mut buf) {
                Ok(n) => n,
                Err(e) => {
                    let msg = e.to_string();
                    if last_error.as_deref() != Some(&msg) {
                        lines.clear();
                        lines.push_str("{\"event\":\"error\",\"dir\":\"");
                        lines.push_str(dir.as_str());
                        lines.push_str("\",\"error\":");
                        json_str(&mut lines, &msg);
                        lines.push_str("}\n");
                        emit(out, &lines);
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
            lines.clear();
            while let Some(f) = stream.next_frame() {
                totals.frames.fetch_add(1, Ordering::Relaxed);
                let forward = match shared {
                    None => true,
                    Some(sh) => {
                        let Ok(mut g) = sh.lock() else {
                            // A poisoned monitor (a panic in another thread) cannot judge:
                            // nothing is forwarded unjudged.
                            continue;
                        };
                        self.judge(dir, &mut g, &f, &mut lines, totals)
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
                    lines.push_str("{\"event\":\"error\",\"dir\":\"");
                    lines.push_str(dir.as_str());
                    lines.push_str("\",\"error\":");
                    json_str(&mut lines, &format!("cannot forward: {e}"));
                    lines.push_str("}\n");
                }
            }
            if !lines.is_empty() {
                emit(out, &lines);
            }
            self.report_counts(dir, &stream, &mut last_counts, &mut last_report, out, false);
        }
        lines.clear();
        self.counts_line(dir, &stream.counts(), &mut lines);
        emit(out, &lines);
    }

    /// One frame through the monitor: whether to forward it, with its verdict line added to
    /// `lines`.
    fn judge(
        &self,
        dir: Dir,
        g: &mut Shared,
        f: &crate::mavio::Frame<'_>,
        lines: &mut String,
        totals: &Totals,
    ) -> bool {
        let outcome = g.monitor.on_frame(f);
        let head = |lines: &mut String, event: &str| {
            let _ = write!(
                lines,
                "{{\"event\":\"{event}\",\"time_us\":{},\"dir\":\"{}\",\"msgid\":{},\"from\":\"{}/{}\",\"signed\":{}",
                f.time_us.unwrap_or(0),
                dir.as_str(),
                f.msgid,
                f.sysid,
                f.compid,
                f.signed
            );
        };
        let forward = match outcome {
            Outcome::Passed => true,
            Outcome::Step { session, state } => {
                if self.steps {
                    head(lines, "step");
                    let _ = writeln!(lines, ",\"session\":{session},\"state\":{state},\"action\":\"forward\"}}");
                }
                true
            }
            Outcome::Ended { session } => {
                if self.steps {
                    head(lines, "end");
                    let _ = write!(lines, ",\"session\":{session}");
                    let protos = g.monitor.protocols();
                    if let Some(s) = g.monitor.summaries().iter().rev().find(|s| s.session == session) {
                        lines.push_str(",\"protocol\":");
                        json_str(lines, &protos[s.protocol].name);
                        let _ = write!(lines, ",\"conformant\":{}", s.conformant);
                    }
                    lines.push_str(",\"action\":\"forward\"}\n");
                }
                true
            }
            Outcome::Violation(i) => {
                totals.violations.fetch_add(1, Ordering::Relaxed);
                let forward = self.mode == Mode::AlertOnly;
                head(lines, "violation");
                if let Some(v) = g.monitor.violation(i) {
                    lines.push_str(",\"kind\":");
                    json_str(lines, v.kind.as_str());
                    if let Some(p) = v.protocol {
                        lines.push_str(",\"protocol\":");
                        json_str(lines, &g.monitor.protocols()[p].name);
                    }
                    if let Some(s) = v.session {
                        let _ = write!(lines, ",\"session\":{s}");
                    }
                    let _ = write!(lines, ",\"state\":{}", v.state);
                    if let Some(field) = &v.field {
                        lines.push_str(",\"field\":");
                        json_str(lines, field);
                    }
                }
                if let Some(db) = self.db {
                    lines.push_str(",\"detail\":");
                    json_str(lines, &g.monitor.describe(db, i));
                }
                let _ = writeln!(lines, ",\"action\":\"{}\"}}", if forward { "alert" } else { "drop" });
                forward
            }
        };
        self.bound(g, lines, totals);
        forward
    }

    /// Keeps the monitor's memory bounded (the module comment says how).
    fn bound(&self, g: &mut Shared, lines: &mut String, totals: &Totals) {
        let m = &g.monitor;
        let recorded = m.violations().len() + m.summaries().len();
        let open = m.stats.sessions_started.saturating_sub(m.stats.sessions_ended);
        let reason = if recorded >= HARD_CAP {
            "record full"
        } else if open >= SESSION_CAP {
            "too many open sessions"
        } else if recorded >= REPORT_CAP && open == 0 {
            ""
        } else {
            return;
        };
        if !reason.is_empty() {
            g.resets += 1;
            totals.resets.fetch_add(1, Ordering::Relaxed);
            let _ = writeln!(
                lines,
                "{{\"event\":\"reset\",\"time_us\":{},\"reason\":\"{reason}\",\"open_sessions_lost\":{open},\"resets\":{}}}",
                now_us(),
                g.resets
            );
        }
        g.monitor = Monitor::new(self.protocols.clone());
    }

    fn counts_line(&self, dir: Dir, c: &Counts, lines: &mut String) {
        let _ = writeln!(
            lines,
            "{{\"event\":\"input\",\"time_us\":{},\"dir\":\"{}\",\"frames\":{},\"signed\":{},\"bad_crc\":{},\"bad_signature\":{},\"bad_flags\":{},\"unknown_id\":{},\"garbage_bytes\":{}}}",
            now_us(),
            dir.as_str(),
            c.frames,
            c.signed,
            c.bad_crc,
            c.bad_signature,
            c.bad_flags,
            c.unknown_id,
            c.garbage_bytes
        );
    }

    /// At most once a second, a line with the input counts of a direction when something
    /// malformed was seen since the last one (a flood of garbage is reported, not echoed).
    fn report_counts(
        &self,
        dir: Dir,
        stream: &Stream,
        last: &mut Counts,
        at: &mut Instant,
        out: &Mutex<Box<dyn Write + Send>>,
        idle: bool,
    ) {
        if !idle && at.elapsed() < Duration::from_secs(1) {
            return;
        }
        let c = stream.counts();
        let bad = |c: &Counts| c.bad_crc + c.bad_signature + c.bad_flags + c.unknown_id + c.garbage_bytes;
        if bad(&c) != bad(last) && at.elapsed() >= Duration::from_secs(1) {
            let mut line = String::new();
            self.counts_line(dir, &c, &mut line);
            emit(out, &line);
            *last = c;
            *at = Instant::now();
        }
    }
}

/// Writes verdict lines and flushes (a reader sees each verdict as it happens).
fn emit(out: &Mutex<Box<dyn Write + Send>>, lines: &str) {
    if let Ok(mut w) = out.lock() {
        let _ = w.write_all(lines.as_bytes());
        let _ = w.flush();
    }
}

#[cfg(test)]
mod tests;
