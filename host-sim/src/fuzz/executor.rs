//! `executor`: interpreted G-code through the executor, planner, segment
//! preparer and stepper (the engine's own task, no link) on a small
//! machine. Invariants: no step leaves the box of the moves committed
//! ([`super::envelope`]), idle or not; once idle without an alarm the step
//! position equals the commanded position; no step while the executor is
//! in alarm; no axis steps faster than `$201` allows, nor (over 8 steps,
//! 10 % slack) faster than its max rate, nor do its pulses overlap; and the
//! simulated work (step interrupts and task passes, [`Sim::work`]) stays
//! within a bound proportional to the steps and virtual time. Work, not
//! host time: a loaded host took 0.429 s for an input that replays in 2 ms
//! (issue 35), and without `-fork` that ended the fuzz run.

use std::cell::{Cell, RefCell};

use burin::interp::Interpreter;
use burin::settings::Settings;
use burin::AXES;

use super::envelope::{Envelope, EnvelopeRec};
use super::Bytes;
use crate::config::{HostModel, MachineConfig, ProbeSurface};
use crate::engine::Sim;
use crate::record::{PinEvent, Recorder, Tee};

/// Virtual time run per check round, and the most a job may take.
const ROUND_S: f64 = 0.02;
const MAX_VIRTUAL_S: f64 = 10.0;
/// Lines and bytes of G-code one input may hold.
const MAX_LINES: usize = 24;
/// Steps over which an axis's rate is measured, and the slack for the
/// timer's rounding and the preparer's segment quantisation.
const RATE_WINDOW: usize = 8;
const RATE_SLACK: f64 = 1.10;
/// Simulated work allowed: a fixed part, per step and per virtual ms. The
/// seeds (the first 24 lines of every corpus file and job, each flag)
/// reach at most 0.085 of it (imperial_wrench.ngc: 14,041 for 1,767 steps
/// in 6.6 s); step interrupts or task passes that loop without progress
/// exceed it by far. A slow path inside one of them is libFuzzer's
/// `-timeout` to find.
const WORK_BASE: u64 = 20_000;
const WORK_PER_STEP: u64 = 8;
const WORK_PER_MS: u64 = 20;

/// The small machine: few steps per mm, a 20 mm envelope.
pub fn small_machine(soft_limits: bool, probe: bool) -> MachineConfig {
    let mut s = Settings::default();
    // Per letter X Y Z A B C (the rotary ones alike); the build's first
    // AXES of them.
    for (i, a) in s.axes.iter_mut().enumerate() {
        a.steps_per_mm = [5.0, 5.0, 10.0, 2.0, 2.0, 2.0][i];
        a.max_rate = [3000.0, 3000.0, 600.0, 1800.0, 1800.0, 1800.0][i];
        a.max_accel = [200.0, 200.0, 50.0, 100.0, 100.0, 100.0][i];
        a.max_travel = [20.0, 20.0, 10.0, 0.0, 0.0, 0.0][i];
    }
    s.soft_limits = soft_limits;
    s.max_step_rate_hz = 50_000.0;
    MachineConfig {
        tick_hz: 96_000_000,
        settings: s,
        limits: [None; AXES],
        probe: probe.then_some(ProbeSurface {
            axis: 2,
            trip_mm: -5.0,
            towards_negative: true,
        }),
        start_position_mm: burin::pad([-10.0, -10.0, -1.0, 0.0]),
        host: HostModel::INSTANT,
        interrupts: Default::default(),
        wiring: None,
        slack_mm: Default::default(),
    }
}

/// Checks each step event as it happens.
struct Steps<'a> {
    tick_hz: f64,
    pulse_ticks: u64,
    /// Shortest legal interval between two steps of one axis, ticks.
    min_interval: u64,
    last: [Option<u64>; AXES],
    /// The last `RATE_WINDOW + 1` step ticks per axis (a ring), and the
    /// shortest time `RATE_WINDOW` steps may take at the axis's max rate.
    recent: [[u64; RATE_WINDOW + 1]; AXES],
    seen: [usize; AXES],
    window_ticks: [u64; AXES],
    /// Steps so far (read between rounds).
    count: &'a Cell<u64>,
}

