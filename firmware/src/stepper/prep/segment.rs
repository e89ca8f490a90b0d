//! One motion segment: walk the profile until at least one whole step is
//! covered, then time those steps from the last step's instant.
//!
//! The walk's own end is not where the steps end: the last step lies a
//! little before it. Timing from the last step's instant keeps a block of
//! a few steps from losing most of a step interval at each segment (a
//! zigzag block of 4 steps took 13.14 ms against the ideal 12.46).

use super::walk::MAX_SEGMENT_TICKS;
use super::{Hold, Preparer, MAX_WALKS_PER_SEGMENT};
use crate::planner::{Block, BlockKind, Planner, Watch};
use crate::realtime::Realtime;
use crate::stepper::Segment;

impl Preparer {
    pub(super) fn motion_segment<const N: usize>(
        &mut self,
        pl: &mut Planner<N>,
        rt: &Realtime,
    ) -> Option<Segment> {
        let b = self.block?;
        let mut time = 0.0f32;
        let mut walks = 0u32;
        let (target, block_end, stopped) = loop {
            let (dt, ended) = self.advance(self.clip_to_block(self.walk_dt(&b), b.length));
            time += dt;
            walks += 1;
            self.walks = self.walks.wrapping_add(1);
            let block_end = self.s_done >= b.length - 1e-6 || (ended && !self.hold_ramp);
            let hold_done = ended && self.hold_ramp && !block_end;
            let target = if block_end {
                b.count
            } else {
                let t = libm::floorf(self.s_done / b.length * b.count as f32);
                (t.max(0.0) as u32).min(b.count)
            };
            if target > self.steps_done || block_end || hold_done {
                break (target, block_end, hold_done);
            }
            // No whole step yet (a slow ramp): hand the time walked so far
            // to the stepper as a wait, so this call stays bounded.
            if walks >= MAX_WALKS_PER_SEGMENT {
                let wait = (time + core::mem::take(&mut self.since_step)) * self.cfg.tick_hz as f32;
                return Some(self.begin_wait(wait, false, rt));
            }
        };
        let n = target.saturating_sub(self.steps_done);
        let prev = self.steps_done as f32;
        self.steps_done = target;
        let s_steps = if block_end {
            b.count as f32
        } else {
            self.s_done / b.length * b.count as f32
        };
        // The segment ends at its last step's instant, not where the walk
        // stopped: the walk went `s_steps - target` steps further, at about
        // the speed it has now. Timing steps from walk ends instead cost a
        // block of a few steps up to 0.7 ms (its last segment had to run a
        // whole step in the time of half a step's walk).
        //
        // Near a stop "the speed it has now" tends to zero and that
        // estimate to infinity (a feed hold ending a hair past a step took
        // all the walked time back, and the step went out as an 11 s wait
        // the resume then sat behind). So it is also held to the share of
        // the walk that lies past the step, at the walk's mean speed since
        // the last step: always less than all of it once a step was made.
        let elapsed = time + self.since_step;
        let step_hz = self.v / b.length * b.count as f32;
        let back = if block_end || stopped || step_hz <= 0.0 {
            0.0
        } else {
            let past = s_steps - target as f32;
            let mean = elapsed * past / (s_steps - prev).max(past);
            crate::num::clamp(past / step_hz, 0.0, mean)
        };
        self.since_step = back;
        let time = elapsed - back;
        // Past the last known line the profile stops (exit speed 0), even if
        // the last segment ends a hair before the ramp's end.
        let next_line = matches!(pl.block(1), Some(n) if n.kind == BlockKind::Line);
        if block_end && !next_line {
            self.v = 0.0;
        }
        let end_speed_zero = stopped || (block_end && self.v <= 1e-3);
        if block_end {
            self.finish_block(pl);
            if self.hold == Hold::Decelerating && pl.is_empty() {
                self.v = 0.0;
            }
        }
        if stopped || (self.hold == Hold::Decelerating && self.v <= 1e-3 && block_end) {
            self.hold = Hold::Held;
            self.v = 0.0;
        }
        if n == 0 {
            // Nothing to step, but the stepper must learn that motion ends
            // here, or running dry would count as an underrun.
            if end_speed_zero || self.hold == Hold::Held {
                let first = core::mem::replace(&mut self.new_block, false);
                return Some(Segment {
                    events: 0,
                    period: self.cfg.min_period,
                    amass: 0,
                    new_block: first,
                    steps: b.steps,
                    count: b.count,
                    dir_mask: b.dir_mask,
                    watch: b.watch,
                    end_of_motion: true,
                    generation: rt.generation(),
                    speed_mm_min: 0.0,
                    line: b.line,
                    cut: 0.0,
                    takeup: b.takeup,
                });
            }
            return None;
        }
        let minor = b.steps.iter().any(|&s| s != 0 && s != b.count);
        let rate = if time > 0.0 {
            n as f32 / time
        } else {
            // Steps with no time walked (a rounding remainder at a block's
            // end): at the speed now, but never slower than the first step
            // from rest at the block's acceleration, sqrt(2a/step) steps/s.
            let per_step = b.length / b.count as f32;
            let from_rest = crate::num::sqrt(2.0 * b.accel.max(0.0) / per_step);
            (self.v / per_step).max(from_rest)
        };
        let dominant = if rate > 0.0 {
            self.cfg.tick_hz as f32 / rate
        } else {
            f32::MAX
        };
        let amass = crate::planner::interval::level(dominant, self.cfg.tick_hz, minor);
        let events = n << amass;
        let ticks = (dominant * n as f32).min(MAX_SEGMENT_TICKS) + self.tick_carry;
        let period_f = ticks / events as f32;
        let mut period = if period_f >= self.cfg.min_period as f32 {
            let max = crate::seams::MAX_PERIOD as f32;
            let p = (period_f.min(max) as u32).max(self.cfg.min_period);
            let rest = ticks - p as f32 * events as f32;
            if period_f > max {
                // Beyond the timer's range: the rest waits after the steps.
                self.tick_carry = 0.0;
                self.wait_left = rest as u64;
                self.wait_end = end_speed_zero || self.hold == Hold::Held;
            } else {
                self.tick_carry = crate::num::clamp(rest, 0.0, p as f32);
            }
            p
        } else {
            // Never faster than the ceiling; the lost time is not made up.
            self.tick_carry = 0.0;
            self.cfg.min_period
        };
        let floor = self.rate_floor(&b, amass);
        if period < floor {
            // Within an event of an axis limit: hold it (see `prep::rate`).
            period = floor;
            self.tick_carry = 0.0;
        }
        let speed_mm_min = rate / b.count as f32 * b.length * 60.0;
        self.max_speed_mm_min = self.max_speed_mm_min.max(speed_mm_min);
        let first = core::mem::replace(&mut self.new_block, false);
        self.last_dir = b.dir_mask;
        Some(Segment {
            events,
            period,
            amass,
            new_block: first,
            steps: b.steps,
            count: b.count,
            dir_mask: b.dir_mask,
            watch: b.watch,
            end_of_motion: end_speed_zero || self.hold == Hold::Held,
            generation: rt.generation(),
            speed_mm_min,
            line: b.line,
            cut: cut_ratio(&b, speed_mm_min),
            takeup: b.takeup,
        })
    }
}

/// `Segment::cut` of a segment of `b` at `speed_mm_min`: only plain feed
/// moves cut (not rapids, homing or probing), and a cutting segment is
/// never 0 however slow it starts.
fn cut_ratio(b: &Block, speed_mm_min: f32) -> f32 {
    let feed = b.programmed * 60.0;
    if b.rapid || b.watch != Watch::default() || !(feed > 0.0 && feed.is_finite()) {
        return 0.0;
    }
    (speed_mm_min / feed).max(f32::MIN_POSITIVE)
}
