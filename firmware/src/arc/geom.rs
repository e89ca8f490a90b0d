//! Arc geometry in the arc's plane, relative to the start point.
//!
//! Everything here works from the start radius `s` (start minus centre)
//! and the chord `d` (end minus start, the difference of two commanded
//! points, so as exact as the program). Nothing takes the difference of
//! two absolute angles or adds a radius to a far-away centre: on a radius
//! of 30 m a chord of 0.01 mm turns by 3.3e-7 rad, under 3 ulp of an f32
//! angle near π/2, and a centre 1e9 mm away is known to 64 mm. Issue 35:
//! such an arc ran as a full circle of 30 m because the two angles came
//! out (nearly) equal.

use core::f32::consts::PI;

use crate::command::{ArcDir, Plane};
use crate::settings::AxisSettings;
use crate::AXES;

/// Start and end closer than this (mm) are one point. The interpreter
/// keeps an I/J centre as given below it (a full circle) and refuses an
/// R-format arc.
pub const SAME_POINT: f32 = 1e-4;

/// The finest step (mm) of the two axes of `plane`. Without a positive
/// step count on either it is infinite, negative or NaN, and
/// [`same_point`] falls back to [`SAME_POINT`].
pub fn plane_step(axes: &[AxisSettings; AXES], plane: Plane) -> f32 {
    let (a, b, _) = plane.axes();
    let spm = |i: usize| axes.get(i).map_or(0.0, |x| x.steps_per_mm);
    1.0 / spm(a).max(spm(b))
}

/// How close (mm, in the plane) start and end must be for the arc to be a
/// full circle: half the finest step (closer points end on the same or a
/// neighbouring step, so the machine cannot tell them apart), but never
/// more than [`SAME_POINT`]. The interpreter refuses an R-format arc
/// shorter than that, so an arc it accepted as going somewhere never turns
/// into a circle; an arc below one step that is not a circle moves at most
/// a step, which is the safe way to be wrong.
pub fn same_point(step: f32) -> f32 {
    if step > 0.0 {
        (0.5 * step).min(SAME_POINT)
    } else {
        SAME_POINT
    }
}

/// The signed sweep (radians, positive counter-clockwise) of an arc whose
/// start radius is `s` (length `r0`, finite and positive) and chord `d`.
///
/// The angle between the start and end radii is `atan2(s × e, s · e)` with
/// `e = s + d`, written with `d` (`s × e = s × d`, `s · e = |s|² + s · d`)
/// and `s` scaled to a unit vector: no cancellation between two large
/// products and no overflow for any finite radius, so a chord of one step
/// on a radius of 1e9 mm gets its angle (about 1e-12 rad) to f32
/// precision. A full circle only when the chord is shorter than `same`
/// (see [`same_point`]) or lies exactly along the radius (the end at the
/// start's angle, as RS274NGC reads it). `turns` adds whole circles.
pub fn sweep(s: [f32; 2], r0: f32, d: [f32; 2], dir: ArcDir, turns: u16, same: f32) -> f32 {
    let full = hypot(d[0], d[1]) < same;
    let th = if full {
        0.0
    } else {
        let u = [s[0] / r0, s[1] / r0];
        let cross = u[0] * d[1] - u[1] * d[0];
        let dot = r0 + u[0] * d[0] + u[1] * d[1];
        libm::atan2f(cross, dot)
    };
    let turn = 2.0 * PI;
    let more = turn * f32::from(turns);
    match dir {
        ArcDir::Ccw if th > 0.0 => th + more,
        ArcDir::Ccw => th + turn + more,
        ArcDir::Cw if th < 0.0 => th - more,
        ArcDir::Cw => th - turn - more,
    }
}

