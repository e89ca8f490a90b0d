//! The segment preparer: walks the oldest planner block's speed profile in
//! steps of [`SEGMENT_S`] and emits one constant-rate [`Segment`] per step.
//!
//! The preparer always plans from the speed it actually has (`v`), so an
//! override, a hold, a resume or a newly appended block only ever changes
//! the profile of the remaining distance, and the block's step count is
//! handed out exactly: the last segment of a block takes every step left.

use super::{Segment, StepConfig};
use crate::planner::{Block, BlockKind, Planner, Profile, Shape};
use crate::realtime::{Realtime, Trip};
use crate::settings::Settings;

/// Target duration of one segment, seconds.
pub const SEGMENT_S: f32 = 0.002;
/// Longest event period of a dwell segment, seconds.
pub(super) const DWELL_CHUNK_S: f32 = 0.01;
/// How far ahead the preparer runs, seconds of queued segments (once
/// [`MIN_QUEUED`] are queued). A feed hold or an override acts on the
/// next segment prepared, so this is their latency. At usual speeds the
/// 16 slots of 2 ms are about this much anyway; at slow feeds a segment
/// is at least one step, and 16 of them were 0.6 s at 20 mm/min on 80
/// steps/mm (GRBL queues 6).
pub const HORIZON_S: f32 = 0.03;
/// Segments always kept queued, whatever their length, so the stepper
/// never waits on the planner task between two of them.
pub const MIN_QUEUED: usize = 2;
/// Durations of the segments pushed last, to sum what is still queued
/// (more than any segment queue holds).
const PUSHED_RING: usize = 32;

pub use super::sink::SegmentSink;

mod hold;
mod rate;
mod run;
mod segment;
mod walk;

pub use walk::MAX_WALKS_PER_SEGMENT;

/// Feed hold progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hold {
    Running,
    Decelerating,
    Held,
}

/// The planner-task half of step generation.
#[derive(Debug)]
pub struct Preparer {
    cfg: StepConfig,
    settings: Settings,
    active: bool,
    block: Option<Block>,
    new_block: bool,
    steps_done: u32,
    /// Distance into the block at the end of the last segment, mm.
    s_done: f32,
    /// Speed at the end of the last segment, mm/s.
    v: f32,
    profile: Profile,
    phase: usize,
    tau: f32,
    s_phase0: f32,
    profile_exit: f32,
    profile_nominal: f32,
    /// Where the entry corner's hold ends, mm into the block
    /// (`planner::passes`).
    hold_end: f32,
    /// The exit corner's hold factor (`Block::hold_m` of the next block;
    /// 0 when motion stops there).
    exit_m: f32,
    /// The running profile is a feed hold's ramp to a stop (not the
    /// planned profile a hold follows up to a corner, see `prep::hold`).
    hold_ramp: bool,
    tick_carry: f32,
    /// Profile time walked past the last step handed out, s: the next
    /// segment's steps are timed from that step's instant.
    since_step: f32,
    dwell_left: u64,
    /// Ticks still to wait before the next segment: the part of a step
    /// interval beyond the timer's range, or time walked without a step.
    wait_left: u64,
    /// The segment the wait follows ended the motion.
    wait_end: bool,
    last_dir: u8,
    hold: Hold,
    /// The hold is a motion cancel (probe contact): cycle start does not
    /// resume it; the executor flushes once it has stopped.
    cancel: bool,
    /// The shape the running profile was planned with (a hold ramp that
    /// crosses into the next block is still evaluated with it).
    pshape: Shape,
    /// Blocks after the running one that its profile still covers (an
    /// S-curve run, `prep::run`), and the length of the block finished
    /// last, mm (where the profile's distances continue from).
    run_blocks: usize,
    done_len: f32,
    last_line: u32,
    /// Profile walk steps taken so far (wrapping): the work measure that
    /// tests and the bench budget hold against [`MAX_WALKS_PER_SEGMENT`].
    walks: u32,
    /// Ticks each of the last [`PUSHED_RING`] segments runs, newest at
    /// `pushed_head - 1` (wrapping).
    pushed: [u32; PUSHED_RING],
    pushed_head: usize,
    /// Highest segment speed so far, mm/min.
    pub max_speed_mm_min: f32,
}

impl Preparer {
    pub const fn new(settings: Settings, cfg: StepConfig) -> Self {
        Preparer {
            cfg,
            settings,
            active: false,
            block: None,
            new_block: false,
            steps_done: 0,
            s_done: 0.0,
            v: 0.0,
            profile: Profile::ZERO,
            phase: 0,
            tau: 0.0,
            s_phase0: 0.0,
            profile_exit: 0.0,
            profile_nominal: 0.0,
            hold_end: 0.0,
            exit_m: 0.0,
            hold_ramp: false,
            tick_carry: 0.0,
            since_step: 0.0,
            dwell_left: 0,
            wait_left: 0,
            wait_end: false,
            last_dir: 0,
            hold: Hold::Running,
            cancel: false,
            pshape: Shape {
                accel: 1.0,
                jerk: 0.0,
                drop: 0.0,
            },
            run_blocks: 0,
            done_len: 0.0,
            last_line: 0,
            walks: 0,
            pushed: [0; PUSHED_RING],
            pushed_head: 0,
            max_speed_mm_min: 0.0,
        }
    }

