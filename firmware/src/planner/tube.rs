//! Stretches of a polyline that stay within a step of a straight line.
//!
//! circle_small.ngc is a 25.4 mm radius circle of 10,000 chords of
//! 0.016 mm, its ends in inch decimals to four places: the commanded
//! points scatter 0.0013 mm across the circle, a tenth of a step at
//! 80 steps/mm, and every chord turns by up to 9° and back. One corner
//! at a time, and even across two chords (`planner::cancel`), that is a
//! tight curve: the curvature rule and the corner holds kept the job to
//! 15 mm/s (10.5 s, against 5.0 s with neither, every limit kept). What
//! the motors do shows only over a longer stretch, and there the circle
//! is what it is.
//!
//! So the planner also looks back over stretches of at least [`SPAN_MM`]
//! of path (the newest plain lines since a stop) and asks whether every
//! vertex in one lies within [`TUBE_STEPS`] of each axis's steps of the
//! line from its first vertex to its last, in the stepped positions the
//! motors go to, each further along that line than the one before (a
//! 0.014 mm Z dip in a steep climb, Cereal.ngc, stays that close but turns
//! Z round: 106 % of its limit when it counted). If so, the motors move as
//! they would along the line, give or take a step, and the corners inside
//! the stretch (whatever comes after its last vertex is that vertex's own
//! corner) are judged on the stretch:
//!
//! * **Curvature.** A path that stays within a tube of half-width `τ`
//!   over a length `L` bends, end to end, no tighter than the circle of
//!   sagitta `τ` over `L`: `r = L²/8τ`. `τ` is the tube plus the half step
//!   the stretch's ends and each vertex were rounded by (the commanded
//!   path is what curves), in the coarsest moving axis's steps: 2 steps,
//!   `r` = 2.8 mm on circle_small's 0.75 mm stretches (its own radius,
//!   25.4 mm, is larger, as for any stretch that passes). The corner's
//!   limit becomes junction deviation's, capped by `v² ≤ c·a·r` with `a`
//!   the least acceleration of the moving axes (the bend's direction is
//!   not known) and `c` = [`CENTRIPETAL`]; a corner whose own limits
//!   already allow more than that is a corner of its own and stays as it
//!   is.
//! * **Ramps.** The blocks on both sides of a released corner take at
//!   most `(1 − c)` of the line's own acceleration limit: a block turned
//!   off the line by rounding allows more on the axis it turned from, and
//!   a run of them averaged above Z's limit on Cereal.ngc (107 %). Each
//!   axis then sees at most `(1 − c)·a_i` along the path and `c·a_i`
//!   across it.
//! * **Holds.** What is left is the wobble about the line, a position
//!   within `τ`: the step-trace meter (a second difference of positions
//!   over 50 ms windows) reads it as at most `4τ/W²`, 8 % of X's 500 mm/s²
//!   at 80 steps/mm (the same order as the step quantisation of any line,
//!   which the meter reads too), so the corners inside hold nothing.
//!
//! Junction deviation stays (it is the stated limit, and on a noisy
//! polyline it is what the time-optimal bound keeps). Corners only rise,
//! and lose their holds, after they were planned, as `planner::quiet`'s
//! releases do, so the passes go back over them; not the newest block's
//! (`planner::cancel` settles it) nor one whose block before the segment
//! preparer may have started (the oldest two). Stretches start every
//! [`ADVANCE`] of the last one's length (at least [`MIN_ADVANCE`] blocks
//! on), so each corner is judged in several: a stretch that fails on one
//! vertex leaves the others to the next ones.

use super::passes::Sides;
use super::*;

/// The least path length a stretch is judged over, mm: the bound `r`
/// grows as its square, and fewer stretches pass (circle_small, whose
/// chords stay within a step of a line for about 1 mm: 0.5 mm, 7.74 s;
/// 0.75, 6.24 s; 1.0, 8.21 s).
pub(super) const SPAN_MM: f32 = 0.75;

