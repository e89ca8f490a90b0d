//! burin's native wire format, shared by the firmware and host tools.
//!
//! # Two protocols on one port
//!
//! The board's USB-CDC port speaks GRBL 1.1 text *and* burin's framed
//! protocol. A session picks its mode with one byte:
//!
//! * Every session starts in **text mode** (power-on, soft reset does *not*
//!   change the mode, but the port being closed/reopened does: the glue calls
//!   the link's `reset` when DTR drops or USB resets, and a pty sim does so
//!   when the client disconnects).
//! * In text mode a **0x00 byte switches to framed mode**. GRBL senders never
//!   send NUL; our client sends `0x00` before its first frame. Any partial text
//!   line received before the 0x00 is discarded without a reply (it was noise).
//! * In framed mode every byte belongs to a COBS frame ending in 0x00, and
//!   realtime commands are [`HostMsg::Realtime`] frames (the device's receive
//!   interrupt recognises these short frames and acts on them at once, so they
//!   still bypass the job queue).
//! * Framed mode ends with a [`HostMsg::Bye`] frame or when the port is
//!   closed; the session is then back in text mode.
//!
//! # Frames
//!
//! `COBS( postcard(msg) ++ crc16_le(postcard(msg)) ) ++ 0x00`, see [`frame`].
//! The CRC is CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF): two bytes is
//! plenty for frames under [`frame::MAX_FRAME`] bytes (it catches every 1-,
//! 2- and 3-bit error and every burst up to 16 bits), and the COBS layer
//! already resynchronises on the next 0x00 after noise. Frames longer than
//! [`frame::MAX_FRAME`] encoded bytes are rejected with
//! [`FrameError::TooLong`], never truncated.
//!
//! # Job lines, sequence numbers and credits
//!
//! * Each job line travels as [`HostMsg::Line`] with a `u32` sequence number.
//!   The device owns the numbering origin: [`DeviceInfo::next_seq`] in the
//!   handshake says which number it expects next (1 on a fresh boot). Numbers
//!   then increase by one with wrapping arithmetic (`u32::MAX` is followed by
//!   0). They are compared as serial numbers (RFC 1982): `seq` is *older* than
//!   `next` when `next.wrapping_sub(seq)` is in `1..=2^31`.
//! * The device executes a line only when `seq == next` and it has a free line
//!   slot; it then answers [`DeviceMsg::Ack`]. An older `seq` (a resend of a
//!   line already acknowledged) is acknowledged again but not executed. A newer
//!   `seq` (a gap: something was lost) or a line without a free slot gets
//!   [`DeviceMsg::Nak`] carrying the expected number and the reason; the host
//!   resends from there (go-back-N). A corrupt frame gets the same `Nak`.
//! * Credits: every `Ack` carries `next` and `credits` (free line slots at that
//!   moment). The host may have sent lines up to `next + credits - 1` and no
//!   further. When slots free up while the host is starved, the device sends
//!   a fresh `Ack` for `next - 1` (a credit refresh).
//! * Soft reset empties the device's queue and voids every line received
//!   before it but not yet queued (in both modes the device discards input
//!   up to the reset, as GRBL empties its receive buffer). It keeps `next`,
//!   so stale resends are recognised as duplicates; the client drops its
//!   unacknowledged lines and re-reads `next_seq` with `Hello`.
//!   "Acknowledged" means "queued for execution": only an operator abort
//!   (reset, alarm) drops queued lines.
//!
//! # Text mode details
//!
//! * Lines end at `\n` or `\r`; `\r\n` counts as one ending. An empty line
//!   is answered `ok` (senders that send blank lines stay in step).
//! * Lines longer than [`MAX_LINE`] bytes are answered `error:11` and
//!   discarded whole, never truncated and run.
//! * The realtime bytes (`?` `!` `~` 0x18 0x84 0x85 0x90–0x9D 0x9E 0xA0
//!   0xA1) are taken out wherever they occur, even inside a comment, as in
//!   GRBL; a UTF-8 comment whose bytes hit that range loses them.
//! * The device can always hold [`RX_WINDOW`] (128) unprocessed bytes, which
//!   `$I` reports in `[OPT:…,<blocks>,128]` for character-counting senders.
//!
//! # Realtime
//!
//! [`Rt`] lists the realtime commands with their GRBL byte values; both
//! protocols share them.
//!
//! # Host side (feature `std`)
//!
//! [`client::Client`] speaks the framed protocol over any `Read + Write`;
//! [`client::grbl::GrblClient`] is a plain GRBL sender (send-response or
//! character counting) for tests and benchmarks; [`client::mem::MemPipe`]
//! is an in-memory duplex pipe to test both without a port.
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(unsafe_code)]
#![warn(missing_debug_implementations)]

pub mod codes;
pub mod frame;
pub mod msg;
pub mod rt;
pub mod session;
pub mod usb_ids;

#[cfg(feature = "std")]
pub mod client;

pub use codes::Code;
pub use frame::{FrameDecoder, FrameError};
pub use msg::{
    DeviceInfo, DeviceMsg, HostMsg, LineText, MachineState, Overrides, ShortText, Status,
};
pub use rt::Rt;
pub use session::{LineVerdict, Session};

/// Protocol version exchanged in the handshake. 2: `Status` carries the
/// accessory bits (`A:`). 3: six axes (`Status`'s positions are
/// `[f32; AXES]`, and the `Pn:` bits after the limits moved up by two).
pub const PROTOCOL_VERSION: u16 = 3;

/// Number of axes the controller drives: X, Y, Z, A, B and C. The one place the
/// count is written: burin (which depends on this crate, never the other
/// way) re-exports it, and every per-axis array, letter, setting number,
/// report field and wire position derives from it. It lives here because
/// the wire layout of [`Status`] depends on it and this crate cannot see
/// burin's.
pub const AXES: usize = 6;

/// Every axis letter in grblHAL's order, the order of every per-axis
/// array; the first [`AXES`] of them are driven.
pub const ALL_AXIS_NAMES: [char; 6] = ['X', 'Y', 'Z', 'A', 'B', 'C'];

const _: () = assert!(AXES >= 3 && AXES <= ALL_AXIS_NAMES.len());

/// The driven axes' letters, in array order.
pub const AXIS_NAMES: [char; AXES] = first_axes(ALL_AXIS_NAMES);

/// This build's share of a table written for every letter of
/// [`ALL_AXIS_NAMES`] (its first [`AXES`] entries).
pub const fn first_axes<T: Copy, const N: usize>(all: [T; N]) -> [T; AXES] {
    let mut out = [all[0]; AXES];
    let mut i = 0;
    while i < AXES {
        out[i] = all[i];
        i += 1;
    }
    out
}

/// Axes carried in positions on the wire: all the controller drives.
/// Devices with fewer axes say so in [`DeviceInfo::axes`] and leave the
/// rest zero.
pub const WIRE_AXES: usize = AXES;

/// Longest job line, in bytes without the terminator, in either protocol.
pub const MAX_LINE: usize = 256;

/// Bytes of unprocessed input the device can always hold. GRBL senders that
/// count characters keep at most this many bytes unacknowledged.
pub const RX_WINDOW: usize = 128;
