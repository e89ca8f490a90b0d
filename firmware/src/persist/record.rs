//! Record keys and encoding. One record per setting and one per offset
//! vector, so `$110=…` rewrites 12 bytes, not the whole table: less wear,
//! and a torn write costs at most the one value being written (the map
//! keeps the previous record of that key until the new one is complete).
//!
//! A record is `[FORMAT, f32 LE…]`. A record of another format (an older
//! firmware's) or length is treated as missing: that item falls back to
//! its default. Offset vectors are the exception: a shorter one is a
//! build's with fewer axes ([`decode_upto`]).

/// Layout version of every record. Bump it when a record's meaning changes.
pub const FORMAT: u8 = 1;

/// `$n` is stored under key `n` (0..=999).
pub const fn setting_key(n: u16) -> u16 {
    n
}

/// Offset vectors: G54..G59.3 are `OFFSETS_KEY + 0..9`, G28 `+ 9`, G30 `+ 10`.
pub const OFFSETS_KEY: u16 = 1000;
/// How many offset vectors are stored.
pub const OFFSET_RECORDS: usize = crate::interp::WCS_COUNT + 2;

/// Tool table entries: `TOOLS_KEY + 0..TOOLS`, each `[number / 65536,
/// number % 65536, offset X Y Z, diameter]` (the halves are exact in
/// `f32`). The 16-tool firmware's `[number, length, diameter]` records
/// are read once and rewritten in this form.
pub const TOOLS_KEY: u16 = 1100;
/// Values in one tool record.
pub const TOOL_VALUES: usize = 3 + crate::interp::tools::TOOL_AXES;

/// Bytes of the longest record (a tool entry).
pub const MAX_RECORD: usize = 1 + 4 * TOOL_VALUES;
const _: () = assert!(MAX_RECORD <= super::flash::MAX_VALUE);

/// Encodes `values` into `buf`, returning the record.
pub fn encode<'b>(values: &[f32], buf: &'b mut [u8; MAX_RECORD]) -> &'b [u8] {
    buf[0] = FORMAT;
    let mut len = 1;
    for (v, dst) in values.iter().zip(buf[1..].chunks_exact_mut(4)) {
        dst.copy_from_slice(&v.to_le_bytes());
        len += 4;
    }
    &buf[..len]
}

/// Decodes a record of 1 to `out.len()` finite values into the front of
/// `out`, returning how many it held: an offset vector written by a build
/// that drove fewer axes (four before burin drove six) is still that
/// vector, its missing axes at 0. On `None`, `out` may hold part of the
/// record: the callers discard it.
pub fn decode_upto(rec: &[u8], out: &mut [f32]) -> Option<usize> {
    let (&format, body) = rec.split_first()?;
    let n = body.len() / 4;
    if format != FORMAT || body.len() % 4 != 0 || n == 0 || n > out.len() {
        return None;
    }
    for (o, b) in out.iter_mut().zip(body.chunks_exact(4)) {
        *o = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        if !o.is_finite() {
            return None;
        }
    }
    Some(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::AXES;

    #[test]
    fn round_trip_and_rejects() {
        let mut buf = [0; MAX_RECORD];
        let rec = encode(&crate::pad([1.5, -2.0, 0.25, 1e6]), &mut buf).to_vec();
        assert_eq!(rec.len(), 1 + 4 * AXES);
        let mut out = [0.0; AXES];
        assert_eq!(decode_upto(&rec, &mut out), Some(AXES));
        assert_eq!(out, crate::pad([1.5, -2.0, 0.25, 1e6]));
        // Longer than `out`, wrong format, empty, NaN.
        let mut one = [0.0];
        assert_eq!(decode_upto(&rec, &mut one), None);
        let mut old = rec.clone();
        old[0] = FORMAT + 1;
        assert_eq!(decode_upto(&old, &mut out), None);
        assert_eq!(decode_upto(&[], &mut out), None);
        let nan = encode(&[f32::NAN], &mut buf).to_vec();
        assert_eq!(decode_upto(&nan, &mut one), None);
    }
}
