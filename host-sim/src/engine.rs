//! The discrete-event simulation: the firmware library's executor, planner,
//! preparer and stepper run against a virtual timer in `u64` ticks.
//!
//! Events at the same tick run in RTIC priority order: the step-timer event
//! (prio 3) first, then realtime input from "USB" (prio 2: hold, resume,
//! overrides, reset), then the parse/plan task (prio 1), which refills the
//! segment queue whenever the stepper took a segment. The step event and
//! USB input take no virtual time. The parse/plan task costs the
//! [`HostModel`](crate::config::HostModel) time per line and per block, and
//! job lines arrive over its link (see `engine/host.rs`). There are no threads,
//! clocks or hash maps, so two runs of the same job are identical event for
//! event.

mod deviation;
mod dma;
mod host;
mod job;
mod pins;
mod step_irq;
mod task;
mod world;

pub use dma::PulseDma;
use std::collections::VecDeque;

use burin::command::Command;
use burin::executor::{Machine, MachineError, Note};
use burin::planner::Speed;
use burin::realtime::Realtime;
use burin::stepper::driver::StepDriver;
use burin::stepper::{Segment, Stepper};
use burin::AXES;
use heapless::spsc::Queue;

use crate::config::{MachineConfig, Masks};
use crate::record::{AxisInfo, PathEvent, Recorder, RunError, RunInfo, Summary};
pub use job::run_job;
pub use pins::{Edge, VirtualHw};
pub use task::DeviceTask;
pub use world::World;

/// The board's queue sizes (the library's, so both shells use the same).
pub use burin::controller::{PLANNER_BLOCKS, SEGMENT_SLOTS};

/// Realtime input, delivered at a tick as the USB interrupt would.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    FeedHold,
    CycleStart,
    FeedOverride(u16),
    RapidOverride(u16),
    Reset,
}

/// A simulated machine.
pub struct Sim<'r> {
    cfg: MachineConfig,
    pub rt: Realtime,
    pub machine: Machine<PLANNER_BLOCKS>,
    pub queue: Queue<Segment, SEGMENT_SLOTS>,
    pub stepper: Stepper,
    pub world: World,
    /// The core's step interrupt, on [`VirtualHw`].
    driver: StepDriver,
    pub hw: VirtualHw,
    masks: Masks,
    now: u64,
    /// When the step interrupt enters next (None: not armed).
    next_step: Option<u64>,
    inputs: VecDeque<(u64, Input)>,
    lines: VecDeque<host::Line>,
    task: host::Task,
    rec: &'r mut dyn Recorder,
    /// Resume automatically after M0/M1 (a batch run has no operator).
    pub auto_resume: bool,
    /// The parse/plan task is `burin::controller` (a virtual board, see
    /// `device_sim`): [`Sim::run_until`] hands control back whenever the
    /// task must run, and only a kick starts the step timer.
    device_mode: bool,
    /// Device mode: the task is due now.
    task_wanted: bool,
    /// Device mode: the sender still has lines for the board (a planned
    /// stop meanwhile is a starved planner).
    pub input_pending: bool,
    /// Device mode: after the task's last pass the session waits for the
    /// machine to stop (`Device::syncing`), so a stop is not starvation.
    pub task_syncing: bool,
    stats: Stats,
}

#[derive(Default)]
struct Stats {
    moves: u32,
    steps: [u64; AXES],
    distance: f64,
    last_path: Option<[f32; AXES]>,
    errors: Vec<RunError>,
    last_speed: f32,
    /// The summary's max feed, from the steps (see `crate::feed`).
    feed: crate::feed::FeedMeter,
    dir: u8,
    dir_changed: u64,
    /// Step pin levels after the last store.
    step_level: u8,
    /// Planner blocks pushed (Path notes), for the task's cost.
    blocks: u64,
    /// Stops where the planner ran empty waiting for a line (link or task time).
    starved: u32,
    /// Steps per mm the recorder was last told of.
    steps_per_mm: [f32; AXES],
    /// Simulated work: step interrupts entered and task passes run.
    work: u64,
    /// The modelled tool against the commanded path.
    deviation: deviation::Deviation,
}

fn machine_error(line: u32, e: MachineError) -> RunError {
    RunError {
        line,
        code: e.code(),
        message: e.to_string(),
    }
}

