//! Trace properties on jobs built from Commands: exact final steps, max rate,
//! max acceleration, path deviation, pulse timing; hold/resume; overrides;
//! S-curve; determinism.
use crate::common;
use burin::command::{Arc, ArcDir, Command, Feed, Plane, Spline};
use burin::settings::{Profile, RapidMode};
use common::*;
use host_sim::engine::Input;

fn arc(
    end: [f32; burin::AXES],
    center: [f32; 2],
    plane: Plane,
    dir: ArcDir,
    turns: u16,
    f: f32,
) -> Command {
    Command::Arc(Arc {
        end,
        center,
        plane,
        dir,
        turns,
        feed: Feed::PerMin(f),
    })
}

/// A job touching every motion kind: lines, rapids, arcs in all planes,
/// helix, full circle, multi-turn, spline, G93, dwell, a reversal.
fn mixed_job() -> Vec<Command> {
    vec![
        Command::Rapid {
            end: burin::pad([5.0, 5.0, 0.0, 0.0]),
        },
        Command::Line {
            end: burin::pad([25.0, 5.0, -1.0, 0.0]),
            feed: Feed::PerMin(1500.0),
        },
        arc(
            burin::pad([25.0, 25.0, -1.0, 0.0]),
            [25.0, 15.0],
            Plane::XY,
            ArcDir::Ccw,
            0,
            2000.0,
        ),
        // full circle, then a 2-turn helix down 2 mm
        arc(
            burin::pad([25.0, 25.0, -1.0, 0.0]),
            [25.0, 15.0],
            Plane::XY,
            ArcDir::Cw,
            0,
            2500.0,
        ),
        arc(
            burin::pad([25.0, 25.0, -3.0, 0.0]),
            [20.0, 25.0],
            Plane::XY,
            ArcDir::Ccw,
            1,
            1800.0,
        ),
        Command::Dwell { seconds: 0.05 },
        arc(
            burin::pad([35.0, 25.0, -3.0, 0.0]),
            [-3.0, 30.0],
            Plane::ZX,
            ArcDir::Cw,
            0,
            1200.0,
        ),
        arc(
            burin::pad([35.0, 30.0, -3.0, 10.0]),
            [27.5, -3.0],
            Plane::YZ,
            ArcDir::Ccw,
            0,
            900.0,
        ),
        Command::Spline(Spline {
            p1: [45.0, 45.0],
            p2: [10.0, 50.0],
            end: burin::pad([5.0, 30.0, -2.0, 10.0]),
            feed: Feed::PerMin(2000.0),
        }),
        Command::Line {
            end: burin::pad([5.0, 10.0, -2.0, 10.0]),
            feed: Feed::InverseTime(60.0),
        },
        Command::Line {
            end: burin::pad([5.0, 12.0, -2.0, 10.0]),
            feed: Feed::PerMin(3000.0),
        },
        Command::Line {
            end: burin::pad([5.0, 11.0, -2.0, 10.0]),
            feed: Feed::PerMin(3000.0),
        },
        Command::Rapid {
            end: burin::pad([0.0, 0.0, 0.0, 0.0]),
        },
    ]
}

#[test]
fn mixed_job_trapezoid() {
    let cfg = config();
    let cmds = mixed_job();
    let r = run(&cfg, &cmds, &[]);
    check_all(&cfg, &r, &cmds, "trapezoid");
}

#[test]
fn mixed_job_scurve() {
    let mut cfg = config();
    cfg.settings.profile = Profile::SCurve;
    let cmds = mixed_job();
    let r = run(&cfg, &cmds, &[]);
    check_all(&cfg, &r, &cmds, "s-curve");
    let t = run(&config(), &cmds, &[]).summary.job_time_s;
    assert!(r.summary.job_time_s > t, "jerk limiting should cost time");
}

