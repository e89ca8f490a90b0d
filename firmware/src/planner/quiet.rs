//! Quiet axes: corners whose velocity change needs no hold.
//!
//! A corner's hold (`planner::passes`) assumes the worst around it: the
//! ramps on both sides at the axis's full acceleration, in the direction
//! of the corner's own change, for a whole window. A zigzag of 0.07 mm
//! blocks is nothing like that: Y swings between ±5.6 mm/s, and no window
//! sees Y change by more than those 11 mm/s, where a window of `W` = 50 ms
//! allows `a·W` = 25. Its holds cost 19 % of the job's time, for an axis
//! that never went above 7 % of its limit.
//!
//! The argument, per axis `i`, with `σ ≤ τ` (both fractions of `W`):
//!
//! * a block is *quiet* in `i` when its speed cap keeps `|v_i| ≤ σ·a_i·W/2`
//!   (its cap is lowered to that when its own natural peak is below it,
//!   so that no later exit can undo it; overrides never pass a cap);
//! * over any stretch of quiet blocks, `v_i` stays within an interval of
//!   width `σ·a_i·W`, whatever the corners between them do;
//! * a corner may skip the hold in `i` when at least `τ·W` of quiet blocks
//!   lie before it and after it. Every window of `W` through that corner
//!   then spends at least `τ·W` inside the quiet stretch, where `v_i`
//!   changes by at most `σ·a_i·W`, and at most `(1 − τ)·W` outside it, where
//!   the axis accelerates at most at `a_i`: in all `(σ + 1 − τ)·a_i·W ≤ a_i·W`.
//!
//! Block times are counted from above (length over the highest speed the
//! block can reach), so the `τ·W` are a lower bound. The quiet time after a
//! corner is not known when the corner is planned: it holds as any corner
//! does, and stops holding (its entry, and the block's before it, may rise)
//! once enough quiet blocks have followed it. Blocks the segment preparer
//! may already have started (the oldest two) are left as they are: holding
//! is always safe.

use super::passes::{Sides, CANCEL_WINDOW_S, HOLD_STRETCH};
use super::*;

/// The velocity spread a quiet block allows, as a share of `a_i·W`.
const SPREAD: f32 = 0.75;
/// The quiet time a corner needs on each side to stop holding, as a share
/// of `W` (at least `SPREAD`).
const TIME: f32 = 0.75;

const W: f32 = CANCEL_WINDOW_S;
/// The share of the shorter block a corner's hold may fill on either
/// side, leaving the block room for the hold of its other end: filled to
/// the end, the two together left no entry but a stop (the backward pass
/// found `w²·m/2` equal to the length, to its last bit).
const ROOM_SHARE: f32 = 0.9;

impl Block {
    /// Set the corner's hold factors (stretched, see `planner::passes`)
    /// and the junction limit that goes with them: the corner's own change
    /// within half a window, and each side of the hold within `room` mm
    /// (the shorter of the two blocks).
    pub(super) fn hold(&mut self, m: Sides, room: f32) {
        self.hold_m = m.post;
        self.hold_pre_m = m.pre;
        self.junction = self.corner;
        let m = m.pre.max(m.post);
        if m > 0.0 {
            self.junction = self.junction.min(0.5 * W * HOLD_STRETCH / m);
            self.junction = self
                .junction
                .min(crate::num::sqrt(2.0 * ROOM_SHARE * room / m));
        }
    }

    /// The corner's limit `corner`, its hold `m` within `room` (as
    /// [`Block::hold`]) and the entry limit that follows, with the block
    /// before at `prev_nominal`: at the push, and again when a queued
    /// corner stops holding (`planner::quiet`), is settled by the chord
    /// after it (`planner::cancel`) or lies in a straight stretch
    /// (`planner::tube`).
    pub(super) fn set_corner(&mut self, corner: f32, m: Sides, room: f32, prev_nominal: f32) {
        self.corner = corner;
        self.hold(m, room);
        self.max_entry = self.junction.min(self.nominal).min(prev_nominal);
    }

    /// The least time the block can take: its length at the highest speed
    /// it can reach from its corner's limit (no hold lowers that limit
    /// below `corner`; after a stop `corner` is 0).
    pub(super) fn min_time(&self) -> f32 {
        let entry = self.corner.min(self.cap);
        let top = self.cap.min(crate::num::sqrt(
            entry * entry + 2.0 * self.accel0() * self.length,
        ));
        if top > 0.0 {
            self.length / top
        } else {
            0.0
        }
    }
}

