//! The proxy's output: its first line and one JSON line per [`Event`] (docs/proxy.md,
//! "Output"), written by hand into a reused buffer, so that the enforcing process needs no
//! renderer and allocates nothing per message: a step's line is built from integers and
//! `&'static str`s into a buffer whose capacity stays from one batch to the next.
//!
//! This is the one writer of JSON outside the renderer of the command line (tests/tidy.rs,
//! rule (d)). Its lines are byte for byte what `serde_json` makes of the same object: keys in
//! byte order (serde_json's map without `preserve_order`), no spaces, strings escaped as
//! serde_json escapes them (`"` and `\`, the short forms `\b \t \n \f \r`, other control
//! characters as `\u00xx`, everything else as it is). The unit tests compare the two.

use super::{At, Event};
use std::io::Write;
use std::sync::Mutex;

/// A JSON object written key by key into a byte buffer. The caller gives the keys in byte
/// order (the tests check every event against serde_json's output).
struct Obj<'b> {
    out: &'b mut Vec<u8>,
    first: bool,
}

impl<'b> Obj<'b> {
    fn new(out: &'b mut Vec<u8>) -> Obj<'b> {
        out.push(b'{');
        Obj { out, first: true }
    }

    fn key(&mut self, k: &str) -> &mut Vec<u8> {
        if !self.first {
            self.out.push(b',');
        }
        self.first = false;
        string(self.out, k);
        self.out.push(b':');
        self.out
    }

    fn str(&mut self, k: &str, v: &str) -> &mut Self {
        let out = self.key(k);
        string(out, v);
        self
    }

    fn opt_str(&mut self, k: &str, v: Option<&str>) -> &mut Self {
        match v {
            Some(v) => self.str(k, v),
            None => {
                self.key(k).extend_from_slice(b"null");
                self
            }
        }
    }

    fn num(&mut self, k: &str, v: u64) -> &mut Self {
        let out = self.key(k);
        number(out, v);
        self
    }

    fn bool(&mut self, k: &str, v: bool) -> &mut Self {
        self.key(k).extend_from_slice(if v { b"true" } else { b"false" });
        self
    }

    /// `sysid/compid`, as a string.
    fn pair(&mut self, k: &str, (a, b): (u8, u8)) -> &mut Self {
        let out = self.key(k);
        out.push(b'"');
        number(out, u64::from(a));
        out.push(b'/');
        number(out, u64::from(b));
        out.push(b'"');
        self
    }

    fn end(&mut self) {
        self.out.push(b'}');
    }
}

/// `v` in decimal.
fn number(out: &mut Vec<u8>, mut v: u64) {
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[i..]);
}

/// `s` as a JSON string, escaped as serde_json escapes it.
fn string(out: &mut Vec<u8>, s: &str) {
    const HEX: &[u8; 16] = b"0123456789abcdef";
    out.push(b'"');
    let bytes = s.as_bytes();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        let short = match b {
            b'"' => b'"',
            b'\\' => b'\\',
            0x08 => b'b',
            0x09 => b't',
            0x0a => b'n',
            0x0c => b'f',
            0x0d => b'r',
            0x00..=0x1f => b'u',
            _ => continue,
        };
        out.extend_from_slice(&bytes[start..i]);
        out.push(b'\\');
        out.push(short);
        if short == b'u' {
            out.extend_from_slice(&[b'0', b'0', HEX[usize::from(b >> 4)], HEX[usize::from(b & 0xf)]]);
        }
        start = i + 1;
    }
    out.extend_from_slice(&bytes[start..]);
    out.push(b'"');
}

/// The proxy's first line (no newline): the ends it opened and what it enforces.
pub fn start_line(
    out: &mut Vec<u8>,
    gcs: &str,
    gcs_local: Option<&str>,
    vehicle: &str,
    vehicle_local: Option<&str>,
    protocols: &[String],
    alert_only: bool,
) {
    let mut o = Obj::new(out);
    o.str("event", "start").str("gcs", gcs).opt_str("gcs_local", gcs_local);
    o.str("mode", if alert_only { "alert-only" } else { "enforce" });
    let list = o.key("protocols");
    list.push(b'[');
    for (i, p) in protocols.iter().enumerate() {
        if i > 0 {
            list.push(b',');
        }
        string(list, p);
    }
    list.push(b']');
    o.str("vehicle", vehicle).opt_str("vehicle_local", vehicle_local).end();
}