#[test]
fn independent_rapids_setting_still_exact() {
    let mut cfg = config();
    cfg.settings.rapid_mode = RapidMode::Independent;
    let cmds = mixed_job();
    let r = run(&cfg, &cmds, &[]);
    check_all(&cfg, &r, &cmds, "independent rapids");
}

#[test]
fn determinism_identical_traces() {
    let cfg = config();
    let cmds = mixed_job();
    let inputs = [
        (0.3, Input::FeedHold),
        (0.5, Input::CycleStart),
        (0.7, Input::FeedOverride(150)),
    ];
    let a = run(&cfg, &cmds, &inputs);
    let b = run(&cfg, &cmds, &inputs);
    assert_eq!(a.rec.events.len(), b.rec.events.len());
    assert_eq!(trace_hash(&a.rec.events), trace_hash(&b.rec.events));
    assert_eq!(a.rec.velocity, b.rec.velocity);
    assert_eq!(a.summary, b.summary);
}

#[test]
fn feed_hold_and_resume_mid_arc() {
    let cfg = config();
    // One big slow arc: a hold 0.4 s in lands in its middle.
    let cmds = vec![
        Command::Line {
            end: burin::pad([50.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(3000.0),
        },
        arc(
            burin::pad([0.0, 0.0, 0.0, 0.0]),
            [25.0, 0.0],
            Plane::XY,
            ArcDir::Ccw,
            0,
            3000.0,
        ),
    ];
    let plain = run(&cfg, &cmds, &[]);
    let r = run(
        &cfg,
        &cmds,
        &[(1.4, Input::FeedHold), (2.0, Input::CycleStart)],
    );
    check_all(&cfg, &r, &cmds, "hold+resume");
    assert_eq!(
        r.summary.steps, plain.summary.steps,
        "hold must not lose or add steps"
    );
    // The machine really stopped: a gap in the step stream after the hold.
    let hz = cfg.tick_hz as u64;
    let gap = r
        .rec
        .events
        .windows(2)
        .map(|w| w[1].tick - w[0].tick)
        .max()
        .unwrap();
    assert!(
        gap > 3 * hz / 10,
        "expected a standstill, longest gap {gap} ticks"
    );
    // and the hold point is on the arc (after the line ends at ~1.07 s)
    let stop = r
        .rec
        .events
        .windows(2)
        .find(|w| w[1].tick - w[0].tick == gap)
        .unwrap()[0];
    assert!(
        stop.tick > 14 * hz / 10 && stop.tick < 2 * hz,
        "stopped at tick {}",
        stop.tick
    );
    assert!(r.summary.job_time_s > plain.summary.job_time_s + 0.4);
}

#[test]
fn feed_override_live() {
    let cfg = config();
    let cmds = vec![
        Command::Line {
            end: burin::pad([100.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(1000.0),
        },
        Command::Line {
            end: burin::pad([100.0, 100.0, 0.0, 0.0]),
            feed: Feed::PerMin(1000.0),
        },
    ];
    let base = run(&cfg, &cmds, &[]);
    let fast = run(&cfg, &cmds, &[(1.0, Input::FeedOverride(200))]);
    let slow = run(&cfg, &cmds, &[(1.0, Input::FeedOverride(10))]);
    check_all(&cfg, &fast, &cmds, "override 200%");
    check_all(&cfg, &slow, &cmds, "override 10%");
    assert!(fast.summary.job_time_s < base.summary.job_time_s * 0.7);
    assert!(slow.summary.job_time_s > base.summary.job_time_s * 3.0);
    let vmax = fast.rec.velocity.iter().map(|v| v.1).fold(0.0, f32::max);
    assert!(
        vmax > 1900.0 && vmax < 2010.0,
        "200% of 1000 mm/min, got {vmax}"
    );
}

#[test]
fn rapid_override_live() {
    let cfg = config();
    let cmds = vec![Command::Rapid {
        end: burin::pad([200.0, 0.0, 0.0, 0.0]),
    }];
    let base = run(&cfg, &cmds, &[]);
    let q = run(&cfg, &cmds, &[(0.0, Input::RapidOverride(25))]);
    check_all(&cfg, &q, &cmds, "rapid 25%");
    let vmax = q.rec.velocity.iter().map(|v| v.1).fold(0.0, f32::max);
    assert!(
        vmax <= 1260.0 && vmax > 1200.0,
        "25% of 5000 mm/min, got {vmax}"
    );
    assert!(q.summary.job_time_s > 3.0 * base.summary.job_time_s);
}

#[test]
fn dwell_takes_its_time() {
    let cfg = config();
    let a = run(
        &cfg,
        &[Command::Line {
            end: burin::pad([1.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(600.0),
        }],
        &[],
    );
    let cmds = vec![
        Command::Line {
            end: burin::pad([1.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(600.0),
        },
        Command::Dwell { seconds: 1.5 },
        Command::Line {
            end: burin::pad([0.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(600.0),
        },
    ];
    let b = run(&cfg, &cmds, &[]);
    let dt = b.summary.job_time_s - 2.0 * a.summary.job_time_s;
    assert!((dt - 1.5).abs() < 0.01, "dwell added {dt} s");
}

#[test]
fn inverse_time_feed_sets_duration() {
    let cfg = config();
    // 2 mm in 1/30 min = 2 s; slow enough that accel ramps are a few % of it.
    let cmds = vec![Command::Line {
        end: burin::pad([2.0, 0.0, 0.0, 0.0]),
        feed: Feed::InverseTime(30.0),
    }];
    let r = run(&cfg, &cmds, &[]);
    assert!(
        (r.summary.job_time_s - 2.0).abs() < 0.02,
        "took {}",
        r.summary.job_time_s
    );
}

#[test]
fn independent_rapid_moves_each_axis_at_its_own_rate() {
    let end = burin::pad([100.0, 0.0, -10.0, 0.0]);
    let cmds = vec![Command::Rapid { end }];
    let last_tick = |r: &Run, axis: usize| {
        r.rec
            .events
            .iter()
            .rev()
            .find(|e| e.step_mask & (1 << axis) != 0)
            .unwrap()
            .tick
    };
    let coord = run(&config(), &cmds, &[]);
    let mut cfg = config();
    cfg.settings.rapid_mode = RapidMode::Independent;
    let ind = run(&cfg, &cmds, &[]);
    check_all(&cfg, &ind, &cmds, "independent rapid");
    // coordinated: Z ends with X; independent: Z (0.6 s at 1000 mm/min) long before X (1.2 s)
    assert!(last_tick(&coord, 2) as f64 > 0.95 * last_tick(&coord, 0) as f64);
    assert!((last_tick(&ind, 2) as f64) < 0.7 * last_tick(&ind, 0) as f64);
    assert!(ind.rec.path.len() == 2, "two legs: {:?}", ind.rec.path);
}

#[test]
fn scurve_limits_jerk_trapezoid_does_not() {
    let cmds = vec![Command::Line {
        end: burin::pad([150.0, 40.0, 0.0, 0.0]),
        feed: Feed::PerMin(4000.0),
    }];
    let mut cfg = config();
    let trap = run(&cfg, &cmds, &[]);
    cfg.settings.profile = Profile::SCurve;
    let s = run(&cfg, &cmds, &[]);
    check_all(&cfg, &s, &cmds, "s-curve line");
    let hz = cfg.tick_hz as f64;
    let (jt, js) = (max_jerk_x(&trap, hz), max_jerk_x(&s, hz));
    println!(
        "max X jerk: trapezoid {jt:.0} mm/s³, s-curve {js:.0} mm/s³ (path limit {})",
        cfg.settings.jerk
    );
    assert!(js <= cfg.settings.jerk as f64 * 1.5, "{js}");
    assert!(jt > cfg.settings.jerk as f64 * 1.8 && jt > 2.0 * js, "{jt}");
}
