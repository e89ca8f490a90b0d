//! How a chord of an arc shares the acceleration budget between the
//! centripetal and the tangential part.
//!
//! On a curve of radius `r` at speed `v` the tool accelerates by `a_n =
//! v²/r` towards the centre (the in-plane normal `n`) and by `a_t` along
//! the path (the chord's direction `u`). Axis `i` feels `a_t·u_i + a_n·n_i`.
//! A block speeds up and slows down, so `a_t` takes both signs, and with
//! `u ⟂ n` in the plane one of the two plane axes always gets the sum of
//! the magnitudes: the exact per-axis limit is
//! `|a_t|·|u_i| + a_n·|n_i| ≤ a_i` on each axis. Each chord is judged in
//! its own direction: a YZ arc at Y 500 / Z 100 mm/s² may turn at 500
//! where its normal lies along Y, and at 100 only where it lies along Z
//! (a single isotropic budget, the smallest axis's, held the whole arc to
//! that axis). Axes outside the plane (a helix's linear axis) only feel
//! `a_t·u_i`, which the block's straight-line limit already covers.
//!
//! The centripetal share `c = a_n/A_n` (`A_n = min_i a_i/|n_i|`, the most
//! the normal direction allows) follows from the speed: an arc the feed
//! keeps slow leaves nearly the whole budget to speeding up and slowing
//! down; a small arc the budget itself keeps slow runs at up to
//! `sqrt(C_MAX_TRAPEZOID·A_n·r)`. Its ramps take what each axis has left
//! at the speed they reach, which falls with `v²` (`Shape::drop`): a ramp
//! from rest gains speed fast while the turn takes little, and slows as it
//! nears the cap, so the cap can sit close to the whole budget. A helix
//! turns only the in-plane part of its speed. S-curve mode keeps one
//! isotropic budget for the whole curve (`Curve::budget`) and `C_MAX`.

use super::*;

/// Largest centripetal share of the budget on a curve in S-curve mode:
/// the rest is left for the tangential ramps, which run at one
/// acceleration a chord (the isotropic rule below holds up to 0.8).
pub const C_MAX: f32 = 0.8;

/// The same in trapezoid mode, where a chord's ramp takes what the speed
/// it reaches leaves (`Shape::drop`): at `c` the ramps near the top are
/// slow, but a ramp from rest gets to 99 % of `sqrt(A_n·r)` within
/// `r·ln(100)/2`. 0.9 / 0.95 / 0.98: bench-motion totals 2005.40 /
/// 2004.88 / 2004.89 s (0.8 before the in-plane helix speed: 2007.16).
pub const C_MAX_TRAPEZOID: f32 = 0.95;

/// What the planner knows about the curve a chord belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Curve {
    /// Smallest radius along the curve, mm; 0: unknown (a spline), then
    /// the chord gets half of the budget each way, whatever its speed.
    pub radius: f32,
    /// Axes of the curve's plane (bit n: axis n).
    pub plane: u8,
}

/// A chord's share of the budget (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChordBudget {
    /// `A_n·r`, mm²/s²: `C_MAX` of it caps `v²`.
    pub ar: f32,
    /// `A_n`, mm/s².
    pub an: f32,
    /// Per plane axis, the tangential limit `α − β·a_n` (`α = a_i/|u_i|`,
    /// `β = |n_i|/|u_i|`); `α` infinite where the chord does not move
    /// the axis (the centripetal cap already keeps it within its limit).
    pub tangent: [[f32; 2]; 2],
}

impl Curve {
    /// The budget of a chord going `unit` under `s`; `None` when the
    /// radius is unknown or the plane is not two axes.
    pub(super) fn budget(&self, s: &Settings, unit: &[f32; AXES]) -> Option<ChordBudget> {
        if !(self.radius.is_finite() && self.radius > 0.0) || self.plane.count_ones() != 2 {
            return None;
        }
        let mut ax = (0..AXES).filter(|i| self.plane >> i & 1 != 0);
        let (p, q) = (ax.next()?, ax.next()?);
        let (up, uq) = (unit[p], unit[q]);
        let norm = crate::num::sqrt(up * up + uq * uq);
        if norm.is_nan() || norm <= 1e-6 {
            return None;
        }
        // In-plane normal: the in-plane direction turned by 90°.
        let n = [libm::fabsf(uq) / norm, libm::fabsf(up) / norm];
        let u = [libm::fabsf(up), libm::fabsf(uq)];
        let a = [s.axes[p].max_accel, s.axes[q].max_accel];
        // S-curve mode keeps the isotropic rule: one budget `A` (the
        // smallest plane axis's) for the whole curve and `a_t ≤ A − a_n/2`,
        // below `sqrt(A² − a_n²)` for `a_n ≤ 0.8·A` and equal to it at both
        // ends. Per-chord budgets read 123 % of Z's acceleration on a 1 mm
        // YZ helix (tort) and the exact split 114 % on a small XZ arc after
        // a plunge (blur_torus), both at 50,000 mm/s³: an S ramp spans
        // chords that each allow a different split.
        if s.profile == crate::settings::Profile::SCurve {
            let an = a[0].min(a[1]);
            return Some(ChordBudget {
                ar: an * self.radius,
                an,
                tangent: [[an, 0.5], [f32::INFINITY, 0.0]],
            });
        }
        let mut an = f32::INFINITY;
        let mut tangent = [[f32::INFINITY, 0.0]; 2];
        for k in 0..2 {
            if n[k] > 1e-6 {
                an = an.min(a[k] / n[k]);
            }
            if u[k] > 1e-6 {
                tangent[k] = [a[k] / u[k], n[k] / u[k]];
            }
        }
        // On a helix only the in-plane part of the speed turns: at path
        // speed `v` the plane axes feel `(v·norm)²/r`, so the cap is
        // `v² ≤ c·A_n·r/norm²` (a hole's helix at a pitch of 0.28 of its
        // circumference turns 8 % less than its circle would).
        (an.is_finite() && an > 0.0).then_some(ChordBudget {
            ar: an * self.radius / (norm * norm),
            an,
            tangent,
        })
    }
}