/// One event as one JSON line (no newline) appended to `out`; `protocols` are the names of
/// the protocols enforced, which the events index.
pub fn event_line(out: &mut Vec<u8>, e: &Event, protocols: &[String]) {
    let name = |p: Option<usize>| p.and_then(|p| protocols.get(p)).map(String::as_str);
    let mut o = Obj::new(out);
    // The frame's fields, each at its place in the byte order of the keys.
    let frame = |o: &mut Obj<'_>, at: &At, event: &str| {
        o.str("dir", at.dir.as_str()).str("event", event).pair("from", at.from).num("msgid", u64::from(at.msgid));
    };
    match e {
        Event::Step { at, session, state } => {
            o.str("action", "forward");
            frame(&mut o, at, "step");
            o.num("session", *session).bool("signed", at.signed).num("state", u64::from(*state));
            o.num("time_us", at.time_us);
        }
        Event::End { at, session, protocol, conformant } => {
            o.str("action", "forward").bool("conformant", *conformant);
            frame(&mut o, at, "end");
            o.opt_str("protocol", name(*protocol)).num("session", *session).bool("signed", at.signed);
            o.num("time_us", at.time_us);
        }
        Event::Late { at, session, forwarded } => {
            o.str("action", if *forwarded { "forward" } else { "drop" });
            frame(&mut o, at, "late");
            o.num("session", *session).bool("signed", at.signed).num("time_us", at.time_us);
        }
        Event::Violation { at, kind, protocol, session, state, field, detail, forwarded } => {
            o.str("action", if *forwarded { "alert" } else { "drop" });
            if let Some(d) = detail {
                o.str("detail", d);
            }
            o.str("dir", at.dir.as_str()).str("event", "violation");
            if let Some(f) = field {
                o.str("field", f);
            }
            o.pair("from", at.from).str("kind", kind.as_str()).num("msgid", u64::from(at.msgid));
            if protocol.is_some() {
                o.opt_str("protocol", name(*protocol));
            }
            if let Some(s) = session {
                o.num("session", *s);
            }
            o.bool("signed", at.signed).num("state", u64::from(*state)).num("time_us", at.time_us);
        }
        Event::Input { time_us, dir, counts: c } => {
            o.num("bad_crc", c.bad_crc).num("bad_flags", c.bad_flags).num("bad_signature", c.bad_signature);
            o.str("dir", dir.as_str()).str("event", "input").num("frames", c.frames);
            o.num("garbage_bytes", c.garbage_bytes).num("signed", c.signed).num("time_us", *time_us);
            o.num("truncated", c.truncated).num("unknown_id", c.unknown_id);
        }
        Event::Reset { time_us, reason, open_sessions_lost, resets } => {
            o.str("event", "reset").num("open_sessions_lost", *open_sessions_lost).str("reason", reason);
            o.num("resets", *resets).num("time_us", *time_us);
        }
        Event::Error { dir, error } => {
            o.str("dir", dir.as_str()).str("error", error).str("event", "error");
        }
    }
    o.end();
}

/// A [`super::Sink`] that writes each batch of events as JSON lines to `W` and flushes it:
/// one write per batch, from a buffer reused across batches.
pub struct Lines<W: Write + Send> {
    state: Mutex<(Vec<u8>, W)>,
    protocols: Vec<String>,
}

impl<W: Write + Send> Lines<W> {
    pub fn new(out: W, protocols: Vec<String>) -> Lines<W> {
        Lines { state: Mutex::new((Vec::with_capacity(4096), out)), protocols }
    }

    /// Writes one line of text (the start line) and flushes.
    pub fn raw_line(&self, line: &[u8]) {
        if let Ok(mut g) = self.state.lock() {
            let (_, w) = &mut *g;
            let _ = w.write_all(line);
            let _ = w.write_all(b"\n");
            let _ = w.flush();
        }
    }
}

impl<W: Write + Send> super::Sink for Lines<W> {
    fn events(&self, events: &[Event]) {
        let Ok(mut g) = self.state.lock() else { return };
        let (buf, w) = &mut *g;
        buf.clear();
        for e in events {
            event_line(buf, e, &self.protocols);
            buf.push(b'\n');
        }
        let _ = w.write_all(buf);
        let _ = w.flush();
    }
}

#[cfg(test)]
mod tests;
