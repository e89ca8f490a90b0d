//! A vertex's speed limits: junction deviation, the curvature rule, and
//! S-curve's turn jerk, on the commanded geometry.

use super::passes::dot;
use super::*;

/// A vertex's speed limits, mm/s: junction deviation (and S-curve's turn
/// jerk), and the curvature rule `v² ≤ a·l/φ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    pub deviation: f32,
    pub curvature: f32,
    /// Junction deviation alone (without S-curve's turn jerk).
    pub jd: f32,
    /// S-curve: the speed at which the turn takes the whole jerk
    /// ([`Planner::curve_jerk_cap`]; infinite if not reckoned).
    pub turn: f32,
}

/// A corner's turn, for its curvature rule (`v² ≤ a·r`, `r` at least
/// `l/φ`): settled again once the chord after it is known
/// (`planner::cancel`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Turn {
    pub a: f32,
    pub phi: f32,
    pub l: f32,
}

impl Turn {
    /// The curvature rule's speed, on a radius of at least `r`.
    pub fn speed(self, r: f32) -> f32 {
        if self.a <= 0.0 {
            return f32::INFINITY;
        }
        crate::num::sqrt(self.a * (self.l / self.phi).max(r))
    }
}

impl Corner {
    const STOP: Corner = Corner {
        deviation: 0.0,
        curvature: 0.0,
        jd: 0.0,
        turn: f32::INFINITY,
    };
    const STRAIGHT: Corner = Corner {
        deviation: f32::INFINITY,
        curvature: f32::INFINITY,
        jd: f32::INFINITY,
        turn: f32::INFINITY,
    };

    /// Both limits.
    pub fn limit(self) -> f32 {
        self.deviation.min(self.curvature)
    }
}

/// How far, in steps of each axis, a chord may stray from the line before
/// it and still be rounding (inch decimals to four places put 0.2 steps of
/// it into a 25 mm circle at 80 steps/mm), not a turn the motors could
/// show (`planner::cancel`). At half a step, the gentle S-bends of a pen
/// plotter's 0.26 mm strokes passed for rounding, and X read 111 % of the
/// curvature check.
pub(super) const ROUNDING_STEPS: f32 = 0.25;

/// Whether an axis whose unit direction changes by `d` strays within
/// rounding ([`ROUNDING_STEPS`]) over a chord of `length` mm.
#[inline]
pub(super) fn within_rounding(d: f32, length: f32, ax: &crate::settings::AxisSettings) -> bool {
    d * length * ax.steps_per_mm <= ROUNDING_STEPS
}

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
    ///
    /// `phi2`: the turn from the chord before the previous one to this one
    /// (S-curve's jerk, and the curvature rule where the previous chord is
    /// rounding: `planner::cancel`). Also returns the corner's turn, for
    /// settling its curvature later.
    pub(super) fn junction_speed(
        &self,
        unit_mm: &[f32; AXES],
        length: f32,
        curve: bool,
        phi2: Option<f32>,
    ) -> (Corner, Turn) {
        let l = length.min(self.prev_length);
        let none = Turn {
            a: 0.0,
            phi: 0.0,
            l,
        };
        if self.prev_nominal <= 0.0 {
            return (Corner::STOP, none);
        }
        let (cos, a) = self.turn(unit_mm, &self.prev_unit_mm);
        if cos > 0.999_999 {
            return (Corner::STOP, none);
        }
        if cos < -0.999_999 {
            // Straight on: no corner to limit.
            return (Corner::STRAIGHT, none);
        }
        let sin_half = crate::num::sqrt(0.5 * (1.0 - cos));
        let r = self.settings.junction_deviation * sin_half / (1.0 - sin_half);
        let v_jd = crate::num::sqrt(a * r);
        let phi = libm::acosf(crate::num::clamp(-cos, -1.0, 1.0)).max(1e-9);
        let a = if curve { self.c_max() * a } else { a };
        let turn = Turn { a, phi, l };
        // The previous chord only a rounding of the line before it.
        let noise = !curve && self.pending & 1 != 0;
        let r_noise = match phi2 {
            Some(p) if noise => two_chords(l, p),
            _ => 0.0,
        };
        let v_jerk = match phi2 {
            _ if curve || self.settings.profile != crate::settings::Profile::SCurve => {
                f32::INFINITY
            }
            Some(p) => self.curve_jerk_cap((l / phi).max(two_chords(l, p))),
            None => self.curve_jerk_cap(l / phi),
        };
        let c = Corner {
            deviation: v_jd.min(v_jerk),
            curvature: turn.speed(r_noise),
            jd: v_jd,
            turn: v_jerk,
        };
        (c, turn)
    }

    /// Cosine of the corner between the reversed previous direction and
    /// `unit` (-1: straight on), and the acceleration the axes allow along
    /// the direction change.
    fn turn(&self, unit: &[f32; AXES], prev: &[f32; AXES]) -> (f32, f32) {
        let cos = -dot(unit, prev);
        let d: [f32; AXES] = core::array::from_fn(|i| unit[i] - prev[i]);
        let dn = crate::num::sqrt(d.iter().map(|v| v * v).sum());
        let mut a = f32::INFINITY;
        for (di, ax) in d.iter().zip(&self.settings.axes) {
            let c = libm::fabsf(*di) / dn;
            if c > 1e-6 {
                a = a.min(ax.max_accel / c);
            }
        }
        (cos, a)
    }
}

/// The radius of a turn by `phi2` over two chords of `l` (S-curve's jerk
/// cap, [`Planner::curve_jerk_cap`], and the curvature rule across a chord
/// of rounding, `planner::cancel`). Chords of a real curve turn alike at
/// every vertex, and this agrees with each vertex's own `l/φ`; a chord of
/// rounding noise (inch decimals on a circle, a step's staircase) turns
/// the path and turns it back at the next vertex, so the axes'
/// acceleration changes sign and averages out instead of building up:
/// there the turn across the two chords is small, and the radius large.
pub(super) fn two_chords(l: f32, phi2: f32) -> f32 {
    2.0 * l / phi2.max(1e-9)
}

/// The angle between two unit directions of cosine `c`, from above: `2·asin(s/2)` of
/// their difference `s` by its series to the fifth power (over by less
/// than 0.1 % up to 60°), which takes a square root where `acosf` took a
/// hundred instructions (bench-target's `plan_block_insns`). Over 60°,
/// `acosf`.
pub(super) fn angle(c: f32) -> f32 {
    let x = 0.5 * crate::num::sqrt((2.0 - 2.0 * c).max(0.0));
    if x <= 0.5 {
        let x2 = x * x;
        2.0 * x * (1.0 + x2 * (1.0 / 6.0 + 0.1 * x2))
    } else {
        libm::acosf(crate::num::clamp(c, -1.0, 1.0))
    }
}
