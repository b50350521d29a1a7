//! MAVLink framing: finding frames in a byte stream, checking them, and resynchronising after
//! garbage.
//!
//! The wire format is MAVLink's (<https://mavlink.io/en/guide/serialization.html>):
//!
//! ```text
//! v1: FE len seq sys comp id               payload[len] crc_lo crc_hi
//! v2: FD len inc cmp seq sys comp id0 id1 id2 payload[len] crc_lo crc_hi [signature: 13]
//! ```
//!
//! The checksum is CRC-16/MCRF4XX over everything after the start byte up to the payload's
//! end, then the message's CRC_EXTRA byte; CRC_EXTRA comes from the `mavlink` crate's
//! generated dialect (`common`, or `ardupilotmega`, which includes `common`), and so does the
//! CRC itself ([`mavlink::calculate_crc`]). A signed MAVLink 2 frame (incompatibility flag
//! 0x01) carries 13 more bytes: link id, 48-bit timestamp, 48-bit SHA-256 signature; with a
//! key the signature is checked ([`mavlink::MAVLinkV2MessageRaw::calculate_signature`]).
//!
//! **Resynchronisation.** The reader looks at each start byte (0xFE, 0xFD) as a candidate
//! frame. A candidate is accepted only when its checksum holds. Any other candidate (bad
//! checksum, bad signature, an incompatibility flag MAVLink does not define) costs one byte:
//! the start byte is skipped and the search goes on from the next byte, so a real frame that
//! starts inside a broken one is still found. (MAVLink's C parser and pymavlink skip the whole
//! declared length of a broken frame instead; see docs/mavio.md for what that changes.)
//!
//! **Unknown message ids.** A frame whose id is not in the dialect has no CRC_EXTRA, so its
//! checksum cannot be checked and nothing distinguishes it from garbage that happens to start
//! with 0xFE or 0xFD. It is *not* yielded (a [`Frame`] is a frame whose checksum was
//! verified; the monitor would not know its fields anyway). It is counted as an unknown
//! message when its framing is self-consistent (the byte right after it is a start byte, or
//! the input ends exactly there), and, like every candidate that is not checked, costs only
//! its start byte: the rule is that **only a frame whose checksum holds consumes more than one
//! byte**, so no verified frame is ever swallowed by a candidate that merely looks like one
//! (the price: an unknown message's bytes are counted as garbage, and start bytes inside its
//! payload as further failed candidates).
//!
//! **What is counted** ([`Counts`]): frames yielded, signed frames among them, candidates with
//! a bad checksum, with a bad signature, with undefined incompatibility flags, unknown
//! message ids, a truncated frame at the end of the input, and garbage bytes: every byte that
//! is not part of a yielded frame, an unknown message or (in a `.tlog`) a frame's timestamp.
//! The bytes of a frame with a bad checksum are garbage too (the checksum failure is counted
//! once, in `bad_crc`).
//!
//! Nothing here allocates per frame: a [`Frame`] borrows the input, and [`Stream`] (bytes in
//! chunks, as from a socket) keeps one buffer that grows to the largest chunk plus one frame.

use super::Frame;
use mavlink::Message;
use std::sync::OnceLock;

/// MAVLink 1 start byte.
pub const STX_V1: u8 = 0xFE;
/// MAVLink 2 start byte.
pub const STX_V2: u8 = 0xFD;
/// Header bytes of a MAVLink 1 frame, the start byte included.
const V1_HEADER: usize = 6;
/// Header bytes of a MAVLink 2 frame, the start byte included.
const V2_HEADER: usize = 10;
/// Checksum bytes.
const CRC_LEN: usize = 2;
/// Signature bytes of a signed MAVLink 2 frame.
const SIGNATURE_LEN: usize = 13;
/// The one incompatibility flag MAVLink 2 defines: the frame is signed.
const IFLAG_SIGNED: u8 = 0x01;
/// The longest frame: a signed MAVLink 2 frame with 255 payload bytes.
pub const MAX_FRAME: usize = V2_HEADER + 255 + CRC_LEN + SIGNATURE_LEN;

