//! One MAVLink frame as read from a log or a link: what the run-time monitor consumes.
//!
//! Readers (`.tlog`, raw streams, `.pcapng`, UDP/TCP links) produce it; the monitor reads it.
//! The payload is as on the wire: MAVLink 2's truncation of trailing zero bytes is not undone
//! (a field beyond the payload's end reads as zero).

/// A frame whose checksum (with the message's CRC_EXTRA) has been verified.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// Microseconds since the Unix epoch, when the log or the clock gives it.
    pub time_us: Option<u64>,
    /// The MAVLink version of the frame: 1 or 2.
    pub version: u8,
    /// The sender's system id.
    pub sysid: u8,
    /// The sender's component id.
    pub compid: u8,
    /// The message id.
    pub msgid: u32,
    /// The payload bytes as received.
    pub payload: &'a [u8],
    /// Whether the frame is a signed MAVLink 2 frame (the signature is not checked here).
    pub signed: bool,
    /// The whole frame as received, for forwarding byte for byte.
    pub raw: &'a [u8],
}
