//! Arc centres and spline control points, in the arc plane's two axes.

use crate::gcode::ErrorKind;
use libm::sqrtf;

type P2 = [f32; 2];

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}
fn len(a: P2) -> f32 {
    sqrtf(a[0] * a[0] + a[1] * a[1])
}

/// Start and end closer than this (mm) are the same point: a full circle.
pub(crate) const SAME_POINT: f32 = 1e-4;

/// LinuxCNC's tolerance for centre-format arcs: the start and end radii may
/// differ by at most 0.5 mm, and by at most 0.005 mm unless that is within
/// 0.1% of the radius.
pub(crate) fn radius_mismatch(rs: f32, re: f32) -> bool {
    let d = (rs - re).abs();
    d > 0.5 || (d > 0.005 && d > 0.001 * rs)
}

/// Centre format (IJK): checks the radii, then moves the centre onto the
/// chord's perpendicular bisector so both radii agree exactly and the
/// segmenter never sees an inconsistent arc.
pub(crate) fn centre_ijk(s: P2, e: P2, c: P2) -> Result<P2, ErrorKind> {
    let rs = len(sub(s, c));
    let re = len(sub(e, c));
    if rs < SAME_POINT || radius_mismatch(rs, re) {
        return Err(ErrorKind::ArcRadius);
    }
    let chord = sub(e, s);
    let d = len(chord);
    if d < SAME_POINT {
        return Ok(c);
    }
    let u = [chord[0] / d, chord[1] / d];
    let m = [(s[0] + e[0]) * 0.5, (s[1] + e[1]) * 0.5];
    let along = (c[0] - m[0]) * u[0] + (c[1] - m[1]) * u[1];
    Ok([c[0] - along * u[0], c[1] - along * u[1]])
}

/// Radius format: the centre on the side that gives the short arc for a
/// positive `r` and the long one for a negative `r`.
pub(crate) fn centre_r(s: P2, e: P2, r: f32, cw: bool) -> Result<P2, ErrorKind> {
    let chord = sub(e, s);
    let d = len(chord);
    if d < SAME_POINT {
        return Err(ErrorKind::InvalidTarget);
    }
    let ar = r.abs();
    let half = d * 0.5;
    let h2 = ar * ar - half * half;
    if h2 < 0.0 {
        let short = half - ar;
        if short > 0.005 && short > 0.001 * ar {
            return Err(ErrorKind::ArcRadius);
        }
    }
    let h = sqrtf(h2.max(0.0));
    let u = [chord[0] / d, chord[1] / d];
    let left = [-u[1], u[0]];
    let m = [(s[0] + e[0]) * 0.5, (s[1] + e[1]) * 0.5];
    // Counter-clockwise short arcs turn left, so their centre is on the left.
    let side = if cw == (r < 0.0) { h } else { -h };
    Ok([m[0] + side * left[0], m[1] + side * left[1]])
}

/// G5.1: the quadratic Bezier with control point `c`, raised to a cubic.
pub(crate) fn quadratic_to_cubic(s: P2, c: P2, e: P2) -> (P2, P2) {
    let k = 2.0 / 3.0;
    (
        [s[0] + k * (c[0] - s[0]), s[1] + k * (c[1] - s[1])],
        [e[0] + k * (c[0] - e[0]), e[1] + k * (c[1] - e[1])],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r_centre_sides() {
        // CCW quarter from (0,0) to (1,1) with R1: centre (0,1)? No: left of
        // travel direction (1,1) is (-1,1), so the short CCW arc's centre is (0,1).
        let c = centre_r([0.0, 0.0], [1.0, 1.0], 1.0, false).unwrap();
        assert!(
            (c[0] - 0.0).abs() < 1e-5 && (c[1] - 1.0).abs() < 1e-5,
            "{c:?}"
        );
        let c = centre_r([0.0, 0.0], [1.0, 1.0], 1.0, true).unwrap();
        assert!(
            (c[0] - 1.0).abs() < 1e-5 && (c[1] - 0.0).abs() < 1e-5,
            "{c:?}"
        );
        let c = centre_r([0.0, 0.0], [1.0, 1.0], -1.0, true).unwrap();
        assert!(
            (c[0] - 0.0).abs() < 1e-5 && (c[1] - 1.0).abs() < 1e-5,
            "{c:?}"
        );
    }

    #[test]
    fn ijk_tolerance() {
        assert!(centre_ijk([0.0, 0.0], [10.0, 0.0], [5.0, 0.0]).is_ok());
        assert_eq!(
            centre_ijk([0.0, 0.0], [10.0, 0.0], [4.0, 0.0]),
            Err(ErrorKind::ArcRadius)
        );
        // 0.004 mm off on a 5 mm radius: fine, and the centre is made exact.
        let c = centre_ijk([0.0, 0.0], [10.0, 0.0], [5.002, 0.0]).unwrap();
        assert!((c[0] - 5.0).abs() < 1e-5);
    }
}
