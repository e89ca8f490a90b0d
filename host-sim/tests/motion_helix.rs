//! Small helical holes (pcb2gcode's drill-milling: 0.1 mm radius, a
//! pitch of 0.18 mm a turn) on the grbl_match machine. Each chord of an
//! arc shares its axes' budget between turning and ramping
//! (`planner::curve`): on a helix only the in-plane part of the speed
//! turns, and a ramp takes what the speed it reaches leaves
//! (`Shape::drop`), so the hole's turns run near `sqrt(a·r)` of the
//! helix, and every axis still keeps its acceleration.

mod common;
use host_sim::bench::{axis_limits, run_job};

/// Eight turns down a 0.1 mm-radius hole at F2540, one G2 a turn.
fn hole() -> String {
    let mut src = String::from("G21 G90 G17\nG0 X0.2 Y0 Z0.2\nG1 Z0 F2540\n");
    for k in 1..=8 {
        src += &format!("G2 X0.2 Y0 Z{:.4} I-0.1 J0\n", -0.178 * f64::from(k));
    }
    src + "G2 X0.2 Y0 I-0.1 J0\nG0 Z1\n"
}

#[test]
fn helical_holes_turn_at_the_helix_budget_within_the_limits() {
    let cfg = common::grbl_match();
    let f = run_job(&cfg, &hole());
    assert!(f.summary.errors.is_empty(), "{:?}", f.summary.errors);
    assert_eq!(f.limits.short_intervals, [0; 4]);
    let (_, amax) = axis_limits(&cfg);
    for (i, (peak, limit)) in f.limits.peak_acc.iter().zip(amax).enumerate().take(3) {
        assert!(
            *peak <= limit * 1.05,
            "axis {i} at {peak:.1} mm/s² (limit {limit:.1})"
        );
    }
    // A turn in the middle (line 8, the fifth): 0.653 mm of helix. The
    // helix's own curvature radius is `r·(1 + (p/2πr)²)` = 0.108 mm:
    // at `sqrt(a·R)` = 7.35 mm/s a turn takes 0.0889 s (the per-axis
    // split lets a chord whose normal lies between X and Y turn faster). With
    // `v² ≤ 0.8·A_n·r` on the circle's radius and one acceleration a
    // chord, that of its top speed (the rule before), a turn took 0.0998 s;
    // now 0.0885.
    let l = f.losses.iter().find(|l| l.line == 8).expect("turn located");
    let t = l.bound_s + l.lost_s;
    assert!(t < 0.095, "a turn takes {t:.4} s");
}