/// The message set whose CRC_EXTRA bytes check the frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Dialect {
    /// `common.xml`.
    Common,
    /// `ardupilotmega.xml`, which includes `common.xml` (and PX4 speaks `common`): the default.
    #[default]
    ArduPilotMega,
}

/// How frames are read.
#[derive(Clone, Copy, Debug, Default)]
pub struct Config {
    /// The dialect whose CRC_EXTRA bytes check the frames.
    pub dialect: Dialect,
    /// The MAVLink 2 signing key: when set, a signed frame whose signature does not match is
    /// not yielded (counted in [`Counts::bad_signature`]). Unsigned frames are yielded either
    /// way ([`Frame::signed`] tells them apart); the replay checks of the signing protocol
    /// (timestamps per link) belong to a live link, not to a log.
    pub key: Option<[u8; 32]>,
}

/// What a reader found, counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Frames yielded (checksum verified).
    pub frames: u64,
    /// Of those, signed MAVLink 2 frames.
    pub signed: u64,
    /// Of those, MAVLink 1 frames.
    pub v1: u64,
    /// Candidate frames of a known message whose checksum did not hold.
    pub bad_crc: u64,
    /// Signed frames whose signature did not match the key.
    pub bad_signature: u64,
    /// MAVLink 2 candidates with an incompatibility flag other than "signed" (MAVLink says to
    /// drop them).
    pub bad_flags: u64,
    /// Candidates framed consistently (a start byte right after them) whose message id the
    /// dialect does not know: real messages of another dialect, or, rarely, garbage.
    pub unknown_id: u64,
    /// A frame cut short by the end of the input (at most one per stream or flow).
    pub truncated: u64,
    /// Bytes belonging to no frame (see the module comment).
    pub garbage_bytes: u64,
}

impl Counts {
    /// Adds `other` to `self`, field by field.
    pub fn add(&mut self, other: &Counts) {
        self.frames += other.frames;
        self.signed += other.signed;
        self.v1 += other.v1;
        self.bad_crc += other.bad_crc;
        self.bad_signature += other.bad_signature;
        self.bad_flags += other.bad_flags;
        self.unknown_id += other.unknown_id;
        self.truncated += other.truncated;
        self.garbage_bytes += other.garbage_bytes;
    }
}

/// CRC_EXTRA of every message id below 65536 of one dialect, -1 where the id is unknown.
type CrcTable = [i16; 65536];

fn build_table<M: Message>() -> Box<CrcTable> {
    let mut t = Box::new([-1i16; 65536]);
    for (id, slot) in t.iter_mut().enumerate() {
        // `extra_crc` answers 0 for an unknown id: only a default message tells known ids.
        if M::default_message_from_id(id as u32).is_some() {
            *slot = i16::from(M::extra_crc(id as u32));
        }
    }
    t
}

fn table(dialect: Dialect) -> &'static CrcTable {
    static COMMON: OnceLock<Box<CrcTable>> = OnceLock::new();
    static APM: OnceLock<Box<CrcTable>> = OnceLock::new();
    match dialect {
        Dialect::Common => COMMON.get_or_init(build_table::<mavlink::dialects::common::MavMessage>),
        Dialect::ArduPilotMega => APM.get_or_init(build_table::<mavlink::dialects::ardupilotmega::MavMessage>),
    }
}

/// The CRC_EXTRA byte of message `id` in `dialect`, or `None` when the dialect does not have it.
pub fn crc_extra(dialect: Dialect, id: u32) -> Option<u8> {
    if let Some(&e) = table(dialect).get(id as usize) {
        return u8::try_from(e).ok();
    }
    let known = match dialect {
        Dialect::Common => mavlink::dialects::common::MavMessage::default_message_from_id(id).is_some(),
        Dialect::ArduPilotMega => mavlink::dialects::ardupilotmega::MavMessage::default_message_from_id(id).is_some(),
    };
    known.then(|| match dialect {
        Dialect::Common => mavlink::dialects::common::MavMessage::extra_crc(id),
        Dialect::ArduPilotMega => mavlink::dialects::ardupilotmega::MavMessage::extra_crc(id),
    })
}

