//! The wire layout of a MAVLink message's payload, and decoding a field from it by name.
//!
//! Why here and not in the `mavlink` crate: the crate decodes a payload into a typed struct
//! per message, with no access to a field by its name, and the monitor must read exactly the
//! fields a protocol lists, chosen at run time from the dialect. So the layout is computed
//! from the dialect (the same XML the static checks read), as the MAVLink specification
//! gives it: the fields that are not extensions sorted by the size of their (element) type,
//! largest first, stable (XML order among equal sizes); the extension fields after them in
//! XML order; little-endian values; a MAVLink 2 payload truncated of its trailing zero bytes
//! reads as zero beyond its end. `tests/monitor.rs` checks this decoder against the crate's
//! decoding of random messages of the common dialect, field by field.

use crate::dialect::{Message, Wire};

/// Where one field of a message lies in its payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    pub offset: u16,
    pub wire: Wire,
    /// The number of elements (1 for a scalar; `N` for `type[N]`).
    pub len: u16,
}

/// The layout of a message: each field's slot, in the XML order of the fields.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub slots: Vec<Slot>,
    /// The payload's length without truncation (MAVLink 2 extensions included).
    pub size: u16,
    /// The length of the MAVLink 1 payload (without extension fields).
    pub base_size: u16,
}

impl Layout {
    /// The layout of `m`.
    pub fn of(m: &Message) -> Layout {
        let mut order: Vec<usize> = (0..m.fields.len()).filter(|&i| !m.fields[i].extension).collect();
        // Stable: equal sizes keep the XML order.
        order.sort_by_key(|&i| std::cmp::Reverse(m.fields[i].wire.bytes()));
        let base = order.len();
        order.extend((0..m.fields.len()).filter(|&i| m.fields[i].extension));
        let mut slots = vec![Slot { offset: 0, wire: Wire::U8, len: 1 }; m.fields.len()];
        let mut at = 0u32;
        let mut base_size = 0u32;
        for (k, &i) in order.iter().enumerate() {
            if k == base {
                base_size = at;
            }
            let f = &m.fields[i];
            let len = f.array.unwrap_or(1);
            slots[i] = Slot { offset: at as u16, wire: f.wire, len: len as u16 };
            at += f.wire.bytes() * len;
        }
        if base == order.len() {
            base_size = at;
        }
        Layout { slots, size: at as u16, base_size: base_size as u16 }
    }

    /// The slot of the field called `name` of `m` (whose layout this is).
    pub fn slot(&self, m: &Message, name: &str) -> Option<Slot> {
        m.fields.iter().position(|f| f.name == name).map(|i| self.slots[i])
    }
}

/// The `len` bytes at `offset` of `payload`, zero beyond its end (MAVLink 2 truncation).
#[inline]
fn bytes<const N: usize>(payload: &[u8], offset: usize) -> [u8; N] {
    let mut out = [0u8; N];
    if let Some(rest) = payload.get(offset..) {
        let n = rest.len().min(N);
        out[..n].copy_from_slice(&rest[..n]);
    }
    out
}

/// A scalar read from the wire.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scalar {
    Int(i128),
    F32(f32),
    F64(f64),
}

/// Element `k` of the field at `slot` (0 for a scalar).
#[inline]
pub fn read(payload: &[u8], slot: Slot, k: usize) -> Scalar {
    let at = slot.offset as usize + k * slot.wire.bytes() as usize;
    match slot.wire {
        Wire::U8 | Wire::Char => Scalar::Int(i128::from(bytes::<1>(payload, at)[0])),
        Wire::I8 => Scalar::Int(i128::from(i8::from_le_bytes(bytes(payload, at)))),
        Wire::U16 => Scalar::Int(i128::from(u16::from_le_bytes(bytes(payload, at)))),
        Wire::I16 => Scalar::Int(i128::from(i16::from_le_bytes(bytes(payload, at)))),
        Wire::U32 => Scalar::Int(i128::from(u32::from_le_bytes(bytes(payload, at)))),
        Wire::I32 => Scalar::Int(i128::from(i32::from_le_bytes(bytes(payload, at)))),
        Wire::U64 => Scalar::Int(i128::from(u64::from_le_bytes(bytes(payload, at)))),
        Wire::I64 => Scalar::Int(i128::from(i64::from_le_bytes(bytes(payload, at)))),
        Wire::F32 => Scalar::F32(f32::from_le_bytes(bytes(payload, at))),
        Wire::F64 => Scalar::F64(f64::from_le_bytes(bytes(payload, at))),
    }
}