impl Recorder for Steps<'_> {
    fn step_event(&mut self, ev: &PinEvent) {
        for i in 0..AXES {
            if ev.step_mask >> i & 1 == 0 {
                continue;
            }
            self.count.set(self.count.get() + 1);
            if let Some(t) = self.last[i] {
                let dt = ev.tick - t;
                assert!(
                    dt > self.pulse_ticks,
                    "axis {i}: pulses at {t} and {} overlap",
                    ev.tick
                );
                assert!(
                    dt >= self.min_interval,
                    "axis {i}: {:.0} steps/s at tick {} (limit {:.0})",
                    self.tick_hz / dt as f64,
                    ev.tick,
                    self.tick_hz / self.min_interval as f64
                );
            }
            self.last[i] = Some(ev.tick);
            let k = self.seen[i];
            self.recent[i][k % (RATE_WINDOW + 1)] = ev.tick;
            self.seen[i] += 1;
            if k >= RATE_WINDOW {
                let first = self.recent[i][(k + 1) % (RATE_WINDOW + 1)];
                assert!(
                    ev.tick - first >= self.window_ticks[i],
                    "axis {i}: {RATE_WINDOW} steps in {} ticks up to tick {}, faster than \
                     its max rate allows ({} ticks)",
                    ev.tick - first,
                    ev.tick,
                    self.window_ticks[i]
                );
            }
        }
    }
}

pub fn executor(data: &[u8]) {
    let mut b = Bytes::new(data);
    let flags = b.u8();
    let cfg = small_machine(flags & 1 != 0, flags & 2 != 0);
    let s = &cfg.settings;
    let (pulse_ticks, _) = cfg.pulse_ticks();
    let tick_hz = f64::from(cfg.tick_hz);
    let count = Cell::new(0);
    let mut rec = Steps {
        tick_hz,
        pulse_ticks: u64::from(pulse_ticks),
        // 1 % for the timer's rounding of each period.
        min_interval: (tick_hz / f64::from(s.max_step_rate_hz) * 0.99) as u64,
        last: [None; AXES],
        recent: [[0; RATE_WINDOW + 1]; AXES],
        seen: [0; AXES],
        window_ticks: std::array::from_fn(|i| {
            let a = &s.axes[i];
            let sps = f64::from(a.max_rate) / 60.0 * f64::from(a.steps_per_mm);
            (RATE_WINDOW as f64 / sps / RATE_SLACK * tick_hz) as u64
        }),
        count: &count,
    };
    let env = RefCell::new(Envelope::new(s.axes.map(|a| a.steps_per_mm)));
    let mut env_rec = EnvelopeRec(&env);
    let mut tee = Tee(vec![&mut rec, &mut env_rec]);
    let mut it = Interpreter::new();
    let mut sim = Sim::new(&cfg, &mut tee);
    env.borrow_mut().settle(sim.rt.position());
    it.set_machine_position(sim.machine.commanded_position());
    for (i, line) in b.rest().split(|&c| c == b'\n').take(MAX_LINES).enumerate() {
        let n = i as u32 + 1;
        let _ = it.execute_line(line, &mut |c| sim.push_command(n, c));
        if it.needs_sync() {
            // The engine runs ahead of nothing here: finish, then sync.
            run(&mut sim, tick_hz, &count, &env);
            it.set_machine_position(sim.machine.commanded_position());
        }
    }
    let done = run(&mut sim, tick_hz, &count, &env);
    if done && sim.machine.alarm().is_none() {
        let want = sim
            .machine
            .motion
            .to_steps(&sim.machine.commanded_position());
        if let Ok(want) = want {
            assert_eq!(
                sim.rt.position(),
                want,
                "idle at a step position other than the commanded {:?}",
                sim.machine.commanded_position()
            );
        }
    }
    let (steps, work) = (count.get(), sim.work());
    let ms = sim.now() / (u64::from(cfg.tick_hz) / 1000);
    let limit = WORK_BASE + WORK_PER_STEP * steps + WORK_PER_MS * ms;
    assert!(
        work <= limit,
        "{work} step interrupts and task passes for {steps} steps in {ms} ms (limit {limit})"
    );
}

/// Run until idle (true) or the virtual time cap, checking the alarm rule
/// at every round: a round that starts and ends in alarm has no step.
fn run(sim: &mut Sim, tick_hz: f64, count: &Cell<u64>, env: &RefCell<Envelope>) -> bool {
    let round = (ROUND_S * tick_hz) as u64;
    let cap = sim.now() + (MAX_VIRTUAL_S * tick_hz) as u64;
    while sim.now() < cap {
        if sim.idle() {
            env.borrow_mut().settle(sim.rt.position());
            return true;
        }
        let (alarm, steps) = (sim.machine.alarm(), count.get());
        let t = sim.now() + round;
        sim.run_until(t);
        if let (Some(a), Some(_)) = (alarm, sim.machine.alarm()) {
            assert_eq!(
                count.get(),
                steps,
                "stepped during alarm {a:?} before tick {t}"
            );
        }
    }
    sim.idle()
}