/// What the bytes at a start byte are.
#[derive(Debug)]
#[allow(clippy::large_enum_variant)]
pub(crate) enum Look<'a> {
    /// A checked frame of this many bytes.
    Frame(Frame<'a>),
    /// Not a frame: skip the start byte. The reason is counted by the caller.
    Bad(Reject),
    /// A consistently framed message the dialect does not know, of this many bytes.
    Unknown(usize),
    /// The input ends before the candidate does (or before the byte after an unknown message).
    NeedMore,
}

/// Why a candidate was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Reject {
    /// Not a start byte, or an unknown message not followed by a start byte.
    Garbage,
    Crc,
    Signature,
    Flags,
    /// A consistently framed message of an id the dialect does not have.
    Unknown,
}

/// Examines the candidate at the start of `buf` (`buf[0]` is expected to be a start byte).
/// `eof`: no more bytes will come after `buf`. `gap`: the bytes expected between one frame
/// and the next start byte (0 in a raw stream, 8 in a `.tlog`: the next timestamp).
pub(crate) fn look<'a>(buf: &'a [u8], cfg: &Config, eof: bool, gap: usize) -> Look<'a> {
    let Some(&stx) = buf.first() else { return Look::NeedMore };
    let (header, version) = match stx {
        STX_V1 => (V1_HEADER, 1u8),
        STX_V2 => (V2_HEADER, 2u8),
        _ => return Look::Bad(Reject::Garbage),
    };
    if buf.len() < header {
        return Look::NeedMore;
    }
    let len = usize::from(buf[1]);
    let (flags, sysid, compid, msgid) = if version == 1 {
        (0u8, buf[3], buf[4], u32::from(buf[5]))
    } else {
        (buf[2], buf[5], buf[6], u32::from_le_bytes([buf[7], buf[8], buf[9], 0]))
    };
    if flags & !IFLAG_SIGNED != 0 {
        return Look::Bad(Reject::Flags);
    }
    let signed = flags & IFLAG_SIGNED != 0;
    let total = header + len + CRC_LEN + if signed { SIGNATURE_LEN } else { 0 };
    if buf.len() < total {
        return Look::NeedMore;
    }
    let Some(extra) = crc_extra(cfg.dialect, msgid) else {
        return match buf.get(total + gap) {
            Some(&b) if b == STX_V1 || b == STX_V2 => Look::Unknown(total),
            Some(_) => Look::Bad(Reject::Garbage),
            None if eof => Look::Unknown(total),
            None => Look::NeedMore,
        };
    };
    let crc_at = header + len;
    let crc = u16::from_le_bytes([buf[crc_at], buf[crc_at + 1]]);
    if mavlink::calculate_crc(&buf[1..crc_at], extra) != crc {
        return Look::Bad(Reject::Crc);
    }
    let raw = &buf[..total];
    if signed {
        if let Some(key) = &cfg.key {
            if !signature_ok(raw, key) {
                return Look::Bad(Reject::Signature);
            }
        }
    }
    Look::Frame(Frame { time_us: None, version, sysid, compid, msgid, payload: &buf[header..crc_at], signed, raw })
}

/// Whether the signature of the signed MAVLink 2 frame `raw` is the one `key` gives.
fn signature_ok(raw: &[u8], key: &[u8; 32]) -> bool {
    let mut m = mavlink::MAVLinkV2MessageRaw::new();
    let Some(dst) = m.as_mut_slice().get_mut(..raw.len()) else { return false };
    dst.copy_from_slice(raw);
    let mut sig = [0u8; 6];
    m.calculate_signature(key, &mut sig);
    raw[raw.len() - 6..] == sig
}

