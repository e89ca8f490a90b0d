//! Small helical holes (pcb2gcode's drill-milling: 0.1 mm radius, a
//! pitch of 0.18 mm a turn) on the grbl_match machine. Each chord of an
//! arc shares its axes' budget between turning and ramping
//! (`planner::curve`): on a helix only the in-plane part of the speed
//! turns, and a ramp takes what the speed it reaches leaves
//! (`Shape::drop`), so the hole's turns run near `sqrt(a·r)` of the
//! helix, and every axis still keeps its acceleration.

use crate::common;
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
    assert_eq!(f.limits.short_intervals, [0; burin::AXES]);
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

/// Feed holds and override drops anywhere in the hole: a hold ramp
/// slows at what its own speed allows, and a chord entered above its new
/// nominal speed slows at the drop line's value there (`Shape::at_top`;
/// above the nominal speed the line runs a little above the exact
/// budget, as the constant acceleration of that speed did before, by
/// more).
#[test]
fn holds_and_overrides_in_a_helical_hole_keep_the_limits() {
    use host_sim::bench::limits::LimitMeter;
    use host_sim::engine::Input;
    let cfg = common::grbl_match();
    let src = hole();
    let plain = run_job(&cfg, &src);
    let (_, amax) = axis_limits(&cfg);
    let mut slowest = 0u64;
    for k in 0..24 {
        let t = plain.time_s * (0.05 + 0.9 * f64::from(k) / 24.0);
        let inputs: Vec<(f64, Input)> = if k % 2 == 0 {
            vec![
                (t, Input::FeedOverride(10)),
                (t + 0.05, Input::FeedOverride(200)),
                (t + 0.12, Input::FeedOverride(100)),
            ]
        } else {
            vec![(t, Input::FeedHold), (t + 0.1, Input::CycleStart)]
        };
        let mut meter = LimitMeter::new(cfg.settings.max_step_rate_hz);
        let summary = host_sim::offline::run_file_with_inputs(&cfg, &src, &mut meter, &inputs);
        assert!(summary.errors.is_empty(), "{:?}", summary.errors);
        let l = &meter.out;
        slowest = slowest.max(l.last_tick - l.first_tick.unwrap_or(0));
        assert_eq!(l.short_intervals, [0; burin::AXES], "at {t:.3} s");
        assert_eq!(l.end_steps, plain.limits.end_steps, "at {t:.3} s");
        for (i, (peak, limit)) in l.peak_acc.iter().zip(amax).enumerate().take(3) {
            assert!(
                *peak <= limit * 1.05,
                "input at {t:.3} s: axis {i} at {peak:.1} mm/s² (limit {limit:.1})"
            );
        }
    }
    // The inputs did act: the slowest run took longer than the plain one.
    let slowest = slowest as f64 / f64::from(cfg.tick_hz);
    assert!(
        slowest > plain.time_s + 0.05,
        "{slowest:.3} s against {:.3} s",
        plain.time_s
    );
}
