//! Step generation, split between two priorities:
//!
//! - [`prep::Preparer`] (parse/plan task) turns planner blocks into short
//!   constant-rate [`Segment`]s and pushes them into a lock-free spsc queue;
//! - [`Stepper`] (step timer interrupt) pops segments and runs Bresenham
//!   across the axes, one timer event at a time.
//!
//! A segment carries a copy of its block's Bresenham numbers, so the
//! interrupt never reads memory the planner task writes: it only pops the
//! queue's consumer end and reads [`Realtime`] atomics.
//!
//! Wiring (RTIC app and host-sim do the same):
//! - one `static RT: Realtime`; the USB interrupt calls `feed_hold`,
//!   `cycle_start`, `set_*_override`, `request_reset` on it;
//! - `heapless::spsc::Queue<Segment, N>` split once: the parse/plan task owns
//!   the `Producer` (it implements [`prep::SegmentSink`]) and calls
//!   `Machine::poll` whenever the step interrupt took a segment or a command
//!   arrived; the step interrupt owns the `Consumer` and the [`Stepper`]:
//!   [`driver::StepDriver::on_interrupt`] runs [`Stepper::on_event`] and
//!   drives the pins and the timer through the hardware seams (pulse
//!   edges, direction setup, enable delay, stop; see [`driver`]);
//! - `ticks == 0` means the stepper went idle: the driver stops the timer.
//!   Whenever the queue is not empty and the driver is not running
//!   ([`Realtime::stepping`]), the task pends the step interrupt, which
//!   starts it (this also lets the stepper drop flushed segments).

pub mod driver;
pub mod prep;
pub mod sink;
#[cfg(test)]
mod tests;

// Defined in `seams`, where the step pins' trait takes them; here too
// because the board app and bench-target name them from the stepper.
pub use crate::seams::{StepConfig, Switches};

use crate::realtime::{Realtime, Trip, SENSE_EXTRA, SENSE_FLUSH, SENSE_HARD, SENSE_WATCH};
use crate::AXES;

/// Highest smoothing level: at low step rates the Bresenham runs at up to
/// 2^3 times the dominant axis's rate so slower axes step at evenly spaced times.
pub use crate::planner::interval::MAX_AMASS;

/// A run of timer events at one constant period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Timer events in this segment (dominant-axis steps << `amass`).
    pub events: u32,
    /// Ticks between events.
    pub period: u32,
    pub amass: u8,
    /// First segment of a block: restart Bresenham with the numbers below.
    pub new_block: bool,
    /// The block's steps per axis and event count.
    pub steps: [u32; AXES],
    pub count: u32,
    pub dir_mask: u8,
    /// Homing switches stop the stepper at once; a probe trip is only
    /// recorded (the planner task then ramps down like a hold).
    pub watch: crate::planner::Watch,
    /// Path speed at the end of this segment reaches zero (end of motion
    /// or completed hold): running dry after it is not an underrun.
    pub end_of_motion: bool,
    /// Realtime generation this segment belongs to (older ones are dropped).
    pub generation: u32,
    /// Path speed during this segment, mm/min (status reports, traces).
    pub speed_mm_min: f32,
    /// Source line of the block.
    pub line: u32,
    /// A segment of a backlash take-up block ([`Block::takeup`]): its
    /// steps turn the motors without moving the tool, so they are not
    /// counted in the position (they go to [`Realtime::takeup`]).
    ///
    /// [`Block::takeup`]: crate::planner::Block::takeup
    pub takeup: bool,
    /// Laser mode's view of this segment: 0 when it does not cut (rapid,
    /// homing, probing, dwell, wait), else the path speed over the
    /// programmed feed (M4 scales the power with it).
    pub cut: f32,
}

/// What one timer event does to the pins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepEvent {
    /// Logical directions after this event (bit set: negative).
    pub dir_mask: u8,
    /// Axes that step at this event.
    pub step_mask: u8,
    /// Ticks until the next event; 0: stop the timer (idle or stopped).
    pub ticks: u32,
}