/// What a framer yields: a checked frame, or (when asked for) the bytes of a consistently
/// framed message of an id the dialect does not know.
#[derive(Debug)]
pub enum Item<'a> {
    Frame(Frame<'a>),
    Unknown(&'a [u8]),
}

/// Whether a start byte inside `frame` (a prefix of `rest`) begins a checked frame; `None`
/// while a candidate inside runs past the end of `rest` (more input decides).
fn inner_frame(frame: &[u8], rest: &[u8], cfg: &Config, eof: bool) -> Option<bool> {
    for (i, &b) in frame.iter().enumerate().skip(1) {
        if b == STX_V1 || b == STX_V2 {
            match look(&rest[i..], cfg, eof, 0) {
                Look::Frame(_) => return Some(true),
                Look::NeedMore => return None,
                _ => {}
            }
        }
    }
    Some(false)
}

/// The framing state shared by the readers: the configuration and the counts.
#[derive(Clone, Debug, Default)]
pub struct Framer {
    /// How frames are checked.
    pub config: Config,
    /// What was found so far.
    pub counts: Counts,
    /// At the end of the input, a candidate ran past the end: it is a truncated frame unless
    /// a checked frame starts after its start byte (then it was garbage).
    pending_truncated: bool,
}

impl Framer {
    /// A framer with `config` and zero counts.
    pub fn new(config: Config) -> Self {
        Framer { config, counts: Counts::default(), pending_truncated: false }
    }

    /// The next frame in `buf` from `*pos` on, advancing `*pos` past it and past everything
    /// skipped before it. `None` when the rest of `buf` holds no complete frame: then `*pos`
    /// is at the first byte that a later chunk could still complete. With `eof` (no more input
    /// after `buf`), a candidate that runs past the end costs its start byte like any other
    /// failed candidate, and the last of them counts as one truncated frame if no checked
    /// frame follows it; its bytes are garbage.
    pub fn next<'b>(&mut self, buf: &'b [u8], pos: &mut usize, eof: bool) -> Option<Frame<'b>> {
        match self.next_item(buf, pos, eof, false) {
            Some(Item::Frame(f)) => Some(f),
            _ => None,
        }
    }

    /// As [`Framer::next`]; with `unknown`, a consistently framed message of an id the
    /// dialect does not know is yielded whole ([`Item::Unknown`], counted in `unknown_id`)
    /// instead of costing its start byte, provided no start byte inside it begins a checked
    /// frame: an unknown frame is never a way to carry a checked frame past the caller (a
    /// receiver that resynchronises byte by byte would find it). Until the input decides
    /// that (a candidate inside runs past the end), it waits, as for any candidate. The
    /// proxy forwards such frames as mavlink-router does.
    pub fn next_item<'b>(&mut self, buf: &'b [u8], pos: &mut usize, eof: bool, unknown: bool) -> Option<Item<'b>> {
        loop {
            let rest = buf.get(*pos..).unwrap_or(&[]);
            // Skip to the next start byte in one pass.
            let skip = rest.iter().position(|&b| b == STX_V1 || b == STX_V2).unwrap_or(rest.len());
            self.counts.garbage_bytes += skip as u64;
            *pos += skip;
            let rest = &rest[skip..];
            if rest.is_empty() {
                if eof && self.pending_truncated {
                    self.counts.truncated += 1;
                    self.pending_truncated = false;
                }
                return None;
            }
            match look(rest, &self.config, eof, 0) {
                Look::Frame(f) => {
                    *pos += f.raw.len();
                    self.pending_truncated = false;
                    self.count_frame(&f);
                    return Some(Item::Frame(f));
                }
                Look::Unknown(total) if unknown => match inner_frame(&rest[..total], rest, &self.config, eof) {
                    Some(false) => {
                        self.counts.unknown_id += 1;
                        *pos += total;
                        self.pending_truncated = false;
                        return Some(Item::Unknown(&rest[..total]));
                    }
                    Some(true) => {
                        self.reject(Reject::Unknown);
                        *pos += 1;
                    }
                    None => return None,
                },
                Look::Unknown(_) => {
                    self.reject(Reject::Unknown);
                    *pos += 1;
                }
                Look::Bad(why) => {
                    self.reject(why);
                    *pos += 1;
                }
                Look::NeedMore if eof => {
                    // Cut short by the end, or a start byte of garbage whose length field
                    // points past the end: a frame after it decides (see `pending_truncated`).
                    self.pending_truncated = true;
                    self.counts.garbage_bytes += 1;
                    *pos += 1;
                }
                Look::NeedMore => return None,
            }
        }
    }

    pub(crate) fn count_frame(&mut self, f: &Frame<'_>) {
        self.counts.frames += 1;
        self.counts.signed += u64::from(f.signed);
        self.counts.v1 += u64::from(f.version == 1);
    }

    /// Counts a rejected candidate; its start byte is garbage.
    pub(crate) fn reject(&mut self, why: Reject) {
        match why {
            Reject::Garbage => {}
            Reject::Crc => self.counts.bad_crc += 1,
            Reject::Signature => self.counts.bad_signature += 1,
            Reject::Flags => self.counts.bad_flags += 1,
            Reject::Unknown => self.counts.unknown_id += 1,
        }
        self.counts.garbage_bytes += 1;
    }
}

