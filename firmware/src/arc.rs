//! Segmenter: arcs and splines become straight chords for the planner.
//!
//! Both are lazy iterators (no buffer): the executor pulls chords only while
//! the planner ring has room. Every point is computed from its parameter
//! directly (no incremental rotation), so errors do not accumulate over
//! multi-turn arcs, and the last chord ends exactly at the commanded end.

use core::f32::consts::PI;

use crate::command::{Arc, Pos, Spline};
use crate::AXES;

mod geom;
use geom::hypot;
pub use geom::{growth, plane_step, radius_mismatch, same_point, sweep, SAME_POINT};

/// More chords than this in one arc or spline is refused rather than run for hours.
pub const MAX_CHORDS: u32 = 1 << 24;

/// Why an arc or spline cannot be cut into chords. The executor maps each
/// onto its own error of the same name, so the reported codes do not change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArcError {
    /// A point, the centre or the tolerance is not finite (or the tolerance
    /// is not positive), or the radius is beyond f32 (over 1e19 mm).
    InvalidNumber,
    /// The start or end point sits on the centre (zero radius), or the
    /// start is off the arc's circle by more than [`radius_mismatch`]
    /// allows even in inches.
    InvalidArc,
    /// More than [`MAX_CHORDS`] chords.
    TooManySegments,
}

/// Largest chord angle whose sagitta stays within `tol` on radius `r`.
///
/// Sagitta of a chord spanning angle φ: `r (1 - cos(φ/2)) = 2 r sin²(φ/4)`.
/// Solving for φ with asin keeps precision in f32 when `tol/r` is tiny
/// (`acos(1 - x)` near 1 loses it).
pub fn max_chord_angle(r: f32, tol: f32) -> f32 {
    if r <= tol {
        return PI / 2.0;
    }
    let x = crate::num::sqrt(tol / (2.0 * r)).min(1.0);
    (4.0 * crate::num::trig::asin(x)).min(PI / 2.0)
}

/// Chords of a circular, helical or spiral (start and end radius differ
/// slightly; the radius is blended linearly) arc.
///
/// Points are the start plus the turned start radius minus itself
/// (`geom::offset`), not the centre plus the radius: on a huge radius the
/// centre is far away and coarse in f32, the displacement from the start
/// is not.
#[derive(Clone, Debug)]
pub struct ArcChords {
    start: Pos,
    end: Pos,
    plane: (usize, usize, usize),
    /// Start minus centre, in the plane.
    s: [f32; 2],
    r0: f32,
    /// End radius minus start radius.
    grow: f32,
    sweep: f32,
    n: u32,
    i: u32,
}

impl ArcChords {
    /// `step` is the machine's finest step in the arc's plane, mm
    /// ([`plane_step`]): start and end closer than [`same_point`] of it
    /// make a full circle.
    pub fn new(start: &Pos, arc: &Arc, tol: f32, step: f32) -> Result<Self, ArcError> {
        let plane = arc.plane.axes();
        let (a, b, _) = plane;
        let [ca, cb] = arc.center;
        let finite = start.iter().chain(arc.end.iter()).all(|v| v.is_finite())
            && ca.is_finite()
            && cb.is_finite()
            && tol.is_finite()
            && tol > 0.0;
        if !finite {
            return Err(ArcError::InvalidNumber);
        }
        let s = [start[a] - ca, start[b] - cb];
        let e = [arc.end[a] - ca, arc.end[b] - cb];
        let d = [arc.end[a] - start[a], arc.end[b] - start[b]];
        let r0 = hypot(s[0], s[1]);
        let r1 = hypot(e[0], e[1]);
        if !(r0.is_finite() && r1.is_finite()) {
            return Err(ArcError::InvalidNumber);
        }
        if r0 < 1e-6 || r1 < 1e-6 {
            return Err(ArcError::InvalidArc);
        }
        let sweep = geom::sweep(s, r0, d, arc.dir, arc.turns, same_point(step));
        let grow = geom::growth(s, e, r0, r1, d);
        if radius_mismatch(r0, r0 + grow, true) {
            return Err(ArcError::InvalidArc);
        }
        let phi = max_chord_angle(r0.max(r1), tol);
        let n = libm::ceilf(libm::fabsf(sweep) / phi).max(1.0);
        if n > MAX_CHORDS as f32 {
            return Err(ArcError::TooManySegments);
        }
        Ok(ArcChords {
            start: *start,
            end: arc.end,
            plane,
            s,
            r0,
            grow,
            sweep,
            n: n as u32,
            i: 0,
        })
    }

    /// Number of chords.
    pub fn chords(&self) -> u32 {
        self.n
    }

    /// The arc for the planner's acceleration split: its smallest radius
    /// and its plane.
    pub fn curve(&self) -> crate::planner::Curve {
        let (a, b, _) = self.plane;
        crate::planner::Curve {
            radius: self.r0 + self.grow.min(0.0),
            plane: (1 << a | 1 << b) as u8,
        }
    }

    /// The signed sweep, radians (positive counter-clockwise).
    pub fn sweep(&self) -> f32 {
        self.sweep
    }

