//! Junction limits, overrides, and the backward/forward planning passes.

use super::cancel::{Pair, PULSE_SHARE};
use super::run::{run_down, RunAhead};
use super::*;

/// The time over which opposite velocity changes at two corners cancel
/// (`Planner::hold_factor`): the window the step trace's acceleration is
/// judged over (`host_sim::bench::limits`), s.
pub(super) const CANCEL_WINDOW_S: f32 = 0.05;

const W: f32 = CANCEL_WINDOW_S;

/// A corner's hold factors, stretched (`v²·m/2` mm each side): `pre` in
/// the block before the corner, `post` in the block after it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sides {
    pub pre: f32,
    pub post: f32,
}

/// A hold's length over the first-order one (`v²·m`). A window centred on
/// the corner weighs the hold's middle most: a hold of `T` seconds frees
/// `T/W·(1 − T/4W)` of it, not `T/W`, so it must be longer than the
/// change's own time `T0 = v·m` by `2(1 − sqrt(1 − x))/x` (`x = T0/W`).
/// With the corner speed capped at `x ≤ 1/2`, 1.17 covers it.
pub(super) const HOLD_STRETCH: f32 = 1.17;

// Corner holds.
//
// A corner passed at speed `v` changes each axis's velocity at once, by
// `v·|Δu_i|` (`Δu` the change of the unit direction). A stepper has no
// other way to turn: the step trace shows that change as acceleration,
// and over any window of time it adds to whatever the ramps on either
// side do there. Ramping at an axis's full acceleration right up to the
// corner and away from it again put Z at 160-173 % of its limit on 3-D
// jobs (over 50 ms windows), at junction-deviation speeds.
//
// So the path speed holds at the corner speed for as long as those
// changes would take at the axes' own accelerations: `max_i v·|Δu_i|/a_i`
// seconds, `v²·m` mm with `m = max_i |Δu_i|/a_i` (the block's `hold_m` is
// that times [`HOLD_STRETCH`]), half before the corner and half after. Over any window the velocity
// change an axis sees is then the ramps' plus the corner's, and the corner's
// took the time the ramps give up: at most the axis's acceleration. The
// hold is the length of the arc junction deviation imagines (`v² = a·R`,
// arc length `R·|Δu|`), a few hundredths of a millimetre at usual corner
// speeds; on a polyline curve at the curvature limit (`v² ≤ a·l/φ`) it
// fills the chords, so the turn alone uses the budget there, and below it
// the ramps get what the turns leave. Chords of one arc or spline hold
// nothing: `planner::curve` already shares their budget.
//
// One-sided holds. An axis that stands still on one side of the corner (a
// plunge after a move in XY: Z is still before it, X and Y after it) has
// no ramp on that side for its change to add to, and the window that
// meets the corner sees the change plus the ramp on the other side only.
// Half the change's own time, on the side where the axis moves, is then
// enough (no stretch): with the change `J = x·a·W` and a hold of `h·W`
// after it, the worst window of the meter's kernel reads
// `a·(1 + x²/2 − x·h)`, which is `a` at `h = x/2` (checked numerically
// against the kernel for `x` up to 0.8).
// So each side holds for the axes that move on it: `Sides::pre` (the
// block before) and `Sides::post` (this block). An XY move between a
// retract and a plunge then holds only for X's and Y's own changes, a
// few hundredths of Z's. Only where the still side lasts a window: a
// change of the same axis at the next corner within it adds to this one
// (two like changes 10 ms apart at `x` = 0.3 read 111 %; a window apart,
// 100 %).
//
// In the passes a block entered at `u` and left at `w` must fit
// `u²·m_in/2 + w²·m_out/2 + ramp(u, w)` in its length (`m_in` its own
// corner's `post`, `m_out` the next corner's `pre`)
// ([`Shape::reach_held`]); the backward pass also keeps every entry low
// enough that the block could hold it at both ends, so the forward pass
// never has to slow a block it already accepted.

