//! Sine, cosine and arcsine in `f32` only.
//!
//! libm's `sinf`/`cosf`/`tanf` evaluate their polynomials in `f64` and
//! reduce the argument with `rem_pio2f`, which is exact for any `f32` but
//! also `f64` work plus a 2.5 KB Payne-Hanek fallback. The Cortex-M4F has no
//! double-precision unit, so on the board all of that is soft-float: about
//! 6 KB of flash (the `f64` add, multiply and divide routines included) and
//! far slower than single-precision arithmetic. G-code needs neither: arc
//! angles stay within a few turns, and the expression functions take
//! degrees, which reduce exactly.
//!
//! Accuracy, against `f64` (`tests`; an ulp taken at the larger of the
//! value and 2^-10): 1.03 ulp at worst over ±4096 rad, 0.69 ulp for
//! degrees over ±1800°. Beyond 2^12 rad the reduction loses bits
//! gradually. Non-finite arguments give NaN.

use core::f32::consts::FRAC_2_PI;

/// π/2 in three parts. The first two have few enough significant bits (8
/// and 11) that `k·part` is exact for |k| < 2^13, and `x - k·PIO2_HI` is
/// exact as well (the two are within a factor of two of each other), so
/// the reduced argument carries only the rounding of the last two terms.
const PIO2_HI: f32 = 1.570_312_5;
const PIO2_MID: f32 = 4.837_513e-4;
const PIO2_LO: f32 = 7.549_79e-8;

/// sin(r) for |r| ≤ π/4: an odd minimax polynomial of degree 7 (the same
/// family of coefficients as Cephes' `sinf`).
#[inline]
fn sin_poly(r: f32) -> f32 {
    let z = r * r;
    ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * r + r
}

/// cos(r) for |r| ≤ π/4: an even minimax polynomial of degree 8.
#[inline]
fn cos_poly(r: f32) -> f32 {
    let z = r * r;
    ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0
}

/// (sin, cos) of `r` (|r| ≤ π/4) turned by `k` quarter turns.
#[inline]
fn quadrant(k: i32, r: f32) -> (f32, f32) {
    let (s, c) = (sin_poly(r), cos_poly(r));
    // `+ 0.0` turns a -0 into +0: sin 180° prints as 0, not -0.
    match k & 3 {
        0 => (s + 0.0, c + 0.0),
        1 => (c + 0.0, -s + 0.0),
        2 => (-s + 0.0, -c + 0.0),
        _ => (-c + 0.0, s + 0.0),
    }
}

/// Nearest integer to `q` (halves away from zero), saturating.
#[inline]
fn nearest(q: f32) -> i32 {
    (q + libm::copysignf(0.5, q)) as i32
}

/// (sin x, cos x), `x` in radians.
pub fn sin_cos(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    let k = nearest(x * FRAC_2_PI);
    let kf = k as f32;
    let r = ((x - kf * PIO2_HI) - kf * PIO2_MID) - kf * PIO2_LO;
    quadrant(k, r)
}

/// (sin x, cos x), `x` in degrees (RS274NGC's SIN, COS and TAN). The
/// reduction by 90° is exact, so `SIN[180]` is 0 and `COS[90]` is 0, not a
/// few ulp off; `TAN[90]` is then a division by zero, which the expression
/// evaluator reports as an error.
pub fn sin_cos_deg(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    // Both steps are exact: `fmodf` always is, and then |x| < 360, 90·k
    // is exact and x lies within a factor of two of it (or k is 0).
    let x = libm::fmodf(x, 360.0);
    let k = nearest(x / 90.0);
    let r = x - k as f32 * 90.0;
    quadrant(k, r * (core::f32::consts::PI / 180.0))
}

/// asin x (|x| ≤ 1; NaN beyond), radians. libm's `asinf` finishes in
/// `f64`; `atan2f` does not, and this form keeps its precision at both
/// ends of the domain ((1 - x)(1 + x) is exact near |x| = 1).
pub fn asin(x: f32) -> f32 {
    libm::atan2f(x, crate::num::sqrt((1.0 - x) * (1.0 + x)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Error in units of the f32 spacing at the true value, with an
    /// absolute floor near zero.
    fn ulps(got: f32, want: f64) -> f64 {
        let ulp = f64::from(f32::EPSILON) * want.abs().max(1.0 / 1024.0);
        (f64::from(got) - want).abs() / ulp
    }

    #[test]
    fn radians_agree_with_f64_to_2_ulp() {
        let mut worst: f64 = 0.0;
        let mut x = -4096.0f32;
        while x <= 4096.0 {
            let (s, c) = sin_cos(x);
            let xd = f64::from(x);
            worst = worst.max(ulps(s, xd.sin())).max(ulps(c, xd.cos()));
            x += 0.001_173;
        }
        assert!(worst <= 2.0, "worst {worst} ulp");
    }

    #[test]
    fn small_angles_are_exact_enough_for_arcs() {
        for i in -2000..=2000 {
            let x = i as f32 * 1e-3;
            let (s, c) = sin_cos(x);
            let xd = f64::from(x);
            assert!(ulps(s, xd.sin()) <= 1.5, "sin {x}");
            assert!(ulps(c, xd.cos()) <= 1.5, "cos {x}");
        }
    }

    #[test]
    fn degrees_reduce_exactly() {
        assert_eq!(sin_cos_deg(180.0), (0.0, -1.0));
        assert_eq!(sin_cos_deg(90.0), (1.0, 0.0));
        assert_eq!(sin_cos_deg(-90.0), (-1.0, 0.0));
        assert_eq!(sin_cos_deg(720.0 + 270.0), (-1.0, 0.0));
        assert_eq!(sin_cos_deg(0.0), (0.0, 1.0));
        let mut worst: f64 = 0.0;
        for i in -7200..=7200 {
            let d = i as f32 * 0.25;
            let (s, c) = sin_cos_deg(d);
            let r = f64::from(d).to_radians();
            worst = worst.max(ulps(s, r.sin())).max(ulps(c, r.cos()));
        }
        assert!(worst <= 2.0, "worst {worst} ulp");
    }

    #[test]
    fn asin_agrees_with_f64() {
        let mut worst: f64 = 0.0;
        for i in -100_000..=100_000 {
            let x = i as f32 * 1e-5;
            worst = worst.max(ulps(asin(x), f64::from(x).asin()));
        }
        assert!(worst <= 2.0, "worst {worst} ulp");
        assert_eq!(asin(1.0), core::f32::consts::FRAC_PI_2);
        assert!(asin(1.5).is_nan());
    }

    #[test]
    fn non_finite_is_nan() {
        assert!(sin_cos(f32::INFINITY).0.is_nan());
        assert!(sin_cos(f32::NAN).1.is_nan());
        assert!(sin_cos_deg(f32::NEG_INFINITY).0.is_nan());
    }
}