    /// Axis-aligned bounds of the whole arc (for soft limits before any
    /// step), on the larger of the two radii.
    pub fn bounds(&self) -> (Pos, Pos) {
        let mut lo = self.start;
        let mut hi = self.start;
        for i in 0..AXES {
            lo[i] = lo[i].min(self.end[i]);
            hi[i] = hi[i].max(self.end[i]);
        }
        let (a, b, _) = self.plane;
        let [sa, sb] = self.s;
        // Axis directions the sweep passes through extend the box, by how
        // far the circle reaches beyond the start along them.
        for k in 0..4 {
            if geom::turn_to_axis(self.s, k, self.sweep >= 0.0) > libm::fabsf(self.sweep) {
                continue;
            }
            let (axis, c, o, sign) = match k {
                0 => (a, sa, sb, 1.0),
                1 => (b, sb, sa, 1.0),
                2 => (a, -sa, sb, -1.0),
                _ => (b, -sb, sa, -1.0),
            };
            let p = self.start[axis] + sign * geom::reach(self.r0, self.grow, c, o);
            lo[axis] = lo[axis].min(p);
            hi[axis] = hi[axis].max(p);
        }
        (lo, hi)
    }
}

impl Iterator for ArcChords {
    type Item = Pos;
    fn next(&mut self) -> Option<Pos> {
        if self.i >= self.n {
            return None;
        }
        self.i += 1;
        if self.i == self.n {
            return Some(self.end);
        }
        let t = self.i as f32 / self.n as f32;
        let (a, b, _) = self.plane;
        let mut p = [0.0; AXES];
        for (k, v) in p.iter_mut().enumerate() {
            *v = self.start[k] + (self.end[k] - self.start[k]) * t;
        }
        let o = geom::offset(self.s, self.sweep * t, self.grow / self.r0 * t);
        p[a] = self.start[a] + o[0];
        p[b] = self.start[b] + o[1];
        Some(p)
    }
}

/// Chords of a cubic Bezier in X/Y (other axes linear in the parameter).
///
/// Uniform parameter steps: the chord error over a parameter span h is at
/// most `h²/8 · max|B''|`, and `|B''| ≤ 6·max(|P0-2P1+P2|, |P1-2P2+P3|)`, so
/// `n = ceil(sqrt(0.75·L/tol))` chords keep every chord within `tol`.
#[derive(Clone, Debug)]
pub struct SplineChords {
    start: Pos,
    end: Pos,
    p1: [f32; 2],
    p2: [f32; 2],
    n: u32,
    i: u32,
}

impl SplineChords {
    pub fn new(start: &Pos, s: &Spline, tol: f32) -> Result<Self, ArcError> {
        let all = start
            .iter()
            .chain(s.end.iter())
            .chain(s.p1.iter())
            .chain(s.p2.iter());
        if !(all.clone().all(|v| v.is_finite()) && tol > 0.0 && tol.is_finite()) {
            return Err(ArcError::InvalidNumber);
        }
        let d = |p0: [f32; 2], p1: [f32; 2], p2: [f32; 2]| {
            hypot(p0[0] - 2.0 * p1[0] + p2[0], p0[1] - 2.0 * p1[1] + p2[1])
        };
        let p0 = [start[0], start[1]];
        let p3 = [s.end[0], s.end[1]];
        let l = d(p0, s.p1, s.p2).max(d(s.p1, s.p2, p3));
        let n = libm::ceilf(crate::num::sqrt(0.75 * l / tol)).max(1.0);
        if n > MAX_CHORDS as f32 {
            return Err(ArcError::TooManySegments);
        }
        Ok(SplineChords {
            start: *start,
            end: s.end,
            p1: s.p1,
            p2: s.p2,
            n: n as u32,
            i: 0,
        })
    }

    pub fn chords(&self) -> u32 {
        self.n
    }

    /// Bounds of the convex hull of the control points: the curve lies inside
    /// it, so checking it against soft limits is safe (if conservative).
    pub fn bounds(&self) -> (Pos, Pos) {
        let mut lo = self.start;
        let mut hi = self.start;
        for i in 0..AXES {
            lo[i] = lo[i].min(self.end[i]);
            hi[i] = hi[i].max(self.end[i]);
        }
        for p in [self.p1, self.p2] {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Point at parameter `t` (0..1).
    pub fn point(&self, t: f32) -> Pos {
        let u = 1.0 - t;
        let (b0, b1, b2, b3) = (u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t);
        let mut p = [0.0; AXES];
        for (k, v) in p.iter_mut().enumerate() {
            *v = self.start[k] + (self.end[k] - self.start[k]) * t;
        }
        for (k, v) in p.iter_mut().take(2).enumerate() {
            *v = b0 * self.start[k] + b1 * self.p1[k] + b2 * self.p2[k] + b3 * self.end[k];
        }
        p
    }
}

impl Iterator for SplineChords {
    type Item = Pos;
    fn next(&mut self) -> Option<Pos> {
        if self.i >= self.n {
            return None;
        }
        self.i += 1;
        if self.i == self.n {
            return Some(self.end);
        }
        Some(self.point(self.i as f32 / self.n as f32))
    }
}