impl<const N: usize> Planner<N> {
    /// The hold factor `m` of the corner before a block going `unit` for
    /// `length` mm (see the module's corner holds): 0 after a stop, on a
    /// straight continuation, and between chords of one curve that turn no
    /// more than the curve itself does over the chord (twice `l/r`, for
    /// rounding), where the curve's own budget applies.
    pub(super) fn hold_factor(
        &self,
        unit: &[f32; AXES],
        length: f32,
        curve: Option<Curve>,
        v_corner: f32,
        quiet: u8,
        long: (u8, bool),
    ) -> (Sides, Pair) {
        // `quiet`: axes whose change here needs no hold (`planner::quiet`).
        let none = (Sides::default(), Pair::NONE);
        if self.prev_nominal <= 0.0 {
            return none;
        }
        let mut quiet = quiet;
        let mut kink = false;
        if let (Some(c), Some(p)) = (curve, self.prev_curve) {
            // A spline (radius unknown) has half of the budget for its
            // turns already; an arc's chords turn by about `l/r`.
            let own = c == p
                && (c.radius <= 0.0 || {
                    let cos = dot(unit, &self.prev_unit_mm);
                    let phi = libm::acosf(crate::num::clamp(cos, -1.0, 1.0));
                    phi <= 2.0 * length / c.radius
                });
            if own {
                // The turn in the curve's plane is its own, which its
                // budget holds (`planner::curve`); a change across the
                // plane is not: a helical hole's last descending turn
                // meeting its flat one (same radius, same plane) stops Z
                // at once, and held nothing (the curvature check read Z
                // 176 % there on milldrilldiatest). Across the plane a
                // change within rounding over the chord is the chords'
                // own `f32` noise (a constant pitch's `u_z` varies by
                // 4e-4 at 130 mm), not a corner.
                quiet |= c.plane;
                for (i, ax) in self.settings.axes.iter().enumerate() {
                    let d = libm::fabsf(unit[i] - self.prev_unit_mm[i]);
                    if super::corner::within_rounding(d, length, ax) {
                        quiet |= 1 << i;
                    } else if c.plane & (1 << i) == 0 {
                        kink = true;
                    }
                }
            }
        }
        let factor = |before: &[f32; AXES]| {
            let mut m = 0.0f32;
            for (i, ax) in self.settings.axes.iter().enumerate() {
                let d = libm::fabsf(unit[i] - before[i]);
                if d > 1e-6 && quiet & (1 << i) == 0 {
                    m = m.max(d / ax.max_accel);
                }
            }
            m
        };
        // Each side holds for the axes that move on it (module doc, one-
        // sided holds): an axis standing still on one side has no ramp
        // there for its change to add to. `m`: the largest change, as
        // `factor` gives it.
        let p = &self.prev_unit_mm;
        let (mut m, mut sides, mut small) = (0.0f32, Sides::default(), true);
        for (i, ax) in self.settings.axes.iter().enumerate() {
            let d = libm::fabsf(unit[i] - p[i]);
            if d <= 1e-6 {
                continue;
            }
            small &= d * length <= PULSE_SHARE * W * W * ax.max_accel;
            if quiet & (1 << i) != 0 {
                continue;
            }
            m = m.max(d / ax.max_accel);
            // An axis counts as still on a side only if it stays still for
            // a window there (`long`: per axis before, this block after):
            // another change of the axis within one would add to this one
            // (a Z valley's floor of one short XY block: 104 %).
            let (pre, post) = (
                libm::fabsf(p[i]) > 1e-6 || long.0 & (1 << i) == 0,
                libm::fabsf(unit[i]) > 1e-6 || !long.1,
            );
            let k = if pre && post { HOLD_STRETCH } else { 1.0 } * d / ax.max_accel;
            if pre {
                sides.pre = sides.pre.max(k);
            }
            if post {
                sides.post = sides.post.max(k);
            }
        }
        // After a chord the turn before this corner was the curve's own
        // (budgeted there), not a change this one could take back.
        let mut pair = Pair {
            pulse_m: if small { m } else { 0.0 },
            kink,
            ..Pair::NONE
        };
        if m <= 0.0 || self.prev_curve.is_some() || self.prev2_unit_mm.iter().all(|&u| u == 0.0) {
            return (sides, pair);
        }
        // Two corners whose changes oppose (a zigzag, rounding noise) leave
        // together only their sum, plus what the block between them keeps
        // apart: `Δ·t/W` of each over a window `W`, `t` that block's time
        // at this corner's speed (`v_corner`, its junction limit).
        let net = factor(&self.prev2_unit_mm);
        let t = if v_corner.is_finite() && v_corner > 0.0 {
            self.prev_length / v_corner
        } else {
            0.0
        };
        let kept = kept_share(m, net, t);
        let sides = Sides {
            pre: sides.pre * kept,
            post: sides.post * kept,
        };
        pair.kept = kept;
        pair.net = Some(net);
        (sides, pair)
    }