    /// All zero bits (the board's machine slot, see
    /// `Settings::ZEROED`): its block is a zero block rather than `None`,
    /// whose niche is not zero. Never run: `Machine::rebuild` replaces it.
    pub const fn zeroed() -> Self {
        Preparer {
            block: Some(Block::ZEROED),
            pshape: Shape {
                accel: 0.0,
                jerk: 0.0,
                drop: 0.0,
            },
            ..Preparer::new(Settings::ZEROED, StepConfig::UNSET)
        }
    }

    /// Forget everything in flight (flush after reset, trip or alarm).
    pub fn reset(&mut self) {
        self.active = false;
        self.block = None;
        self.run_blocks = 0;
        self.v = 0.0;
        self.tick_carry = 0.0;
        self.since_step = 0.0;
        self.wait_left = 0;
        self.hold = Hold::Running;
        self.cancel = false;
    }

    pub fn hold(&self) -> Hold {
        self.hold
    }
    /// No block in progress.
    pub fn is_idle(&self) -> bool {
        !self.active && self.wait_left == 0
    }
    /// Source line of the block prepared last.
    pub fn line(&self) -> u32 {
        self.last_line
    }
    /// Current planned path speed, mm/s.
    pub fn speed(&self) -> f32 {
        self.v
    }
    /// Profile walk steps taken since power-up (wrapping). One segment
    /// takes at most [`MAX_WALKS_PER_SEGMENT`], one fill at most that
    /// times the free queue slots.
    pub fn walks(&self) -> u32 {
        self.walks
    }

    /// Push segments until the queue is full, or holds [`HORIZON_S`] of
    /// motion (and at least [`MIN_QUEUED`] segments), or there is nothing
    /// to prepare.
    ///
    /// Bounded work: each pass of the loop pushes a segment or ends it, so
    /// at most the queue's free slots; each segment costs at most one
    /// planner block per block finished without a step (a ring of `N`) and
    /// [`MAX_WALKS_PER_SEGMENT`] profile walk steps of at most 5 phases.
    ///
    /// A limit or e-stop interrupt may preempt this at any point: it records
    /// the trip, then bumps the generation. Taking the generation first and
    /// stamping it on every segment of this fill makes whatever this pass
    /// prepares from the old plan stale if the bump lands mid-fill; a hard
    /// limit seen before the first segment stops the fill (the planner task
    /// flushes on its next pass). Homing and probe trips keep filling: their
    /// sequences go on (pull-off, the probe's deceleration).
    pub fn fill<const N: usize>(
        &mut self,
        pl: &mut Planner<N>,
        rt: &Realtime,
        sink: &mut impl SegmentSink,
    ) {
        let generation = rt.generation();
        if rt.trip() == Trip::HardLimit {
            return;
        }
        let horizon = (HORIZON_S * self.cfg.tick_hz as f32) as u64;
        while !sink.is_full() {
            let queued = sink.len();
            if queued >= MIN_QUEUED && self.queued_ticks(queued) >= horizon {
                break;
            }
            match self.next_segment(pl, rt) {
                Some(mut seg) => {
                    seg.generation = generation;
                    let ticks = u64::from(seg.events) * u64::from(seg.period);
                    if sink.push(seg).is_err() {
                        break;
                    }
                    self.pushed[self.pushed_head % PUSHED_RING] =
                        ticks.min(u64::from(u32::MAX)) as u32;
                    self.pushed_head = (self.pushed_head + 1) % PUSHED_RING;
                }
                None => break,
            }
        }
    }

    /// Ticks the newest `queued` segments run (the oldest of them may be
    /// part-run already: an overestimate by less than one segment).
    fn queued_ticks(&self, queued: usize) -> u64 {
        (1..=queued.min(PUSHED_RING))
            .map(|k| u64::from(self.pushed[(self.pushed_head + PUSHED_RING - k) % PUSHED_RING]))
            .sum()
    }

    fn shape(&self) -> Shape {
        self.block.map_or(
            Shape {
                accel: 1.0,
                jerk: 0.0,
                drop: 0.0,
            },
            |b| b.shape(&self.settings),
        )
    }

    /// The speed the running profile should end at: the entry of the block
    /// after it (after its run, `prep::run`).
    fn exit_target<const N: usize>(&self, pl: &Planner<N>) -> f32 {
        match pl.block(self.run_blocks + 1) {
            Some(b) if b.kind == BlockKind::Line => b.entry,
            _ => 0.0,
        }
    }

