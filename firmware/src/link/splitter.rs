//! Interrupt side of the link: runs in the USB receive interrupt, takes the
//! realtime commands out of the byte stream at once, and queues everything
//! else as [`RxToken`]s for the task-side [`super::LineAssembler`].
//!
//! Realtime bytes are caught here, not in the assembler, so a feed hold acts
//! even when the job queue is full and nobody is reading lines. In framed
//! mode realtime commands are short frames; this side holds back the first
//! [`SNIFF`] bytes of every frame, and a frame that ends within them and is
//! a valid `Realtime` message is acted on here and never queued.

use super::rt::RtFlags;
use super::{RxToken, TokenSink, TOKEN_OVERFLOW, TOKEN_RESET, TOKEN_TEXT_MODE};
use protocol::{frame, HostMsg, Rt};

/// Frames up to this many encoded bytes are checked for realtime commands
/// (an encoded `Realtime` frame is 5 bytes).
pub const SNIFF: usize = 16;

/// Free ring tokens the interrupt should see before reading a USB packet:
/// at most one token per byte, plus the owed mode-reset and overflow
/// markers, plus a held-back frame start released by this packet.
pub const PACKET_ROOM: usize = 64 + 2 + SNIFF;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Text,
    /// Framed; `passthrough` once the current frame outgrew the sniff buffer.
    Framed {
        passthrough: bool,
    },
}

/// Splits the raw receive stream into realtime flags and ring tokens.
#[derive(Clone, Debug)]
pub struct RxSplitter {
    mode: Mode,
    hold: [u8; SNIFF],
    hold_len: usize,
    /// Bytes were dropped and the marker is not in the ring yet.
    dropped: bool,
    /// A mode reset is waiting for room in the ring.
    reset_pending: bool,
    /// Soft-reset markers waiting for room in the ring.
    marks_pending: u32,
    /// Text mode: the last byte was 0xC2, the UTF-8 lead of the realtime
    /// bytes 0x80..=0xBF (bCNC and cncjs send 0x92 as `C2 92`).
    utf8_c2: bool,
    /// Text mode: continuation bytes of another UTF-8 character still to
    /// drop (they are never realtime commands).
    utf8_rest: u8,
}

impl Default for RxSplitter {
    fn default() -> Self {
        Self::new()
    }
}

impl RxSplitter {
    pub const fn new() -> Self {
        RxSplitter {
            mode: Mode::Text,
            hold: [0; SNIFF],
            hold_len: 0,
            dropped: false,
            reset_pending: false,
            marks_pending: 0,
            utf8_c2: false,
            utf8_rest: 0,
        }
    }

    /// True while the link is in framed mode.
    pub fn is_framed(&self) -> bool {
        matches!(self.mode, Mode::Framed { .. })
    }

    /// The port was closed or USB reset: back to text mode. The marker goes
    /// through the ring so the assembler switches at the same point.
    pub fn reset(&mut self, ring: &mut impl TokenSink, flags: &RtFlags) {
        self.mode = Mode::Text;
        flags.set_framed(false);
        self.hold_len = 0;
        self.utf8_c2 = false;
        self.utf8_rest = 0;
        self.reset_pending = true;
        // Unread input before this point is void, like before a soft reset
        // (the task flushes up to this marker when it hears of the close).
        self.dropped = false;
        flags.note_reset_mark();
        self.marks_pending = self.marks_pending.saturating_add(1);
        self.put_pending(ring);
    }

    /// Soft-reset markers that were dropped with unread input (see
    /// [`super::RxBacklog::port_reset`]) are still owed to the ring.
    pub fn owe_reset_marks(&mut self, n: u32) {
        self.marks_pending = self.marks_pending.saturating_add(n);
    }

    /// Handle one received chunk (any size; the USB packet is at most 64).
    pub fn feed(&mut self, chunk: &[u8], ring: &mut impl TokenSink, flags: &RtFlags) {
        for &b in chunk {
            match self.mode {
                Mode::Text => self.text_byte(b, ring, flags),
                Mode::Framed { passthrough } => self.framed_byte(b, passthrough, ring, flags),
            }
        }
    }