/// What the interrupt keeps of the running segment, pre-computed once per
/// segment so an event is a handful of adds and compares.
///
/// `repr(C)`, the per-event fields first: with them (and [`Stepper`]'s)
/// within 124 bytes of the struct's start, Thumb's 16-bit loads and
/// stores reach them, so the common step is fewer flash lines (each cold
/// line costs the flash's wait states; bench-target).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
struct Running {
    /// Per-event Bresenham increments (steps << (MAX_AMASS - amass)).
    inc: [u32; AXES],
    /// Position change per step of each axis (±1, from the direction).
    delta: [i32; AXES],
    threshold: u32,
    period: u32,
    /// What takes this segment's events off the plain path, against
    /// [`Realtime`]'s attention byte: [`SENSE_WATCH`] (it watches a limit
    /// or the probe), [`SENSE_HARD`] (hard limits apply if armed) and
    /// [`SENSE_FLUSH`] (always: a flush stops any segment).
    sense: u8,
    /// The segment steps an axis past the fourth (B, C): only then does
    /// the step event run theirs.
    extra: bool,
    /// False for dwells: a switch that is already closed while standing
    /// still is not a new event.
    moving: bool,
    watch: crate::planner::Watch,
    generation: u32,
    speed_mm_min: f32,
    line: u32,
}

impl Running {
    fn sense(&self) -> u8 {
        let w = self.watch;
        let watch = (self.moving && w.limits != 0) || w.probe != 0;
        let hard = self.moving && !w.homing;
        let extra = u8::from(self.extra) * SENSE_EXTRA;
        (u8::from(watch) * SENSE_WATCH) | (u8::from(hard) * SENSE_HARD) | SENSE_FLUSH | extra
    }
}

/// The interrupt half: Bresenham over the current segment. `repr(C)`,
/// the per-event fields first (see `Running`).
#[derive(Debug)]
#[repr(C)]
pub struct Stepper {
    run: Running,
    acc: [u32; AXES],
    position: [i32; AXES],
    /// Events left in the running segment (0: none running).
    left: u32,
    pub cfg: StepConfig,
    dir: u8,
    halted: Option<u32>,
    last_end: bool,
    /// A segment was popped since [`Stepper::take_popped`] (the task then
    /// has room to fill).
    popped: bool,
}

impl Stepper {
    pub fn new(cfg: StepConfig) -> Self {
        Stepper {
            cfg,
            run: Running::default(),
            left: 0,
            acc: [0; AXES],
            position: [0; AXES],
            dir: 0,
            halted: None,
            last_end: true,
            popped: false,
        }
    }