impl<const N: usize> Planner<N> {
    /// Largest centripetal share under the settings' profile.
    pub(super) fn c_max(&self) -> f32 {
        match self.settings.profile {
            crate::settings::Profile::Trapezoid => C_MAX_TRAPEZOID,
            crate::settings::Profile::SCurve => C_MAX,
        }
    }

    /// Cap and path acceleration of a chord block whose nominal speed is
    /// `b.nominal` (called again when the overrides change it), with the
    /// centripetal share at most `c_max` ([`Planner::c_max`]).
    pub(super) fn curve_limits(b: &mut Block, c_max: f32) {
        if b.curve_ar <= 0.0 {
            return;
        }
        let vmax = crate::num::sqrt(c_max * b.curve_ar);
        b.nominal = b.nominal.min(vmax);
        // a_n at the top speed: `v²/r = c·A_n`.
        let an = (b.nominal * b.nominal / b.curve_ar).min(c_max) * b.curve_an;
        b.accel = b.tangent_accel(an);
    }

    /// In S-curve mode, the fastest a curve of radius `r` may be run at a
    /// steady speed: going round it at `v`, each axis's acceleration turns
    /// with it, a jerk of `v³/r²`, so `v ≤ cbrt(j·r²)` (7.7 mm/s on a
    /// 0.3 mm hole at 5000 mm/s³, where the acceleration allowed 11).
    pub(super) fn curve_jerk_cap(&self, r: f32) -> f32 {
        let j = self.settings.jerk;
        if self.settings.profile != crate::settings::Profile::SCurve || !(j > 0.0 && r > 0.0) {
            return f32::INFINITY;
        }
        crate::num::cbrt(j * r * r)
    }
}

impl Block {
    /// Take in a turn whose jerk cap is `v` ([`Planner::curve_jerk_cap`]):
    /// `turn_v` keeps the least finite one.
    pub(super) fn turn_at(&mut self, v: f32) {
        if v.is_finite() && (self.turn_v <= 0.0 || v < self.turn_v) {
            self.turn_v = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A YZ arc on a machine whose Z accelerates at a fifth of Y.
    fn yz() -> (Settings, Curve) {
        let mut s = Settings::default();
        s.axes[1].max_accel = 500.0;
        s.axes[2].max_accel = 100.0;
        (
            s,
            Curve {
                radius: 3.0,
                plane: 0b110,
            },
        )
    }

    #[test]
    fn each_chord_turns_at_what_its_normal_axis_allows() {
        let (s, c) = yz();
        // Going along Z the normal lies along Y: 500 to turn, Z's 100 to ramp.
        let b = c.budget(&s, &crate::pad([0.0, 0.0, 1.0, 0.0])).unwrap();
        assert_eq!((b.an, b.ar), (500.0, 1500.0));
        // tangent[k]: the plane's axes in order, Y then Z.
        assert_eq!(b.tangent[0][0], f32::INFINITY);
        assert_eq!(b.tangent[1], [100.0, 0.0]);
        // Going along Y the normal lies along Z: Z's 100 to turn.
        let b = c.budget(&s, &crate::pad([0.0, 1.0, 0.0, 0.0])).unwrap();
        assert_eq!(b.an, 100.0);
        assert_eq!(b.tangent[0], [500.0, 0.0]);
    }

    #[test]
    fn a_diagonal_chord_keeps_each_axis_within_its_limit_at_the_top_speed() {
        let (s, c) = yz();
        let h = core::f32::consts::FRAC_1_SQRT_2;
        let u = crate::pad([0.0, h, h, 0.0]);
        let cb = c.budget(&s, &u).unwrap();
        let mut b = Block::EMPTY;
        (b.curve_ar, b.curve_an, b.curve_tangent) = (cb.ar, cb.an, cb.tangent);
        b.nominal = 1e6;
        b.line_accel = 100.0 / h;
        Planner::<4>::curve_limits(&mut b, C_MAX);
        let an = b.nominal * b.nominal / c.radius;
        // |a_t|·|u_i| + a_n·|n_i| on each plane axis: Z is the tight one.
        let z = b.accel * h + an * h;
        assert!((z - 100.0).abs() < 0.01, "Z at {z}");
        assert!(b.accel > 0.0);
    }
}
