//! Walking the speed profile in time, with every loop bounded, and the
//! segments that stand still (waits and dwells).
//!
//! The old walk took fixed [`SEGMENT_S`] steps until a whole step was
//! covered. At `G1 X-1 F0.0001` one step is 7 500 s away: 3.75 million
//! walk steps per segment, and worse, once the time into a phase (`tau`)
//! passes about 33 500 s, `tau + 0.002` rounds back to `tau` in `f32`, the
//! profile never moves again and `Machine::poll` never returns. Three
//! rules keep the walk finite:
//!
//! - at constant speed the walk jumps straight to the next whole step
//!   (or the phase end), so a slow cruise costs one walk step per step;
//! - a walk step is never shorter than [`TAU_ULPS`] of `tau`'s precision,
//!   so `tau` always moves (and the rounding stays below 0.4 % of a step);
//! - one segment takes at most [`MAX_WALKS_PER_SEGMENT`] walk steps; if
//!   they cover no whole step, the time walked goes out as a wait (events
//!   that step nothing) and the next segment goes on from there;
//! - a step interval longer than the driver may time is split: the
//!   step's event takes [`crate::seams::MAX_PERIOD`] ticks and the rest
//!   follows as a wait,
//!   so the steps keep their times. The planner refuses feeds whose
//!   cruise would need that (`FeedTooSlow`) and floors the feed override
//!   at the timer's reach, so only slow ramps get there.

use super::{Preparer, DWELL_CHUNK_S, SEGMENT_S};
use crate::planner::ramp::PHASES;
use crate::planner::Block;
use crate::realtime::Realtime;
use crate::stepper::{Segment, MAX_AMASS};

/// Walk steps one segment may take before the time walked goes out as a
/// wait. With constant-speed jumps a segment needs one or two; only long
/// ramps of slow machines (first step more than 64 × 2 ms into a ramp)
/// reach it.
pub const MAX_WALKS_PER_SEGMENT: u32 = 64;

/// Most ticks one segment may span, steps and trailing wait together
/// (64 timer ranges, 48 min at 96 MHz): only a block the planner did not
/// check (no tick rate set) or a ramp of an absurdly low acceleration
/// gets near it, and then the timing is off but the wait is finite.
pub(super) const MAX_SEGMENT_TICKS: f32 = crate::seams::MAX_PERIOD as f32 * 256.0;

/// A walk step is at least `tau / TAU_ULPS`: `f32` has 24 bits, so adding
/// it moves `tau` by at least 2^8 units in the last place.
const TAU_ULPS: f32 = 65_536.0;

impl Preparer {
    /// Length of the next walk step, seconds.
    pub(super) fn walk_dt(&self, b: &Block) -> f32 {
        let mut dt = SEGMENT_S;
        if let Some(ph) = self.profile.phases.get(self.phase) {
            if ph.v0 == ph.v1 && ph.v0 > 0.0 && b.count > 0 {
                // Constant speed: where the next whole step is, exactly.
                let next = (self.steps_done + 1) as f32 / b.count as f32 * b.length;
                // A hair past it, so f32 rounding cannot land just short
                // and cost a second walk step.
                let to_step = (next - self.s_done) / ph.v0 * (1.0 + 1.0 / 4096.0);
                dt = dt.max(to_step.min(ph.time - self.tau));
            }
        }
        dt.max(self.tau / TAU_ULPS)
    }

    /// Walk the profile for `dt` seconds ([`Preparer::walk_to`]); returns
    /// the time actually walked and whether the profile ended.
    pub(super) fn advance(&mut self, dt: f32) -> (f32, bool) {
        let (phase, tau, s_phase0, used) = self.walk_to(dt);
        (self.phase, self.tau, self.s_phase0) = (phase, tau, s_phase0);
        if self.phase < PHASES {
            // (A phase with `t0 > 0` is the tail of a ramp that started
            // before this profile.)
            let (v, s) = self.at(self.phase, self.tau);
            self.v = v;
            self.s_done = self.s_phase0 + s;
            (used, false)
        } else {
            self.v = self.profile.exit_speed();
            self.s_done = self.s_phase0;
            (used, true)
        }
    }

