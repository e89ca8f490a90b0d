//! The capture buffer: stored lines from the bottom up (subroutine
//! bodies, then the block being captured), saved call locals from the top
//! down, so both share one fixed array.
//!
//! A line record is `len: u16, line number: u32, bytes`; a saved local is
//! `tag, …` where the tag is 0 for `#n` (then `n: u16, value: f32`) or the
//! length of a name (then the name and the value).

use crate::gcode::{Local, Name};

/// The capture buffer's size in bytes.
pub const CAPTURE_BYTES: usize = 2048;
/// A line record's header: length and line number.
pub const HEADER: usize = 6;

#[derive(Clone, Debug)]
pub struct Arena {
    buf: [u8; CAPTURE_BYTES],
    /// End of the line records.
    pub top: u16,
    /// Start of the saved locals (`CAPTURE_BYTES` when none).
    pub low: u16,
}

impl Arena {
    pub const fn new() -> Self {
        Arena {
            buf: [0; CAPTURE_BYTES],
            top: 0,
            low: CAPTURE_BYTES as u16,
        }
    }

    pub fn free(&self) -> usize {
        usize::from(self.low.saturating_sub(self.top))
    }

    /// Appends a line record; false (nothing written) without room.
    pub fn push_line(&mut self, n: u32, text: &[u8]) -> bool {
        let need = HEADER + text.len();
        let at = usize::from(self.top);
        if need > self.free() {
            return false;
        }
        let Some(dst) = self.buf.get_mut(at..at + need) else {
            return false;
        };
        let len = text.len() as u16;
        let (hdr, body) = dst.split_at_mut(HEADER);
        hdr[..2].copy_from_slice(&len.to_le_bytes());
        hdr[2..].copy_from_slice(&n.to_le_bytes());
        body.copy_from_slice(text);
        self.top += need as u16;
        true
    }

    /// The record at `at`: its line number, text and the next record's
    /// offset; `None` at or past the end of the records.
    pub fn line(&self, at: u16) -> Option<(u32, &[u8], u16)> {
        let a = usize::from(at);
        if at >= self.top {
            return None;
        }
        let hdr = self.buf.get(a..a + HEADER)?;
        let len = usize::from(u16::from_le_bytes([hdr[0], hdr[1]]));
        let n = u32::from_le_bytes([hdr[2], hdr[3], hdr[4], hdr[5]]);
        let text = self.buf.get(a + HEADER..a + HEADER + len)?;
        Some((n, text, (a + HEADER + len) as u16))
    }

    /// Removes the records in `from..to`, moving the later ones down.
    pub fn cut(&mut self, from: u16, to: u16) {
        let (f, t, top) = (usize::from(from), usize::from(to), usize::from(self.top));
        if f >= t || t > top {
            return;
        }
        self.buf.copy_within(t..top, f);
        self.top -= to - from;
    }

    /// Saves one local above the records; false without room.
    pub fn push_local(&mut self, l: &Local) -> bool {
        let mut rec = [0u8; 2 + crate::gcode::params::NAME_MAX + 4];
        let size = match l {
            Local::Num(n, v) => {
                rec[1..3].copy_from_slice(&n.to_le_bytes());
                rec[3..7].copy_from_slice(&v.to_le_bytes());
                7
            }
            Local::Named(name, v) => {
                let b = name.as_bytes();
                rec[0] = b.len() as u8;
                if let Some(d) = rec.get_mut(1..1 + b.len()) {
                    d.copy_from_slice(b);
                }
                if let Some(d) = rec.get_mut(1 + b.len()..5 + b.len()) {
                    d.copy_from_slice(&v.to_le_bytes());
                }
                5 + b.len()
            }
        };
        if size > self.free() {
            return false;
        }
        let at = usize::from(self.low) - size;
        if let (Some(d), Some(s)) = (self.buf.get_mut(at..at + size), rec.get(..size)) {
            d.copy_from_slice(s);
        }
        self.low = at as u16;
        true
    }

    /// The newest saved local, removed.
    pub fn pop_local(&mut self) -> Option<Local> {
        let at = usize::from(self.low);
        let tag = usize::from(*self.buf.get(at)?);
        let f = |s: &[u8]| {
            s.get(..4)
                .map_or(0.0, |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        let (l, size) = if tag == 0 {
            let b = self.buf.get(at + 1..at + 7)?;
            (Local::Num(u16::from_le_bytes([b[0], b[1]]), f(&b[2..])), 7)
        } else {
            let b = self.buf.get(at + 1..at + 5 + tag)?;
            let mut name = Name::empty();
            for &c in b.get(..tag)? {
                name.push(c).ok()?;
            }
            (Local::Named(name, f(b.get(tag..)?)), 5 + tag)
        };
        self.low = (at + size) as u16;
        Some(l)
    }
}