/// The string of a `char[N]` field: its bytes up to the first NUL (or all N), zero beyond
/// the payload's end.
pub fn read_str(payload: &[u8], slot: Slot) -> &[u8] {
    let start = (slot.offset as usize).min(payload.len());
    let end = (slot.offset as usize + slot.len as usize).min(payload.len());
    let s = &payload[start..end];
    match s.iter().position(|&b| b == 0) {
        Some(n) => &s[..n],
        None => s,
    }
}

/// Writes a scalar into `payload` at element `k` of `slot` (for tests, benchmarks and
/// examples that build frames; `payload` must be `size` bytes long). An integer is written
/// in the field's width (two's complement), a float rounded to the field's format.
pub fn write(payload: &mut [u8], slot: Slot, k: usize, v: Scalar) {
    let at = slot.offset as usize + k * slot.wire.bytes() as usize;
    let n = slot.wire.bytes() as usize;
    let mut put = |b: &[u8]| {
        if let Some(dst) = payload.get_mut(at..at + n) {
            dst.copy_from_slice(&b[..n]);
        }
    };
    let i = match v {
        Scalar::Int(i) => i,
        Scalar::F32(x) => x as i128,
        Scalar::F64(x) => x as i128,
    };
    match slot.wire {
        Wire::F32 => put(&(match v {
            Scalar::F32(x) => x,
            Scalar::F64(x) => x as f32,
            Scalar::Int(i) => i as f32,
        })
        .to_le_bytes()),
        Wire::F64 => put(&(match v {
            Scalar::F32(x) => f64::from(x),
            Scalar::F64(x) => x,
            Scalar::Int(i) => i as f64,
        })
        .to_le_bytes()),
        _ => put(&(i as i64).to_le_bytes()),
    }
}

/// Writes a string into a `char[N]` field (cut at N bytes, NUL-padded).
pub fn write_str(payload: &mut [u8], slot: Slot, s: &[u8]) {
    for k in 0..slot.len as usize {
        if let Some(b) = payload.get_mut(slot.offset as usize + k) {
            *b = s.get(k).copied().unwrap_or(0);
        }
    }
}

/// `payload` with its trailing zero bytes removed, as MAVLink 2 sends it (at least one byte).
pub fn truncate(payload: &[u8]) -> &[u8] {
    let n = payload.iter().rposition(|&b| b != 0).map_or(1, |i| i + 1);
    &payload[..n.min(payload.len())]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mission_item_int_is_laid_out_by_size_then_extensions() {
        let d = crate::dialect::builtin("common").expect("common");
        let m = d.message("MISSION_ITEM_INT").expect("MISSION_ITEM_INT");
        let l = Layout::of(m);
        // param1..4 (float), x, y (int32), z (float) first, then seq (uint16), command
        // (uint16), then the uint8 fields, then the extension mission_type.
        assert_eq!(l.slot(m, "param1").map(|s| s.offset), Some(0));
        assert_eq!(l.slot(m, "seq").map(|s| s.offset), Some(28));
        assert_eq!(l.slot(m, "command").map(|s| s.offset), Some(30));
        assert_eq!(l.slot(m, "target_system").map(|s| s.offset), Some(32));
        assert_eq!(l.base_size, 37);
        assert_eq!(l.slot(m, "mission_type").map(|s| s.offset), Some(37));
        assert_eq!(l.size, 38);
    }

    #[test]
    fn truncated_payloads_read_zero_and_strings_stop_at_nul() {
        let d = crate::dialect::builtin("common").expect("common");
        let m = d.message("PARAM_SET").expect("PARAM_SET");
        let l = Layout::of(m);
        let mut p = vec![0u8; l.size as usize];
        let id = l.slot(m, "param_id").unwrap();
        write_str(&mut p, id, b"MC_PITCH_P");
        write(&mut p, l.slot(m, "param_value").unwrap(), 0, Scalar::F32(0.5));
        assert_eq!(read_str(&p, id), b"MC_PITCH_P");
        assert_eq!(read(&p, l.slot(m, "param_value").unwrap(), 0), Scalar::F32(0.5));
        let short = truncate(&p);
        assert!(short.len() < p.len());
        assert_eq!(read(short, l.slot(m, "param_type").unwrap(), 0), Scalar::Int(0));
        assert_eq!(read_str(short, id), b"MC_PITCH_P");
    }
}