    /// Position in steps (the tool's: backlash take-up steps are not
    /// counted, see [`Segment::takeup`]).
    pub fn position(&self) -> [i32; AXES] {
        self.position
    }
    /// Where the motors stand, in steps: [`Self::position`] plus the
    /// take-up steps loaded so far ([`Realtime::takeup`]) less those of the
    /// running take-up segment still to come. For host-sim, which follows
    /// the pins; never on the step path.
    pub fn motor_position(&self, rt: &Realtime) -> [i32; AXES] {
        let takeup = rt.takeup();
        let running = self.left > 0 && self.run.delta == [0; AXES];
        core::array::from_fn(|i| {
            let rest = if running {
                self.bresenham_steps(i, self.left)
            } else {
                0
            };
            let sign = if self.dir & (1 << i) != 0 { -1 } else { 1 };
            self.position[i]
                .wrapping_add(takeup[i])
                .wrapping_sub(sign * rest)
        })
    }
    /// Steps axis `i` makes in the next `events` events of the running
    /// segment: Bresenham adds `inc` per event and steps each time the
    /// accumulator reaches the threshold (at most once an event).
    fn bresenham_steps(&self, i: usize, events: u32) -> i32 {
        let t = u64::from(self.run.threshold).max(1);
        let n = (u64::from(self.acc[i]) + u64::from(self.run.inc[i]) * u64::from(events)) / t;
        n.min(i32::MAX as u64) as i32
    }
    /// Set the position (homing, power-up); only while idle.
    pub fn set_position(&mut self, rt: &Realtime, pos: [i32; AXES]) {
        self.position = pos;
        for (i, p) in pos.iter().enumerate() {
            rt.store_position(i, *p);
        }
    }
    /// Speed of the running segment, mm/min (0 when idle).
    pub fn speed_mm_min(&self) -> f32 {
        self.run.speed_mm_min
    }
    /// Source line of the running segment.
    pub fn line(&self) -> u32 {
        self.run.line
    }
    /// Whether a segment left the queue since the last call. Tested
    /// before it is cleared: the step event, which nearly always finds it
    /// false, then stores nothing.
    #[inline(always)]
    pub fn take_popped(&mut self) -> bool {
        if self.popped {
            self.popped = false;
            return true;
        }
        false
    }
    pub fn is_idle(&self) -> bool {
        self.left == 0
    }
    /// The motion it runs was flushed (a reset, alarm or halt made a new
    /// segment generation): what it computed last is the end of it.
    pub fn is_flushed(&self, rt: &Realtime) -> bool {
        self.run.generation != rt.generation()
    }

    #[inline(always)]
    fn event(&self, step_mask: u8, ticks: u32) -> StepEvent {
        StepEvent {
            dir_mask: self.dir,
            step_mask,
            ticks,
        }
    }

    fn idle(&mut self, rt: &Realtime) -> StepEvent {
        if !self.last_end && self.halted.is_none() {
            rt.count_underrun();
        }
        self.last_end = true;
        self.left = 0;
        if self.run.speed_mm_min != 0.0 {
            self.run.speed_mm_min = 0.0;
            rt.set_running(0.0, 0, 0.0);
        }
        rt.set_stepper_idle(true);
        self.event(0, 0)
    }

    fn trip(&mut self, rt: &Realtime, trip: Trip, mask: u8, generation: u32) -> StepEvent {
        rt.set_trip(trip, mask, &self.position);
        self.halted = Some(generation);
        self.idle(rt)
    }

    /// Take a popped segment; returns a direction-change event if the
    /// direction pins must settle before its first step.
    fn load(&mut self, rt: &Realtime, s: &Segment) -> Option<StepEvent> {
        if let Some(p) = rt.take_new_position() {
            self.position = p;
        }
        rt.set_stepper_idle(false);
        self.left = s.events;
        self.last_end = s.end_of_motion;
        let shift = MAX_AMASS.saturating_sub(s.amass);
        let mut watch = s.watch;
        // Tripped already: the rest of the move only ramps down.
        if watch.probe != 0 && rt.trip() == Trip::Probe {
            watch.probe = 0;
        }
        let dir = if s.new_block { s.dir_mask } else { self.dir };
        self.run = Running {
            inc: s.steps.map(|n| n << shift),
            threshold: s.count << MAX_AMASS,
            period: s.period,
            watch,
            generation: s.generation,
            speed_mm_min: s.speed_mm_min,
            line: s.line,
            moving: s.steps.iter().any(|&n| n != 0),
            // A take-up's steps turn the motors, not the tool's position.
            delta: core::array::from_fn(|i| match (s.takeup, dir & (1 << i) != 0) {
                (true, _) => 0,
                (false, true) => -1,
                (false, false) => 1,
            }),
            sense: 0,
            extra: s.steps.iter().skip(4).any(|&n| n != 0),
        };
        self.run.sense = self.run.sense();
        rt.set_running(s.speed_mm_min, s.line, s.cut);
        if s.new_block {
            self.acc = [self.run.threshold / 2; AXES];
        }
        if s.takeup {
            // Counted whole as the segment starts: exact once it ends
            // (a flush in the middle of one loses the position anyway).
            for i in 0..AXES {
                let n = self.bresenham_steps(i, s.events);
                rt.add_takeup(i, if dir & (1 << i) != 0 { -n } else { n });
            }
        }
        if s.new_block && s.dir_mask != self.dir {
            self.dir = s.dir_mask;
            return Some(self.event(0, self.cfg.dir_setup_ticks));
        }
        None
    }