impl<'r> Sim<'r> {
    pub fn new(cfg: &MachineConfig, rec: &'r mut dyn Recorder) -> Self {
        let rt = Realtime::new();
        let mut machine = Machine::new(cfg.settings, cfg.tick_hz);
        let mut stepper = Stepper::new(machine.step_config());
        let world = World::new(cfg);
        let irq = cfg.interrupts.ticks(cfg.tick_hz);
        let start = cfg.start_position_mm;
        // An out-of-range start position falls back to 0.
        if machine.set_position(&rt, &start).is_err() {
            let _ = machine.set_position(&rt, &[0.0; AXES]);
        }
        stepper.set_position(&rt, rt.position());
        let s = &cfg.settings;
        let sc = machine.step_config();
        let info = RunInfo {
            tick_hz: cfg.tick_hz,
            axes: std::array::from_fn(|i| AxisInfo {
                name: burin::AXIS_NAMES[i],
                steps_per_mm: s.axes[i].steps_per_mm,
                max_rate_mm_min: s.axes[i].max_rate,
                max_accel_mm_s2: s.axes[i].max_accel,
                travel_mm: s.axes[i].max_travel,
            }),
            pulse_ticks: sc.pulse_ticks,
            dir_setup_ticks: sc.dir_setup_ticks,
        };
        rec.start(&info);
        let stats = Stats {
            last_path: Some(machine.commanded_position()),
            feed: crate::feed::FeedMeter::new(
                cfg.tick_hz,
                s.axes.map(|a| a.steps_per_mm),
                s.axes.map(|a| a.max_rate),
            ),
            steps_per_mm: s.axes.map(|a| a.steps_per_mm),
            ..Stats::default()
        };
        Sim {
            cfg: cfg.clone(),
            rt,
            machine,
            queue: Queue::new(),
            stepper,
            world,
            driver: StepDriver::new(),
            hw: VirtualHw::new(irq, cfg.tick_hz, s.step_invert, s.dir_invert),
            masks: irq.masks,
            now: 0,
            next_step: None,
            inputs: VecDeque::new(),
            lines: VecDeque::new(),
            task: host::Task::new(&cfg.host, cfg.tick_hz),
            rec,
            auto_resume: true,
            device_mode: false,
            task_wanted: false,
            input_pending: false,
            task_syncing: false,
            stats,
        }
    }

    pub fn now(&self) -> u64 {
        self.now
    }
    pub fn tick_hz(&self) -> u32 {
        self.cfg.tick_hz
    }
    /// Simulated work so far: step interrupts entered and parse/plan task
    /// passes run. A measure of host effort that does not depend on how
    /// loaded the host is (the fuzz targets bound it per input).
    pub fn work(&self) -> u64 {
        self.stats.work
    }
    /// Errors so far.
    pub fn errors(&self) -> &[RunError] {
        &self.stats.errors
    }
    /// Last G38.x result (machine mm, contact).
    pub fn probe_result(&self) -> Option<([f32; AXES], bool)> {
        self.machine.probe_result()
    }

    /// Schedule realtime input at `tick` (kept in tick order; equal ticks in call order).
    pub fn input_at(&mut self, tick: u64, input: Input) {
        let at = self
            .inputs
            .iter()
            .position(|(t, _)| *t > tick)
            .unwrap_or(self.inputs.len());
        self.inputs.insert(at, (tick, input));
    }

    /// Queue a command as if line `line` produced it (no link time; one
    /// line's parse cost per line number).
    pub fn push_command(&mut self, line: u32, cmd: Command) {
        match self.lines.back_mut() {
            Some(l) if l.line == line && l.bytes == 0 && !l.taken => l.cmds.push_back(cmd),
            _ => self.push_line(line, 0, vec![cmd]),
        }
    }

    /// Queue the commands of one G-code line of `bytes` bytes (with its
    /// newline): it reaches the task over the link, then costs a line's
    /// parse time even when it holds no command.
    pub fn push_line(&mut self, line: u32, bytes: u32, cmds: Vec<Command>) {
        self.lines.push_back(host::Line::new(line, bytes, cmds));
    }

    fn apply_input(&mut self, i: Input) {
        match i {
            Input::FeedHold => self.rt.feed_hold(),
            Input::CycleStart => self.rt.cycle_start(),
            Input::FeedOverride(p) => self.rt.set_feed_override(p),
            Input::RapidOverride(p) => self.rt.set_rapid_override(p),
            Input::Reset => self.rt.request_reset(),
        }
    }

    /// True when nothing is moving, queued or pending: the machine is
    /// idle as the library defines it (`Machine::idle`), no host line waits
    /// and neither the task nor the step timer is due.
    pub fn idle(&self) -> bool {
        self.lines.is_empty()
            && self.task.wake.is_none()
            && self.machine.idle(&self.rt, &self.queue)
            && self.next_step.is_none()
    }

    /// Run until idle (or stuck on a hold nobody releases), then return.
    pub fn run(&mut self) {
        self.run_until(u64::MAX);
    }

