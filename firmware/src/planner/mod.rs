//! Look-ahead planner: a ring of blocks (straight moves in integer steps, or
//! dwells) with entry speeds chosen so every block can still stop at the end
//! of the known path.
//!
//! Replanning is incremental: `planned` marks the first block whose entry
//! speed can still rise. Blocks before it either enter at their junction limit
//! or accelerate as hard as allowed from the block before, so nothing
//! appended later can change them. The backward pass stops as soon as an
//! entry speed stops changing; the forward pass starts at `planned`.

mod cancel;
mod corner;
mod curve;
pub mod interval;
mod merge;
mod passes;
mod push;
mod quiet;
pub mod ramp;
mod run;
mod tube;

use crate::command::Pos;
use crate::settings::Settings;
use crate::AXES;
pub use curve::Curve;
pub use ramp::{Phase, Profile, Shape};
pub use run::{nominal_near, RunAhead, CURVE_RUN_JERK, RUN_BLOCKS};

/// Why a block was not queued. The executor maps `Full` onto its `Busy` and
/// the rest onto its errors of the same name, so the reported codes do not
/// change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlanError {
    /// The ring has no free slot (the caller checks `is_full` first).
    Full,
    /// A target, steps/mm, rate or acceleration is not a finite number in range.
    InvalidNumber,
    /// One block would need more than [`MAX_BLOCK_STEPS`] steps on an axis.
    MoveTooLong,
    /// This axis's max rate times its steps/mm exceeds `max_step_rate_hz`.
    StepRateTooHigh { axis: u8 },
    /// Feed rate or move time zero, negative or not finite.
    InvalidFeed,
    /// So slow that one step would be further apart than the step timer
    /// can count (see `Planner::set_tick_hz`).
    FeedTooSlow,
}

/// What a block does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockKind {
    Line,
    /// G4: stand still this many timer ticks.
    Dwell {
        ticks: Ticks,
    },
}

/// A dwell's timer ticks, a `u64` kept as two halves: aligned to 8 bytes it
/// set the whole block's alignment, and the ring's 64 blocks grew by 512 B
/// of padding when a block gained one byte (`run_pos`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ticks([u32; 2]);

impl Ticks {
    pub const fn new(t: u64) -> Self {
        Ticks([t as u32, (t >> 32) as u32])
    }

    pub const fn get(self) -> u64 {
        (self.0[1] as u64) << 32 | self.0[0] as u64
    }
}

/// What stops a block early (homing switches, probe).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Watch {
    /// Stop when any of these axes' limit switches closes.
    pub limits: u8,
    /// 1: stop when the probe closes; 2: stop when it opens.
    pub probe: u8,
    /// A homing move: hard limits do not apply (it starts on a closed switch).
    pub homing: bool,
}

/// Speed request of a move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    /// Path speed in mm/s (feed override applies).
    Feed(f32),
    /// The whole move takes this many seconds (G93; feed override applies).
    Time(f32),
    /// As fast as the axes allow (rapid override applies).
    Rapid,
}

