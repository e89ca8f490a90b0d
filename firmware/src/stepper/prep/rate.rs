//! The per-step rate floor: no single step interval of any axis shorter
//! than its rate limit (`$110`… with `$100`…) or `$201` allows.
//!
//! A segment's rate is planned as a path speed, in `f32`, and its period
//! rounded down to whole ticks; and Bresenham spaces a minor axis' steps
//! `floor(C/s)` or `ceil(C/s)` events apart (`C` the block's events,
//! `s` the axis' steps), so on a near-diagonal move at the axis limit
//! single intervals come out a full event short of the average. Holding
//! the period at `ceil(limit / floor(C/s))` per axis keeps every interval
//! at or above the limit; it only ever acts within an event of the limit.

use super::Preparer;
use crate::planner::Block;
use crate::AXES;

impl Preparer {
    /// Shortest event period (ticks) at which no axis of `b` steps faster
    /// than its limit, with `amass` events per dominant step.
    pub(super) fn rate_floor(&self, b: &Block, amass: u8) -> u32 {
        let tick_hz = self.cfg.tick_hz as f32;
        let events = (b.count as u64) << amass;
        let mut floor = 0u32;
        for i in 0..AXES {
            let s = b.steps[i];
            if s == 0 {
                continue;
            }
            let ax = &self.settings.axes[i];
            let hz = (ax.max_rate / 60.0 * ax.steps_per_mm).min(self.settings.max_step_rate_hz);
            if !(hz.is_finite() && hz > 0.0) {
                continue;
            }
            let limit = libm::ceilf(tick_hz / hz);
            let k = (events / s as u64).max(1) as f32;
            let p = libm::ceilf(limit / k);
            if p.is_finite() && p > floor as f32 {
                floor = p.min(crate::seams::MAX_PERIOD as f32) as u32;
            }
        }
        floor
    }
}