/// How far a vertex may lie off the stretch's line, in steps of each
/// axis (rounding alone puts a vertex half a step off).
const TUBE_STEPS: f32 = 1.0;

/// Where the next stretch starts along the last one, as a share of its
/// length, and in blocks at least: each test walks the stretch's blocks
/// and each release replans from its first corner, so bench-target's
/// 0.1 mm circle (8 blocks a stretch, every corner released) tested and
/// replanned at every push (14,400 instructions a block); at least every
/// 6 blocks, 11,021 (circle_small: every 4, 6.44 s; 6, 6.24 s; 8, 7.36 s).
const ADVANCE: f32 = 0.125;
const MIN_ADVANCE: usize = 6;

/// The share of the least axis acceleration a released corner's bend may
/// take; the ramps beside it keep the rest (`(1 − c)`). circle_small:
/// 0.5, 6.52 s; 0.7, 6.24 s; 0.85, 6.39 s.
const CENTRIPETAL: f32 = 0.7;

/// The stretch being followed: the newest `blocks` blocks, from `anchor`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tube {
    /// Its first vertex, steps.
    anchor: [i32; AXES],
    /// Its length to the newest block's end, mm.
    len: f32,
    /// How many of the newest blocks it spans (0: none yet).
    blocks: u16,
}

impl Tube {
    /// No stretch (all zero bits: the machine's placeholder stays in .bss).
    pub const NONE: Tube = Tube {
        anchor: [0; AXES],
        len: 0.0,
        blocks: 0,
    };
}

/// What a straight stretch allows.
#[derive(Clone, Copy)]
struct Straight {
    /// The least acceleration of the axes that move, mm/s².
    a: f32,
    /// The path acceleration the axes allow along the stretch's line.
    a_line: f32,
    /// The coarsest step of the axes that move, mm.
    step_mm: f32,
}

impl<const N: usize> Planner<N> {
    /// Follow the stretch after a push that started at `start` (steps) and
    /// ran `len_mm`: a plain line (anything else ends the stretch), merged
    /// into the newest block or not. Returns the lowest block whose entry
    /// may rise (`len` if none).
    pub(super) fn extend_tube(
        &mut self,
        start: [i32; AXES],
        len_mm: f32,
        plain: bool,
        merged: bool,
    ) -> usize {
        let none = self.len;
        let t = &mut self.tube;
        if !plain {
            t.blocks = 0;
            return none;
        }
        if t.blocks == 0 {
            t.anchor = start;
            t.len = 0.0;
        }
        t.blocks += u16::from(!merged);
        t.len += len_mm;
        let (anchor, total, blocks) = (t.anchor, t.len, t.blocks as usize);
        if blocks > self.len {
            // Its start was popped: begin again at the next push.
            self.tube.blocks = 0;
            return none;
        }
        if total < SPAN_MM || blocks < 3 {
            return none;
        }
        let newest = self.len - 1;
        let first = self.len - blocks;
        let straight = self.stretch_is_straight(&anchor, first, newest);
        // The next stretch begins at the first vertex [`ADVANCE`] along
        // this one: every corner is judged in several.
        let (mut at, mut next) = (0.0f32, newest);
        for j in first + 1..=newest {
            at += self.at(j - 1).length;
            if at >= ADVANCE * total && j - first >= MIN_ADVANCE {
                next = j;
                break;
            }
        }
        let next_anchor = self.at(next - 1).target;
        self.tube = Tube {
            anchor: next_anchor,
            len: total - at,
            blocks: (newest - next + 1) as u16,
        };
        match straight {
            Some(line) => self.release_tube(first, newest, total, line),
            None => none,
        }
    }

