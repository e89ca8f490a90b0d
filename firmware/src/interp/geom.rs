//! Arc centres and spline control points, in the arc plane's two axes.

use crate::gcode::ErrorKind;

type P2 = [f32; 2];

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}
fn len(a: P2) -> f32 {
    crate::num::sqrt(a[0] * a[0] + a[1] * a[1])
}

/// Start and end closer than this (mm) are the same point: a full circle
/// (the segmenter's threshold never exceeds it, see `arc::same_point`).
pub(crate) use crate::arc::SAME_POINT;

pub(crate) use crate::arc::radius_mismatch;

/// How far (mm) an R-format radius may fall short of half the chord: the
/// arc is then the semicircle on the chord (LinuxCNC 2.9, measured).
pub(crate) const R_SHORTFALL: f32 = 0.001;

/// Centre format (IJK): checks the radii and keeps the centre where the
/// program put it, as LinuxCNC does (its canonical arc carries the given
/// centre): when the end radius differs from the start radius (within
/// [`radius_mismatch`]) the path is a spiral whose radius blends from one
/// to the other (`arc::ArcChords`), not an arc about a moved centre, which
/// ran up to 1.4 mm off LinuxCNC's path at r = 3000 (issue 30).
///
/// The end radius is the start radius plus what the chord adds
/// ([`crate::arc::growth`]): two f32 radii near 1e8 mm are 8 mm apart per
/// ulp, which the check would take for a radius mismatch (issue 35).
pub(crate) fn centre_ijk(s: P2, e: P2, c: P2, inch: bool) -> Result<P2, ErrorKind> {
    let (sv, ev) = (sub(s, c), sub(e, c));
    let chord = sub(e, s);
    let rs = len(sv);
    let re = rs + crate::arc::growth(sv, ev, rs, len(ev), chord);
    if rs < SAME_POINT || radius_mismatch(rs, re, inch) {
        return Err(ErrorKind::ArcRadius);
    }
    Ok(c)
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
    if h2 < 0.0 && half - ar > R_SHORTFALL {
        return Err(ErrorKind::ArcRadius);
    }
    let h = crate::num::sqrt(h2.max(0.0));
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
        assert!(centre_ijk([0.0, 0.0], [10.0, 0.0], [5.0, 0.0], false).is_ok());
        assert_eq!(
            centre_ijk([0.0, 0.0], [10.0, 0.0], [4.0, 0.0], false),
            Err(ErrorKind::ArcRadius)
        );
        // 0.004 mm off on a 5 mm radius: fine, and the centre stays where
        // it was given (LinuxCNC's spiral, not a moved centre).
        let c = centre_ijk([0.0, 0.0], [10.0, 0.0], [5.002, 0.0], false).unwrap();
        assert_eq!(c, [5.002, 0.0]);
    }

    /// Issue 14's figures: |dr| 0.02 on r=10 and 0.9 on r=1000 pass;
    /// 0.03 on r=10 (> 0.0283 and > 0.1 %) and 2.9 on r=5000 fail. In
    /// inches the same rule scales to 0.0718 mm and 7.18 mm.
    #[test]
    fn centre_tolerance_is_linuxcnc_29() {
        assert!(!radius_mismatch(10.0, 10.02, false));
        assert!(!radius_mismatch(1000.0, 1000.9, false));
        assert!(radius_mismatch(10.0, 10.03, false));
        assert!(radius_mismatch(5000.0, 5002.9, false));
        assert!(!radius_mismatch(5000.0, 5002.8, false));
        assert!(!radius_mismatch(10.0, 10.07, true));
        assert!(radius_mismatch(10.0, 10.08, true));
        assert!(!radius_mismatch(7620.0, 7627.1, true));
        assert!(radius_mismatch(7620.0, 7627.3, true));
    }

    /// R short of half the chord: up to 0.001 mm cuts the semicircle, more is an error.
    #[test]
    fn r_shortfall() {
        let c = centre_r([0.0, 0.0], [10.0, 0.0], 4.9995, true).unwrap();
        assert!((c[0] - 5.0).abs() < 1e-5 && c[1].abs() < 1e-5, "{c:?}");
        assert_eq!(
            centre_r([0.0, 0.0], [10.0, 0.0], 4.998, true),
            Err(ErrorKind::ArcRadius)
        );
        // 0.1 % of R used to pass silently; no longer.
        assert_eq!(
            centre_r([0.0, 0.0], [2000.0, 0.0], 999.5, true),
            Err(ErrorKind::ArcRadius)
        );
    }
}
