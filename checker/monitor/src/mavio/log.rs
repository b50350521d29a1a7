//! MAVLink logs: `.tlog` files, raw byte streams and packet captures, recognised from their
//! content.
//!
//! A `.tlog` (written by MAVProxy, QGroundControl, Mission Planner) is a sequence of records,
//! each an 8-byte big-endian timestamp (microseconds since the Unix epoch) followed by one
//! MAVLink frame; the timestamp is kept as [`Frame::time_us`]. A raw stream (a serial or UDP
//! dump, `.bin`/`.raw`) is frames back to back with no time. Captures are read by
//! [`super::pcap`].
//!
//! In a `.tlog` a frame is looked for only where the record structure puts one (8 bytes after
//! the previous frame); a failed candidate there (bad checksum, bad signature, undefined
//! flags) is counted, and the reader then resynchronises: it looks for the next start byte
//! that begins a checked frame at least 8 bytes further on, and takes the 8 bytes before it
//! as that frame's timestamp. What lies in between is garbage (start bytes in it are not
//! counted as failed candidates: inside a timestamp 0xFE and 0xFD are ordinary bytes). A
//! record whose message the dialect does not know is counted and skipped the same way.

use super::parse::{look, Config, Counts, Framer, Look, RawReader, STX_V1, STX_V2};
use super::pcap::{self, CaptureCounts, CaptureError};
use super::Frame;

/// The formats a log can be in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Timestamped records (`.tlog`).
    Tlog,
    /// Frames back to back, no time.
    Raw,
    /// A pcapng capture.
    Pcapng,
    /// A classic pcap capture.
    Pcap,
}

impl Format {
    /// The format's usual name.
    pub fn name(self) -> &'static str {
        match self {
            Format::Tlog => "tlog",
            Format::Raw => "raw",
            Format::Pcapng => "pcapng",
            Format::Pcap => "pcap",
        }
    }
}

/// How much of the file [`detect`] reads.
const DETECT_WINDOW: usize = 1 << 16;

/// The format of `bytes`, from their content: the capture magics, else the spacing of the
/// first checked frames (8 bytes between one frame's end and the next frame's start is a
/// `.tlog`, none a raw stream; a file with no two frames in its first 64 KiB is a `.tlog` when
/// its first frame starts 8 bytes in, else raw). The file's name is not needed.
pub fn detect(bytes: &[u8]) -> Format {
    if pcap::is_pcapng(bytes) {
        return Format::Pcapng;
    }
    if pcap::is_pcap(bytes) {
        return Format::Pcap;
    }
    let window = &bytes[..bytes.len().min(DETECT_WINDOW)];
    let (mut tlog, mut raw) = (0u32, 0u32);
    let mut first: Option<usize> = None;
    let mut prev_end: Option<usize> = None;
    for f in RawReader::new(window, Config::default()) {
        let start = f.raw.as_ptr() as usize - window.as_ptr() as usize;
        first.get_or_insert(start);
        match prev_end.map(|e| start - e) {
            Some(8) => tlog += 1,
            Some(0) => raw += 1,
            _ => {}
        }
        prev_end = Some(start + f.raw.len());
        if tlog + raw >= 16 {
            break;
        }
    }
    if tlog > raw || (tlog == raw && first == Some(8)) {
        Format::Tlog
    } else {
        Format::Raw
    }
}

/// The frames of a `.tlog`, each with its record's timestamp.
#[derive(Clone, Debug)]
pub struct TlogReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    framer: Framer,
}

impl<'a> TlogReader<'a> {
    /// A reader over the whole `.tlog` in `bytes`.
    pub fn new(bytes: &'a [u8], config: Config) -> Self {
        TlogReader { bytes, pos: 0, framer: Framer::new(config) }
    }

    /// What was found so far.
    pub fn counts(&self) -> Counts {
        self.framer.counts
    }

    fn timed(&self, at: usize, f: Frame<'a>) -> Frame<'a> {
        let ts: [u8; 8] = self.bytes[at..at + 8].try_into().unwrap_or([0; 8]);
        Frame { time_us: Some(u64::from_be_bytes(ts)), ..f }
    }

    /// The next checked frame starting at least 8 bytes after `from`, with its timestamp;
    /// everything before its timestamp is garbage.
    fn resync(&mut self, from: usize) -> Option<Frame<'a>> {
        let b = self.bytes;
        let mut s = from + 8;
        while s < b.len() {
            if b[s] == STX_V1 || b[s] == STX_V2 {
                if let Look::Frame(f) = look(&b[s..], &self.framer.config, true, 8) {
                    self.framer.counts.garbage_bytes += (s - 8 - from) as u64;
                    self.pos = s + f.raw.len();
                    self.framer.count_frame(&f);
                    return Some(self.timed(s - 8, f));
                }
            }
            s += 1;
        }
        self.framer.counts.garbage_bytes += (b.len() - from) as u64;
        self.pos = b.len();
        None
    }
}

