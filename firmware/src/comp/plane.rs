//! Plane geometry for cutter compensation: points as `[f32; 2]` in the
//! plane's two axes, the vector helpers, and the arc and side rules the
//! corner cases in `geom.rs` are built from.

use super::{CompOn, Side};
use crate::command::{Arc, ArcDir, Command, Pos};
use crate::gcode::ErrorKind;
use crate::num::trig::sin_cos;
use core::f32::consts::{FRAC_PI_2, PI};
use libm::atan2f;

/// A point in the plane. The core is `f32` throughout (no soft-float
/// `f64` on the board); near a tangent an intersection is ill-conditioned
/// (an error e in a distance moves it by sqrt(2 r e)), so intersections
/// are worked out as vectors (foot of the perpendicular, half chord), not
/// through angles whose rounding the square root would magnify.
pub(super) type P = [f32; 2];

pub(super) fn cos(a: f32) -> f32 {
    sin_cos(a).1
}

pub(super) fn sin(a: f32) -> f32 {
    sin_cos(a).0
}

pub(super) fn tan(a: f32) -> f32 {
    let (s, c) = sin_cos(a);
    s / c
}

pub(super) fn sqrt(x: f32) -> f32 {
    crate::num::sqrt(x)
}

pub(super) fn atan2(y: f32, x: f32) -> f32 {
    atan2f(y, x)
}

/// LinuxCNC's `TOLERANCE_CONCAVE_CORNER`.
pub(super) const SMALL: f32 = 0.05;
/// LinuxCNC's `TOLERANCE_EQUAL`.
pub(super) const EQUAL: f32 = 0.0001;

pub(super) fn dist(a: P, b: P) -> f32 {
    let (x, y) = (a[0] - b[0], a[1] - b[1]);
    sqrt(x * x + y * y)
}

pub(super) fn angle(from: P, to: P) -> f32 {
    atan2(to[1] - from[1], to[0] - from[0])
}

pub(super) fn at(p: P, r: f32, a: f32) -> P {
    let (s, c) = sin_cos(a);
    [p[0] + r * c, p[1] + r * s]
}

pub(super) fn wide(p: [f32; 2]) -> P {
    p
}

pub(super) fn narrow(p: P) -> [f32; 2] {
    p
}

/// LinuxCNC's signed turn count: +n counterclockwise, -n clockwise.
pub(super) fn turn(a: &Arc) -> i32 {
    let n = 1 + i32::from(a.turns);
    match a.dir {
        ArcDir::Ccw => n,
        ArcDir::Cw => -n,
    }
}

/// The signed angle an arc of `turn` sweeps from `s` to `e` about `c`.
pub(super) fn sweep(s: P, c: P, turn: i32, e: P) -> f32 {
    if turn == 0 {
        return 0.0;
    }
    let t1 = angle(c, s);
    let mut t2 = angle(c, e);
    if turn < 0 {
        if t2 >= t1 {
            t2 -= 2.0 * PI;
        }
        t2 - t1 + (turn + 1) as f32 * 2.0 * PI
    } else {
        if t2 <= t1 {
            t2 += 2.0 * PI;
        }
        t2 - t1 + (turn - 1) as f32 * 2.0 * PI
    }
}

/// The tool runs inside an arc of this turn direction.
pub(super) fn inside(side: Side, turn: i32) -> bool {
    (side == Side::Left && turn > 0) || (side == Side::Right && turn < 0)
}

pub(super) fn set_uv(p: &mut Pos, on: &CompOn, uv: P) {
    let (u, v, _) = on.plane.axes();
    p[u] = uv[0];
    p[v] = uv[1];
}

pub(super) fn uv(p: &Pos, on: &CompOn) -> P {
    let (u, v, _) = on.plane.axes();
    [p[u], p[v]]
}

pub(super) fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

pub(super) fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1]]
}

pub(super) fn scale(a: P, k: f32) -> P {
    [a[0] * k, a[1] * k]
}

pub(super) fn dot(a: P, b: P) -> f32 {
    a[0] * b[0] + a[1] * b[1]
}

pub(super) fn unit(a: P) -> P {
    scale(a, 1.0 / sqrt(dot(a, a)))
}

/// The normal of direction `t` on the compensation side.
pub(super) fn side_normal(side: Side, t: P) -> P {
    match side {
        Side::Left => [-t[1], t[0]],
        Side::Right => [t[1], -t[0]],
    }
}

/// The direction of the last move, from the tool's offset `n` off the
/// programmed point (square to it, the side's normal turned back).
pub(super) fn prev_direction(side: Side, n: P) -> P {
    let n = unit(n);
    match side {
        Side::Left => [n[1], -n[0]],
        Side::Right => [-n[1], n[0]],
    }
}

/// Half the chord where a line `x` from the centre cuts a circle of radius
/// `r`; a line beyond the circle cannot be reached without gouging
/// (LinuxCNC's `|l| > 1`), a few ulp over is a tangent.
pub(super) fn across(r: f32, x: f32) -> Result<f32, ErrorKind> {
    let h2 = (r - x) * (r + x);
    if h2 < -1e-6 * r * r {
        return Err(ErrorKind::CompGouge);
    }
    Ok(sqrt(h2.max(0.0)))
}

/// Where the line through `q` along unit `t` meets the circle about `o` of
/// radius `rho`: the foot of `o` on the line, then `sigma` times half the
/// chord along `t`. Vector form: exact for lines along the axes, and no
/// angle's rounding is magnified near a tangent.
pub(super) fn line_meets_circle(q: P, t: P, o: P, rho: f32, sigma: f32) -> Result<P, ErrorKind> {
    let foot = add(q, scale(t, dot(sub(o, q), t)));
    let off = dist(foot, o);
    let h = across(rho, off)?;
    Ok(add(foot, scale(t, sigma * h)))
}

/// +90 degrees for the left side, -90 for the right.
pub(super) fn side_turn(side: Side) -> f32 {
    match side {
        Side::Left => FRAC_PI_2,
        Side::Right => -FRAC_PI_2,
    }
}

pub(super) fn is_plane_or_helix(on: &CompOn, i: usize) -> bool {
    let (u, v, h) = on.plane.axes();
    i == u || i == v || i == h
}

pub(super) fn set_end(cmd: &mut Command, on: &CompOn, e: P) {
    if let Command::Rapid { end } | Command::Line { end, .. } = cmd {
        set_uv(end, on, e);
    }
}