    /// One timer event. `pop` takes the next segment from the queue;
    /// `sw` reads the switch pin levels now (only when the segment watches
    /// a switch or hard limits are armed). Inlined into the step driver's
    /// rise, its one hot caller (saves the call and the returned event's
    /// round trip through the stack, about 20 instructions a step).
    ///
    /// The common event, within a running segment of the current
    /// generation and reading no switch, is Bresenham alone; everything
    /// else (a new segment, a flush, a halt, the switches) is out of line.
    #[inline(always)]
    pub fn on_event(
        &mut self,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
        sw: impl FnOnce() -> Switches,
    ) -> StepEvent {
        // A halt leaves `left` at 0, so the one test covers it too.
        if self.left == 0 {
            if let Some(ev) = self.next_segment(rt, pop) {
                return ev;
            }
        }
        // A flush, a switch to read or B/C to step: one load, one AND.
        let attention = self.run.sense & rt.attention();
        let mut mask = 0;
        if attention == SENSE_HARD {
            // Hard limits alone, the common case while they are armed:
            // the switch read and one test stay inline (a closed switch
            // goes out of line to trip). bench-target: the whole path
            // with hard limits on cost 414 cycles, 124 over it with them
            // off, when this went through `attend` (a call, the flush's
            // atomic read-modify-write and the full switch logic).
            let s = sw();
            if s.limits ^ self.cfg.limit_invert != 0 {
                if let Some(ev) = self.check_switches(rt, s) {
                    return ev;
                }
            }
        } else if attention != 0 {
            match self.attend(rt, pop, sw) {
                Ok(extra) => mask = extra,
                Err(ev) => return ev,
            }
        }
        // Written out per axis: the size-optimised build keeps a loop,
        // and its counter cost more than the axes' own work. B and C
        // (slots past AXES compile to nothing) step in `attend`, which a
        // segment moving them always takes ([`SENSE_EXTRA`]): unrolled
        // here they cost 36 cycles of bench-target's step path, behind a
        // test of their own 20 (the branch lands on a cold flash line).
        const _: () = assert!(AXES <= 6);
        let t = self.run.threshold;
        mask |= self.axis::<0>(rt, t)
            | self.axis::<1>(rt, t)
            | self.axis::<2>(rt, t)
            | self.axis::<3>(rt, t);
        self.left -= 1;
        self.event(mask, self.run.period)
    }

    /// One axis's Bresenham step: its bit in the step mask if it steps.
    /// An axis without steps in this segment (its increment 0, its
    /// accumulator below the threshold) runs the same add, compare and
    /// store: no taken branch, which costs more than the store once flash
    /// wait states are counted (bench-target, issue 28).
    /// A slot `I` past [`AXES`] is no axis: the constant test folds away,
    /// and `I % AXES` keeps the (dead) indexing in bounds for the compiler.
    #[inline(always)]
    fn axis<const I: usize>(&mut self, rt: &Realtime, threshold: u32) -> u8 {
        if I >= AXES {
            return 0;
        }
        let i = I % AXES;
        let inc = self.run.inc[i];
        let acc = self.acc[i] + inc;
        if acc < threshold {
            self.acc[i] = acc;
            return 0;
        }
        self.acc[i] = acc - threshold;
        let p = self.position[i] + self.run.delta[i];
        self.position[i] = p;
        rt.store_position(i, p);
        1 << i
    }

