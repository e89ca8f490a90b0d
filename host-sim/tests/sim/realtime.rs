//! Realtime changes in the middle of motion: feed hold during an S-curve
//! ramp, feed override drops ahead of a corner.
use crate::common;
use burin::command::{Command, Feed};
use burin::settings::Profile;
use common::*;
use host_sim::engine::Input;

/// Feed hold issued while an S-curve ramp is at full acceleration: the
/// acceleration first returns to zero at the jerk limit before the
/// deceleration starts, so the measured jerk stays within the limit (same
/// estimate and tolerance as `scurve_limits_jerk_trapezoid_does_not`: ×1.5
/// for 25 ms bin quantisation), and resume ends on the exact final step.
#[test]
fn scurve_hold_mid_acceleration_keeps_jerk_limit() {
    let cmds = vec![Command::Line {
        end: burin::pad([150.0, 40.0, 0.0, 0.0]),
        feed: Feed::PerMin(4000.0),
    }];
    let mut cfg = config();
    cfg.settings.profile = Profile::SCurve;
    // 0→66.7 mm/s at ≈517 mm/s², 5000 mm/s³: jerk phases of 0.1 s with
    // 0.03 s at full acceleration between them; 0.11 s is in the middle.
    let r = run(
        &cfg,
        &cmds,
        &[(0.11, Input::FeedHold), (1.0, Input::CycleStart)],
    );
    check_all(&cfg, &r, &cmds, "s-curve hold mid-accel");
    let hz = cfg.tick_hz as f64;
    let gap = r
        .rec
        .events
        .windows(2)
        .map(|w| w[1].tick - w[0].tick)
        .max()
        .unwrap();
    assert!(
        gap as f64 > 0.2 * hz,
        "expected a standstill, longest gap {gap}"
    );
    let js = max_jerk_x(&r, hz);
    println!(
        "hold mid-accel: max X jerk {js:.0} mm/s³ (limit {})",
        cfg.settings.jerk
    );
    assert!(js <= cfg.settings.jerk as f64 * 1.5, "{js}");
}

/// Path speed (mm/s) around the first tick at which axis `axis` steps:
/// the highest segment speed recorded within 4 ms before it.
fn speed_at_corner(r: &Run, hz: f64, axis: usize) -> f64 {
    let t = r
        .rec
        .events
        .iter()
        .find(|e| e.step_mask & (1 << axis) != 0)
        .unwrap()
        .tick;
    let from = t.saturating_sub((0.004 * hz) as u64);
    let before = r
        .rec
        .velocity
        .iter()
        .rev()
        .find(|v| v.0 <= from)
        .map_or(0.0, |v| v.1);
    r.rec
        .velocity
        .iter()
        .filter(|v| v.0 > from && v.0 <= t)
        .map(|v| v.1)
        .fold(before, f32::max) as f64
        / 60.0
}

/// Largest change of the path speed between neighbouring segments as a
/// fraction of what `a_path` (mm/s²) allows. The trace records each 2 ms
/// segment's average speed at its start, so neighbours `i`, `i+1` are at
/// most `t(i+2) - t(i)` apart in the middle; 10% + 0.3 mm/s cover rounding
/// of the step rate. A speed cut at a block start (infinite deceleration)
/// shows up here even where the 25 ms accel bins smooth it out.
fn max_speed_jump(r: &Run, hz: f64, a_path: f64) -> f64 {
    r.rec
        .velocity
        .windows(3)
        .filter(|w| w[0].1 > 0.0 && w[1].1 > 0.0)
        .map(|w| {
            let dv = ((w[1].1 - w[0].1) / 60.0).abs() as f64;
            let dt = (w[2].0 - w[0].0) as f64 / hz;
            dv / (a_path * dt * 1.1 + 0.3)
        })
        .fold(0.0, f64::max)
}

/// Feed override drops to 10% at many points of a move that ends in a 30°
/// corner (junction limit ≈12 mm/s at 50 mm/s, 5 mm/s after the drop).
/// Speed at the corner: never above the junction limit; at most the
/// override-scaled limit whenever the drop left room to brake to it.
/// Acceleration stays within the limit throughout (check_all).
#[test]
fn feed_override_drop_before_a_corner() {
    let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
    let cmds = vec![
        Command::Line {
            end: burin::pad([60.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(3000.0),
        },
        Command::Line {
            end: burin::pad([60.0 + 10.0 * c, 10.0 * s, 0.0, 0.0]),
            feed: Feed::PerMin(3000.0),
        },
    ];
    for profile in [Profile::Trapezoid, Profile::SCurve] {
        let mut cfg = config();
        cfg.settings.profile = profile;
        let hz = cfg.tick_hz as f64;
        let plain = run(&cfg, &cmds, &[]);
        let v_j = speed_at_corner(&plain, hz, 1);
        assert!(v_j > 10.0 && v_j < 16.0, "{profile:?}: corner at {v_j}");
        let t_corner = plain
            .rec
            .events
            .iter()
            .find(|e| e.step_mask & 2 != 0)
            .unwrap()
            .tick as f64
            / hz;
        let mut t = 0.05;
        while t < t_corner {
            let r = run(&cfg, &cmds, &[(t, Input::FeedOverride(10))]);
            check_all(
                &cfg,
                &r,
                &cmds,
                &format!("{profile:?} override drop at {t:.2} s"),
            );
            let jump = max_speed_jump(&r, hz, 577.0);
            assert!(
                jump <= 1.0,
                "{profile:?} drop at {t:.2}: path speed jumps ({jump:.2} of the limit)"
            );
            let v = speed_at_corner(&r, hz, 1);
            assert!(
                v <= v_j * 1.02 + 0.5,
                "{profile:?} drop at {t:.2}: {v} at the corner"
            );
            // 50 → 5 mm/s takes at most 2.5 mm (trapezoid) / 5.2 mm (S) = 0.1 s.
            if t < t_corner - 0.25 {
                assert!(
                    v <= 5.0 * 1.02 + 0.5,
                    "{profile:?} drop at {t:.2}: {v} at the corner"
                );
            }
            t += 0.05;
        }
    }
}
