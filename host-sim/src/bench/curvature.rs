//! The curvature check of `cargo xtask bench-motion` (issue 31): what the
//! 50 ms windows of [`super::limits`] cannot see. A window averages a
//! small hole's turn away (a 0.1 mm hole turns the velocity round in a few
//! milliseconds), so on curves each axis's centripetal acceleration is
//! judged directly: `v²·|n_i|/r`, with `r` the radius of the circle
//! through three path vertices (consecutive ones, or a few chords apart
//! where consecutive ones lie within half a step of a line, see [`check`];
//! on an arc, the arc's own radius: its chord ends lie on it), `n` that
//! circle's unit normal at the middle vertex and `v` the speed the step
//! trace passed it at.
//!
//! The vertices are the commanded ones (in mm, not rounded to steps: a
//! chord of a step or two would read as a corner in steps), located in the
//! trace where it stands exactly on each one in steps ([`super::losses`]).
//! `v` is the slower of the mean speeds in the trace on either side, so a
//! vertex is not charged with a speed the machine only reached away from
//! it. Only vertices that turn by at most [`MAX_TURN`] count: a sharper
//! turn is a corner, not a sampled curve, and the circle through its
//! three points is not a path the tool follows (junction deviation judges
//! corners, and the windows what the axes do around them).

use burin::AXES;

use super::bound::PieceProfile;

/// The sharpest turn per vertex read as a curve, rad (just over 45°: an
/// octagon is a curve, a square is corners).
pub const MAX_TURN: f64 = 0.8;

/// The curvature check's figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Curvature {
    /// Peak centripetal acceleration per axis over the job's curve
    /// vertices, mm/s².
    pub peak: [f64; AXES],
    /// Where: the piece whose end is that vertex.
    pub at: [usize; AXES],
}

/// The widest stencil, in chords each side of a vertex: circle_small's
/// chords of 0.016 mm on a radius of 25.4 mm need 40 for half a step.
pub const MAX_SPAN: usize = 64;

