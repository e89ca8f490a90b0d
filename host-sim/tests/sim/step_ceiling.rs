//! One step-rate ceiling (issue 28): the planner plans no step sooner
//! than the step driver makes it. Before, the planner capped at `$201`
//! and the driver spaced rises by `$0` + the pulse end's latency + the
//! minimum low time as well: at `$0=5` the driver ran at 97 kHz under a
//! plan of 200 kHz, fell behind, and the move took twice its planned time.
//! Here a long X move at the axis's top rate, with settings as an older
//! store or a config file may hold them (`$201` above the ceiling that
//! `$0` allows), must step at the one ceiling, take the time the plan
//! gives at that rate, and never space two rises closer than it.

use crate::common;
use burin::command::{Command, Feed};
use burin::stepper::StepConfig;
use burin::AXES;
use common::*;
use host_sim::config::{Interrupts, MaskPhase, PulseEnd};
use host_sim::engine::Sim;
use host_sim::record::Recorder;

/// The fastest commanded path speed of the run, mm/min (the plan).
struct Top(f32);
impl Recorder for Top {
    fn velocity(&mut self, _tick: u64, mm_per_min: f32) {
        self.0 = self.0.max(mm_per_min);
    }
}

const STEPS: i64 = 4000;

#[test]
fn planner_and_driver_share_the_ceiling() {
    for pulse_us in [2.0f32, 5.0, 10.0] {
        let mut cfg = config();
        let s = &mut cfg.settings;
        s.step_pulse_us = pulse_us;
        s.max_step_rate_hz = 200_000.0;
        s.axes[0].steps_per_mm = 80.0;
        s.axes[0].max_rate = 200_000.0 / 80.0 * 60.0;
        s.axes[0].max_accel = 1.0e7;
        cfg.interrupts = Interrupts {
            step_entry_ns: 250,
            step_handler_ns: 1600,
            step_fall_ns: 600,
            pulse_end: PulseEnd::Hardware { latency_ns: 333 },
            mask_window_us: 0.0,
            mask_period_us: 1000.0,
            mask_phase: MaskPhase::Random(1),
            ..Interrupts::default()
        };
        let sc = StepConfig::new(&cfg.settings, cfg.tick_hz);
        let mut rec = Top(0.0);
        let mut sim = Sim::new(&cfg, &mut rec);
        sim.record_edges();
        let mm = STEPS as f32 / 80.0;
        sim.push_command(
            1,
            Command::Line {
                end: burin::pad([mm, 0.0, 0.0, 0.0]),
                feed: Feed::PerMin(1.0e6),
            },
        );
        sim.run();
        let sum = sim.summary(1, [0.0; AXES]);
        assert!(sum.errors.is_empty(), "{pulse_us} µs: {:?}", sum.errors);
        assert_eq!(sum.final_position_steps[0], STEPS);
        let rises: Vec<u64> = sim
            .edges()
            .windows(2)
            .filter(|w| w[0].step & 1 == 0 && w[1].step & 1 != 0)
            .map(|w| w[1].tick)
            .collect();
        assert!(rises.len() as i64 >= STEPS - 1, "{} rises", rises.len());
        let gaps: Vec<u64> = rises.windows(2).map(|w| w[1] - w[0]).collect();
        let shortest = gaps.iter().copied().min().unwrap_or(u64::MAX);
        let period = u64::from(sc.min_period);
        assert!(
            shortest >= period,
            "{pulse_us} µs: rises {shortest} < {period} ticks apart"
        );
        // The plan's fastest step period: never shorter than the ceiling
        // (the planner plans no faster than the driver steps).
        drop(sim);
        let planned_hz = f64::from(rec.0) / 60.0 * 80.0;
        let planned = (f64::from(cfg.tick_hz) / planned_hz).ceil() as u64;
        assert!(
            planned >= period,
            "{pulse_us} µs: planned {planned} < {period} ticks"
        );
        // At the top rate (the ramps take a few steps at 1e7 mm/s²) the
        // driver keeps the plan's period: no gap longer than it (it does
        // not fall behind and catch up).
        let cruise = &gaps[gaps.len() / 4..gaps.len() * 3 / 4];
        let longest = cruise.iter().copied().max().unwrap_or(0);
        assert!(
            longest <= planned + 1,
            "{pulse_us} µs: the driver fell behind the plan ({longest} > {planned} ticks)"
        );
        // So the move takes the plan's time.
        let plan_s = STEPS as f64 * planned as f64 / f64::from(cfg.tick_hz);
        assert!(
            sum.job_time_s < plan_s * 1.02 + 1e-3,
            "{pulse_us} µs: {:.3} ms, planned {:.3} ms",
            sum.job_time_s * 1e3,
            plan_s * 1e3
        );
        println!(
            "$0={pulse_us}: ceiling {period} ticks ({:.0} Hz), planned {planned}, shortest {shortest}, longest {longest}, job {:.3} ms",
            f64::from(cfg.tick_hz) / period as f64,
            sum.job_time_s * 1e3
        );
    }
}