    /// The exit corner's hold factor on this side (0 when motion stops
    /// there).
    fn exit_hold_m<const N: usize>(pl: &Planner<N>) -> f32 {
        match pl.block(1) {
            Some(b) if b.kind == BlockKind::Line => b.hold_pre_m,
            _ => 0.0,
        }
    }

    fn set_profile(&mut self, p: Profile) {
        self.hold_ramp = false;
        self.pshape = self.shape().at_top(self.v);
        self.profile = p;
        self.phase = 0;
        self.tau = 0.0;
        self.s_phase0 = self.s_done;
    }

    /// What is left of the entry corner's hold, mm, for the speed there
    /// is now (`v²·m/2`): a feed hold that stopped inside it resumes from
    /// rest, where there is nothing left to hold (held at the entry speed
    /// it crawled at 10⁻⁶ mm/s for hours).
    fn entry_hold_left(&self) -> f32 {
        let m = self.block.map_or(0.0, |b| b.hold_m);
        (self.hold_end - self.s_done).min(0.5 * self.v * self.v * m)
    }

    fn replan<const N: usize>(&mut self, pl: &Planner<N>) {
        let Some(b) = self.block else { return };
        let (p, shape, exit, run) = self.plan_run(pl, &b);
        self.profile_exit = exit;
        self.profile_nominal = b.nominal;
        self.exit_m = Self::exit_hold_m(pl);
        self.set_profile(p);
        self.pshape = shape;
        self.run_blocks = run;
    }

    fn start_block<const N: usize>(&mut self, pl: &Planner<N>) -> bool {
        let Some(b) = pl.block(0).copied() else {
            return false;
        };
        self.block = Some(b);
        self.last_line = b.line;
        self.active = true;
        self.new_block = true;
        self.steps_done = 0;
        self.s_done = 0.0;
        match b.kind {
            BlockKind::Dwell { ticks } => {
                self.dwell_left = ticks.get();
                self.v = 0.0;
            }
            BlockKind::Line if self.run_blocks > 0 && self.hold == Hold::Running => {
                // The running profile goes on into this block (`prep::run`):
                // its distances now count from here. No corner hold here.
                self.run_blocks -= 1;
                self.s_phase0 -= self.done_len;
                self.s_done = 0.0;
                self.hold_end = 0.0;
                self.exit_m = Self::exit_hold_m(pl);
            }
            BlockKind::Line => {
                self.run_blocks = 0;
                // Only the hard limits: after an override drop the previous
                // block may not have reached this one's (lower) planned
                // entry, and cutting the speed here would be a jump.
                self.v = self.v.min(b.junction.min(b.cap));
                self.hold_end = 0.5 * self.v * self.v * b.hold_m;
                self.exit_m = Self::exit_hold_m(pl);
                if self.hold != Hold::Decelerating || !self.plan_hold(false) {
                    self.replan(pl);
                }
            }
        }
        true
    }

    fn finish_block<const N: usize>(&mut self, pl: &mut Planner<N>) {
        self.done_len = self.block.map_or(0.0, |b| b.length);
        pl.pop();
        self.active = false;
        self.block = None;
    }

    fn next_segment<const N: usize>(
        &mut self,
        pl: &mut Planner<N>,
        rt: &Realtime,
    ) -> Option<Segment> {
        if self.wait_left > 0 {
            return Some(self.wait_chunk(rt));
        }
        if rt.hold_requested() && self.hold == Hold::Running {
            self.begin_hold();
        }
        if self.hold == Hold::Held {
            if self.cancel || !rt.take_cycle_start() {
                return None;
            }
            rt.clear_hold();
            self.hold = Hold::Running;
            if self.active && self.block.is_some_and(|b| b.kind == BlockKind::Line) {
                self.replan(pl);
            }
        }
        // Each pass returns or finishes a planner block: at most N + 1 passes.
        loop {
            if !self.active && !self.start_block(pl) {
                return None;
            }
            let b = self.block?;
            if let BlockKind::Dwell { .. } = b.kind {
                // A hold pauses a dwell where it is (nothing to ramp down):
                // cycle start goes on with the time left.
                if self.hold != Hold::Running {
                    self.hold = Hold::Held;
                    return None;
                }
                if let Some(seg) = self.dwell_segment(rt, &b) {
                    return Some(seg);
                }
                self.finish_block(pl);
                continue;
            }
            if self.hold == Hold::Running {
                let exit = self.exit_target(pl);
                let changed = exit != self.profile_exit
                    || b.nominal != pl.block(0).map_or(b.nominal, |c| c.nominal);
                if changed && self.can_replan() {
                    if let Some(c) = pl.block(0) {
                        self.block = Some(*c);
                    }
                    self.replan(pl);
                }
            }
            if let Some(seg) = self.motion_segment(pl, rt) {
                return Some(seg);
            }
            if self.hold == Hold::Held {
                return None;
            }
        }
    }
}