/// One planned move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    pub kind: BlockKind,
    /// Absolute step counts at the end of the block.
    pub target: [i32; AXES],
    /// Steps per axis (absolute values) and the Bresenham event count.
    pub steps: [u32; AXES],
    pub count: u32,
    /// Bit set: axis moves towards negative.
    pub dir_mask: u8,
    /// Path length, mm: the commanded move's, which the programmed feed
    /// is a speed along, not the length of its step-rounded ends (a chord
    /// of 1.3 steps steps as 1 or 2; over a dense curve the stepped
    /// polyline is 4-5 % longer). The steps are spread over it evenly, and
    /// `cap` holds each axis's step rate (`interval`).
    pub length: f32,
    /// Requested speed before override, mm/s (infinite for rapids).
    pub programmed: f32,
    pub rapid: bool,
    /// Highest path speed the axes allow, mm/s.
    pub cap: f32,
    /// Path speed after override and cap, mm/s.
    pub nominal: f32,
    /// Path acceleration the axes allow, mm/s².
    pub accel: f32,
    /// The same along a straight line (a chord of a curve shares it with
    /// the centripetal acceleration: `accel` is less).
    pub line_accel: f32,
    /// Chord of an arc: `A_n·r`, `A_n` and the tangential limits of its
    /// plane axes (`planner::curve::ChordBudget`); `curve_ar` 0 otherwise.
    pub curve_ar: f32,
    pub curve_an: f32,
    pub curve_tangent: [[f32; 2]; 2],
    /// Slowest path speed the step timer can time, mm/s: the feed override
    /// never takes `nominal` below it.
    pub floor: f32,
    /// Cornering limit at the junction with the previous block, mm/s.
    pub junction: f32,
    /// The corner at this block's entry, for its hold (`planner::passes`):
    /// the stretched largest `|Δu_i| / a_i` over the axes that move after
    /// it, s²/mm (0: no corner to hold, as between chords of one curve).
    pub hold_m: f32,
    /// The same over the axes that move before it: the hold the block
    /// before this one keeps at its exit.
    pub hold_pre_m: f32,
    /// The corner's limit before its hold lowers it (junction deviation
    /// and curvature), mm/s.
    pub corner: f32,
    /// Junction deviation's limit alone, mm/s: what a corner inside a
    /// stretch within a step of a line may rise to (`planner::tube`).
    pub jd: f32,
    /// The hold once the axes in `release` stop holding (`planner::quiet`).
    pub hold_fixed: passes::Sides,
    /// Axes whose velocity the block keeps small (bit per axis), and the
    /// axes its entry corner holds only until quiet blocks follow.
    pub quiet: u8,
    pub release: u8,
    pub max_entry: f32,
    pub entry: f32,
    pub watch: Watch,
    /// Backlash take-up (`motion::Pipeline`): its steps turn the motors
    /// but do not move the tool, so the step interrupt leaves them out of
    /// the reported position; never merged with a neighbour.
    pub takeup: bool,
    /// Its place in its S-curve run (`planner::run`), fixed when it was
    /// queued: 0 starts a run.
    pub run_pos: u8,
    /// S-curve: the least speed at which a turn of its (its entry corner,
    /// an arc's chord) takes the whole jerk, `cbrt(j·r²)`
    /// (`Planner::curve_jerk_cap`), mm/s; 0 where none does (zero bits,
    /// so an empty ring needs no load image). `planner::run` caps runs
    /// that turn below it.
    pub turn_v: f32,
    /// Source line, for errors and traces.
    pub line: u32,
}

impl Block {
    const EMPTY: Block = Block {
        kind: BlockKind::Line,
        target: [0; AXES],
        steps: [0; AXES],
        count: 0,
        dir_mask: 0,
        length: 0.0,
        programmed: 0.0,
        rapid: false,
        cap: 0.0,
        nominal: 0.0,
        accel: 1.0,
        line_accel: 1.0,
        curve_ar: 0.0,
        curve_an: 0.0,
        curve_tangent: [[f32::INFINITY, 0.0]; 2],
        floor: 0.0,
        junction: 0.0,
        hold_m: 0.0,
        hold_pre_m: 0.0,
        corner: 0.0,
        jd: 0.0,
        hold_fixed: passes::Sides {
            pre: 0.0,
            post: 0.0,
        },
        quiet: 0,
        release: 0,
        max_entry: 0.0,
        entry: 0.0,
        watch: Watch {
            limits: 0,
            probe: 0,
            homing: false,
        },
        takeup: false,
        run_pos: 0,
        turn_v: 0.0,
        line: 0,
    };

    /// All zero bits, for storage nothing reads yet (the board's machine
    /// slot, `Machine::placeholder`, lands in `.bss` that way).
    pub const ZEROED: Block = Block {
        accel: 0.0,
        line_accel: 0.0,
        curve_tangent: [[0.0; 2]; 2],
        ..Block::EMPTY
    };

    pub fn shape(&self, s: &Settings) -> Shape {
        let jerk = match s.profile {
            crate::settings::Profile::Trapezoid => 0.0,
            crate::settings::Profile::SCurve => s.jerk.max(1e-3),
        };
        // A trapezoid chord ramps with what its top speed leaves
        // (`planner::curve`): the line from the acceleration at rest to
        // the one at `nominal`, below the exact (concave) limit between.
        if jerk <= 0.0 && self.curve_ar > 0.0 && self.nominal > 0.0 {
            let a0 = self.accel0();
            if a0 > self.accel {
                return Shape {
                    accel: a0,
                    jerk,
                    drop: (a0 - self.accel) / (self.nominal * self.nominal),
                };
            }
        }
        Shape {
            accel: self.accel,
            jerk,
            drop: 0.0,
        }
    }

