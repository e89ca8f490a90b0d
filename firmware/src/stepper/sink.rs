//! The producer end of the segment queue, as the preparer sees it.

use super::Segment;

/// Where a segment queue's producer end lives: the spsc producer on the
/// MCU, a plain queue in host-sim.
pub trait SegmentSink {
    fn push(&mut self, s: Segment) -> Result<(), Segment>;
    fn is_full(&self) -> bool;
    fn is_empty(&self) -> bool;
}

impl SegmentSink for heapless::spsc::Producer<'_, Segment> {
    fn push(&mut self, s: Segment) -> Result<(), Segment> {
        self.enqueue(s)
    }
    fn is_full(&self) -> bool {
        !self.ready()
    }
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<const N: usize> SegmentSink for heapless::spsc::Queue<Segment, N> {
    fn push(&mut self, s: Segment) -> Result<(), Segment> {
        self.enqueue(s)
    }
    fn is_full(&self) -> bool {
        heapless::spsc::Queue::is_full(self)
    }
    fn is_empty(&self) -> bool {
        heapless::spsc::Queue::is_empty(self)
    }
}
