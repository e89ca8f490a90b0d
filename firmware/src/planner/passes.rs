//! Junction limits, overrides, and the backward/forward planning passes.

use super::*;

/// The time over which opposite velocity changes at two corners cancel
/// (`Planner::hold_factor`): the window the step trace's acceleration is
/// judged over (`host_sim::bench::limits`), s.
pub(super) const CANCEL_WINDOW_S: f32 = 0.05;

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
    /// Cornering speed at the junction with the previous block.
    ///
    /// Junction deviation: round the corner by a circle tangent to both moves
    /// whose closest approach to the corner is `δ`. With `c = sin(θ/2)` of the
    /// corner's half angle (θ = π when straight), the circle's radius is
    /// `R = δ·c/(1 − c)` and `v = sqrt(a·R)` keeps the centripetal
    /// acceleration within `a`.
    ///
    /// Chords of a curve turn by a small angle φ every chord length `l`, so
    /// the tool really follows a curve of radius about `l/φ`. Junction
    /// deviation alone allows `a·δ/tol` there (5× the limit with GRBL's
    /// defaults); the second limit `v² ≤ a·l/φ` keeps curves honest.
    ///
    /// Both judge the commanded geometry (`unit_mm`, `length` in mm), not
    /// the step-rounded one: a G1 chord of a step or two can look like a
    /// 45° corner in steps (a radius of 0.016 mm on a 25 mm circle), which
    /// it is not; the motors' one-step jitter around the commanded line
    /// averages out like that of any Bresenham line.
    ///
    /// `a` is the acceleration the axes allow along the direction change
    /// (the difference of the two unit vectors), not along either move.
    pub(super) fn junction_speed(&self, unit_mm: &[f32; AXES], length: f32, curve: bool) -> f32 {
        if self.prev_nominal <= 0.0 {
            return 0.0;
        }
        let (cos, a) = self.turn(unit_mm, &self.prev_unit_mm);
        if cos > 0.999_999 {
            return 0.0;
        }
        if cos < -0.999_999 {
            // Straight on: no corner to limit.
            return f32::INFINITY;
        }
        let sin_half = libm::sqrtf(0.5 * (1.0 - cos));
        let r = self.settings.junction_deviation * sin_half / (1.0 - sin_half);
        let v_jd = libm::sqrtf(a * r);
        let phi = libm::acosf(crate::num::clamp(-cos, -1.0, 1.0)).max(1e-9);
        let l = length.min(self.prev_length);
        let a_curve = if curve { self.c_max() * a } else { a };
        let v_curve = libm::sqrtf(a_curve * l / phi);
        let v_jerk = if curve || self.settings.profile != crate::settings::Profile::SCurve {
            f32::INFINITY
        } else {
            self.curve_jerk_cap(self.turn_radius(unit_mm, l, phi))
        };
        v_jd.min(v_curve).min(v_jerk)
    }

    /// The radius an S-curve run turns on at a vertex, for the turn's jerk
    /// (`v³/r²`, [`Self::curve_jerk_cap`]; an arc's chords have their
    /// arc's cap already): the larger of the vertex's own `l/φ` and the
    /// turn from the block before the previous one over two chords. Chords
    /// of a real curve turn alike, and both agree; a zigzag of noise
    /// (chords a few steps long alternating a few steps across a line,
    /// inch decimals on a circle) turns back at the next vertex, so its
    /// axes' acceleration changes sign from chord to chord and averages
    /// out instead of building up: there the two-chord turn is small and
    /// does not slow the line down to its noise.
    fn turn_radius(&self, unit: &[f32; AXES], l: f32, phi: f32) -> f32 {
        let r = l / phi;
        if self.prev2_unit_mm.iter().all(|&u| u == 0.0) {
            return r;
        }
        let cos2 = dot(unit, &self.prev2_unit_mm);
        let phi2 = libm::acosf(crate::num::clamp(cos2, -1.0, 1.0)).max(1e-9);
        r.max(2.0 * l / phi2)
    }

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
    ) -> Sides {
        // `quiet`: axes whose change here needs no hold (`planner::quiet`).
        let none = Sides::default();
        if self.prev_nominal <= 0.0 {
            return none;
        }
        let cos = dot(unit, &self.prev_unit_mm);
        if let (Some(c), Some(p)) = (curve, self.prev_curve) {
            let phi = libm::acosf(crate::num::clamp(cos, -1.0, 1.0));
            if c == p && c.radius > 0.0 && phi <= 2.0 * length / c.radius {
                return none;
            }
            if c == p && c.radius <= 0.0 {
                // A spline (radius unknown) has half of the budget for
                // its turns already.
                return none;
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
        let (mut m, mut sides) = (0.0f32, none);
        for (i, ax) in self.settings.axes.iter().enumerate() {
            let d = libm::fabsf(unit[i] - p[i]);
            if d <= 1e-6 || quiet & (1 << i) != 0 {
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
        if m <= 0.0 || self.prev_curve.is_some() || self.prev2_unit_mm.iter().all(|&u| u == 0.0) {
            return sides;
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
        let kept = m.min(net + m * (t / CANCEL_WINDOW_S).min(1.0)) / m;
        Sides {
            pre: sides.pre * kept,
            post: sides.post * kept,
        }
    }

    /// Cosine of the corner between the reversed previous direction and
    /// `unit` (-1: straight on), and the acceleration the axes allow along
    /// the direction change.
    fn turn(&self, unit: &[f32; AXES], prev: &[f32; AXES]) -> (f32, f32) {
        let cos = -dot(unit, prev);
        let d: [f32; AXES] = core::array::from_fn(|i| unit[i] - prev[i]);
        let dn = libm::sqrtf(d.iter().map(|v| v * v).sum());
        let mut a = f32::INFINITY;
        for (di, ax) in d.iter().zip(&self.settings.axes) {
            let c = libm::fabsf(*di) / dn;
            if c > 1e-6 {
                a = a.min(ax.max_accel / c);
            }
        }
        (cos, a)
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
        let shape_of = |b: &Block, s: &Settings| b.shape(s);
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
        while k > 1 {
            k -= 1;
            let b = &mut blocks[(tail + k) % N];
            let mut new = if b.kind == BlockKind::Line {
                let both = b.hold_m + next_m;
                let held = if both > 0.0 {
                    libm::sqrtf(2.0 * b.length / both)
                } else {
                    f32::INFINITY
                };
                b.max_entry
                    .min(held)
                    .min(shape_of(b, st).reach_held(next_entry, b.length, next_m, b.hold_m))
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
            if unchanged && k < down_to && (k <= planned || (!full && k + 1 < self.len)) {
                break;
            }
        }
        if let Some(k) = lowered {
            self.planned = k - 1;
        }
        // Forward: no block may be entered faster than the previous can reach
        // (in S-curve mode, than the run it ends can, `planner::run`).
        let mut run = self.run_before(self.planned + 1);
        let (st, blocks, tail) = (&self.settings, &mut self.blocks, self.tail);
        for k in self.planned + 1..self.len {
            let (prev, b) = pair(blocks, (tail + k - 1) % N, (tail + k) % N);
            let mut reach = match prev.kind {
                BlockKind::Line => shape_of(prev, st).reach_held(
                    prev.entry,
                    prev.length,
                    prev.hold_m,
                    b.hold_pre_m,
                ),
                BlockKind::Dwell { .. } => 0.0,
            };
            if let Some(r) = run.as_mut() {
                if let Some(v) = r.step(prev, b, st) {
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
}

/// The cosine between two unit directions.
fn dot(a: &[f32; AXES], b: &[f32; AXES]) -> f32 {
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