    /// The path acceleration the block allows at rest: on a trapezoid
    /// chord, with no centripetal part yet.
    pub fn accel0(&self) -> f32 {
        if self.curve_ar <= 0.0 {
            return self.accel;
        }
        self.tangent_accel(0.0).max(self.accel)
    }

    /// A chord's path acceleration while it turns at `an` mm/s²: each
    /// plane axis's tangential limit `α − β·a_n` (`planner::curve`), and
    /// the straight-line limit.
    pub(super) fn tangent_accel(&self, an: f32) -> f32 {
        self.curve_tangent
            .iter()
            .fold(self.line_accel, |acc, [alpha, beta]| {
                acc.min(alpha - beta * an)
            })
    }
}

/// Largest Bresenham count a block may have (the stepper scales counts by 2^3).
pub const MAX_BLOCK_STEPS: u32 = 1 << 27;

/// The look-ahead ring. `N` blocks (64 or more on the F411).
#[derive(Debug)]
pub struct Planner<const N: usize> {
    blocks: [Block; N],
    tail: usize,
    len: usize,
    /// Offset from the tail of the first block whose entry may still rise.
    planned: usize,
    /// Blocks the passes have visited, wrapping: what planning costs, for
    /// host-sim's model of the task's time (`Planner::work`; off the board
    /// only).
    #[cfg(not(target_os = "none"))]
    work: u32,
    /// Step position at the end of the last block pushed.
    position: [i32; AXES],
    /// The previous block's commanded direction (see `position_mm`).
    prev_unit_mm: [f32; AXES],
    /// The direction before that (zero after a stop): a corner that takes
    /// back the one before it (a zigzag, rounding noise) holds only for
    /// what the two leave together.
    prev2_unit_mm: [f32; AXES],
    /// Whether the newest block's corner (bit 0) and the one before it
    /// (bit 1) turn by rounding only, their curvature pending
    /// (`planner::cancel`).
    pending: u8,
    /// The turn across the newest block's predecessor chord (from the
    /// chord before it to the newest; taken whenever that corner was
    /// pending, `pending` bit 1), and the newest
    /// block's corner's turn (`planner::cancel`). Zero in `new`, as every
    /// field: the machine's placeholder stays in .bss.
    prev_phi2: f32,
    prev_turn: corner::Turn,
    /// The share of its hold the previous block's corner gave up
    /// (`planner::cancel`; 0 when nothing took it back: the machine's
    /// placeholder, built from `new`, must stay all zero bits, in .bss).
    prev_given_up: f32,
    /// The newest block's corner's `Pair::pulse_m` (`planner::cancel`).
    prev_pulse_m: f32,
    /// Commanded end of the last block pushed, mm: corners are judged on
    /// the commanded geometry, not on the step-rounded one (a chord of a
    /// step or two can look like a 45° corner in steps).
    position_mm: [f32; AXES],
    /// Path speed the previous block's junction may carry (0 after a stop).
    prev_nominal: f32,
    prev_length: f32,
    /// Per axis: the least time (s) the blocks since the last one that
    /// moved the axis take (one-sided holds, `planner::passes`).
    still_time: [f32; AXES],
    /// Per axis: how long (at least, s) the blocks since the last one in
    /// which the axis's velocity may be large have taken (`planner::quiet`).
    quiet_time: [f32; AXES],
    /// Axes some queued corner may still stop holding (a superset).
    release_pending: u8,
    /// The curve the previous block was a chord of, if any.
    prev_curve: Option<Curve>,
    /// The stretch of the newest blocks being checked for straightness
    /// (`planner::tube`).
    tube: tube::Tube,
    feed_pct: f32,
    rapid_pct: f32,
    /// The step timer's clock; 0 until [`set_tick_hz`](Self::set_tick_hz)
    /// (then no slow-feed refusal and no interval cap).
    tick_hz: u32,
    pub settings: Settings,
}

impl<const N: usize> Planner<N> {
    pub const fn new(settings: Settings) -> Self {
        Planner {
            blocks: [Block::EMPTY; N],
            tail: 0,
            len: 0,
            planned: 0,
            #[cfg(not(target_os = "none"))]
            work: 0,
            position: [0; AXES],
            prev_unit_mm: [0.0; AXES],
            prev2_unit_mm: [0.0; AXES],
            pending: 0,
            prev_phi2: 0.0,
            prev_turn: corner::Turn {
                a: 0.0,
                phi: 0.0,
                l: 0.0,
            },
            prev_given_up: 0.0,
            prev_pulse_m: 0.0,
            position_mm: [0.0; AXES],
            prev_nominal: 0.0,
            prev_length: 0.0,
            still_time: [f32::INFINITY; AXES],
            quiet_time: [f32::INFINITY; AXES],
            release_pending: 0,
            prev_curve: None,
            tube: tube::Tube::NONE,
            feed_pct: 1.0,
            rapid_pct: 1.0,
            tick_hz: 0,
            settings,
        }
    }