/// The point at angle `th` along the arc, relative to the start: `s`
/// turned by `th`, minus `s`, with the radius grown by the fraction `k` of
/// itself (a spiral: `k` is the growth so far over `r0`).
///
/// Turning and subtracting are done in one step,
/// `(cos θ − 1)·s + sin θ·s⊥`, with `1 − cos θ` as `sin²θ / (1 + cos θ)`
/// near 0: a tiny turn of a huge radius keeps its precision (the
/// displacement is a few steps, not the difference of two numbers near
/// 1e9), and every point still lies on the circle for any `th`.
pub fn offset(s: [f32; 2], th: f32, k: f32) -> [f32; 2] {
    let (sin, cos) = crate::num::trig::sin_cos(th);
    let vers = if cos > 0.0 {
        sin * sin / (1.0 + cos)
    } else {
        1.0 - cos
    };
    let oa = -vers * s[0] - sin * s[1];
    let ob = -vers * s[1] + sin * s[0];
    [oa + k * (s[0] + oa), ob + k * (s[1] + ob)]
}

/// LinuxCNC 2.9's tolerance for centre-format arcs, as measured with its
/// `rs274` (issue 14): the start and end radii may differ by at most
/// 100 × `tol`, and by more than `tol` only when that is within 0.1 % of
/// the larger radius. `tol` is 0.0283 mm in G21 and 0.00283 in (0.0718 mm)
/// in G20: LinuxCNC keeps one constant per unit, so the limits are 2.83 mm
/// and 7.18 mm. Looser than one might pick, but files LinuxCNC runs must run.
///
/// The executor holds every arc to the looser (inch) form of it, against
/// its own start: the interpreter checked the arc against where it
/// believed the machine was, and a command refused before it (a soft
/// limit on the first command of a line) leaves that belief wrong.
pub fn radius_mismatch(rs: f32, re: f32, inch: bool) -> bool {
    let tol = if inch { 0.002_828 * 25.4 } else { 0.028_28 };
    let d = (rs - re).abs();
    d > 100.0 * tol || (d > tol && d > 0.001 * rs.max(re))
}

/// `r1 − r0`, the radius the arc gains from start to end, from the chord:
/// `(|e|² − |s|²) / (r0 + r1) = d · (s + e) / (r0 + r1)`, without the
/// cancellation of two radii near 1e9 that differ by a few µm.
pub fn growth(s: [f32; 2], e: [f32; 2], r0: f32, r1: f32, d: [f32; 2]) -> f32 {
    let k = r0 + r1;
    d[0] / k * (s[0] + e[0]) + d[1] / k * (s[1] + e[1])
}

/// How far beyond the start, along one of the plane's axis directions,
/// the circle of radius `r0 + grow.max(0)` reaches: `r − c`, where `c` is
/// the start radius' component along that direction and `o` the other
/// one. `r0 − c` is `o² / (r0 + c)` when `c` is positive (it would cancel).
pub fn reach(r0: f32, grow: f32, c: f32, o: f32) -> f32 {
    let near = if c > 0.0 { o * o / (r0 + c) } else { r0 - c };
    near + grow.max(0.0)
}

/// The angle (0 up to 2π) the arc turns, in its own direction, from the
/// start radius `s` to the axis direction `k` (0: +a, 1: +b, 2: −a, 3:
/// −b). `atan2` of the cross and dot product of `s` with a unit axis
/// vector is exact in its inputs (they are ±components of `s`), so an axis
/// just past the start of a huge arc is found as such.
pub fn turn_to_axis(s: [f32; 2], k: usize, ccw: bool) -> f32 {
    let (cross, dot) = match k & 3 {
        0 => (-s[1], s[0]),
        1 => (s[0], s[1]),
        2 => (s[1], -s[0]),
        _ => (-s[0], -s[1]),
    };
    let a = libm::atan2f(cross, dot);
    wrap(if ccw { a } else { -a })
}

/// `x` wrapped into `[0, 2π)` (2π itself when rounding lands there).
fn wrap(x: f32) -> f32 {
    x - libm::floorf(x / (2.0 * PI)) * 2.0 * PI
}

/// √(a² + b²) in `f32`: libm's `hypotf` sums the squares in `f64`, soft
/// float on the board, to be safe from overflow at 1e19, far beyond any
/// length in mm (a larger radius is refused as not finite).
pub(super) fn hypot(a: f32, b: f32) -> f32 {
    crate::num::sqrt(a * a + b * b)
}
