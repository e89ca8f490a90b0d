//! The producer end of the segment queue, as the preparer sees it.

use super::Segment;

/// Where a segment queue's producer end lives: the spsc producer on the
/// MCU, a plain queue in host-sim.
pub trait SegmentSink {
    fn push(&mut self, s: Segment) -> Result<(), Segment>;
    fn is_full(&self) -> bool;
    fn is_empty(&self) -> bool;
    /// Segments queued and not yet taken by the stepper (the one it runs
    /// now is already taken).
    fn len(&self) -> usize;
}

impl SegmentSink for heapless::spsc::Producer<'_, Segment> {
    fn push(&mut self, s: Segment) -> Result<(), Segment> {
        self.enqueue(s)
    }
    fn is_full(&self) -> bool {
        !self.ready()
    }
    fn is_empty(&self) -> bool {
        heapless::spsc::Producer::len(self) == 0
    }
    fn len(&self) -> usize {
        heapless::spsc::Producer::len(self)
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
    fn len(&self) -> usize {
        heapless::spsc::Queue::len(self)
    }
}
