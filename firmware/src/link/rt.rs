//! Realtime commands handed from the receive interrupt to the tasks as bits
//! of one atomic word: no lock, no queue to get stuck behind a job, and a
//! command raised twice before it is handled acts once (as in GRBL: two
//! quick `!` are one hold; two `0x91` are one +10 % step).

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use protocol::Rt;

/// Pending realtime commands plus the receive-overflow flag.
#[derive(Debug, Default)]
pub struct RtFlags {
    pending: AtomicU32,
    overflow: AtomicBool,
    framed: AtomicBool,
    /// Soft-reset markers put into the ring so far (wrapping).
    reset_marks: AtomicU32,
}

impl RtFlags {
    pub const fn new() -> Self {
        RtFlags {
            pending: AtomicU32::new(0),
            overflow: AtomicBool::new(false),
            framed: AtomicBool::new(false),
            reset_marks: AtomicU32::new(0),
        }
    }

    /// Mark `rt` pending (interrupt side).
    pub fn raise(&self, rt: Rt) {
        self.pending.fetch_or(rt.bit(), Ordering::Release);
    }

    /// Take every pending command at once (task side).
    pub fn take(&self) -> RtSet {
        RtSet(self.pending.swap(0, Ordering::Acquire))
    }

    /// Take only the pending commands in `mask`; the rest stay pending
    /// (the task acts on commands that need no reply room at once, and
    /// leaves `?` and soft reset until their reply fits).
    pub fn take_masked(&self, mask: u32) -> RtSet {
        RtSet(self.pending.fetch_and(!mask, Ordering::Acquire) & mask)
    }

    /// Whether anything is pending, without taking it (for a wake-up check).
    pub fn any(&self) -> bool {
        self.pending.load(Ordering::Acquire) != 0
    }

    /// Record that input bytes were dropped (interrupt side).
    pub fn set_overflow(&self) {
        self.overflow.store(true, Ordering::Release);
    }

    /// The receive side's current mode (set by the splitter). Replies to
    /// realtime commands (status) use it: text `<…>` or a `Status` frame.
    pub fn is_framed(&self) -> bool {
        self.framed.load(Ordering::Acquire)
    }

    pub(super) fn set_framed(&self, framed: bool) {
        self.framed.store(framed, Ordering::Release);
    }

    pub(super) fn note_reset_mark(&self) {
        self.reset_marks.fetch_add(1, Ordering::Release);
    }

    /// Soft-reset markers queued so far; the assembler discards input up to
    /// the last of them (see `LineAssembler::flush_reset`).
    pub fn reset_marks(&self) -> u32 {
        self.reset_marks.load(Ordering::Acquire)
    }

    /// Whether bytes were dropped since the last call (clears the flag).
    pub fn take_overflow(&self) -> bool {
        self.overflow.swap(false, Ordering::Acquire)
    }
}

/// A set of realtime commands taken from [`RtFlags`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct RtSet(pub u32);

impl RtSet {
    pub fn contains(self, rt: Rt) -> bool {
        self.0 & rt.bit() != 0
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The commands, highest priority (soft reset) first.
    pub fn iter(self) -> impl Iterator<Item = Rt> {
        Rt::iter_bits(self.0)
    }
}
