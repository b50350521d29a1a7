//! MAVLink in packet captures: `.pcapng` and classic `.pcap` files, the UDP and TCP payloads
//! of each flow read as a MAVLink byte stream.
//!
//! A minimal reader, not a crate: of the Rust pcap readers, `pcap-file`'s current line is a
//! release candidate (3.0.0-rc) and `pcap-parser` brings `nom` and two more crates; both stop
//! at the capture's blocks, leaving the link, IP, UDP and TCP layers to the caller anyway. The
//! blocks MAVLink captures use are few (pcapng: section header, interface description,
//! enhanced and simple packet; pcap: the file header and records), so they are read here, in
//! either byte order, with every length checked against the bytes present.
//!
//! Layers read: link types NULL/LOOP (0, 108), Ethernet (1, with 802.1Q tags), raw IP (101,
//! 228, 229), Linux cooked v1 and v2 (113, 276); IPv4 (unfragmented; fragments are counted
//! and skipped) and IPv6 (UDP or TCP directly after the fixed header); UDP and TCP. Each
//! direction of each flow (addresses, ports, protocol) is its own [`Stream`]: a frame split
//! across TCP segments is joined, a TCP segment already seen (a retransmission) is dropped by
//! its sequence number, and a gap (a segment the capture missed) is left to resynchronisation.
//! Each frame carries the time of the packet that completed it.

use super::parse::{Config, Counts, Stream};
use super::Frame;

/// What a capture held besides frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaptureCounts {
    /// Packets read.
    pub packets: u64,
    /// Packets that carried UDP or TCP payload (read as MAVLink).
    pub payload_packets: u64,
    /// Packets skipped: another link type or protocol, IP fragments, cut headers.
    pub skipped_packets: u64,
    /// Flows (one direction of one UDP or TCP conversation).
    pub flows: u64,
    /// TCP segments dropped as already seen (retransmissions).
    pub retransmissions: u64,
}

/// Why a capture could not be read (past the point given, nothing more is read).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CaptureError {
    /// Byte offset in the file of the block or record that is malformed.
    pub offset: usize,
    /// What is wrong.
    pub what: &'static str,
}

/// Whether `bytes` starts like a pcapng file.
pub fn is_pcapng(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0x0a, 0x0d, 0x0d, 0x0a])
}

/// Whether `bytes` starts like a classic pcap file (either byte order, micro or nanoseconds).
pub fn is_pcap(bytes: &[u8]) -> bool {
    matches!(
        bytes.get(..4),
        Some([0xa1, 0xb2, 0xc3, 0xd4] | [0xd4, 0xc3, 0xb2, 0xa1] | [0xa1, 0xb2, 0x3c, 0x4d] | [0x4d, 0x3c, 0xb2, 0xa1])
    )
}

/// A flow's key: protocol, source and destination address (IPv4 mapped into 16 bytes) and port.
type FlowKey = (u8, [u8; 16], u16, [u8; 16], u16);

struct Flow {
    key: FlowKey,
    stream: Stream,
    /// TCP: the sequence number of the next byte expected.
    next_seq: Option<u32>,
}

