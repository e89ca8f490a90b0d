//! `Shape::reach` in S-curve mode, solved in closed form, against the same
//! S ramp solved by bisection in `f64`: never a speed whose ramp is longer
//! than the distance (the planner's entries must stay reachable), and
//! within a small fraction of the exact answer (the look-ahead must not
//! throw speed away).

use burin::planner::Shape;
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
        let s = Shape { accel, jerk };
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
    };
    let v = 20.0;
    let full = 500.0 * 500.0 / 5000.0;
    let len = s.dist(v, v + full);
    let below = s.reach(v, len * 0.999);
    let above = s.reach(v, len * 1.001);
    assert!(below < v + full && above > v + full, "{below} {above}");
    assert!(above - below < 0.01 * full);
}
