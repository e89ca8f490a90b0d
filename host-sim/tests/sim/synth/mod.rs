//! A synthetic run for testing the writers without the engine: a square, a
//! circle (as chords) and a curve, each move with a trapezoid speed profile,
//! stepped by Bresenham at the times that profile gives.

#![allow(dead_code)] // each test crate uses a different part

use burin::AXES;
use host_sim::record::{AxisInfo, PathKind, PinEvent, Recorder, RunInfo, Summary};

pub const TICK_HZ: u32 = 96_000_000;
pub const PULSE: u32 = 192; // 2 µs
pub const SETUP: u32 = 96; // 1 µs
pub const SPM: f32 = 80.0;

pub fn info() -> RunInfo {
    let ax = |name, spm| AxisInfo {
        name,
        steps_per_mm: spm,
        max_rate_mm_min: 5000.0,
        max_accel_mm_s2: 500.0,
        travel_mm: 300.0,
    };
    RunInfo {
        tick_hz: TICK_HZ,
        axes: std::array::from_fn(|i| {
            // X and Y fine, Z a leadscrew, the rotary letters 10 per degree.
            let spm = [SPM, SPM, 400.0, 10.0, 10.0, 10.0];
            ax(burin::AXIS_NAMES[i], spm[i])
        }),
        pulse_ticks: PULSE,
        dir_setup_ticks: SETUP,
    }
}

/// The moves: (kind, end point mm, feed mm/min).
pub fn moves() -> Vec<(PathKind, [f32; 2], f32)> {
    let mut m = vec![
        (PathKind::Rapid, [-150.0, -150.0], 5000.0),
        (PathKind::Feed, [-50.0, -150.0], 1500.0),
        (PathKind::Feed, [-50.0, -50.0], 1500.0),
        (PathKind::Feed, [-150.0, -50.0], 1500.0),
        (PathKind::Feed, [-150.0, -150.0], 1500.0),
        (PathKind::Rapid, [-70.0, -100.0], 5000.0),
    ];
    for i in 1..=72 {
        let a = f32::from(i as u8) * 5.0f32.to_radians();
        m.push((
            PathKind::Arc,
            [-100.0 + 30.0 * a.cos(), -100.0 + 30.0 * a.sin()],
            2000.0,
        ));
    }
    for i in 1..=40 {
        let t = i as f32 / 40.0;
        let x = -150.0 + 100.0 * t;
        let y = -20.0 - 15.0 * (t * std::f32::consts::TAU).sin();
        m.push((PathKind::Spline, [x, y], 1200.0));
    }
    m.push((PathKind::Rapid, [-1.0, -1.0], 5000.0));
    m
}

/// Seconds to travel distance `s` of a move of length `l` that starts and
/// ends at rest, with peak speed `v` and acceleration `a`.
fn time_at(s: f64, l: f64, v: f64, a: f64) -> f64 {
    let ramp = (v * v / (2.0 * a)).min(l / 2.0);
    let vp = (2.0 * a * ramp).sqrt();
    let t_ramp = vp / a;
    let cruise = (l - 2.0 * ramp) / vp.max(1e-9);
    if s <= ramp {
        (2.0 * s / a).sqrt()
    } else if s <= l - ramp {
        t_ramp + (s - ramp) / vp
    } else {
        let rem = (l - s).max(0.0);
        t_ramp + cruise + t_ramp - (2.0 * rem / a).sqrt()
    }
}

/// Feeds the whole run to `r`; returns the summary it was finished with.
pub fn run(r: &mut dyn Recorder) -> Summary {
    let info = info();
    r.start(&info);
    let hz = f64::from(TICK_HZ);
    let mut pos = burin::pad([-80i64, -80, -400, 0]);
    let mut tick: u64 = 1000;
    let mut dir_mask = 0u8;
    let mut dir_changed = 0u64;
    let mut steps = [0u64; AXES];
    let mut dist = 0.0;
    let mut max_feed: f64 = 0.0;
    let mut cur = [-1.0f64, -1.0];
    for (kind, to, feed) in moves() {
        r.commanded(1, kind, burin::pad([to[0], to[1], -1.0, 0.0]));
        let target = [
            (f64::from(to[0]) * 80.0).round() as i64,
            (f64::from(to[1]) * 80.0).round() as i64,
        ];
        let d = [target[0] - pos[0], target[1] - pos[1]];
        let n = d[0].abs().max(d[1].abs());
        let l = (f64::from(to[0]) - cur[0]).hypot(f64::from(to[1]) - cur[1]);
        cur = [f64::from(to[0]), f64::from(to[1])];
        if n == 0 {
            continue;
        }
        dist += l;
        let v = f64::from(feed) / 60.0;
        let a = 500.0;
        max_feed = max_feed.max(feed.into());
        let new_dir = u8::from(d[0] < 0) | (u8::from(d[1] < 0) << 1);
        let t0 = tick + u64::from(SETUP);
        if new_dir != dir_mask {
            dir_mask = new_dir;
            dir_changed = tick;
        }
        let mut err = [0i64; 2];
        let mut next_sample = 0.0;
        for k in 1..=n {
            let s = l * k as f64 / n as f64;
            let t = time_at(s, l, v, a);
            let ev_tick = t0 + (t * hz) as u64;
            let mut mask = 0u8;
            for i in 0..2 {
                err[i] += d[i].abs();
                if 2 * err[i] >= n {
                    err[i] -= n;
                    pos[i] += d[i].signum();
                    steps[i] += 1;
                    mask |= 1 << i;
                }
            }
            if t >= next_sample {
                let speed = (2.0 * a * s.min(l - s)).sqrt().min(v) * 60.0;
                r.velocity(ev_tick, speed as f32);
                next_sample = t + 0.002;
            }
            r.step_event(&PinEvent {
                tick: ev_tick,
                dir_mask,
                step_mask: mask,
                dir_changed_tick: dir_changed,
                pos,
            });
            tick = ev_tick;
        }
        r.velocity(tick, 0.0);
        tick += u64::from(PULSE) * 4;
    }
    let mm = |i: usize| pos[i] as f64 / f64::from(info.axes[i].steps_per_mm);
    let summary = Summary {
        lines: 120,
        moves: moves().len() as u32,
        job_time_s: tick as f64 / hz,
        distance_mm: dist,
        max_feed_mm_min: max_feed,
        steps,
        final_position_steps: pos,
        final_position_mm: burin::pad([mm(0), mm(1), mm(2), mm(3)]),
        final_work_position_mm: burin::pad([mm(0) + 100.0, mm(1) + 100.0, mm(2), mm(3)]),
        planner_underruns: 0,
        max_tool_deviation_mm: 0.0,
        errors: vec![host_sim::record::RunError {
            line: 7,
            code: 33,
            message: "invalid target: \"quoted\" & <odd>".into(),
        }],
    };
    r.finish(&summary).expect("finish");
    summary
}

pub fn event(tick: u64, dir_mask: u8, step_mask: u8, pos: [i64; burin::AXES]) -> PinEvent {
    PinEvent {
        tick,
        dir_mask,
        step_mask,
        dir_changed_tick: 0,
        pos,
    }
}

pub fn empty_summary() -> Summary {
    Summary {
        lines: 0,
        moves: 0,
        job_time_s: 0.0,
        distance_mm: 0.0,
        max_feed_mm_min: 0.0,
        steps: [0; burin::AXES],
        final_position_steps: [0; burin::AXES],
        final_position_mm: [0.0; burin::AXES],
        final_work_position_mm: [0.0; burin::AXES],
        planner_underruns: 0,
        max_tool_deviation_mm: 0.0,
        errors: vec![],
    }
}