impl<'a> Iterator for TlogReader<'a> {
    type Item = Frame<'a>;
    fn next(&mut self) -> Option<Frame<'a>> {
        let b = self.bytes;
        let at = self.pos;
        if at >= b.len() {
            return None;
        }
        let Some(rest) = b.get(at + 8..).filter(|r| !r.is_empty()) else {
            // A timestamp (or part of one) with no frame after it.
            self.framer.counts.truncated += 1;
            self.pos = b.len();
            return None;
        };
        match look(rest, &self.framer.config, true, 8) {
            Look::Frame(f) => {
                self.pos = at + 8 + f.raw.len();
                self.framer.count_frame(&f);
                Some(self.timed(at, f))
            }
            Look::Unknown(_) => {
                self.framer.counts.unknown_id += 1;
                self.resync(at)
            }
            Look::NeedMore => {
                self.framer.counts.truncated += 1;
                self.pos = b.len();
                None
            }
            Look::Bad(why) => {
                self.framer.reject(why);
                // `reject` counted the start byte as garbage; `resync` counts from `at`.
                self.framer.counts.garbage_bytes -= 1;
                self.resync(at)
            }
        }
    }
}

/// What reading a log found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogSummary {
    /// The format read.
    pub format: Format,
    /// Framing counts.
    pub counts: Counts,
    /// For captures: packets, flows, skipped packets.
    pub capture: Option<CaptureCounts>,
    /// For captures: what stopped the reading early.
    pub error: Option<CaptureError>,
}

/// Reads the log in `bytes` (format from [`detect`]) and hands every frame to `each`, in order.
///
/// ```
/// use mochi_monitor::mavio::{log::{read_log, Format}, parse::Config};
/// // One .tlog record: time 1 s, then a MAVLink 1 HEARTBEAT.
/// let mut b = 1_000_000u64.to_be_bytes().to_vec();
/// b.extend([0xfe, 0x09, 0x00, 0x01, 0x01, 0x00, 0x04, 0, 0, 0, 0x02, 0x03, 0x51, 0x03, 0x03, 0xe4, 0xe1]);
/// let mut times = vec![];
/// let s = read_log(&b, Config::default(), |f| times.push(f.time_us));
/// assert_eq!(s.format, Format::Tlog);
/// assert_eq!(times, [Some(1_000_000)]);
/// ```
pub fn read_log(bytes: &[u8], config: Config, each: impl FnMut(Frame<'_>)) -> LogSummary {
    read_log_as(detect(bytes), bytes, config, each)
}

/// [`read_log`] in a given format.
pub fn read_log_as(format: Format, bytes: &[u8], config: Config, mut each: impl FnMut(Frame<'_>)) -> LogSummary {
    match format {
        Format::Tlog => {
            let mut r = TlogReader::new(bytes, config);
            r.by_ref().for_each(&mut each);
            LogSummary { format, counts: r.counts(), capture: None, error: None }
        }
        Format::Raw => {
            let mut r = RawReader::new(bytes, config);
            r.by_ref().for_each(&mut each);
            LogSummary { format, counts: r.counts(), capture: None, error: None }
        }
        Format::Pcapng | Format::Pcap => {
            let (counts, cap, error) = pcap::read_capture(bytes, config, each);
            LogSummary { format, counts, capture: Some(cap), error }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HB: [u8; 17] = [0xfe, 0x09, 0x00, 0x01, 0x01, 0x00, 0x04, 0, 0, 0, 0x02, 0x03, 0x51, 0x03, 0x03, 0xe4, 0xe1];

    fn tlog(times: &[u64]) -> Vec<u8> {
        let mut b = Vec::new();
        for t in times {
            b.extend(t.to_be_bytes());
            b.extend(HB);
        }
        b
    }

    #[test]
    fn tlog_and_raw_are_told_apart_by_content() {
        assert_eq!(detect(&tlog(&[1, 2, 3])), Format::Tlog);
        assert_eq!(detect(&HB.repeat(3)), Format::Raw);
        assert_eq!(detect(&tlog(&[5])), Format::Tlog);
    }

    #[test]
    fn a_bad_record_in_a_tlog_costs_only_itself() {
        let mut b = tlog(&[1, 2, 3]);
        b[8 + 25 + 10] ^= 0xff; // the second record's payload
        let mut r = TlogReader::new(&b, Config::default());
        let times: Vec<_> = r.by_ref().map(|f| f.time_us).collect();
        assert_eq!(times, [Some(1), Some(3)]);
        let c = r.counts();
        assert_eq!((c.bad_crc, c.garbage_bytes, c.truncated), (1, 25, 0));
    }

    #[test]
    fn timestamps_with_start_bytes_in_them_are_not_candidates() {
        let t = 0x0005_fefd_fefd_fefd;
        let b = tlog(&[t, t + 1]);
        let mut r = TlogReader::new(&b, Config::default());
        assert_eq!(r.by_ref().count(), 2);
        assert_eq!(r.counts(), Counts { frames: 2, v1: 2, ..Counts::default() });
    }
}
