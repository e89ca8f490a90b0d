//! What a simulation run reports, as a stream: the engine calls a
//! [`Recorder`] as things happen, so a multi-million-step job never has to be
//! held in memory. Writers for CSV traces, VCD, SVG plots and the JSON summary
//! implement this trait; several can be chained with [`Tee`].

use burin::executor::Geometry;
use burin::AXES;

/// One step-timer event that changed an output: after it, the axes stand at `pos`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinEvent {
    /// Virtual time of the rising step edge, in timer ticks.
    pub tick: u64,
    /// Direction pin levels after this event (bit n: axis n negative), before inversion.
    pub dir_mask: u8,
    /// Axes that stepped at this event (rising edge at `tick`; the falling
    /// edge follows as [`Recorder::step_fall`], at least
    /// `RunInfo::pulse_ticks` later).
    pub step_mask: u8,
    /// Tick at which the direction pins last changed (for setup-time checks).
    pub dir_changed_tick: u64,
    /// Machine position in steps after this event.
    pub pos: [i64; AXES],
}

/// What kind of commanded move a path vertex ends: the executor's own
/// type, so the recorders and the core cannot drift apart.
pub use burin::executor::PathKind;

/// The commanded path with its requested speeds, for references that
/// replan the job independently of the planner (bench-motion's time bound).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathEvent {
    /// A straight piece (arcs and splines arrive as their chords) ending at
    /// `to_mm`, at most at `feed_mm_s` (infinite for rapids), or taking
    /// `seconds` when the feed is given as a time (G93).
    To {
        kind: PathKind,
        to_mm: [f32; AXES],
        feed_mm_s: f32,
        seconds: Option<f32>,
    },
    /// Motion stops here: a dwell of `seconds`, or a synced command (0).
    Stop { seconds: f32 },
}

/// Static facts about the run, known before the first event.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInfo {
    pub tick_hz: u32,
    pub axes: [AxisInfo; AXES],
    /// Step pulse width in ticks.
    pub pulse_ticks: u32,
    /// Direction setup time in ticks.
    pub dir_setup_ticks: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct AxisInfo {
    pub name: char,
    pub steps_per_mm: f32,
    pub max_rate_mm_min: f32,
    pub max_accel_mm_s2: f32,
    pub travel_mm: f32,
}

/// An error met while running the job.
#[derive(Clone, Debug, PartialEq)]
pub struct RunError {
    /// 1-based source line.
    pub line: u32,
    /// Stable numeric code (the core's error code).
    pub code: u16,
    pub message: String,
}

/// End-of-run figures; the JSON summary's fields are these, by name.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    pub lines: u32,
    pub moves: u32,
    pub job_time_s: f64,
    pub distance_mm: f64,
    pub max_feed_mm_min: f64,
    pub steps: [u64; AXES],
    pub final_position_steps: [i64; AXES],
    pub final_position_mm: [f64; AXES],
    pub final_work_position_mm: [f64; AXES],
    pub planner_underruns: u32,
    pub errors: Vec<RunError>,
    /// Largest distance from the modelled tool (behind the machine's
    /// slack, `MachineConfig::slack_mm`) to the commanded path, mm,
    /// measured at every step interrupt.
    pub max_tool_deviation_mm: f64,
}

/// Receives a run as it happens.
pub trait Recorder {
    fn start(&mut self, _info: &RunInfo) {}
    fn step_event(&mut self, _ev: &PinEvent) {}
    /// The step pins in `mask` fell at `tick` (the real end of the pulses
    /// the step driver raised; at least `RunInfo::pulse_ticks` after them).
    fn step_fall(&mut self, _tick: u64, _mask: u8) {}
    /// A commanded path vertex (arcs and splines arrive as their chords).
    fn commanded(&mut self, _line: u32, _kind: PathKind, _to_mm: [f32; AXES]) {}
    /// The same path as [`commanded`](Self::commanded), with speeds and stops.
    fn path(&mut self, _ev: &PathEvent) {}
    /// The executor committed to a move from `start` (machine mm), before
    /// planning it: an arc or spline as commanded, not its chords.
    fn motion(&mut self, _line: u32, _start: [f32; AXES], _geometry: &Geometry) {}
    /// Steps per mm changed (`$100`-`$103`, only while idle): step positions
    /// after this count in the new scale (the position was redefined).
    fn rescaled(&mut self, _steps_per_mm: [f32; AXES]) {}
    /// Commanded path speed at `tick`, recorded whenever it changes.
    fn velocity(&mut self, _tick: u64, _mm_per_min: f32) {}
    fn finish(&mut self, _summary: &Summary) -> std::io::Result<()> {
        Ok(())
    }
}

/// Records nothing.
pub struct Discard;
impl Recorder for Discard {}

/// Sends everything to several recorders.
pub struct Tee<'a>(pub Vec<&'a mut dyn Recorder>);

impl Recorder for Tee<'_> {
    fn start(&mut self, info: &RunInfo) {
        self.0.iter_mut().for_each(|r| r.start(info));
    }
    fn step_event(&mut self, ev: &PinEvent) {
        self.0.iter_mut().for_each(|r| r.step_event(ev));
    }
    fn step_fall(&mut self, tick: u64, mask: u8) {
        self.0.iter_mut().for_each(|r| r.step_fall(tick, mask));
    }
    fn commanded(&mut self, line: u32, kind: PathKind, to_mm: [f32; AXES]) {
        self.0
            .iter_mut()
            .for_each(|r| r.commanded(line, kind, to_mm));
    }
    fn path(&mut self, ev: &PathEvent) {
        self.0.iter_mut().for_each(|r| r.path(ev));
    }
    fn motion(&mut self, line: u32, start: [f32; AXES], geometry: &Geometry) {
        self.0
            .iter_mut()
            .for_each(|r| r.motion(line, start, geometry));
    }
    fn rescaled(&mut self, steps_per_mm: [f32; AXES]) {
        self.0.iter_mut().for_each(|r| r.rescaled(steps_per_mm));
    }
    fn velocity(&mut self, tick: u64, mm_per_min: f32) {
        self.0.iter_mut().for_each(|r| r.velocity(tick, mm_per_min));
    }
    fn finish(&mut self, summary: &Summary) -> std::io::Result<()> {
        for r in self.0.iter_mut() {
            r.finish(summary)?;
        }
        Ok(())
    }
}
