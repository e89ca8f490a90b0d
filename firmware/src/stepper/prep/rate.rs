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

impl Preparer {
    /// Shortest event period (ticks) at which no axis of `b` steps faster
    /// than its limit, with `amass` events per dominant step
    /// ([`crate::planner::interval::floor_ticks`]).
    pub(super) fn rate_floor(&self, b: &Block, amass: u8) -> u32 {
        crate::planner::interval::floor_ticks(
            &self.settings,
            self.cfg.tick_hz,
            &b.steps,
            b.count,
            amass,
        )
    }
}