    /// All zero bits (the board's machine slot, see
    /// [`Settings::ZEROED`]); [`Planner::reset`] makes it a planner.
    pub const fn zeroed() -> Self {
        Planner {
            blocks: [Block::ZEROED; N],
            still_time: [0.0; AXES],
            quiet_time: [0.0; AXES],
            feed_pct: 0.0,
            rapid_pct: 0.0,
            ..Planner::new(Settings::ZEROED)
        }
    }

    /// [`Planner::new`], in place: every field as `new` sets it but the
    /// ring's storage, which nothing reads while `len` is 0. `$n=`
    /// rebuilds the machine deep in the parse task's stack, and a second
    /// ring of blocks built there took the F401's stack within a few
    /// hundred bytes of its end.
    pub fn reset(&mut self, settings: Settings) {
        let Planner {
            blocks: _,
            tail,
            len,
            planned,
            #[cfg(not(target_os = "none"))]
                work: _,
            position,
            prev_unit_mm,
            prev2_unit_mm,
            pending,
            prev_phi2,
            prev_turn,
            prev_given_up,
            prev_pulse_m,
            position_mm,
            prev_nominal,
            prev_length,
            still_time,
            quiet_time,
            release_pending,
            prev_curve,
            tube,
            feed_pct,
            rapid_pct,
            tick_hz,
            settings,
        } = Planner::<0>::new(settings);
        self.tail = tail;
        self.len = len;
        self.planned = planned;
        self.position = position;
        self.prev_unit_mm = prev_unit_mm;
        self.prev2_unit_mm = prev2_unit_mm;
        self.pending = pending;
        self.prev_phi2 = prev_phi2;
        self.prev_turn = prev_turn;
        self.prev_given_up = prev_given_up;
        self.prev_pulse_m = prev_pulse_m;
        self.position_mm = position_mm;
        self.prev_nominal = prev_nominal;
        self.prev_length = prev_length;
        self.still_time = still_time;
        self.quiet_time = quiet_time;
        self.release_pending = release_pending;
        self.prev_curve = prev_curve;
        self.tube = tube;
        self.feed_pct = feed_pct;
        self.rapid_pct = rapid_pct;
        self.tick_hz = tick_hz;
        self.settings = settings;
    }

    /// The step timer's clock: with it, feeds whose steps would be further
    /// apart than the 32-bit timer reaches are refused
    /// ([`PlanError::FeedTooSlow`]). The executor sets it; a bare planner
    /// (tests, benches) checks nothing and the preparer still stays bounded.
    pub fn set_tick_hz(&mut self, tick_hz: u32) {
        self.tick_hz = tick_hz;
    }

    pub fn len(&self) -> usize {
        self.len
    }

    /// Blocks the backward and forward passes have visited since power-up,
    /// wrapping (kept through [`Planner::reset`]): S-curve planning costs
    /// about that many S ramps. Counted off the board only (host-sim's
    /// model of the task's time); 0 on it, where the count would only move
    /// the code (bench-target's step path is timed with its flash lines
    /// cold, and shifted by the count's few instructions it read 321
    /// cycles against 311).
    pub fn work(&self) -> u32 {
        #[cfg(not(target_os = "none"))]
        return self.work;
        #[cfg(target_os = "none")]
        0
    }

