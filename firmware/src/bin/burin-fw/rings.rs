//! The queues between the tasks: their sizes, and the parse task's byte
//! sink into the TX ring. Everything the task decides lives in
//! `burin::controller`; this only hands reply bytes to the link interrupt.
use burin::session::Tx;
use heapless::spsc::Producer;

// The sizes are the library's, so host-sim runs with the board's queues.
pub use burin::controller::{PLANNER_BLOCKS, SEGMENT_SLOTS, TX_RING};

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