    /// Takes a computed event's steps back out of the position: the driver
    /// dropped it unpulsed (a halt came between its computation and its
    /// rise). The event is the running segment's, so each step it counted
    /// was that segment's `delta`: nothing for a take-up's steps, which the
    /// position never counted.
    #[cold]
    pub fn take_back(&mut self, rt: &Realtime, ev: &StepEvent) {
        for i in 0..AXES {
            if ev.step_mask & (1 << i) != 0 {
                self.position[i] -= self.run.delta[i];
                rt.store_position(i, self.position[i]);
            }
        }
    }

    /// The running segment ended or was flushed, or a halt holds: takes the
    /// next segment of the current generation. `Some`: the event to return
    /// instead of a step (idle, or a direction change before the first).
    ///
    /// `#[cold]` (and `attend`, `check_switches`, the driver's
    /// `poll_cold`): the compiler then lays the common step out as one
    /// straight run of flash lines, each line a cold one costs 3 wait
    /// states (bench-target with hard limits: 322 -> 315 cycles when made).
    #[inline(never)]
    #[cold]
    fn next_segment(
        &mut self,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
    ) -> Option<StepEvent> {
        let generation = rt.generation();
        if let Some(g) = self.halted {
            if g == generation {
                return Some(self.idle(rt));
            }
            self.halted = None;
        }
        // A flush (reset, alarm) stops the running segment at once, not at its end.
        if self.left > 0 && self.run.generation != generation {
            self.left = 0;
            self.last_end = true;
        }
        while self.left == 0 {
            let Some(s) = pop() else {
                return Some(self.idle(rt));
            };
            self.popped = true;
            if s.generation != generation {
                continue;
            }
            if let Some(ev) = self.load(rt, &s) {
                return Some(ev);
            }
        }
        None
    }

    /// The attention byte has one of this segment's reasons: a flush
    /// (the running segment is dropped at once, not at its end), then the
    /// switches, then B and C. `Err`: the event to return instead of a
    /// step; `Ok`: B's and C's step bits of this event.
    #[inline(never)]
    #[cold]
    fn attend(
        &mut self,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
        sw: impl FnOnce() -> Switches,
    ) -> Result<u8, StepEvent> {
        if rt.take_flush() && self.run.generation != rt.generation() {
            if let Some(ev) = self.next_segment(rt, pop) {
                return Err(ev);
            }
        }
        if self.run.sense & rt.attention() & (SENSE_WATCH | SENSE_HARD) != 0 {
            if let Some(ev) = self.check_switches(rt, sw()) {
                return Err(ev);
            }
        }
        let t = self.run.threshold;
        Ok(if self.run.extra {
            self.axis::<4>(rt, t) | self.axis::<5>(rt, t)
        } else {
            0
        })
    }

    /// Homing and probe watches and hard limits, on the levels read now.
    /// `Some`: the event to return instead of a step (a trip).
    #[inline(never)]
    #[cold]
    fn check_switches(&mut self, rt: &Realtime, sw: Switches) -> Option<StepEvent> {
        let generation = self.run.generation;
        let watch = self.run.watch;
        let lim = sw.limits ^ self.cfg.limit_invert;
        if lim != 0 && self.run.moving {
            if watch.limits & lim != 0 {
                return Some(self.trip(rt, Trip::Homing, watch.limits & lim, generation));
            }
            if rt.limits_armed() && !watch.homing {
                return Some(self.trip(rt, Trip::HardLimit, lim, generation));
            }
        }
        if watch.probe != 0 {
            let probe = sw.probe ^ self.cfg.probe_invert;
            if (watch.probe == 1 && probe) || (watch.probe == 2 && !probe) {
                // Record where it tripped and keep stepping: the planner task
                // ramps down within the acceleration limit and flushes the rest.
                rt.set_trip(Trip::Probe, 0, &self.position);
                self.run.watch.probe = 0;
                self.run.sense = self.run.sense();
            }
        }
        None
    }
}
