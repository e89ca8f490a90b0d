//! How a chord of an arc shares the acceleration budget between the
//! centripetal and the tangential part.
//!
//! On a curve of radius `r` at speed `v` the tool accelerates by `a_n =
//! v²/r` towards the centre and by `a_t` along the path. The normal `n` and
//! the tangent `u` are orthogonal unit vectors, so for every axis
//! `|a_t·u_i + a_n·n_i| ≤ sqrt(a_t² + a_n²)·sqrt(u_i² + n_i²) ≤
//! sqrt(a_t² + a_n²)`: keeping `sqrt(a_t² + a_n²)` within the smallest limit
//! `A` of the arc plane's axes keeps every one of them within its own. Axes
//! outside the plane (a helix's linear axis) only feel `a_t·u_i`, which the
//! block's straight-line limit already covers.
//!
//! The centripetal share `c = a_n/A` follows from the fastest the chord
//! may run: an arc the feed keeps slow (`v² ≪ A·r`) leaves nearly the whole
//! budget to speeding up and slowing down; a small arc the budget itself
//! keeps slow runs at `sqrt(C_MAX·A·r)` and ramps at `sqrt(1 − C_MAX²)·A`.

use super::*;

/// Largest centripetal share of the budget on a curve: the rest
/// (`sqrt(1 − 0.8²) = 0.6`) is left for the tangential ramps.
pub const C_MAX: f32 = 0.8;

/// What the planner knows about the curve a chord belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Curve {
    /// Smallest radius along the curve, mm; 0: unknown (a spline), then
    /// the chord gets half of the budget each way, whatever its speed.
    pub radius: f32,
    /// Axes of the curve's plane (bit n: axis n).
    pub plane: u8,
}

impl Curve {
    /// `A·r` and `A` of this curve under `s` (see the module doc); `None`
    /// when the radius is unknown.
    pub(super) fn budget(&self, s: &Settings) -> Option<(f32, f32)> {
        if !(self.radius.is_finite() && self.radius > 0.0) || self.plane == 0 {
            return None;
        }
        let a = (0..AXES)
            .filter(|i| self.plane >> i & 1 != 0)
            .map(|i| s.axes[i].max_accel)
            .fold(f32::INFINITY, f32::min);
        a.is_finite().then_some((a * self.radius, a))
    }
}

impl<const N: usize> Planner<N> {
    /// Cap and path acceleration of a chord block whose nominal speed is
    /// `b.nominal` (called again when the overrides change it).
    pub(super) fn curve_limits(b: &mut Block) {
        if b.curve_ar <= 0.0 {
            return;
        }
        let vmax = libm::sqrtf(C_MAX * b.curve_ar);
        b.nominal = b.nominal.min(vmax);
        let c = (b.nominal * b.nominal / b.curve_ar).min(C_MAX);
        b.accel = b
            .line_accel
            .min(libm::sqrtf((1.0 - c * c).max(0.0)) * b.curve_a);
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