    /// Text mode: realtime bytes, single or UTF-8 encoded, act at once;
    /// every other byte above 0x7F is dropped (as GRBL 1.1 does), so it
    /// never reaches a line.
    fn text_byte(&mut self, b: u8, ring: &mut impl TokenSink, flags: &RtFlags) {
        if b >= 0x80 {
            if core::mem::take(&mut self.utf8_c2) {
                if let Some(rt) = Rt::from_byte(b) {
                    self.realtime(rt, ring, flags);
                }
                return;
            }
            if self.utf8_rest > 0 && b & 0xC0 == 0x80 {
                self.utf8_rest -= 1;
                return;
            }
            self.utf8_rest = 0;
            if let Some(rt) = Rt::from_byte(b) {
                self.realtime(rt, ring, flags);
                return;
            }
            match b {
                0xC2 => self.utf8_c2 = true,
                0xC3..=0xDF => self.utf8_rest = 1,
                0xE0..=0xEF => self.utf8_rest = 2,
                0xF0..=0xF7 => self.utf8_rest = 3,
                _ => {}
            }
            return;
        }
        self.utf8_c2 = false;
        self.utf8_rest = 0;
        if let Some(rt) = Rt::from_byte(b) {
            self.realtime(rt, ring, flags);
            return;
        }
        if b == 0 {
            self.mode = Mode::Framed { passthrough: false };
            flags.set_framed(true);
            self.hold_len = 0;
        }
        self.put(RxToken::from(b), ring, flags);
    }

    fn framed_byte(
        &mut self,
        b: u8,
        passthrough: bool,
        ring: &mut impl TokenSink,
        flags: &RtFlags,
    ) {
        if passthrough {
            if b == 0 {
                self.mode = Mode::Framed { passthrough: false };
            }
            self.put(RxToken::from(b), ring, flags);
            return;
        }
        if b != 0 {
            if let Some(slot) = self.hold.get_mut(self.hold_len) {
                *slot = b;
                self.hold_len += 1;
            } else {
                self.flush_hold(ring, flags);
                self.mode = Mode::Framed { passthrough: true };
                self.put(RxToken::from(b), ring, flags);
            }
            return;
        }
        // End of a short frame: is it realtime or the end of the session?
        let mut copy = self.hold;
        let len = self.hold_len;
        match copy.get_mut(..len).map(frame::decode::<HostMsg>) {
            Some(Ok(HostMsg::Realtime(rt))) => {
                self.hold_len = 0;
                self.realtime(rt, ring, flags);
                return;
            }
            Some(Ok(HostMsg::Bye)) => {
                self.mode = Mode::Text;
                flags.set_framed(false);
            }
            _ => {}
        }
        self.flush_hold(ring, flags);
        self.put(0, ring, flags);
    }

    /// A soft reset also leaves a marker in the ring, *before* the flag is
    /// raised: the task then throws away exactly the input that came before
    /// the reset (GRBL empties its receive buffer on reset, and senders
    /// count on it), keeping what the sender sent after it.
    ///
    /// The reset is counted at once, before its marker is in the ring (the
    /// ring may be full): the assembler then discards everything up to
    /// that marker, whenever it arrives.
    fn realtime(&mut self, rt: Rt, ring: &mut impl TokenSink, flags: &RtFlags) {
        if rt == Rt::SoftReset {
            flags.note_reset_mark();
            self.marks_pending = self.marks_pending.saturating_add(1);
            self.put_pending(ring);
        }
        flags.raise(rt);
    }

    fn flush_hold(&mut self, ring: &mut impl TokenSink, flags: &RtFlags) {
        let hold = self.hold;
        for &b in hold.iter().take(self.hold_len) {
            self.put(RxToken::from(b), ring, flags);
        }
        self.hold_len = 0;
    }

    /// Queue a token; on a full ring drop it and leave an overflow marker at
    /// the first chance, so the assembler knows which line was damaged.
    fn put(&mut self, t: RxToken, ring: &mut impl TokenSink, flags: &RtFlags) {
        if self.put_pending(ring) && ring.push(t) {
            return;
        }
        self.dropped = true;
        flags.set_overflow();
    }

    /// Deliver owed markers (mode reset first); false if the ring is full.
    fn put_pending(&mut self, ring: &mut impl TokenSink) -> bool {
        if self.reset_pending {
            if !ring.push(TOKEN_TEXT_MODE) {
                return false;
            }
            self.reset_pending = false;
        }
        if self.dropped {
            if !ring.push(TOKEN_OVERFLOW) {
                return false;
            }
            self.dropped = false;
        }
        while self.marks_pending > 0 {
            if !ring.push(TOKEN_RESET) {
                return false;
            }
            self.marks_pending -= 1;
        }
        true
    }
}