/// The frames of a complete raw MAVLink byte stream (no timestamps), in order.
///
/// ```
/// use mochi_monitor::mavio::parse::{Config, RawReader};
/// // A MAVLink 1 HEARTBEAT from system 1, component 1, after two bytes of garbage.
/// let bytes = [0x00, 0x42, 0xfe, 0x09, 0x00, 0x01, 0x01, 0x00,
///              0x04, 0, 0, 0, 0x02, 0x03, 0x51, 0x03, 0x03, 0xe4, 0xe1];
/// let mut r = RawReader::new(&bytes, Config::default());
/// let f = r.next().unwrap();
/// assert_eq!((f.version, f.sysid, f.compid, f.msgid), (1, 1, 1, 0));
/// assert!(r.next().is_none());
/// assert_eq!(r.counts().garbage_bytes, 2);
/// ```
#[derive(Clone, Debug)]
pub struct RawReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    framer: Framer,
}

impl<'a> RawReader<'a> {
    /// A reader over `bytes`, the whole stream.
    pub fn new(bytes: &'a [u8], config: Config) -> Self {
        RawReader { bytes, pos: 0, framer: Framer::new(config) }
    }

    /// What was found so far (all of it once the iterator is exhausted).
    pub fn counts(&self) -> Counts {
        self.framer.counts
    }
}

impl<'a> Iterator for RawReader<'a> {
    type Item = Frame<'a>;
    fn next(&mut self) -> Option<Frame<'a>> {
        self.framer.next(self.bytes, &mut self.pos, true)
    }
}

/// A stream fed in chunks (as from a socket or a TCP flow): bytes go in with [`Stream::push`],
/// frames come out with [`Stream::next_frame`] until it answers `None`, and [`Stream::finish`]
/// closes it. A frame split across chunks is yielded once its last byte has arrived.
///
/// The buffer keeps only what is not yet consumed (at most one incomplete frame) plus the
/// newest chunk: memory stays bounded by the largest chunk plus [`MAX_FRAME`] whatever the
/// input, and no allocation happens once it has grown to that.
#[derive(Clone, Debug)]
pub struct Stream {
    buf: Vec<u8>,
    pos: usize,
    time_us: Option<u64>,
    framer: Framer,
}

impl Stream {
    /// An empty stream.
    pub fn new(config: Config) -> Self {
        Stream { buf: Vec::with_capacity(4096), pos: 0, time_us: None, framer: Framer::new(config) }
    }

    /// Appends a chunk. Frames completed by it carry `time_us` (the time the chunk arrived).
    pub fn push(&mut self, chunk: &[u8], time_us: Option<u64>) {
        if self.pos > 0 {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        self.buf.extend_from_slice(chunk);
        self.time_us = time_us;
    }

    /// The next complete frame or, when the dialect does not know its id, the bytes of a
    /// consistently framed message ([`Framer::next_item`]); `None` until more bytes are
    /// pushed.
    pub fn next_item(&mut self) -> Option<Item<'_>> {
        let t = self.time_us;
        match self.framer.next_item(&self.buf, &mut self.pos, false, true)? {
            Item::Frame(f) => Some(Item::Frame(Frame { time_us: t, ..f })),
            u => Some(u),
        }
    }

