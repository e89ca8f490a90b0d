//! Feed hold at any instant of a move, on any of a few machines: the
//! deceleration ends within the time its ramp needs (after the segments
//! already queued), and after the
//! resume the move takes no longer than it would have without the hold
//! plus the standstill and two ramps. A hold that ended a hair past a step
//! at almost no speed once timed that step from that speed (an 11 s wait
//! the resume sat behind; `tests/data/pty/hold-ends-past-a-step.trace`).
mod common;
use burin::command::{Command, Feed};
use common::*;
use host_sim::engine::Input;
use proptest::prelude::*;

fn end_tick(r: &Run) -> u64 {
    r.rec.events.last().map_or(0, |e| e.tick)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn a_hold_anywhere_stops_in_its_ramp_and_resumes(
        dx in -120.0f32..120.0,
        dy in -120.0f32..120.0,
        dz in -5.0f32..5.0,
        feed in 20.0f32..6000.0,
        at in 0.0f64..1.0,
        accel_x in prop::sample::select(vec![50.0f32, 500.0, 3000.0]),
        steps_x in prop::sample::select(vec![40.0f32, 80.0, 320.0]),
    ) {
        prop_assume!(dx.abs() + dy.abs() > 0.5);
        let mut cfg = config();
        cfg.settings.axes[0].max_accel = accel_x;
        cfg.settings.axes[0].steps_per_mm = steps_x;
        let cmds = vec![Command::Line { end: [dx, dy, dz, 0.0], feed: Feed::PerMin(feed) }];
        let hz = cfg.tick_hz as f64;
        let free = run(&cfg, &cmds, &[]);
        let t_free = end_tick(&free) as f64 / hz;
        // The hold somewhere in the move, the resume 0.5 s after the stop.
        let t_hold = at * t_free;
        let a_min = cfg.settings.axes.iter().map(|a| a.max_accel).fold(f32::MAX, f32::min) as f64;
        let v_max = feed as f64 / 60.0;
        // Segments already queued still run: up to SEGMENT_SLOTS of them,
        // each at least 2 ms or one step of the dominant axis.
        let d = [dx, dy, dz];
        let len = d.iter().map(|v| (*v as f64).powi(2)).sum::<f64>().sqrt();
        let step_hz = (0..3)
            .map(|i| v_max * (d[i] as f64).abs() / len * cfg.settings.axes[i].steps_per_mm as f64)
            .fold(0.0, f64::max);
        let queued = host_sim::engine::SEGMENT_SLOTS as f64 * (1.0 / step_hz).max(0.002);
        let ramp = v_max / a_min + queued + 0.05;
        let t_go = t_hold + ramp + 0.5;
        let r = run(&cfg, &cmds, &[(t_hold, Input::FeedHold), (t_go, Input::CycleStart)]);
        check_all(&cfg, &r, &cmds, "hold anywhere");
        let hold_tick = (t_hold * hz) as u64;
        let go_tick = (t_go * hz) as u64;
        let last_held = r.rec.events.iter().filter(|e| e.tick >= hold_tick && e.tick < go_tick).map(|e| e.tick).max();
        if let Some(t) = last_held {
            let stop = (t - hold_tick) as f64 / hz;
            prop_assert!(stop <= ramp, "held steps went on {stop:.3} s after the hold (ramp {ramp:.3} s)");
        }
        let t_end = end_tick(&r) as f64 / hz;
        let bound = t_free + (t_go - t_hold) + 2.0 * ramp + 0.05;
        prop_assert!(t_end <= bound, "ended at {t_end:.3} s, bound {bound:.3} s (free run {t_free:.3} s)");
    }
}
