//! `Shape::reach` in S-curve mode, solved in closed form, against the same
//! S ramp solved by bisection in `f64`: never a speed whose ramp is longer
//! than the distance (the planner's entries must stay reachable), and
//! within a small fraction of the exact answer (the look-ahead must not
//! throw speed away).

use burin::planner::{Profile, Shape};
use proptest::prelude::*;

/// The S ramp's distance from `v0` to `v1`, in `f64` (`planner::ramp`).
fn dist(a: f64, j: f64, v0: f64, v1: f64) -> f64 {
    let dv = (v1 - v0).abs();
    let t = if dv * j >= a * a {
        dv / a + a / j
    } else {
        2.0 * (dv / j).sqrt()
    };
    0.5 * (v0 + v1) * t
}

/// The fastest `x ≥ v` whose ramp from `v` fits in `len`, by bisection.
fn exact(a: f64, j: f64, v: f64, len: f64) -> f64 {
    let (mut lo, mut hi) = (v, (v * v + 2.0 * a * len).sqrt() + 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if dist(a, j, v, mid) <= len {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    #[test]
    fn s_reach_fits_and_is_the_fastest_that_does(
        accel in 10.0f32..5000.0,
        jerk in 100.0f32..1.0e6,
        v in prop_oneof![Just(0.0f32), 0.0f32..500.0],
        len in prop_oneof![Just(0.0f32), 0.0f32..1.0, 0.0f32..200.0],
    ) {
        let s = Shape { accel, jerk, drop: 0.0 };
        let x = s.reach(v, len);
        prop_assert!(x >= v, "{x} below {v}");
        prop_assert!(s.dist(v, x) <= len, "ramp {} > {len}", s.dist(v, x));
        let want = exact(accel.into(), jerk.into(), v.into(), len.into());
        let err = (f64::from(x) - want).abs();
        prop_assert!(err <= 1e-4 * want.max(1.0), "{x} against {want}");
    }
}

/// The closed form's two cases meet where the ramp first reaches full
/// acceleration (`dv = a²/j`): a distance just either side of that ramp's
/// own gives speeds just either side of its end.
#[test]
fn the_two_cases_meet_at_full_acceleration() {
    let s = Shape {
        accel: 500.0,
        jerk: 5000.0,
        drop: 0.0,
    };
    let v = 20.0;
    let full = 500.0 * 500.0 / 5000.0;
    let len = s.dist(v, v + full);
    let below = s.reach(v, len * 0.999);
    let above = s.reach(v, len * 1.001);
    assert!(below < v + full && above > v + full, "{below} {above}");
    assert!(above - below < 0.01 * full);
}

// Trapezoid chords of a curve ramp with what their top speed leaves
// (`Shape::drop`, `planner::curve`): the acceleration at speed `v` is
// `accel − drop·v²`. The passes' reach and the preparer's profile must
// both stay within it at every speed they run at.
proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    #[test]
    fn reach_with_drop_fits_at_its_own_top_and_wastes_nothing(
        accel in 10.0f32..5000.0,
        left in 0.02f32..1.0,
        vn in 0.5f32..200.0,
        v in 0.0f32..1.0,
        len in prop_oneof![Just(0.0f32), 0.0f32..1.0, 0.0f32..200.0],
    ) {
        // `left`: the share of `accel` still free at `vn`.
        let drop = accel * (1.0 - left) / (vn * vn);
        let s = Shape { accel, jerk: 0.0, drop };
        let v = v * vn;
        let x = s.reach(v, len).min(vn);
        prop_assert!(x >= v * (1.0 - 1e-6), "{x} below {v}");
        // The ramp at the acceleration its top allows fits in `len`...
        let a = f64::from(accel) - f64::from(drop) * f64::from(x) * f64::from(x);
        let need = (f64::from(x).powi(2) - f64::from(v).powi(2)) / (2.0 * a);
        // (`f32` squares: `x²` carries a few ulps, `x²·ε/a` mm of ramp.)
        let ulps = 4.0 * f64::from(x).powi(2) * f64::from(f32::EPSILON) / a;
        prop_assert!(need <= f64::from(len) * (1.0 + 1e-4) + ulps, "ramp {need} > {len}");
        // ...and is the fastest that does (below the cruise speed).
        if x < vn * 0.999 {
            prop_assert!(need >= f64::from(len) * (1.0 - 1e-3) - ulps, "ramp {need} < {len}");
        }
    }

    #[test]
    fn a_profile_at_its_top_never_runs_faster_than_its_acceleration_allows(
        accel in 10.0f32..5000.0,
        left in 0.02f32..1.0,
        vn in 0.5f32..200.0,
        v0 in 0.0f32..1.0,
        v1 in 0.0f32..1.0,
        len in prop_oneof![0.0f32..1.0, 0.0f32..200.0],
    ) {
        let drop = accel * (1.0 - left) / (vn * vn);
        let s = Shape { accel, jerk: 0.0, drop };
        let (v0, v1) = (v0 * vn, v1 * vn);
        let top = s.top(v0, vn, v1, len);
        let c = s.at_top(top);
        let p = Profile::plan(&c, v0, vn, v1, len);
        let fastest = p.phases.iter().map(|ph| ph.v0.max(ph.v1)).fold(0.0f32, f32::max);
        prop_assert!(fastest <= top * (1.0 + 1e-4) + 1e-5, "runs at {fastest}, top {top}");
        prop_assert!(c.accel > 0.0 && c.drop == 0.0);
        // An exit the passes' reach allows is reached.
        if v1 <= s.reach(v0, len) * (1.0 - 1e-3) {
            let exit = p.exit_speed();
            prop_assert!(exit >= v1 * (1.0 - 1e-3) - 1e-5, "leaves at {exit}, asked {v1}");
        }
        let ulps = 4.0 * v0.max(top) * v0.max(top) * f32::EPSILON / c.accel;
        prop_assert!(p.total_dist() <= len * (1.0 + 1e-4) + ulps, "{} > {len}", p.total_dist());
    }
}
