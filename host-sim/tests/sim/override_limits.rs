//! Feed overrides and feed holds while a corner-heavy job runs: the
//! planner replans the whole ring (`set_overrides`), settled entries and
//! the block being stepped included, and the preparer plans a hold ramp
//! from wherever it is. The limits of issue 12 must still hold: per-axis
//! acceleration ≤ 105 % over 50 ms windows, no step interval below the
//! rate limit, and the job ends where it was commanded to.

use crate::common;
use burin::command::{Command, Feed};
use burin::settings::Profile;
use common::{bench_jobs, grbl_match as machine};
use host_sim::bench::limits::{LimitMeter, TraceLimits};
use host_sim::config::MachineConfig;
use host_sim::engine::{Input, Sim};

/// Z valleys and ridges, then square XY corners (as `motion_limits`).
fn corners() -> Vec<Command> {
    let line = |x: f32, y: f32, z: f32| Command::Line {
        end: burin::pad([x, y, z, 0.0]),
        feed: Feed::PerMin(4000.0),
    };
    let mut v: Vec<Command> = (1..=12)
        .map(|k| line(k as f32 * 3.0, 0.0, if k % 2 == 1 { -1.0 } else { 0.0 }))
        .collect();
    for (x, y) in [(36.0, 20.0), (16.0, 20.0), (16.0, 5.0), (30.0, 5.0)] {
        v.push(line(x, y, 0.0));
    }
    v
}

#[test]
fn overrides_and_holds_at_any_time_keep_the_axis_limits() {
    for profile in [Profile::Trapezoid, Profile::SCurve] {
        let mut cfg = machine();
        cfg.settings.profile = profile;
        keeps_the_limits(&cfg);
    }
}

fn keeps_the_limits(cfg: &MachineConfig) {
    let cmds = corners();
    let mut worst = [0.0f64; 3];
    let plain = run(cfg, &cmds, &[]);
    let mut slowest = 0u64;
    for k in 0..40 {
        let t = 0.05 + k as f64 * 0.09;
        for (a, b) in [(200, 10), (10, 200), (50, 150), (150, 30)] {
            let inputs = [
                (t, Input::FeedOverride(a)),
                (t + 0.13, Input::FeedOverride(b)),
                (t + 0.41, Input::FeedOverride(100)),
            ];
            let l = run(cfg, &cmds, &inputs);
            check(
                cfg,
                &l,
                &plain,
                &format!("at {t:.2} s, {a} then {b} %"),
                &mut worst,
            );
            slowest = slowest.max(l.last_tick);
        }
        let inputs = [(t, Input::FeedHold), (t + 0.3, Input::CycleStart)];
        let l = run(cfg, &cmds, &inputs);
        check(cfg, &l, &plain, &format!("hold at {t:.2} s"), &mut worst);
    }
    println!(
        "{:?}: worst acceleration X/Y/Z {worst:.3?} of the limits",
        cfg.settings.profile
    );
    // The overrides did act (10 % for 0.13 s, then 200 %, on a job whose
    // corners keep it slow: 4.24 s against 3.96 s at worst).
    let hz = f64::from(cfg.tick_hz);
    let (t0, t1) = (plain.last_tick as f64 / hz, slowest as f64 / hz);
    assert!(
        t1 > t0 + 0.1,
        "{t1:.3} s against {t0:.3} s without overrides"
    );
}

fn check(
    cfg: &MachineConfig,
    l: &TraceLimits,
    plain: &TraceLimits,
    what: &str,
    worst: &mut [f64; 3],
) {
    assert_eq!(l.short_intervals, [0; burin::AXES], "{what}");
    assert_eq!(l.end_steps, plain.end_steps, "{what}");
    for (i, w) in worst.iter_mut().enumerate() {
        let lim = f64::from(cfg.settings.axes[i].max_accel);
        *w = w.max(l.peak_acc[i] / lim);
        let t0 = l.first_tick.unwrap_or(0);
        assert!(
            l.peak_acc[i] <= lim * 1.05,
            "{what}: axis {i} at {:.1} mm/s², limit {lim}, {:.4} s after the first step",
            l.peak_acc[i],
            l.peak_acc_tick[i].saturating_sub(t0) as f64 / f64::from(cfg.tick_hz)
        );
    }
}

fn run(cfg: &MachineConfig, cmds: &[Command], inputs: &[(f64, Input)]) -> TraceLimits {
    let mut meter = LimitMeter::new(cfg.settings.max_step_rate_hz);
    {
        let mut sim = Sim::new(cfg, &mut meter);
        for (i, c) in cmds.iter().enumerate() {
            sim.push_command(i as u32 + 1, c.clone());
        }
        for (t, i) in inputs {
            sim.input_at((t * f64::from(cfg.tick_hz)) as u64, *i);
        }
        sim.run();
    }
    meter.out
}

/// Every bench-motion job (outside the repo; skipped when absent), a
/// hold, a resume and feed override changes (30 %, 180 %, 100 %) at two
/// points of each, streamed through the virtual board as `cargo xtask
/// sim` streams them. An override drop lowers the exits of blocks that
/// can no longer reach them: they crossed their corners with no exit hold
/// (Z at 110 % in Cereal's curves) until `Profile::plan_held` left at the
/// slowest speed that still holds the corner.
#[test]
fn bench_jobs_with_holds_and_overrides_keep_the_limits() {
    for (path, src) in bench_jobs() {
        let name = path.rsplit('/').next().unwrap_or(&path);
        for profile in [Profile::Trapezoid, Profile::SCurve] {
            let mut cfg = machine();
            cfg.settings.profile = profile;
            let plain = host_sim::bench::run_job(&cfg, &src);
            let mut worst = [0.0f64; 3];
            for k in [1.0, 2.0] {
                let t = plain.time_s * k / 3.0;
                let inputs = [
                    (t, Input::FeedHold),
                    (t + 0.5, Input::CycleStart),
                    (t + 1.0, Input::FeedOverride(30)),
                    (t + 1.7, Input::FeedOverride(180)),
                    (t + 2.5, Input::FeedOverride(100)),
                ];
                let mut meter = LimitMeter::new(cfg.settings.max_step_rate_hz);
                let summary =
                    host_sim::offline::run_file_with_inputs(&cfg, &src, &mut meter, &inputs);
                assert!(summary.errors.is_empty(), "{name}: {:?}", summary.errors);
                let what = format!("{name}, {profile:?}, hold at {t:.2} s");
                check(&cfg, &meter.out, &plain.limits, &what, &mut worst);
            }
            println!("{name} {profile:?}: worst acceleration X/Y/Z {worst:.3?} of the limits");
        }
    }
}
