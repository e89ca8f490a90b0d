//! The serial link: GRBL 1.1 text and burin's framed protocol on one port.
//!
//! Split in two halves so the USB interrupt never waits for the parser and
//! the parser never holds a lock the interrupt needs:
//!
//! ```text
//! USB OTG_FS ISR (prio 2)          parse/plan task (prio 1)
//!   RxSplitter::feed(chunk)          LineAssembler::poll(consumer)
//!     realtime -> RtFlags (atomic)     -> LinkEvent::{Line, System, Frame, ...}
//!     rest -> spsc ring of RxToken     RtFlags::take() -> realtime commands
//! ```
//!
//! Mode selection (see the `protocol` crate docs): text at start; a 0x00
//! byte switches to framed; `Bye` or [`RxSplitter::reset`] (port closed,
//! USB reset) switches back. Both halves switch at the same point of the
//! stream because the switch travels through the ring as a token.
//!
//! The ring carries `u16` tokens, not bytes, so markers (receive overflow,
//! mode reset) sit at the exact place in the stream where they happened.
//! [`RX_RING`] tokens hold more than the [`protocol::RX_WINDOW`] of 128 bytes
//! that character-counting senders rely on, plus a USB packet of slack.
//!
//! On a soft reset the task must call [`LineAssembler::flush_reset`] right
//! after taking the flag: it drops the input that arrived before the reset.
//!
//! [`Link`] bundles both halves with a plain ring for the tests. Both shells
//! use the halves themselves: the interrupt (or host-sim's `receive`) feeds
//! the splitter, the controller's task polls the assembler.

mod assembler;
mod backlog;
pub mod framed;
pub mod reply;
pub mod rt;
mod splitter;
pub mod syscmd;

pub use assembler::{LineAssembler, LinkEvent};
pub use backlog::RxBacklog;
pub use framed::{encode_reply, FramedAction, FramedPort};
pub use rt::{RtFlags, RtSet};
pub use splitter::{RxSplitter, PACKET_ROOM, SNIFF};
pub use syscmd::SysCmd;

use heapless::{spsc, Deque};

/// What the device fills once per status request; text mode prints it with
/// [`reply::status`], framed mode sends it as `DeviceMsg::Status`.
pub type StatusSnapshot = protocol::Status;

/// One ring entry: a received byte (0..=255) or a marker.
pub type RxToken = u16;
/// Input was dropped here (ring full): the line it hit is reported, not run.
pub const TOKEN_OVERFLOW: RxToken = 0x100;
/// The port was reset: back to text mode from here on.
pub const TOKEN_TEXT_MODE: RxToken = 0x101;
/// A soft reset (0x18 or a `Realtime(SoftReset)` frame) arrived here:
/// everything before it is void.
pub const TOKEN_RESET: RxToken = 0x102;

/// Ring size for the RTIC app: `heapless::spsc::Queue<RxToken, RX_RING>`
/// holds `RX_RING - 1` tokens.
pub const RX_RING: usize = 256;
/// Tokens that ring holds (one slot tells full from empty): what a
/// shell with a plain queue holds, to hold what the board does.
pub const RX_RING_HOLDS: usize = RX_RING - 1;

/// Tokens an [`RxBacklog`] holds while the ring is full (both shells use
/// this size, so host-sim's flow control is the board's): realtime bytes
/// behind that much text still act on arrival. Beyond it the board NAKs
/// its USB OUT endpoint and host-sim's pty leaves input in the kernel; the
/// host holds the rest. 8 KiB of the F411's RAM (the F401 holds half:
/// `boards/f401.rs`).
pub const RX_BACKLOG: usize = 4096;

/// Which protocol the port speaks right now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkMode {
    Text,
    Framed,
}

/// Where the splitter puts tokens.
pub trait TokenSink {
    /// Queue `t`; false if full.
    fn push(&mut self, t: RxToken) -> bool;
    /// Room left, in tokens (the ISR reads a packet only with
    /// [`PACKET_ROOM`] free, so the ring overflows only on misuse).
    fn free(&self) -> usize;
}

/// Where the assembler takes tokens from.
pub trait TokenSource {
    fn pop(&mut self) -> Option<RxToken>;
    /// Tokens waiting.
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl TokenSink for spsc::Producer<'_, RxToken> {
    fn push(&mut self, t: RxToken) -> bool {
        self.enqueue(t).is_ok()
    }
    fn free(&self) -> usize {
        self.capacity() - self.len()
    }
}

impl TokenSource for spsc::Consumer<'_, RxToken> {
    fn pop(&mut self) -> Option<RxToken> {
        self.dequeue()
    }
    fn len(&self) -> usize {
        spsc::Consumer::len(self)
    }
}

impl<const N: usize> TokenSink for Deque<RxToken, N> {
    fn push(&mut self, t: RxToken) -> bool {
        self.push_back(t).is_ok()
    }
    fn free(&self) -> usize {
        self.capacity() - self.len()
    }
}

impl<const N: usize> TokenSource for Deque<RxToken, N> {
    fn pop(&mut self) -> Option<RxToken> {
        self.pop_front()
    }
    fn len(&self) -> usize {
        Deque::len(self)
    }
}

/// Both halves and a ring in one value, for single-threaded users (the
/// tests). `feed` plays the interrupt, `poll` the task.
#[derive(Debug)]
pub struct Link {
    splitter: RxSplitter,
    assembler: LineAssembler,
    ring: Deque<RxToken, RX_RING>,
    flags: RtFlags,
}

impl Default for Link {
    fn default() -> Self {
        Self::new()
    }
}

impl Link {
    pub const fn new() -> Self {
        Link {
            splitter: RxSplitter::new(),
            assembler: LineAssembler::new(),
            ring: Deque::new(),
            flags: RtFlags::new(),
        }
    }

    /// Bytes the link can take now without dropping any. Like the USB
    /// endpoint, a transport should hold bytes back rather than overfill.
    pub fn room(&self) -> usize {
        self.ring.free().saturating_sub(2 + SNIFF)
    }

    /// Receive bytes (the interrupt's job). Realtime commands are flagged
    /// at once; take them with [`Link::take_realtime`].
    pub fn feed(&mut self, bytes: &[u8]) {
        self.splitter.feed(bytes, &mut self.ring, &self.flags);
    }

    /// The port was closed or reopened: back to text mode.
    pub fn reset(&mut self) {
        self.splitter.reset(&mut self.ring, &self.flags);
    }

    /// Next line, command or frame, if a complete one has arrived.
    pub fn poll(&mut self) -> Option<LinkEvent<'_>> {
        self.assembler.poll(&mut self.ring)
    }

    /// Realtime commands raised since the last call. On a soft reset the
    /// input received before it is discarded here, as the RTIC task does
    /// with [`LineAssembler::flush_reset`].
    pub fn take_realtime(&mut self) -> RtSet {
        let set = self.flags.take();
        if set.contains(protocol::Rt::SoftReset) {
            self.assembler.flush_reset(&mut self.ring, &self.flags);
        }
        set
    }

    /// The shared flags (an RTIC app keeps its own in a `static`).
    pub fn flags(&self) -> &RtFlags {
        &self.flags
    }

    /// Mode of the lines coming out of [`Link::poll`].
    pub fn mode(&self) -> LinkMode {
        self.assembler.mode()
    }

    /// Received bytes not yet turned into events (ring plus partial line):
    /// `RX_WINDOW - rx_pending()` is the `Bf:` receive figure.
    pub fn rx_pending(&self) -> usize {
        self.ring.len() + self.assembler.pending()
    }
}
