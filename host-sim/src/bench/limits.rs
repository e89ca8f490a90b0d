//! What the step trace itself says about the axis limits: peak velocity
//! and acceleration per axis, and step intervals shorter than the rate
//! limits allow. Measured on the steps as they left the pins, so it judges
//! the planner, the preparer and the step driver together.
//!
//! Velocity, acceleration and jerk are taken over windows of [`WINDOW_S`]:
//! with `x(t)` the step position, `v = (x(t+W) − x(t))/W`,
//! `a = (x(t+2W) − 2·x(t+W) + x(t))/W²` and
//! `j = (x(t+3W) − 3·x(t+2W) + 3·x(t+W) − x(t))/W³`, evaluated every
//! [`GRID_S`]. Each is a weighted average of the true motion's value over
//! its windows (the kernels are B-splines of unit weight), so it never
//! exceeds the true peak; a window that long averages out the step
//! quantisation (one X step over 50 ms² is 5 mm/s², 1 % of 500) yet still
//! sees a corner's acceleration. The jerk's quantisation is larger, up to
//! [`jerk_quantum`] (400 mm/s³ on an 80 steps/mm axis), and a corner's
//! instant velocity change `Δv` reads as up to `Δv/W²` (2.5 mm/s: 1,000
//! mm/s³).

use burin::AXES;

use crate::record::{PinEvent, Recorder, RunInfo, Summary};

/// Window length of the velocity and acceleration figures.
pub const WINDOW_S: f64 = 0.05;
/// Spacing of the sliding windows.
pub const GRID_S: f64 = 0.001;
/// Slack on a single step interval, in timer ticks: the step timer counts
/// whole ticks, so a rate exactly at the limit may come out one tick short.
pub const INTERVAL_SLACK_TICKS: u64 = 1;

/// Figures of one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TraceLimits {
    /// First and last step, ticks.
    pub first_tick: Option<u64>,
    pub last_tick: u64,
    /// Peak |velocity| per axis over the windows, mm/s.
    pub peak_vel: [f64; AXES],
    /// Peak |acceleration| per axis over the windows, mm/s².
    pub peak_acc: [f64; AXES],
    /// Peak |jerk| per axis over the windows, mm/s³, and where (the
    /// middle of its three windows, timer ticks).
    pub peak_jerk: [f64; AXES],
    pub peak_jerk_tick: [u64; AXES],
    /// Where each peak acceleration was: the middle of its two windows,
    /// in timer ticks (the trace's clock).
    pub peak_acc_tick: [u64; AXES],
    /// Step intervals shorter than the axis' rate limit allows, per axis.
    pub short_intervals: [u64; AXES],
    /// The shortest step interval seen per axis, ticks.
    pub min_interval: [u64; AXES],
    /// Final step position.
    pub end_steps: [i64; AXES],
}

/// The most a jerk figure can be off by step quantisation on an axis of
/// `steps_per_mm`: each sample trails the true position by less than a
/// step, and the third difference's weights are +1, +3 and −3, −1, so the
/// error stays below 4 steps.
pub fn jerk_quantum(steps_per_mm: f64) -> f64 {
    4.0 / steps_per_mm / (WINDOW_S * WINDOW_S * WINDOW_S)
}

/// Recorder that fills [`TraceLimits`] as the run goes.
pub struct LimitMeter {
    max_step_hz: f64,
    tick_hz: f64,
    steps_per_mm: [f64; AXES],
    /// Shortest allowed interval per axis, ticks.
    min_ticks: [u64; AXES],
    grid_ticks: u64,
    /// Window length in grid samples.
    w: usize,
    /// Step position at the grid times, newest last (3w+1 kept).
    samples: std::collections::VecDeque<[i64; AXES]>,
    next_grid: u64,
    pos: [i64; AXES],
    last_step: [Option<u64>; AXES],
    pub out: TraceLimits,
}

impl LimitMeter {
    /// `max_step_rate_hz`: `$201`, the fastest any single axis may step.
    pub fn new(max_step_rate_hz: f32) -> Self {
        LimitMeter {
            max_step_hz: f64::from(max_step_rate_hz),
            tick_hz: 1.0,
            steps_per_mm: [1.0; AXES],
            min_ticks: [0; AXES],
            grid_ticks: 1,
            w: 1,
            samples: Default::default(),
            next_grid: 0,
            pos: [0; AXES],
            last_step: [None; AXES],
            out: TraceLimits {
                min_interval: [u64::MAX; AXES],
                ..Default::default()
            },
        }
    }