    #[inline(always)]
    fn count_work(&mut self, visits: usize) {
        #[cfg(not(target_os = "none"))]
        {
            self.work = self.work.wrapping_add(visits as u32);
        }
        #[cfg(target_os = "none")]
        let _ = visits;
    }
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    pub fn is_full(&self) -> bool {
        self.len >= N
    }
    /// Block `k` counted from the oldest (0 is the one being executed).
    pub fn block(&self, k: usize) -> Option<&Block> {
        if k < self.len {
            self.blocks.get((self.tail + k) % N)
        } else {
            None
        }
    }
    fn at(&mut self, k: usize) -> &mut Block {
        let i = (self.tail + k) % N;
        &mut self.blocks[i]
    }
    /// Drop the oldest block (the preparer has turned it all into segments).
    pub fn pop(&mut self) {
        if self.len > 0 {
            self.tail = (self.tail + 1) % N;
            self.len -= 1;
            self.planned = self.planned.saturating_sub(1);
        }
    }
    /// Drop everything (reset, hard limit, probe or homing stop) and take the
    /// stepper's actual position as the new start.
    pub fn clear(&mut self, position: [i32; AXES]) {
        self.len = 0;
        self.planned = 0;
        self.position = position;
        self.position_mm = self.steps_mm(&position);
        self.stop_junction();
    }

    fn steps_mm(&self, steps: &[i32; AXES]) -> [f32; AXES] {
        core::array::from_fn(|i| steps[i] as f32 / self.settings.axes[i].steps_per_mm)
    }
    /// Step position at the end of everything planned.
    /// The last queued move's commanded end, mm (where the next starts).
    pub fn commanded_mm(&self) -> &Pos {
        &self.position_mm
    }

    pub fn position(&self) -> [i32; AXES] {
        self.position
    }
    /// The next block must start from standstill (after dwell, sync, hold-flush).
    pub fn stop_junction(&mut self) {
        self.prev_nominal = 0.0;
        self.prev_unit_mm = [0.0; AXES];
        self.prev2_unit_mm = [0.0; AXES];
        self.pending = 0;
        self.tube = tube::Tube::NONE;
        // From rest: nothing moved before the next block.
        self.quiet_time = [f32::INFINITY; AXES];
    }

    /// Steps for a machine position in mm: rounded from the absolute target,
    /// so the step count of a job never drifts from summing rounded deltas.
    pub fn to_steps(&self, mm: &Pos) -> Result<[i32; AXES], PlanError> {
        let mut out = [0i32; AXES];
        for i in 0..AXES {
            out[i] = crate::num::round_i32(mm[i] * self.settings.axes[i].steps_per_mm)
                .ok_or(PlanError::InvalidNumber)?;
        }
        Ok(out)
    }

    /// Queue a straight move to `target` steps. A zero-length move is dropped.
    /// The caller checks `is_full` first.
    pub fn push_line(
        &mut self,
        target: [i32; AXES],
        speed: Speed,
        watch: Watch,
        line: u32,
    ) -> Result<(), PlanError> {
        let mm = self.steps_mm(&target);
        self.push(target, &mm, speed, watch, line, push::Piece::Line)
    }

    /// [`push_line`](Self::push_line) to a commanded position in mm (rounded
    /// to steps here); its corners are judged on the mm geometry.
    pub fn push_line_mm(
        &mut self,
        end: &Pos,
        speed: Speed,
        watch: Watch,
        line: u32,
    ) -> Result<(), PlanError> {
        let target = self.to_steps(end)?;
        self.push(target, end, speed, watch, line, push::Piece::Line)
    }

    /// Queue one chord of an arc or spline, ending at `end` mm. On a curve
    /// the axes feel the tangential and the centripetal acceleration at
    /// once: `planner::curve` splits the budget between them.
    pub fn push_chord(
        &mut self,
        end: &Pos,
        speed: Speed,
        line: u32,
        curve: Curve,
    ) -> Result<(), PlanError> {
        let target = self.to_steps(end)?;
        self.push(
            target,
            end,
            speed,
            Watch::default(),
            line,
            push::Piece::Chord(curve),
        )
    }

    /// Queue a dwell; motion stops before it.
    pub fn push_dwell(&mut self, ticks: u64, line: u32) -> Result<(), PlanError> {
        if self.is_full() {
            return Err(PlanError::Full);
        }
        let b = Block {
            kind: BlockKind::Dwell {
                ticks: Ticks::new(ticks),
            },
            target: self.position,
            line,
            ..Block::EMPTY
        };
        let k = self.len;
        *self.at(k) = b;
        self.len += 1;
        self.stop_junction();
        self.replan(false);
        Ok(())
    }

    fn nominal(&self, b: &Block) -> f32 {
        let pct = if b.rapid {
            self.rapid_pct
        } else {
            self.feed_pct
        };
        let v = if b.rapid {
            b.cap * pct
        } else {
            b.programmed * pct
        };
        v.max(b.floor).min(b.cap)
    }
}
