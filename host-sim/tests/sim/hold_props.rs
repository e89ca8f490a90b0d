//! Feed hold at any instant of a move, on any of a few machines: the
//! deceleration ends within the time its ramp needs (after the segments
//! already queued), and after the
//! resume the move takes no longer than it would have without the hold
//! plus the standstill and two ramps. A hold that ended a hair past a step
//! at almost no speed once timed that step from that speed (an 11 s wait
//! the resume sat behind; `tests/data/pty/hold-ends-past-a-step.trace`).
use crate::common;
use burin::command::{Command, Feed};
use burin::stepper::prep::{HORIZON_S, MIN_QUEUED};
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
        let cmds = vec![Command::Line { end: burin::pad([dx, dy, dz, 0.0]), feed: Feed::PerMin(feed) }];
        let hz = cfg.tick_hz as f64;
        let free = run(&cfg, &cmds, &[]);
        let t_free = end_tick(&free) as f64 / hz;
        // The hold somewhere in the move, the resume 0.5 s after the stop.
        let t_hold = at * t_free;
        let a_min = cfg.settings.axes.iter().map(|a| a.max_accel).fold(f32::MAX, f32::min) as f64;
        let v_max = feed as f64 / 60.0;
        // Segments already queued still run: the preparer runs HORIZON_S
        // ahead (at least MIN_QUEUED segments), so at most that plus the
        // segment that crossed it and the one running, each at least 2 ms
        // or one step of the dominant axis. (All 16 slots ran before:
        // 0.6 s at 20 mm/min on 80 steps/mm.)
        let d = [dx, dy, dz];
        let len = d.iter().map(|v| (*v as f64).powi(2)).sum::<f64>().sqrt();
        let step_hz = (0..3)
            .map(|i| v_max * (d[i] as f64).abs() / len * cfg.settings.axes[i].steps_per_mm as f64)
            .fold(0.0, f64::max);
        let seg = (1.0 / step_hz).max(0.002);
        let queued = (HORIZON_S as f64 + 2.0 * seg).max((MIN_QUEUED + 1) as f64 * seg);
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

/// At a slow feed every segment is one step, and a hold acts on the next
/// segment prepared: the steps already queued run first. With the
/// preparer running HORIZON_S ahead that is at most MIN_QUEUED steps and
/// the running one (0.11 s at 20 mm/min on 80 steps/mm), where it was all
/// 16 slots (0.6 s).
#[test]
fn a_hold_at_a_slow_feed_acts_within_a_few_steps() {
    let cfg = config();
    let spm = f64::from(cfg.settings.axes[0].steps_per_mm);
    let feed = 20.0;
    let cmds = vec![Command::Line {
        end: burin::pad([5.0, 0.0, 0.0, 0.0]),
        feed: Feed::PerMin(feed),
    }];
    let (t_hold, t_go) = (2.0, 4.0);
    let r = run(
        &cfg,
        &cmds,
        &[(t_hold, Input::FeedHold), (t_go, Input::CycleStart)],
    );
    check_all(&cfg, &r, &cmds, "slow hold");
    let hz = cfg.tick_hz as f64;
    let (hold_tick, go_tick) = ((t_hold * hz) as u64, (t_go * hz) as u64);
    let held: Vec<u64> = r
        .rec
        .events
        .iter()
        .map(|e| e.tick)
        .filter(|&t| t >= hold_tick && t < go_tick)
        .collect();
    let step_s = 60.0 / (f64::from(feed) * spm);
    let late = held.last().map_or(0.0, |&t| (t - hold_tick) as f64 / hz);
    println!(
        "hold at {feed} mm/min: {} steps after it, the last {late:.3} s later (one step: {step_s:.4} s)",
        held.len()
    );
    assert!(
        r.rec.events.iter().any(|e| e.tick < hold_tick),
        "not started"
    );
    assert!(
        held.len() <= MIN_QUEUED + 1,
        "{} steps after the hold",
        held.len()
    );
    assert!(late <= (MIN_QUEUED + 1) as f64 * step_s, "{late:.3} s");
}
