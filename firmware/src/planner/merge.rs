//! Folding a move into the newest queued block when it only continues it.
//!
//! A job of collinear short moves (a CAM post that splits a line into
//! 0.025 mm pieces) fills the ring with blocks of two steps each: 64 of them
//! are 1.6 mm of look-ahead, and the planner must be able to stop within
//! that, so it never gets past about 40 mm/s. Such a move changes nothing
//! about the path (same direction in steps, no corner), so it is merged
//! into the block before it and the look-ahead grows with the job instead.

use super::*;

impl<const N: usize> Planner<N> {
    /// Merge `b` into the newest block if it continues it exactly: same
    /// direction in whole steps (the step counts are proportional, so the
    /// merged Bresenham line is the same line), same speed request, plain
    /// lines on both sides (no chord, watch or dwell), and in laser mode
    /// the same program line. The oldest block is
    /// never touched: the segment preparer works on a copy of it.
    pub(super) fn merge(&mut self, b: &Block) -> bool {
        if self.len < 2 || self.prev_nominal <= 0.0 {
            return false;
        }
        let k = self.len - 1;
        let p = *self.at(k);
        let plain = |x: &Block| {
            x.kind == BlockKind::Line
                && x.watch == Watch::default()
                && x.curve_ar == 0.0
                && x.accel == x.line_accel
        };
        // In laser mode power follows the running line (an S between two
        // G1 moves takes effect where the second starts): keep lines apart.
        let laser_split = self.settings.laser_mode && p.line != b.line;
        if !(plain(&p) && plain(b))
            || laser_split
            || p.dir_mask != b.dir_mask
            || p.rapid != b.rapid
            || p.programmed != b.programmed
            || p.cap != b.cap
        {
            return false;
        }
        let proportional = (0..AXES).all(|i| {
            u64::from(p.steps[i]) * u64::from(b.count) == u64::from(b.steps[i]) * u64::from(p.count)
        });
        let count = u64::from(p.count) + u64::from(b.count);
        if !proportional || count > u64::from(MAX_BLOCK_STEPS) {
            return false;
        }
        let m = self.at(k);
        for i in 0..AXES {
            m.steps[i] += b.steps[i];
        }
        m.count = count as u32;
        m.target = b.target;
        m.length += b.length;
        m.floor = m.floor.min(b.floor);
        m.line = b.line;
        true
    }
}