    /// Run events up to and including `until`; afterwards the clock reads
    /// `until` (or later, if it already did).
    pub fn run_until(&mut self, until: u64) {
        if !self.device_mode {
            self.plan_task();
        }
        loop {
            while let Some(&(t, i)) = self.inputs.front() {
                if t > self.now {
                    break;
                }
                self.inputs.pop_front();
                self.apply_input(i);
                self.plan_task();
            }
            if self.device_mode && self.task_wanted {
                return;
            }
            // The task starts a stopped timer when it finds segments queued.
            if !self.device_mode
                && self.next_step.is_none()
                && !self.queue.is_empty()
                && self.now >= self.task.busy_until
            {
                self.next_step = Some(self.masks.unmasked_at(self.now));
            }
            let t_in = self.inputs.front().map(|(t, _)| *t);
            let t_task = self.task_due();
            let next = earliest(earliest(self.next_step, t_in), t_task);
            let next = match next {
                Some(n) => n,
                None if self.device_mode => {
                    self.advance_clock(until);
                    return;
                }
                None => {
                    if self.auto_resume
                        && self.machine.motion.hold() == burin::stepper::prep::Hold::Held
                    {
                        self.rt.cycle_start();
                        self.plan_task();
                        if !self.queue.is_empty() {
                            continue;
                        }
                    }
                    self.plan_task();
                    if self.queue.is_empty() && self.task_due().is_none() {
                        self.advance_clock(until);
                        return;
                    }
                    continue;
                }
            };
            if next > until {
                self.advance_clock(until);
                return;
            }
            self.now = next;
            if self.next_step == Some(next) {
                let before = self.queue.len();
                self.step_event();
                if self.queue.len() != before || self.next_step.is_none() {
                    self.plan_task();
                }
            }
            if t_task == Some(next) && self.task_due().is_some_and(|t| t <= next) {
                self.plan_task();
            }
        }
    }

    /// Nothing happens before `until`: virtual time still passes (a bounded
    /// run ends at its bound; an unbounded one stays at the last event).
    fn advance_clock(&mut self, until: u64) {
        if until != u64::MAX {
            self.now = self.now.max(until);
        }
    }

    /// Figures for the summary (`lines` and work offsets come from the caller).
    pub fn summary(&self, lines: u32, wco: [f32; AXES]) -> Summary {
        let s = &self.cfg.settings;
        let pos = self.rt.position();
        let mm: [f64; AXES] =
            std::array::from_fn(|i| pos[i] as f64 / s.axes[i].steps_per_mm as f64);
        Summary {
            lines,
            moves: self.stats.moves,
            job_time_s: self.now as f64 / self.cfg.tick_hz as f64,
            distance_mm: self.stats.distance,
            max_feed_mm_min: self.stats.feed.max_mm_min,
            steps: self.stats.steps,
            final_position_steps: std::array::from_fn(|i| pos[i] as i64),
            final_position_mm: mm,
            final_work_position_mm: std::array::from_fn(|i| mm[i] - wco[i] as f64),
            planner_underruns: self.rt.underruns() + self.stats.starved,
            max_tool_deviation_mm: self.stats.deviation.max_mm,
            errors: self.stats.errors.clone(),
        }
    }

    /// Hand the summary to the recorder.
    pub fn finish(&mut self, summary: &Summary) -> std::io::Result<()> {
        self.rec.finish(summary)
    }
}

/// The earlier of two optional times (a plain match: an iterator chain
/// here cost a quarter of the simulation's time).
#[inline]
fn earliest(a: Option<u64>, b: Option<u64>) -> Option<u64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

fn note(stats: &mut Stats, rec: &mut dyn Recorder, n: Note) {
    match n {
        Note::Path {
            line,
            kind: k,
            end,
            speed,
        } => {
            if let Some(p) = stats.last_path {
                let d2: f32 = p.iter().zip(&end).map(|(a, b)| (a - b) * (a - b)).sum();
                stats.distance += (d2 as f64).sqrt();
            }
            stats.last_path = Some(end);
            stats.deviation.point(end);
            stats.blocks += 1;
            rec.commanded(line, k, end);
            let (feed_mm_s, seconds) = match speed {
                Speed::Feed(v) => (v, None),
                Speed::Time(t) => (f32::INFINITY, Some(t)),
                Speed::Rapid => (f32::INFINITY, None),
            };
            rec.path(&PathEvent::To {
                kind: k,
                to_mm: end,
                feed_mm_s,
                seconds,
            });
        }
        Note::Stop { seconds, .. } => rec.path(&PathEvent::Stop { seconds }),
        Note::Error { line, error } => stats.errors.push(machine_error(line, error)),
        Note::Probed { position, .. } => {
            stats.last_path = Some(position);
        }
        Note::Move {
            line,
            start,
            geometry,
        } => {
            stats.deviation.point(start);
            rec.motion(line, start, &geometry);
        }
        Note::Homed { .. } => {}
        Note::Executed { .. } => {}
    }
}
