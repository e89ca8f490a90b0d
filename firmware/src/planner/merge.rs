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
    /// lines on both sides (no chord, watch, dwell or backlash take-up), and in laser mode
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
                && !x.takeup
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
        // The pieces' caps differ where their commanded lengths round to
        // different step counts (2, 2, 3, 2 steps for 2.03 each): each one's
        // own step rate is capped (`interval`), the merged line's is even.
        // A cap below the line's own (a quiet axis) stays.
        let steps: [u32; AXES] = core::array::from_fn(|i| p.steps[i] + b.steps[i]);
        let length = p.length + b.length;
        let own = |x: &Block| {
            if x.cap < self.line_cap(&x.steps, x.count, x.length) * (1.0 - 1e-5) {
                x.cap
            } else {
                f32::INFINITY
            }
        };
        let (op, ob) = (own(&p), own(b));
        // One lowered for a quiet axis and the other not: the merged line
        // would keep the low cap all along (`planner::quiet`).
        if op != ob && (op.is_infinite() || ob.is_infinite() || libm::fabsf(op - ob) > 1e-4 * op) {
            return false;
        }
        let cap = op.min(ob).min(self.line_cap(&steps, count as u32, length));
        // A lower cap is safe while the block can still be entered as
        // planned: it is the newest, planned to stop at its end, and the
        // blocks before it only see its entry.
        if cap.is_nan() || cap < p.entry {
            return false;
        }
        let mut m = p;
        m.steps = steps;
        m.count = count as u32;
        m.target = b.target;
        m.length = length;
        m.cap = cap;
        m.floor = m.floor.min(b.floor);
        m.line = b.line;
        m.nominal = self.nominal(&m);
        m.max_entry = m.max_entry.min(m.nominal);
        *self.at(k) = m;
        true
    }

    /// A line's speed cap from its steps alone: each axis's rate over its
    /// share of the direction in steps, and single intervals (`interval`).
    pub(super) fn line_cap(&self, steps: &[u32; AXES], count: u32, length: f32) -> f32 {
        let s = &self.settings;
        let mm: [f32; AXES] = core::array::from_fn(|i| steps[i] as f32 / s.axes[i].steps_per_mm);
        let len = crate::num::sqrt(mm.iter().map(|v| v * v).sum());
        let mut cap = interval::speed_cap(s, self.tick_hz, steps, count, length);
        for (m, ax) in mm.iter().zip(&s.axes) {
            if *m > 0.0 {
                cap = cap.min(ax.max_rate / 60.0 * len / m);
            }
        }
        cap
    }
}