    /// The next complete frame, or `None` until more bytes are pushed.
    pub fn next_frame(&mut self) -> Option<Frame<'_>> {
        let t = self.time_us;
        self.framer.next(&self.buf, &mut self.pos, false).map(|f| Frame { time_us: t, ..f })
    }

    /// Ends the stream: the frames still complete in the buffer, then the counts (an
    /// incomplete frame left over is counted as truncated). Call [`Stream::next_frame`] until
    /// `None` first; `finish` yields what is left through `each`.
    pub fn finish(&mut self, mut each: impl FnMut(Frame<'_>)) -> Counts {
        let t = self.time_us;
        while let Some(f) = self.framer.next(&self.buf, &mut self.pos, true) {
            each(Frame { time_us: t, ..f });
        }
        self.buf.clear();
        self.pos = 0;
        self.framer.counts
    }

    /// What was found so far.
    pub fn counts(&self) -> Counts {
        self.framer.counts
    }

    /// Bytes held (for tests of the memory bound).
    pub fn buffered(&self) -> usize {
        self.buf.len() - self.pos
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn heartbeat_v1() -> Vec<u8> {
        vec![0xfe, 0x09, 0x00, 0x01, 0x01, 0x00, 0x04, 0, 0, 0, 0x02, 0x03, 0x51, 0x03, 0x03, 0xe4, 0xe1]
    }

    #[test]
    fn crc_extra_matches_the_spec() {
        // HEARTBEAT 50, SYS_STATUS 124, MISSION_ITEM_INT 38, PARAM_VALUE 220 (common.xml).
        for (id, e) in [(0, 50), (1, 124), (73, 38), (22, 220)] {
            assert_eq!(crc_extra(Dialect::Common, id), Some(e), "id {id}");
            assert_eq!(crc_extra(Dialect::ArduPilotMega, id), Some(e), "id {id}");
        }
        // AHRS (163) is ardupilotmega only.
        assert_eq!(crc_extra(Dialect::Common, 163), None);
        assert!(crc_extra(Dialect::ArduPilotMega, 163).is_some());
        assert_eq!(crc_extra(Dialect::ArduPilotMega, 0xff_ffff), None);
    }

    #[test]
    fn a_flipped_bit_is_a_bad_crc_and_resync_finds_the_next_frame() {
        let mut b = heartbeat_v1();
        b[8] ^= 1;
        b.extend(heartbeat_v1());
        let mut r = RawReader::new(&b, Config::default());
        assert!(r.next().is_some());
        assert!(r.next().is_none());
        let c = r.counts();
        assert_eq!((c.frames, c.bad_crc, c.garbage_bytes), (1, 1, 17));
    }

    #[test]
    fn a_cut_frame_at_the_end_is_truncated() {
        let mut b = heartbeat_v1();
        b.extend(&heartbeat_v1()[..10]);
        let mut r = RawReader::new(&b, Config::default());
        assert_eq!(r.by_ref().count(), 1);
        assert_eq!(r.counts().truncated, 1);
    }

    #[test]
    fn an_unknown_id_followed_by_a_frame_is_counted_and_costs_one_byte() {
        // A v2 frame with message id 0xABCDEF (in no dialect), 3 payload bytes, then a frame.
        let mut b = vec![0xfd, 3, 0, 0, 7, 1, 1, 0xef, 0xcd, 0xab, 0xfe, 0xfe, 0xfe, 0, 0];
        b.extend(heartbeat_v1());
        let mut r = RawReader::new(&b, Config::default());
        assert_eq!(r.by_ref().count(), 1);
        let c = r.counts();
        // Its 15 bytes are garbage; the start bytes inside its payload are failed candidates
        // (cut short by the frame after them, so their checksums fail).
        assert_eq!((c.unknown_id, c.garbage_bytes), (1, 15));
    }

    #[test]
    fn undefined_incompatibility_flags_are_dropped() {
        let b = vec![0xfd, 0, 0x02, 0, 0, 1, 1, 0, 0, 0, 0, 0];
        let mut r = RawReader::new(&b, Config::default());
        assert!(r.next().is_none());
        assert_eq!(r.counts().bad_flags, 1);
    }
}
