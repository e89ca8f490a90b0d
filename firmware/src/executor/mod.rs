//! The executor, the sequencer: takes [`Command`]s in program order, turns
//! them into [`Move`]s (arcs and splines as chords, independent rapids as
//! legs, canned cycles and M6 as scripts) and hands every one to the motion
//! pipeline through its one gateway, [`Pipeline::submit`]; runs homing,
//! G27 and probing as small state machines; keeps alarms and the
//! position-lost flag. It never touches the planner or the preparer: the
//! pipeline ([`crate::motion`]) owns them and the motion settings.
//!
//! It lives in the parse/plan task. It talks to the step interrupt only
//! through the pipeline and [`Realtime`].

mod error;
mod homing;
mod pending;
mod script;
mod submit;

pub use error::MachineError;
pub use homing::Homing;
pub use script::ToolEvent;

use crate::arc::{ArcChords, SplineChords};
use crate::command::{Arc, AxisMask, Command, Feed, Pos, ProbeKind, Spline};
use crate::motion::{Move, Pipeline};
use crate::planner::{Curve, Speed, Watch};
use crate::realtime::{Realtime, Trip};
use crate::seams::{StepConfig, Switches};
use crate::settings::{RapidMode, Settings};
use crate::stepper::prep::SegmentSink;
use crate::AXES;

/// Chords (arc, spline or rapid legs) the executor plans in one call: a
/// bound on the task's work per pass, above the planner ring (a productive
/// chord takes a slot) so it never limits planning.
pub const CHORDS_PER_CALL: u32 = 256;

/// What kind of move a path vertex ends (for traces and plots).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    Rapid,
    Feed,
    Arc,
    Spline,
    Probe,
    Home,
}