impl<const N: usize> Planner<N> {
    /// The axes in which `b` is quiet (bit per axis), with `b.cap` lowered
    /// to keep them so; and those in which the corner before it may stop
    /// holding once quiet blocks follow it. `unit` is the block's direction.
    pub(super) fn quiet_axes(&self, b: &mut Block, unit: &[f32; AXES]) -> (u8, u8) {
        let entry = if self.prev_nominal <= 0.0 {
            0.0
        } else {
            b.junction.min(b.cap).min(self.prev_nominal)
        };
        // Its peak if it leaves no faster than it enters (a block between
        // two like corners), entered at most at its corner's limit and at
        // the previous block's speed: quiet blocks are capped no lower than
        // that. (Only the choice to cap rests on this guess; once capped,
        // the block is quiet whatever its entry.)
        let natural = b
            .cap
            .min(crate::num::sqrt(entry * entry + b.accel * b.length));
        let (mut quiet, mut release) = (0u8, 0u8);
        let mut cap = b.cap;
        for (i, ax) in self.settings.axes.iter().enumerate() {
            let u = libm::fabsf(unit[i]);
            let limit = if u > 1e-6 {
                0.5 * SPREAD * ax.max_accel * W / u
            } else {
                f32::INFINITY
            };
            if natural <= limit && limit >= b.floor {
                quiet |= 1 << i;
                cap = cap.min(limit);
                if self.quiet_time[i] >= TIME * W {
                    release |= 1 << i;
                }
            }
        }
        if cap < b.cap {
            b.cap = cap;
            b.nominal = self.nominal(b);
            Self::curve_limits(b, self.c_max());
        }
        (quiet, release)
    }

    /// Count a block (just pushed, or merged into the newest one) that
    /// takes at least `time` s into the quiet stretches.
    pub(super) fn count_quiet(&mut self, time: f32, quiet: u8) {
        for i in 0..AXES {
            if quiet & (1 << i) == 0 {
                self.quiet_time[i] = 0.0;
            } else {
                self.quiet_time[i] += time;
            }
        }
    }

    /// Stop holding at the corners that now have enough quiet blocks after
    /// them. Returns the lowest block whose entry may rise (`len` if none).
    pub(super) fn release_quiet(&mut self) -> usize {
        let mut lowest = self.len;
        let newest = match self.len.checked_sub(1) {
            Some(k) if k >= 2 => k,
            _ => return lowest,
        };
        let pending = self.release_pending;
        if pending == 0 {
            return lowest;
        }
        let last = self.at(newest).min_time();
        // Axes still pending in the blocks walked (exact once the walk
        // reaches the oldest block it may touch).
        let mut seen = 0u8;
        // Quiet time from each corner to the newest block's end, per axis
        // (negative once a block that is not quiet comes between).
        let mut after = [0.0f32; AXES];
        let mut c = newest;
        while c >= 2 {
            // Three fields, not a copy of the block.
            let (time, quiet, release) = {
                let b = self.at(c);
                (b.min_time(), b.quiet, b.release)
            };
            for (i, t) in after.iter_mut().enumerate() {
                *t = if quiet & (1 << i) != 0 && *t >= 0.0 {
                    *t + time
                } else {
                    -1.0
                };
            }
            if release != 0 {
                let axes = (0..AXES).filter(|i| release & (1 << i) != 0);
                if axes.clone().all(|i| after[i] >= TIME * W) {
                    let prev = *self.at(c - 1);
                    let b = self.at(c);
                    b.release = 0;
                    b.set_corner(
                        b.corner,
                        b.hold_fixed,
                        prev.length.min(b.length),
                        prev.nominal,
                    );
                    lowest = c - 1;
                } else if axes.clone().any(|i| after[i] < 0.0) {
                    // A loud block came first: this corner keeps its hold.
                    self.at(c).release = 0;
                } else {
                    seen |= release;
                }
            }
            // Corners further back had this much quiet after them at the
            // last push already, so they were settled then. Only the axes
            // some corner may still release count: an axis that never
            // moves is quiet all along, and walking back through 37.5 ms
            // of it took 6,000 instructions a block.
            let settled = |i: usize| after[i] < 0.0 || after[i] - last >= TIME * W;
            if (0..AXES).all(|i| pending & (1 << i) == 0 || settled(i)) {
                break;
            }
            c -= 1;
        }
        if c < 2 {
            self.release_pending = seen;
        }
        if lowest < self.len {
            self.planned = self.planned.min(lowest.saturating_sub(1));
        }
        lowest
    }
}
