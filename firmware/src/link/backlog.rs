//! Input that arrived while the token ring was full.
//!
//! The receive side must never drop text and never let a realtime byte wait
//! behind it. So every received byte goes through the [`super::RxSplitter`]
//! at once (realtime bytes and frames act there, on arrival), and what the
//! splitter queues goes to the ring, or, while the ring is full, to this
//! backlog, in order. [`RxBacklog::pump`] moves it on as the task frees the
//! ring. A shell reads new input only while [`RxBacklog::room`] has space
//! for it (the USB interrupt NAKs its OUT endpoint otherwise, host-sim's
//! pty leaves it in the kernel), so nothing is lost; the backlog is only as
//! large as the slack a shell wants between that flow control and the ring.
//!
//! Both shells share this: the board's `usb.rs` and host-sim's
//! `VirtualDevice::receive`.

use super::rt::RtFlags;
use super::{RxSplitter, RxToken, TokenSink, TOKEN_RESET};
use heapless::Deque;

/// Tokens waiting for room in the ring (`N` of them at most).
#[derive(Clone, Debug)]
pub struct RxBacklog<const N: usize> {
    held: Deque<RxToken, N>,
}

impl<const N: usize> Default for RxBacklog<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// The ring, with the backlog behind it: a token goes to the ring only
/// while nothing is held, so the order is kept.
struct Spill<'a, R, const N: usize> {
    ring: &'a mut R,
    held: &'a mut Deque<RxToken, N>,
}

impl<R: TokenSink, const N: usize> TokenSink for Spill<'_, R, N> {
    fn push(&mut self, t: RxToken) -> bool {
        if self.held.is_empty() && self.ring.push(t) {
            return true;
        }
        self.held.push_back(t).is_ok()
    }
    fn free(&self) -> usize {
        self.ring.free() + (N - self.held.len())
    }
}

impl<const N: usize> RxBacklog<N> {
    pub const fn new() -> Self {
        RxBacklog { held: Deque::new() }
    }

    /// Bytes a shell may hand to [`Self::feed`] now without any being
    /// dropped: one byte can release a held-back frame start, and markers
    /// may be owed (see [`super::PACKET_ROOM`]).
    pub fn room(&self, ring: &impl TokenSink) -> usize {
        (ring.free() + N - self.held.len()).saturating_sub(2 + super::SNIFF)
    }

    /// Tokens held here.
    pub fn len(&self) -> usize {
        self.held.len()
    }

    pub fn is_empty(&self) -> bool {
        self.held.is_empty()
    }

    /// Move held tokens into the ring as far as it has room; then take
    /// `bytes` (realtime commands act now, the rest queues behind).
    pub fn feed(
        &mut self,
        splitter: &mut RxSplitter,
        bytes: &[u8],
        ring: &mut impl TokenSink,
        flags: &RtFlags,
    ) {
        self.pump(ring);
        let mut sink = Spill {
            ring,
            held: &mut self.held,
        };
        splitter.feed(bytes, &mut sink, flags);
    }

    /// Move held tokens into the ring as far as it has room. Returns true
    /// when anything moved.
    pub fn pump(&mut self, ring: &mut impl TokenSink) -> bool {
        let mut moved = false;
        while let Some(&t) = self.held.front() {
            if !ring.push(t) {
                break;
            }
            self.held.pop_front();
            moved = true;
        }
        moved
    }

    /// The port was closed or reopened: what the old client sent and the
    /// device has not read yet is void, and the link goes back to text
    /// mode. Soft-reset markers among the dropped input still count (the
    /// task discards up to them), so the splitter owes them to the ring.
    pub fn port_reset(
        &mut self,
        splitter: &mut RxSplitter,
        ring: &mut impl TokenSink,
        flags: &RtFlags,
    ) {
        let marks = self.held.iter().filter(|&&t| t == TOKEN_RESET).count();
        self.held.clear();
        splitter.owe_reset_marks(marks as u32);
        self.pump(ring);
        let mut sink = Spill {
            ring,
            held: &mut self.held,
        };
        splitter.reset(&mut sink, flags);
    }
}