/// The curvature check over a job. `hit_s[k]`: when the trace stood on
/// piece `k`'s end, s (None when it passed it between steps); `step_mm`:
/// each axis's step.
///
/// The circle at a vertex goes through it and the vertices `j` chords
/// before and after it, `j` the least (up to [`MAX_SPAN`]) that puts the
/// middle one at least half a step off the line through the other two.
/// Nearer, the points are no curve the motors resolve: they step the same
/// either way (circle_small's decimals, 0.0001", read as 9.5° turns every
/// 0.016 mm, a radius of 0.09 mm on a circle of 25 mm), while a dense
/// polyline that does curve shows it over a few chords.
pub fn check(prof: &[PieceProfile], hit_s: &[Option<f64>], step_mm: [f64; AXES]) -> Curvature {
    let mut out = Curvature::default();
    let hit = |k: usize| hit_s.get(k).copied().flatten();
    let dot = |x: &[f64; AXES], y: &[f64; AXES]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    for k in 1..prof.len().saturating_sub(1) {
        let Some(t1) = hit(k) else { continue };
        let b = prof[k].end_mm;
        for j in 1..=MAX_SPAN.min(k).min(prof.len() - 1 - k) {
            let (Some(t0), Some(t2)) = (hit(k - j), hit(k + j)) else {
                continue;
            };
            if t1 <= t0 || t2 <= t1 {
                break;
            }
            let (a, c) = (prof[k - j].end_mm, prof[k + j].end_mm);
            let ab: [f64; AXES] = std::array::from_fn(|i| b[i] - a[i]);
            let bc: [f64; AXES] = std::array::from_fn(|i| c[i] - b[i]);
            let ac: [f64; AXES] = std::array::from_fn(|i| c[i] - a[i]);
            let (lab, lbc, ac2) = (dot(&ab, &ab).sqrt(), dot(&bc, &bc).sqrt(), dot(&ac, &ac));
            if lab < 1e-12 || lbc < 1e-12 || ac2 < 1e-24 {
                break;
            }
            let phi = (dot(&ab, &bc) / (lab * lbc)).clamp(-1.0, 1.0).acos();
            if phi > MAX_TURN {
                // A corner, not a curve.
                break;
            }
            let d: [f64; AXES] = std::array::from_fn(|i| bc[i] / lbc - ab[i] / lab);
            let dn = dot(&d, &d).sqrt();
            if dn < 1e-12 {
                continue;
            }
            let n = d.map(|x| x / dn);
            // The middle vertex's distance from the line AC.
            let off = (lab * lab - dot(&ab, &ac).powi(2) / ac2).max(0.0).sqrt();
            let step = (0..AXES)
                .filter(|&i| n[i].abs() > 0.1)
                .map(|i| step_mm[i])
                .fold(0.0, f64::max);
            if off < 0.5 * step {
                continue;
            }
            // AC subtends the turn at B: r = |AC| / (2·sin φ).
            let r = ac2.sqrt() / (2.0 * phi.sin());
            let len = |from: usize, to: usize| prof[from..to].iter().map(|p| p.len).sum::<f64>();
            let v = (len(k - j + 1, k + 1) / (t1 - t0)).min(len(k + 1, k + j + 1) / (t2 - t1));
            for (i, ni) in n.iter().enumerate() {
                let c = v * v * ni.abs() / r;
                if c > out.peak[i] {
                    out.peak[i] = c;
                    out.at[i] = k;
                }
            }
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::PathKind;

    /// Chords of a circle of radius `r` run at `v`: each vertex reads
    /// `v²/r` on the axis its normal points along.
    fn circle(r: f64, v: f64, n: usize) -> (Vec<PieceProfile>, Vec<Option<f64>>) {
        let pt = |k: usize| {
            let t = k as f64 / n as f64 * std::f64::consts::TAU;
            burin::pad([r * t.cos(), r * t.sin()])
        };
        let mut prof = Vec::new();
        let mut hits = Vec::new();
        let mut time = 0.0;
        for k in 1..=n {
            let (p, q) = (pt(k - 1), pt(k));
            let d: [f64; AXES] = std::array::from_fn(|i| q[i] - p[i]);
            let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
            time += len / v;
            prof.push(PieceProfile {
                end_mm: q,
                unit: d.map(|x| x / len),
                kind: PathKind::Arc,
                len,
                v0: v,
                v1: v,
                cap: v,
                accel: 1.0,
                end_s: time,
            });
            hits.push(Some(time));
        }
        (prof, hits)
    }

    #[test]
    fn a_circle_reads_its_centripetal_acceleration_per_axis() {
        let (prof, hits) = circle(0.5, 10.0, 64);
        let p = check(&prof, &hits, [0.0125; AXES]).peak;
        // 64 chords: the circumradius is r; the normal comes within half a
        // chord's turn of each axis (cos 2.8° of the full figure).
        let want = 100.0 / 0.5;
        assert!((p[0] - want).abs() < 0.01 * want, "{p:?}");
        assert!((p[1] - want).abs() < 0.01 * want, "{p:?}");
        assert_eq!(p[2], 0.0);
    }

    #[test]
    fn corners_and_unlocated_vertices_are_not_curves() {
        // A square: every turn is 90°.
        let (prof, hits) = circle(10.0, 50.0, 4);
        assert_eq!(check(&prof, &hits, [0.0125; AXES]).peak, [0.0; AXES]);
        let (prof, mut hits) = circle(0.5, 10.0, 64);
        hits.iter_mut().for_each(|h| *h = None);
        assert_eq!(check(&prof, &hits, [0.0125; AXES]).peak, [0.0; AXES]);
    }

    /// A straight line whose commanded points wiggle by a fifth of a step
    /// (decimals of inches) is no curve; a wiggle of two steps over
    /// chords six times as long is (turns of 28°).
    #[test]
    fn wiggles_below_half_a_step_are_not_curves() {
        let line = |w: f64, l: f64| {
            let mut prof = Vec::new();
            let mut hits = Vec::new();
            let mut p = [0.0f64; AXES];
            for k in 1..=40 {
                let q = burin::pad([l * k as f64, if k % 2 == 0 { w } else { 0.0 }, 0.0, 0.0]);
                let d: [f64; AXES] = std::array::from_fn(|i| q[i] - p[i]);
                let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
                prof.push(PieceProfile {
                    end_mm: q,
                    unit: d.map(|x| x / len),
                    kind: PathKind::Feed,
                    len,
                    v0: 8.0,
                    v1: 8.0,
                    cap: 8.0,
                    accel: 1.0,
                    end_s: 0.0,
                });
                hits.push(Some(k as f64 * 0.002));
                p = q;
            }
            check(&prof, &hits, [0.0125; AXES]).peak
        };
        assert_eq!(line(0.0025, 0.016), [0.0; AXES]);
        assert!(line(0.025, 0.1)[1] > 1000.0);
    }
}