    /// Where walking `dt` more seconds lands, without moving: the phase,
    /// the time into it, the distance at its start, and the time really
    /// walked (less where the profile ends). [`Preparer::advance`] moves
    /// there; `prep::run` looks ahead with it to end a walk on a block's
    /// end. The loop crosses at most the [`PHASES`] phases.
    pub(super) fn walk_to(&self, mut dt: f32) -> (usize, f32, f32, f32) {
        let (mut phase, mut tau, mut s0, mut used) = (self.phase, self.tau, self.s_phase0, 0.0);
        while dt > 0.0 && phase < PHASES {
            let ph = self.profile.phases[phase];
            let rem = ph.time - tau;
            if dt < rem {
                tau += dt;
                used += dt;
                dt = 0.0;
            } else {
                used += rem.max(0.0);
                dt -= rem.max(0.0);
                phase += 1;
                s0 += ph.dist;
                tau = 0.0;
            }
        }
        (phase, tau, s0, used)
    }

    /// Start waiting `ticks` (time walked without a step, or the part of
    /// a step interval beyond the timer's range) and return its first
    /// chunk. `end` marks a wait after the end of motion.
    pub(super) fn begin_wait(&mut self, ticks: f32, end: bool, rt: &Realtime) -> Segment {
        self.wait_left = ticks.min(MAX_SEGMENT_TICKS) as u64;
        self.wait_end = end;
        self.wait_chunk(rt)
    }

    /// The next piece of the pending wait: events that step nothing, each
    /// at most the timer's range apart. It keeps the block's Bresenham
    /// state (no `new_block`, and a count so large that the accumulators,
    /// which stay below any real block's threshold, never reach it) and
    /// times the next step from the wait's end (the wait took the time
    /// walked since the last step), so the step's time is kept.
    pub(super) fn wait_chunk(&mut self, rt: &Realtime) -> Segment {
        let left = self.wait_left.max(u64::from(self.cfg.min_period));
        let period = left.min(u64::from(crate::seams::MAX_PERIOD)) as u32;
        let events = (left / u64::from(period)).min(u64::from(u32::MAX)) as u32;
        self.wait_left = left - u64::from(period) * u64::from(events);
        // A remainder below the shortest period is not worth an event.
        if self.wait_left < u64::from(self.cfg.min_period) {
            self.wait_left = 0;
        }
        Segment {
            events,
            period,
            amass: 0,
            new_block: false,
            steps: [0; crate::AXES],
            count: u32::MAX >> MAX_AMASS,
            dir_mask: self.last_dir,
            watch: Default::default(),
            end_of_motion: self.wait_end,
            generation: rt.generation(),
            speed_mm_min: self.v * 60.0,
            line: self.last_line,
            cut: 0.0,
            takeup: false,
        }
    }

    /// The next piece of a G4 dwell: one event that steps nothing, at
    /// most [`DWELL_CHUNK_S`] long. One chunk per segment, so the queue
    /// holds only the horizon's worth of a dwell: a feed hold pauses it
    /// within that (the rest waits in `dwell_left`), and a move behind it
    /// is not queued until the dwell is nearly over (one segment of 3 s
    /// let the move's first segment in behind it, which then ran in the
    /// hold).
    pub(super) fn dwell_segment(&mut self, rt: &Realtime, b: &Block) -> Option<Segment> {
        if self.dwell_left == 0 {
            return None;
        }
        let chunk = (DWELL_CHUNK_S * self.cfg.tick_hz as f32) as u64;
        let period = self.dwell_left.min(chunk.max(1)) as u32;
        let events = 1;
        self.dwell_left -= u64::from(period);
        let first = core::mem::replace(&mut self.new_block, false);
        Some(Segment {
            events,
            period,
            amass: 0,
            new_block: first,
            steps: [0; crate::AXES],
            count: 1,
            dir_mask: self.last_dir,
            watch: Default::default(),
            end_of_motion: true,
            generation: rt.generation(),
            speed_mm_min: 0.0,
            line: b.line,
            cut: 0.0,
            takeup: false,
        })
    }
}