    /// Standing still after the last step: let the windows see the stop.
    pub fn flush(&mut self) {
        for _ in 0..=3 * self.w {
            self.sample();
        }
        self.out.end_steps = self.pos;
    }

    fn sample(&mut self) {
        self.samples.push_back(self.pos);
        if self.samples.len() > 3 * self.w + 1 {
            self.samples.pop_front();
        }
        let n = self.samples.len();
        if n < self.w + 1 {
            return;
        }
        let wt = self.w as f64 * self.grid_ticks as f64 / self.tick_hz;
        let (x2, x1) = (self.samples[n - 1], self.samples[n - 1 - self.w]);
        for i in 0..AXES {
            let v = (x2[i] - x1[i]) as f64 / self.steps_per_mm[i] / wt;
            self.out.peak_vel[i] = self.out.peak_vel[i].max(v.abs());
        }
        if n == 3 * self.w + 1 {
            let (xm, x0) = (self.samples[n - 1 - 2 * self.w], self.samples[0]);
            for i in 0..AXES {
                let d3 = (x2[i] - 3 * x1[i] + 3 * xm[i] - x0[i]) as f64;
                let j = d3 / self.steps_per_mm[i] / (wt * wt * wt);
                if j.abs() > self.out.peak_jerk[i] {
                    self.out.peak_jerk[i] = j.abs();
                    let back = (3 * self.w as u64 * self.grid_ticks) / 2;
                    self.out.peak_jerk_tick[i] = self.next_grid.saturating_sub(back);
                }
            }
        }
        if n > 2 * self.w {
            let x0 = self.samples[n - 1 - 2 * self.w];
            for i in 0..AXES {
                let d2 = (x2[i] - 2 * x1[i] + x0[i]) as f64;
                let a = d2 / self.steps_per_mm[i] / (wt * wt);
                if a.abs() > self.out.peak_acc[i] {
                    self.out.peak_acc[i] = a.abs();
                    let back = self.w as u64 * self.grid_ticks;
                    self.out.peak_acc_tick[i] = self.next_grid.saturating_sub(back);
                }
            }
        }
    }
}

impl Recorder for LimitMeter {
    fn start(&mut self, info: &RunInfo) {
        let max_step_hz = self.max_step_hz;
        self.tick_hz = f64::from(info.tick_hz);
        for (i, a) in info.axes.iter().enumerate() {
            self.steps_per_mm[i] = f64::from(a.steps_per_mm);
            let hz =
                (f64::from(a.max_rate_mm_min) / 60.0 * f64::from(a.steps_per_mm)).min(max_step_hz);
            self.min_ticks[i] = if hz > 0.0 {
                (self.tick_hz / hz).floor() as u64
            } else {
                0
            };
        }
        self.grid_ticks = ((GRID_S * self.tick_hz) as u64).max(1);
        self.w = ((WINDOW_S / GRID_S).round() as usize).max(1);
    }

    fn step_event(&mut self, ev: &PinEvent) {
        if ev.step_mask == 0 {
            return;
        }
        if self.out.first_tick.is_none() {
            self.out.first_tick = Some(ev.tick);
            self.next_grid = ev.tick;
            // Where the machine stood (within this one step) before it.
            self.pos = ev.pos;
        }
        while self.next_grid <= ev.tick {
            self.sample();
            self.next_grid += self.grid_ticks;
        }
        for i in 0..AXES {
            if ev.step_mask >> i & 1 == 0 {
                continue;
            }
            if let Some(t) = self.last_step[i] {
                let dt = ev.tick - t;
                self.out.min_interval[i] = self.out.min_interval[i].min(dt);
                if dt + INTERVAL_SLACK_TICKS < self.min_ticks[i] {
                    self.out.short_intervals[i] += 1;
                }
            }
            self.last_step[i] = Some(ev.tick);
        }
        self.pos = ev.pos;
        self.out.last_tick = ev.tick;
    }

    fn finish(&mut self, _summary: &Summary) -> std::io::Result<()> {
        self.flush();
        Ok(())
    }
}