    /// Apply new override percentages: every block's nominal speed and
    /// junction limit change, so the whole ring is replanned.
    pub fn set_overrides(&mut self, feed_pct: u8, rapid_pct: u8) {
        self.feed_pct = feed_pct as f32 / 100.0;
        self.rapid_pct = rapid_pct as f32 / 100.0;
        let mut prev_nominal = None;
        let c_max = self.c_max();
        for k in 0..self.len {
            let mut b = *self.at(k);
            b.nominal = self.nominal(&b);
            Self::curve_limits(&mut b, c_max);
            if b.kind == BlockKind::Line {
                let pn = prev_nominal.unwrap_or(b.entry);
                b.max_entry = b.junction.min(b.nominal).min(pn);
                prev_nominal = Some(b.nominal);
            } else {
                prev_nominal = Some(0.0);
            }
            *self.at(k) = b;
        }
        if self.prev_nominal > 0.0 {
            if let Some(p) = prev_nominal {
                self.prev_nominal = p;
            }
        }
        self.replan(true);
    }

    /// Backward then forward pass. `full` ignores the early stop.
    pub fn replan(&mut self, full: bool) {
        self.replan_to(full, self.len);
    }

    /// [`Planner::replan`], with the backward pass going on at least down
    /// to block `down_to` (a corner there stopped holding: its entry and
    /// the block's before it may rise).
    pub(super) fn replan_to(&mut self, full: bool, down_to: usize) {
        if self.len == 0 {
            return;
        }
        if full {
            self.planned = 0;
        }
        let scurve = self.settings.profile == crate::settings::Profile::SCurve;
        // A corner that stopped holding may complete the promise of every
        // block before it in its run (`planner::run`): those may rise too.
        let down_to = if scurve && down_to < self.len {
            let first =
                down_to.saturating_sub(usize::from(self.blocks[(self.tail + down_to) % N].run_pos));
            self.planned = self.planned.min(first.saturating_sub(1));
            first
        } else {
            down_to
        };
        // One backward pass for each profile, so that trapezoid mode pays
        // nothing for S-curve runs (bench-target's plan_block_insns).
        let lowered = if scurve {
            self.backward::<true>(full, down_to)
        } else {
            self.backward::<false>(full, down_to)
        };
        if let Some(k) = lowered {
            self.planned = k - 1;
        }
        // Forward: no block may be entered faster than the previous can reach
        // (in S-curve mode, than the run it ends can, `planner::run`).
        let mut run = self.run_before(self.planned + 1);
        let first = self.planned + 1;
        self.count_work(self.len.saturating_sub(first));
        let (st, blocks, tail) = (&self.settings, &mut self.blocks, self.tail);
        for k in first..self.len {
            let (prev, b) = pair(blocks, (tail + k - 1) % N, (tail + k) % N);
            let mut reach = match prev.kind {
                BlockKind::Line => {
                    prev.shape(st)
                        .reach_held(prev.entry, prev.length, prev.hold_m, b.hold_pre_m)
                }
                BlockKind::Dwell { .. } => 0.0,
            };
            if let Some(r) = run.as_mut() {
                if let Some(v) = r.step(prev, b, st, reach <= b.entry) {
                    reach = reach.max(v);
                }
            }
            if reach <= b.entry {
                b.entry = reach;
                self.planned = k;
            } else if b.entry >= b.max_entry {
                self.planned = k;
            }
        }
    }

