//! The queues between the tasks: their sizes, and the parse task's byte
//! sink into the TX ring. Everything the task decides lives in
//! `burin::controller`; this only hands reply bytes to the link interrupt.
use burin::session::Tx;
use heapless::spsc::Producer;

/// Planner ring size (blocks of look-ahead).
pub const PLANNER_BLOCKS: usize = 64;
/// Prepared segments between the parse task and the step interrupt
/// (`heapless::spsc` keeps one slot free).
pub const SEGMENT_SLOTS: usize = 16;
/// Reply bytes waiting for the link interrupt.
pub const TX_RING: usize = 1024;

/// Reply bytes towards the link interrupt.
pub struct TxRing<'a> {
    pub ring: &'a mut Producer<'static, u8>,
    /// Bytes that found the ring full (never expected: the controller
    /// runs the session only with `TX_HEADROOM` free).
    pub dropped: u32,
}

impl Tx for TxRing<'_> {
    fn send(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.ring.enqueue(b).is_err() {
                self.dropped = self.dropped.wrapping_add(1);
            }
        }
    }
    fn room(&self) -> usize {
        self.ring.capacity() - self.ring.len()
    }
}