    /// Whether the vertices between block `first`'s start (`anchor`) and
    /// block `newest`'s end all lie within the tube of the line between
    /// those two, and if so what the stretch allows.
    fn stretch_is_straight(
        &self,
        anchor: &[i32; AXES],
        first: usize,
        newest: usize,
    ) -> Option<Straight> {
        let d: [f32; AXES] =
            core::array::from_fn(|i| self.position[i].wrapping_sub(anchor[i]) as f32);
        let dd: f32 = d.iter().map(|v| v * v).sum();
        if dd <= 0.0 {
            return None;
        }
        let mut moving = 0u8;
        // Each vertex further along the line than the one before: a block
        // that goes back along it (a 0.014 mm Z dip in a steep climb, in
        // Cereal.ngc) turns the axes round, however close it stays.
        let mut along = 0.0f32;
        for j in first..newest {
            let b = &self.blocks[(self.tail + j) % N];
            let w: [f32; AXES] =
                core::array::from_fn(|i| b.target[i].wrapping_sub(anchor[i]) as f32);
            let t = passes::dot(&w, &d) / dd;
            if t <= along || t >= 1.0 {
                return None;
            }
            along = t;
            for i in 0..AXES {
                if libm::fabsf(w[i] - t * d[i]) > TUBE_STEPS {
                    return None;
                }
                moving |= u8::from(b.steps[i] != 0) << i;
            }
        }
        // The line's own acceleration limit, from its direction in mm.
        let mm: [f32; AXES] = core::array::from_fn(|i| d[i] / self.settings.axes[i].steps_per_mm);
        let len = crate::num::sqrt(mm.iter().map(|v| v * v).sum());
        let (mut a, mut a_line, mut step_mm) = (f32::INFINITY, f32::INFINITY, 0.0f32);
        for (i, ax) in self.settings.axes.iter().enumerate() {
            if moving & (1 << i) != 0 || d[i] != 0.0 {
                a = a.min(ax.max_accel);
                step_mm = step_mm.max(1.0 / ax.steps_per_mm);
            }
            let u = libm::fabsf(mm[i]) / len;
            if u > 1e-6 {
                a_line = a_line.min(ax.max_accel / u);
            }
        }
        Some(Straight { a, a_line, step_mm })
    }

    /// Raise the corners inside a straight stretch of `total` mm (blocks
    /// `first` to `newest`) to the stretch's curvature bound, drop their
    /// holds, and leave the blocks around them the rest of the
    /// acceleration (module doc).
    fn release_tube(&mut self, first: usize, newest: usize, total: f32, line: Straight) -> usize {
        let mut lowest = self.len;
        let r = total * total / (8.0 * (TUBE_STEPS + 1.0) * line.step_mm);
        let turn_v = self.curve_jerk_cap(r);
        let v = crate::num::sqrt(CENTRIPETAL * line.a * r).min(turn_v);
        let ramp = (1.0 - CENTRIPETAL) * line.a_line;
        // Not the newest block's corner (`planner::cancel` settles it), nor
        // the ones whose block before may be the preparer's.
        for j in (first + 1).max(3)..newest {
            let prev_nominal = self.at(j - 1).nominal;
            let b = self.at(j);
            let corner = b.jd.min(v);
            // A corner faster than the stretch's bend allows is one of its
            // own and keeps its hold; one already released is left alone.
            if b.corner > v || (corner <= 1.05 * b.corner && b.hold_m == 0.0 && b.hold_pre_m == 0.0)
            {
                continue;
            }
            b.hold_fixed = Sides::default();
            b.release = 0;
            // No hold: the room it would need does not matter.
            b.set_corner(corner.max(b.corner), Sides::default(), 0.0, prev_nominal);
            b.turn_v = 0.0;
            b.turn_at(turn_v);
            // The ramps on both sides take the line's acceleration, less
            // the bend's share: a block turned off the line by rounding
            // allows more on the axis it turned from, and a run of them
            // averaged above Z's limit on Cereal.ngc (107 %).
            b.accel = b.accel.min(ramp);
            let p = self.at(j - 1);
            p.accel = p.accel.min(ramp);
            lowest = lowest.min(j - 2);
        }
        if lowest < self.len {
            self.planned = self.planned.min(lowest.saturating_sub(1));
        }
        lowest
    }
}