/// Reads the packets of a capture and hands every MAVLink frame found to `each`, in the
/// order the packets were captured. Returns the framing counts (all flows added up), the
/// capture's counts, and the error that stopped the reading early, if any (what was read
/// before it is still reported).
pub fn read_capture(
    bytes: &[u8],
    config: Config,
    mut each: impl FnMut(Frame<'_>),
) -> (Counts, CaptureCounts, Option<CaptureError>) {
    let mut st = State { config, flows: Vec::new(), counts: CaptureCounts::default() };
    let err = if is_pcapng(bytes) {
        read_pcapng(bytes, &mut |link, t, data| st.packet(link, t, data, &mut each))
    } else if is_pcap(bytes) {
        read_pcap(bytes, &mut |link, t, data| st.packet(link, t, data, &mut each))
    } else {
        Some(CaptureError { offset: 0, what: "not a pcap or pcapng file" })
    };
    let mut counts = Counts::default();
    for f in &mut st.flows {
        counts.add(&f.stream.finish(&mut each));
    }
    st.counts.flows = st.flows.len() as u64;
    (counts, st.counts, err)
}

struct State {
    config: Config,
    flows: Vec<Flow>,
    counts: CaptureCounts,
}

impl State {
    fn packet(&mut self, link: u32, time_us: Option<u64>, data: &[u8], each: &mut impl FnMut(Frame<'_>)) {
        self.counts.packets += 1;
        let Some((key, seq, payload)) = transport(link, data) else {
            self.counts.skipped_packets += 1;
            return;
        };
        self.counts.payload_packets += 1;
        let i = match self.flows.iter().position(|f| f.key == key) {
            Some(i) => i,
            None => {
                self.flows.push(Flow { key, stream: Stream::new(self.config), next_seq: None });
                self.flows.len() - 1
            }
        };
        let flow = &mut self.flows[i];
        let mut payload = payload;
        if let Some(seq) = seq {
            if let Some(next) = flow.next_seq {
                // Bytes before `next` were seen already: drop them (serial-number arithmetic).
                let behind = next.wrapping_sub(seq);
                if (1..0x8000_0000).contains(&behind) {
                    if behind as usize >= payload.len() {
                        self.counts.retransmissions += 1;
                        return;
                    }
                    payload = &payload[behind as usize..];
                }
            }
            let start = flow.next_seq.filter(|n| n.wrapping_sub(seq) < 0x8000_0000).unwrap_or(seq);
            flow.next_seq = Some(start.wrapping_add(payload.len() as u32));
        }
        flow.stream.push(payload, time_us);
        while let Some(f) = flow.stream.next_frame() {
            each(f);
        }
    }
}

fn u16_at(b: &[u8], at: usize, le: bool) -> Option<u16> {
    let x: [u8; 2] = b.get(at..at + 2)?.try_into().ok()?;
    Some(if le { u16::from_le_bytes(x) } else { u16::from_be_bytes(x) })
}

fn u32_at(b: &[u8], at: usize, le: bool) -> Option<u32> {
    let x: [u8; 4] = b.get(at..at + 4)?.try_into().ok()?;
    Some(if le { u32::from_le_bytes(x) } else { u32::from_be_bytes(x) })
}

/// The packets of a pcapng file: (link type, time in µs, packet bytes).
fn read_pcapng(bytes: &[u8], each: &mut impl FnMut(u32, Option<u64>, &[u8])) -> Option<CaptureError> {
    let mut at = 0usize;
    let mut le = true;
    // Per interface of the current section: link type and the timestamp unit (ticks per s).
    let mut ifaces: Vec<(u32, u64)> = Vec::new();
    while at < bytes.len() {
        let bad = |what| Some(CaptureError { offset: at, what });
        let Some(kind) = u32_at(bytes, at, le) else { return bad("block header cut short") };
        if kind == 0x0a0d_0d0a {
            // Section header: the byte-order magic decides how the rest is read.
            match bytes.get(at + 8..at + 12) {
                Some([0x4d, 0x3c, 0x2b, 0x1a]) => le = true,
                Some([0x1a, 0x2b, 0x3c, 0x4d]) => le = false,
                _ => return bad("section header without a byte-order magic"),
            }
            ifaces.clear();
        }
        let Some(len) = u32_at(bytes, at + 4, le).map(|l| l as usize) else { return bad("block header cut short") };
        if len < 12 || len % 4 != 0 || at + len > bytes.len() {
            return bad("block length out of range");
        }
        let body = &bytes[at + 8..at + len - 4];
        match kind {
            1 => {
                let Some(link) = u16_at(body, 0, le) else { return bad("interface block cut short") };
                let mut unit = 1_000_000u64;
                // Options from byte 8: code, length, value padded to 4 bytes.
                let mut o = 8usize;
                while let (Some(code), Some(olen)) = (u16_at(body, o, le), u16_at(body, o + 2, le)) {
                    if code == 0 {
                        break;
                    }
                    if code == 9 && olen >= 1 {
                        if let Some(&r) = body.get(o + 4) {
                            let e = u32::from(r & 0x7f);
                            unit = if r & 0x80 == 0 { 10u64.checked_pow(e) } else { 1u64.checked_shl(e) }.unwrap_or(0);
                        }
                    }
                    o += 4 + usize::from(olen).div_ceil(4) * 4;
                }
                ifaces.push((u32::from(link), unit));
            }
            6 => {
                let (Some(iface), Some(hi), Some(lo), Some(cap)) =
                    (u32_at(body, 0, le), u32_at(body, 4, le), u32_at(body, 8, le), u32_at(body, 12, le))
                else {
                    return bad("packet block cut short");
                };
                let Some(data) = body.get(20..20 + cap as usize) else { return bad("packet longer than its block") };
                let Some(&(link, unit)) = ifaces.get(iface as usize) else {
                    return bad("packet of an undeclared interface");
                };
                let ticks = (u64::from(hi) << 32) | u64::from(lo);
                let time = (unit > 0).then(|| (u128::from(ticks) * 1_000_000 / u128::from(unit)) as u64);
                each(link, time, data);
            }
            3 => {
                let Some(&(link, _)) = ifaces.first() else { return bad("packet of an undeclared interface") };
                let Some(orig) = u32_at(body, 0, le) else { return bad("packet block cut short") };
                let data = &body[4..];
                each(link, None, &data[..data.len().min(orig as usize)]);
            }
            _ => {}
        }
        at += len;
    }
    None
}

/// The packets of a classic pcap file.
fn read_pcap(bytes: &[u8], each: &mut impl FnMut(u32, Option<u64>, &[u8])) -> Option<CaptureError> {
    let (le, nanos) = match bytes.get(..4) {
        Some([0xd4, 0xc3, 0xb2, 0xa1]) => (true, false),
        Some([0xa1, 0xb2, 0xc3, 0xd4]) => (false, false),
        Some([0x4d, 0x3c, 0xb2, 0xa1]) => (true, true),
        _ => (false, true),
    };
    let Some(link) = u32_at(bytes, 20, le) else {
        return Some(CaptureError { offset: 0, what: "file header cut short" });
    };
    let link = link & 0x0fff_ffff;
    let mut at = 24usize;
    while at < bytes.len() {
        let (Some(sec), Some(frac), Some(cap)) =
            (u32_at(bytes, at, le), u32_at(bytes, at + 4, le), u32_at(bytes, at + 8, le))
        else {
            return Some(CaptureError { offset: at, what: "record header cut short" });
        };
        let Some(data) = bytes.get(at + 16..at + 16 + cap as usize) else {
            return Some(CaptureError { offset: at, what: "record longer than the file" });
        };
        let frac_us = if nanos { u64::from(frac) / 1000 } else { u64::from(frac) };
        each(link, Some(u64::from(sec) * 1_000_000 + frac_us), data);
        at += 16 + cap as usize;
    }
    None
}

/// The flow, TCP sequence number and payload of a UDP or TCP packet; `None` for anything else.
fn transport(link: u32, data: &[u8]) -> Option<(FlowKey, Option<u32>, &[u8])> {
    let (ethertype, ip) = match link {
        0 | 108 => {
            // The address family, in the capturing host's order (NULL) or big-endian (LOOP).
            let fam = u32_at(data, 0, link == 0)?;
            let fam = if link == 0 && fam > 0xffff { fam.swap_bytes() } else { fam };
            (if fam == 2 { 0x0800 } else { 0x86dd }, data.get(4..)?)
        }
        1 => {
            let mut off = 12;
            let mut t = u16_at(data, off, false)?;
            while t == 0x8100 || t == 0x88a8 {
                off += 4;
                t = u16_at(data, off, false)?;
            }
            (t, data.get(off + 2..)?)
        }
        101 | 228 | 229 => (if data.first()? >> 4 == 6 { 0x86dd } else { 0x0800 }, data),
        113 => (u16_at(data, 14, false)?, data.get(16..)?),
        276 => (u16_at(data, 0, false)?, data.get(20..)?),
        _ => return None,
    };
    let (proto, src, dst, l4) = match ethertype {
        0x0800 => {
            let ihl = usize::from(ip.first()? & 0x0f) * 4;
            let total = usize::from(u16_at(ip, 2, false)?);
            let frag = u16_at(ip, 6, false)?;
            if frag & 0x3fff != 0 || ihl < 20 {
                return None;
            }
            let mut s = [0u8; 16];
            let mut d = [0u8; 16];
            s[12..].copy_from_slice(ip.get(12..16)?);
            d[12..].copy_from_slice(ip.get(16..20)?);
            (*ip.get(9)?, s, d, ip.get(ihl..total.min(ip.len()).max(ihl))?)
        }
        0x86dd => {
            let plen = usize::from(u16_at(ip, 4, false)?);
            let s: [u8; 16] = ip.get(8..24)?.try_into().ok()?;
            let d: [u8; 16] = ip.get(24..40)?.try_into().ok()?;
            (*ip.get(6)?, s, d, ip.get(40..(40 + plen).min(ip.len()))?)
        }
        _ => return None,
    };
    let sport = u16_at(l4, 0, false)?;
    let dport = u16_at(l4, 2, false)?;
    match proto {
        17 => {
            let len = usize::from(u16_at(l4, 4, false)?).clamp(8, l4.len());
            Some(((17, src, sport, dst, dport), None, l4.get(8..len)?))
        }
        6 => {
            let seq = u32_at(l4, 4, false)?;
            let off = usize::from(l4.get(12)? >> 4) * 4;
            let flags = *l4.get(13)?;
            // SYN takes one sequence number before the data.
            let seq = if flags & 0x02 != 0 { seq.wrapping_add(1) } else { seq };
            Some(((6, src, sport, dst, dport), Some(seq), l4.get(off.max(20)..)?))
        }
        _ => None,
    }
}