    /// The backward pass of [`Planner::replan_to`] (`S`: in S-curve mode,
    /// reckoning runs, `planner::run`); returns the lowest block it lowered
    /// at or below `planned`.
    fn backward<const S: bool>(&mut self, full: bool, down_to: usize) -> Option<usize> {
        // Backward: the newest block must be able to stop at its end, and
        // every block must fit its corners' holds. Appending a block never
        // lowers an entry without holds (the block before it was planned to
        // stop, which is the most an exit can ask). With them it can: a
        // corner whose hold costs more distance than stopping would
        // (`m > 1/a`) lowers the entry of the block before it. So the pass
        // may go on below `planned`, only lowering there, and stops at the
        // first entry that does not change.
        let planned = self.planned;
        let mut lowered = None;
        let mut next_entry = 0.0f32;
        let mut next_m = 0.0f32; // the next corner's hold before it
        let mut k = self.len;
        // The settings and the ring borrowed apart: a copy of either per
        // block was most of bench-target's plan_block_insns memcpy.
        let (st, blocks, tail) = (&self.settings, &mut self.blocks, self.tail);
        // In S-curve mode, the rest of block `k`'s run and the block after
        // it (`planner::run`), carried down the pass.
        let mut ahead: Option<(RunAhead, Option<usize>)> = None;
        // Whether the entry of that block after the run changed in this
        // pass, and whether the last block's did.
        let (mut exit_moved, mut moved) = (false, false);
        let top = k;
        while k > 1 {
            k -= 1;
            let exit = if S {
                let (run, exit) = run_down(blocks, tail, k, self.len, ahead);
                if exit == Some(k + 1) {
                    exit_moved = moved;
                }
                ahead = Some((run, exit));
                exit.map(|e| {
                    let x = &blocks[(tail + e) % N];
                    (x.entry, x.hold_pre_m)
                })
            } else {
                None
            };
            let b = &mut blocks[(tail + k) % N];
            let mut new = if b.kind == BlockKind::Line {
                let both = b.hold_m + next_m;
                let held = if both > 0.0 {
                    crate::num::sqrt(2.0 * b.length / both)
                } else {
                    f32::INFINITY
                };
                let alone = held.min(
                    b.shape(st)
                        .reach_held(next_entry, b.length, next_m, b.hold_m),
                );
                // The run's promise, where its cap leaves it room to be
                // the faster.
                let run = match (exit, ahead) {
                    (Some((x, x_m)), Some((run, _))) => {
                        let cap = run.cap();
                        (cap > alone)
                            .then(|| run.promise(cap, x, x_m, b.hold_m, st))
                            .flatten()
                    }
                    _ => None,
                };
                b.max_entry.min(run.map_or(alone, |p| p.max(alone)))
            } else {
                0.0
            };
            if k <= planned {
                new = new.min(b.entry);
                if new != b.entry {
                    lowered = Some(k);
                }
            }
            let unchanged = new == b.entry;
            b.entry = new;
            next_entry = new;
            next_m = b.hold_pre_m;
            moved = !unchanged;
            // The blocks before read this entry and, in S-curve mode, the
            // entry after this block's run.
            let settled = !S || !exit_moved;
            if unchanged && settled && k < down_to && (k <= planned || (!full && k + 1 < self.len))
            {
                break;
            }
        }
        self.count_work(top - k);
        lowered
    }
}

/// The share of a corner's hold that a pair of corners keeps: `m` the
/// corner's own largest change (as `|Δu_i|/a_i`), `net` what the two
/// changes leave together, `t` the time between them, s. Over a window `W`
/// the pair reads as its net change plus the velocity the block between
/// them holds apart for `t`: at most `net + m·t/W` (module doc of
/// [`super::cancel`]).
pub(super) fn kept_share(m: f32, net: f32, t: f32) -> f32 {
    m.min(net + m * (t / CANCEL_WINDOW_S).min(1.0)) / m
}

/// The cosine between two unit directions.
pub(super) fn dot(a: &[f32; AXES], b: &[f32; AXES]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Block `prev` to read and block `k` to change, of the ring (`prev != k`),
/// without copying either out.
fn pair<const N: usize>(blocks: &mut [Block; N], prev: usize, k: usize) -> (&Block, &mut Block) {
    if prev < k {
        let (lo, hi) = blocks.split_at_mut(k);
        (&lo[prev], &mut hi[0])
    } else {
        let (lo, hi) = blocks.split_at_mut(prev);
        (&hi[0], &mut lo[k])
    }
}