/// A move's geometry as commanded, before arcs and splines become chords.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Geometry<'a> {
    /// A line, rapid (independent legs included: they stay within its
    /// box), probing or homing move, straight to here.
    Straight(&'a Pos),
    Arc(&'a Arc),
    Spline(&'a Spline),
}

/// Things the executor reports as they happen.
#[derive(Clone, Debug, PartialEq)]
pub enum Note<'a> {
    /// The executor committed to a move from `start`, before any of it is
    /// planned. The fuzz targets check every step against these (an arc's
    /// box with its bulge), so the check does not trust the segmenter or
    /// the planner it checks.
    Move {
        line: u32,
        start: Pos,
        geometry: Geometry<'a>,
    },
    /// A straight piece of commanded path was planned, ending here (mm),
    /// at this requested speed (references such as bench-motion's time
    /// bound replan the job from these).
    Path {
        line: u32,
        kind: PathKind,
        end: Pos,
        speed: Speed,
    },
    /// Motion comes to a standstill here, in order with the path: a dwell
    /// (its length, s) or a command that waits for motion to end (0).
    Stop { line: u32, seconds: f32 },
    /// A command failed or an alarm went off while running.
    Error { line: u32, error: MachineError },
    /// A non-motion command ran, in order with motion.
    Executed { line: u32, command: &'a Command },
    /// G38.x finished: where the probe tripped (or the move ended).
    Probed {
        line: u32,
        position: Pos,
        contact: bool,
    },
    /// Homing finished for these axes; the position was redefined.
    Homed { axes: AxisMask },
}

#[derive(Clone, Debug)]
enum Chords {
    Arc(ArcChords),
    Spline(SplineChords),
    /// Legs of an independent-axis rapid.
    Legs {
        pts: [Pos; AXES],
        n: usize,
        i: usize,
    },
}

/// Tagged, `None` first: a zero byte (the placeholder's, see there).
#[derive(Clone, Debug)]
#[repr(u8)]
enum Pending {
    None,
    Chords {
        chords: Chords,
        speed: Speed,
        line: u32,
    },
    Sync {
        command: Command,
        line: u32,
    },
    ProbeWait {
        end: Pos,
        speed: Speed,
        kind: ProbeKind,
        line: u32,
    },
    ProbeRun {
        kind: ProbeKind,
        line: u32,
    },
    /// The probe tripped at `at`; the move is ramping down before the rest
    /// of it is dropped.
    ProbeStop {
        at: Pos,
        line: u32,
    },
    Homing(Homing),
    /// An error found after its line was acknowledged ([`Machine::fault`]):
    /// the motion ramps down, then `error` becomes the alarm.
    Fault {
        error: MachineError,
        line: u32,
    },
}

/// Machine state as reported to the operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    Idle,
    Run,
    Hold,
    Homing,
    Alarm,
}

/// `Option<(Pos, bool)>` with a zero `None` (the niche of
/// `Option<(Pos, bool)>` is a 2 in the `bool`; see `Machine::placeholder`).
#[derive(Clone, Copy, Debug)]
#[repr(u8)]
enum Probed {
    None,
    At(Pos, bool),
}

/// The executor. `N` is the planner ring size.
#[derive(Debug)]
pub struct Machine<const N: usize> {
    /// Where every motion goes ([`Pipeline::submit`]); shells and tests
    /// read the planner and the preparer through it.
    pub motion: Pipeline<N>,
    pending: Pending,
    alarm: Option<MachineError>,
    position_lost: bool,
    homed: AxisMask,
    /// End of everything accepted so far, mm (where the next command starts).
    commanded: Pos,
    override_epoch: u32,
    switches: Switches,
    /// Last G38.x result ([`Machine::probe_result`]).
    probed: Probed,
    /// A canned cycle or tool change being expanded, and its line.
    script: Option<(script::Script, u32)>,
    tool_event: Option<ToolEvent>,
    /// Trip Z of the first tool the setter measured (`$211=2`).
    tool_reference: Option<f32>,
    /// The last fault, until the session takes it to report it.
    fault: Option<(MachineError, u32)>,
}

impl<const N: usize> Machine<N> {
    pub fn new(settings: Settings, tick_hz: u32) -> Self {
        Machine {
            motion: Pipeline::new(settings, tick_hz),
            pending: Pending::None,
            alarm: None,
            position_lost: false,
            homed: 0,
            commanded: [0.0; AXES],
            override_epoch: 0,
            switches: Switches::default(),
            probed: Probed::None,
            script: None,
            tool_event: None,
            tool_reference: None,
            fault: None,
        }
    }

    /// A machine of all zero bits, built at compile time: the board's
    /// static slot starts as this and [`Machine::rebuild`] turns it into
    /// `Machine::new(settings, tick_hz)` in place before anything else
    /// touches it (zero settings would divide by a zero `steps_per_mm`).
    /// Built at run time, `Machine::new` needs the whole machine (about
    /// 11 KB with 64 blocks) as a temporary on the stack, which the F401's
    /// 20 KiB stack cannot spare; zero bits put the static in `.bss`
    /// rather than `.data`, whose load image cost 11 KB of flash
    /// (`cargo xtask build` checks where the slot lands). The enums it
    /// holds are tagged so that their `None` is zero (`Pending`, `Probed`,
    /// `MachineError`, `ToolEvent`, `Script`).
    pub const fn placeholder() -> Self {
        Machine {
            motion: Pipeline::zeroed(),
            pending: Pending::None,
            alarm: None,
            position_lost: false,
            homed: 0,
            commanded: [0.0; AXES],
            override_epoch: 0,
            switches: Switches {
                limits: 0,
                probe: false,
            },
            probed: Probed::None,
            script: None,
            tool_event: None,
            tool_reference: None,
            fault: None,
        }
    }

    /// [`Machine::new`], in place (`$n=`): the planner keeps its ring's
    /// storage ([`Pipeline::rebuild`]), so no second machine is built on the
    /// stack (`Machine::new`'s frame is 15.6 KB on the F401 image). The
    /// sequencer's fields start as in `new`, which are the placeholder's:
    /// taken from that constant, no second pipeline is built either.
    pub fn rebuild(&mut self, settings: Settings, tick_hz: u32) {
        self.motion.rebuild(settings, tick_hz);
        let Machine {
            motion: _,
            pending,
            alarm,
            position_lost,
            homed,
            commanded,
            override_epoch,
            switches,
            probed,
            script,
            tool_event,
            tool_reference,
            fault,
        } = Machine::<0>::placeholder();
        self.pending = pending;
        self.alarm = alarm;
        self.position_lost = position_lost;
        self.homed = homed;
        self.commanded = commanded;
        self.override_epoch = override_epoch;
        self.switches = switches;
        self.probed = probed;
        self.script = script;
        self.tool_event = tool_event;
        self.tool_reference = tool_reference;
        self.fault = fault;
    }

    /// Last G38.x result: position (mm) and whether contact happened.
    pub fn probe_result(&self) -> Option<(Pos, bool)> {
        match self.probed {
            Probed::None => None,
            Probed::At(p, c) => Some((p, c)),
        }
    }

    pub fn settings(&self) -> &Settings {
        self.motion.settings()
    }
    pub fn step_config(&self) -> StepConfig {
        self.motion.step_config()
    }
    /// Ready for the next command (nothing left to feed to the planner).
    pub fn ready(&self) -> bool {
        matches!(self.pending, Pending::None) && self.script.is_none() && self.motion.has_room()
    }

    /// [`ready`](Self::ready), and the planner may take more before the
    /// next [`poll`](Self::poll) fills the segment queue
    /// ([`crate::motion::PLAN_BURST_SCURVE`]): what a caller feeding
    /// commands in a loop checks.
    pub fn may_plan(&self) -> bool {
        self.ready() && self.motion.may_plan()
    }

    /// The planner's passes' work so far ([`crate::planner::Planner::work`]).
    pub fn plan_work(&self) -> u32 {
        self.motion.planner().work()
    }
    pub fn alarm(&self) -> Option<MachineError> {
        self.alarm
    }
    pub fn position_lost(&self) -> bool {
        self.position_lost
    }
    pub fn homed(&self) -> AxisMask {
        self.homed
    }
    /// Where the next command starts, machine mm.
    pub fn commanded_position(&self) -> Pos {
        self.commanded
    }
    pub fn state(&self, rt: &Realtime) -> State {
        if self.alarm.is_some() {
            State::Alarm
        } else if matches!(self.pending, Pending::Homing(_)) {
            State::Homing
        } else if (self.motion.hold() != crate::stepper::prep::Hold::Running
            && !self.motion.cancelling())
            || rt.hold_requested()
        {
            State::Hold
        } else if self.drained(rt) {
            State::Idle
        } else {
            State::Run
        }
    }

    /// Alarm without motion to stop (a sleep's wake-up): the position is
    /// not trusted until `$X` or homing.
    pub fn lock(&mut self, e: MachineError) {
        if self.alarm.is_none() {
            self.alarm = Some(e);
        }
    }

    /// Set the position at power-up (or from a test), mm.
    pub fn set_position(&mut self, rt: &Realtime, mm: &Pos) -> Result<(), MachineError> {
        let steps = self.motion.to_steps(mm)?;
        self.motion.redefine(rt, &steps);
        self.commanded = *mm;
        Ok(())
    }

    fn steps_to_mm(&self, steps: &[i32; AXES]) -> Pos {
        self.motion.steps_to_mm(steps)
    }

    /// Idle, the one definition both shells use (the session's
    /// `MotionPort::motion_idle`, host-sim's `Sim::idle`): nothing waits to
    /// be planned (no homing, probe, script or full planner) and no motion
    /// is left ([`Self::motion_idle`]).
    pub fn idle(&self, rt: &Realtime, sink: &impl SegmentSink) -> bool {
        self.ready() && self.motion_idle(rt, sink)
    }

    /// No motion left: nothing planned, prepared, queued for the step
    /// interrupt or being stepped ([`Pipeline::motion_idle`]).
    pub fn motion_idle(&self, rt: &Realtime, sink: &impl SegmentSink) -> bool {
        self.motion.motion_idle(rt, sink)
    }

    /// [`Self::motion_idle`] as far as the machine sees without the segment
    /// queue: the status report's Idle ([`Pipeline::drained`]).
    fn drained(&self, rt: &Realtime) -> bool {
        self.motion.drained(rt)
    }

    fn speed(feed: Feed) -> Result<Speed, MachineError> {
        match feed {
            Feed::PerMin(f) if f > 0.0 && f.is_finite() => Ok(Speed::Feed(f / 60.0)),
            Feed::InverseTime(v) if v > 0.0 && v.is_finite() => Ok(Speed::Time(60.0 / v)),
            _ => Err(MachineError::InvalidFeed),
        }
    }

    /// Soft limits: the envelope is `[-travel, 0]` when homing towards
    /// positive, `[0, travel]` towards negative; travel 0 means unlimited.
    /// The box `lo`..`hi` must lie inside it (a jog's target is checked
    /// before its `ok`, as GRBL's error 15).
    pub fn check_soft(&self, lo: &Pos, hi: &Pos) -> Result<(), MachineError> {
        let s = self.motion.settings();
        if !s.soft_limits {
            return Ok(());
        }
        const EPS: f32 = 1e-3;
        for i in 0..AXES {
            let t = s.axes[i].max_travel;
            if t <= 0.0 {
                continue;
            }
            let (min, max) = if s.homing_dir_invert & (1 << i) != 0 {
                (0.0, t)
            } else {
                (-t, 0.0)
            };
            if lo[i] < min - EPS || hi[i] > max + EPS {
                return Err(MachineError::SoftLimit { axis: i as u8 });
            }
        }
        Ok(())
    }

    fn push_line(
        &mut self,
        end: &Pos,
        speed: Speed,
        watch: Watch,
        line: u32,
        kind: PathKind,
        obs: &mut dyn FnMut(Note),
    ) -> Result<(), MachineError> {
        self.motion.submit(Move::Line {
            end: *end,
            speed,
            watch,
            line,
        })?;
        obs(Note::Move {
            line,
            start: self.commanded,
            geometry: Geometry::Straight(end),
        });
        self.commanded = *end;
        obs(Note::Path {
            line,
            kind,
            end: *end,
            speed,
        });
        Ok(())
    }

    /// Drop everything queued and take the stepper's position as truth.
    fn flush(&mut self, rt: &Realtime) {
        self.commanded = self.motion.flush(rt);
    }

    fn raise_alarm(
        &mut self,
        rt: &Realtime,
        e: MachineError,
        line: u32,
        obs: &mut dyn FnMut(Note),
    ) {
        self.flush(rt);
        self.pending = Pending::None;
        self.script = None;
        self.alarm = Some(e);
        obs(Note::Error { line, error: e });
    }

    /// Run the executor's background work: reset and trips, overrides,
    /// chords, synced commands, homing/probing, then fill the segment queue.
    /// `sw` are the switch pin levels as read now.
    pub fn poll(
        &mut self,
        rt: &Realtime,
        sink: &mut impl SegmentSink,
        sw: Switches,
        obs: &mut dyn FnMut(Note),
    ) {
        self.switches = sw;
        let estop = rt.estop();
        if rt.take_reset() {
            // Position is lost only where the stepper moves: a finished
            // hold, a dwell or motion not yet started stop exactly.
            let moving = !self.motion_idle(rt, sink) && !rt.at_rest();
            self.flush(rt);
            self.pending = Pending::None;
            self.script = None;
            rt.clear_hold();
            if moving {
                self.position_lost = true;
            }
            if moving && !estop {
                self.alarm = Some(MachineError::ResetDuringMotion);
                obs(Note::Error {
                    line: 0,
                    error: MachineError::ResetDuringMotion,
                });
            }
        }
        // A pressed e-stop latches the alarm, also when it was already
        // pressed at power-up (no edge then).
        if estop && self.alarm != Some(MachineError::EStop) {
            if !self.motion_idle(rt, sink) {
                self.position_lost = true;
            }
            rt.clear_hold();
            self.raise_alarm(rt, MachineError::EStop, 0, obs);
        }
        // A failed hardware path latches its alarm the same way, for good.
        if let Some(fault) = rt.hw_fault() {
            let e = MachineError::HardwareFault { fault };
            if self.alarm != Some(e) && !estop {
                if !self.motion_idle(rt, sink) {
                    self.position_lost = true;
                }
                rt.clear_hold();
                self.raise_alarm(rt, e, 0, obs);
            }
        }
        let epoch = rt.override_epoch();
        if epoch != self.override_epoch {
            self.override_epoch = epoch;
            self.motion
                .set_overrides(rt.feed_override(), rt.rapid_override());
        }
        match rt.trip() {
            Trip::None => {}
            Trip::HardLimit => {
                let mask = rt.trip_mask();
                self.position_lost = true;
                let line = self.motion.line();
                self.raise_alarm(rt, MachineError::HardLimit { mask }, line, obs);
            }
            Trip::Probe => match self.pending {
                // Stopping dead would need infinite deceleration: the trip
                // position is kept and the move ramps down like a hold.
                Pending::ProbeRun { line, .. } => {
                    let at = self.steps_to_mm(&rt.trip_position());
                    self.pending = Pending::ProbeStop { at, line };
                    self.motion.cancel_motion();
                }
                Pending::ProbeStop { at, line } => {
                    if self.motion.stopped(rt, sink) {
                        // The flush takes the stop point (past the trip) as
                        // the commanded position; the interpreter resyncs to it.
                        self.flush(rt);
                        self.probed = Probed::At(at, true);
                        obs(Note::Probed {
                            line,
                            position: at,
                            contact: true,
                        });
                        self.pending = Pending::None;
                    }
                }
                // Stopping for a fault already: its alarm's flush clears
                // the trip.
                Pending::Fault { .. } => {}
                _ => {
                    self.flush(rt);
                    self.pending = Pending::None;
                }
            },
            Trip::Homing => {
                let (mask, at) = (rt.trip_mask(), rt.trip_position());
                self.flush(rt);
                if let Pending::Homing(h) = &mut self.pending {
                    h.tripped(mask, &at);
                }
            }
        }
        if let Pending::Chords { line, .. } = self.pending {
            if let Err(e) = self.feed_chords(obs) {
                self.fault(e, line);
            }
        }
        self.end_fault(rt, sink, obs);
        if !matches!(self.pending, Pending::None | Pending::Chords { .. })
            && self.motion_idle(rt, sink)
        {
            self.run_pending(rt, obs);
        }
        self.run_script(rt, obs);
        // Before any new segment is queued: a homing move, which seeks the
        // switches, never runs armed.
        rt.set_limits_armed(self.limits_armed(rt));
        self.motion.fill(rt, sink);
    }

    /// Hard limits apply (`$21`), except while homing (it seeks the
    /// switches) and in alarm (nothing moves; a switch still closed after a
    /// trip must not raise the alarm again and again).
    pub fn limits_armed(&self, rt: &Realtime) -> bool {
        self.motion.settings().hard_limits
            && !matches!(self.state(rt), State::Homing | State::Alarm)
    }
}
