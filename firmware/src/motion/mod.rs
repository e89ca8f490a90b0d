//! The motion pipeline behind one gateway: every motion the sequencer
//! (`executor`) decides on enters here as a typed [`Move`] through
//! [`Pipeline::submit`], and nowhere else. The pipeline owns what turns
//! moves into steps: the motion settings, the planner, the segment
//! preparer, the step configuration and the commanded motor position, and
//! it says when motion is idle.
//!
//! One entry is where per-move corrections plug in (grblHAL's `mc_line`):
//! whatever the sequencer asks, it asks in machine mm, and what the planner
//! and the stepper see may differ from it only here.
//!
//! Backlash compensation (`$160`-`$163`, [`Settings::backlash_mm`]) is the
//! first: the planner works in motor steps, which are the commanded
//! position plus `comp`. When a move reverses an axis, a take-up block
//! (a rapid line on the reversing axes alone, so their rate and
//! acceleration limits hold and the reversal stops at its corner) moves
//! the motors across the slack first and `comp` changes by it. An axis
//! whose slack is taken up towards its homing direction (`$23`) has
//! `comp` 0, the other way `∓backlash`: that is the state assumed at
//! power-up and kept through homing and position redefinitions, which
//! change coordinates, not the mechanism. The step interrupt leaves
//! take-up steps out of the position ([`crate::stepper::Segment::takeup`])
//! and adds them to [`Realtime::takeup`], so the reported position never
//! shows them, and a flush takes `comp` back from what ran.
//!
//! ```text
//! executor (sequencer) --Move--> Pipeline::submit --> planner --> preparer --> step ISR
//! ```

use crate::command::Pos;
use crate::planner::{Curve, PlanError, Planner, Speed, Watch};
use crate::realtime::Realtime;
use crate::seams::StepConfig;
use crate::settings::Settings;
use crate::stepper::prep::{Hold, Preparer, SegmentSink};
use crate::AXES;

/// One motion request, in machine mm, with the source line it came from
/// (for `Ln:`, errors and traces).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Move {
    /// A straight line (a feed, a rapid or one leg of it, a probing or
    /// homing move) to `end`; `watch` stops it on a switch.
    Line {
        end: Pos,
        speed: Speed,
        watch: Watch,
        line: u32,
    },
    /// One chord of an arc or spline ending at `end`: the planner shares
    /// the axes' acceleration between the turn and the path (`curve`).
    Chord {
        end: Pos,
        speed: Speed,
        curve: Curve,
        line: u32,
    },
    /// Stand still this long (finite, not negative; the caller checks);
    /// motion stops before it.
    Dwell { seconds: f32, line: u32 },
}

/// The motion pipeline. `N` is the planner ring size.
#[derive(Debug)]
pub struct Pipeline<const N: usize> {
    planner: Planner<N>,
    prep: Preparer,
    cfg: StepConfig,
    /// Motor steps minus commanded steps per axis at the end of what is
    /// planned: the backlash taken up away from the homing direction.
    comp: [i32; AXES],
    /// Moves queued since the segment queue was last filled.
    burst: u8,
}

/// Moves the planner takes between two fills of the segment queue in
/// S-curve mode. Where the look-ahead binds, each costs up to 1.3 ms on
/// the board (`cargo xtask bench-target`, `plan_chord_scurve_insns`,
/// 96,317 instructions: its passes walk the ring twice, 120 blocks at 740
/// instructions each), and the preparer runs only 30 ms ahead of the step
/// interrupt (`stepper::prep`): 64 moves planned in one go into such a
/// ring walk about 4,000 blocks, 40 ms, and the step interrupt would run
/// out of segments in the middle of a move (host-sim charging the then
/// 2.1 ms of a block to every block showed it: Z at 119 % of its
/// acceleration on a helix after a rapid). Four take at most about 5 ms,
/// 8 ms beside 100 kHz of stepping. Trapezoid mode's 64 take 6.5 ms
/// (`plan_block_insns`), so it has no bound.
pub const PLAN_BURST_SCURVE: u8 = 4;

impl<const N: usize> Pipeline<N> {
    pub fn new(settings: Settings, tick_hz: u32) -> Self {
        let cfg = StepConfig::new(&settings, tick_hz);
        let mut planner = Planner::new(settings);
        planner.set_tick_hz(tick_hz);
        Pipeline {
            planner,
            prep: Preparer::new(settings, cfg),
            cfg,
            comp: [0; AXES],
            burst: 0,
        }
    }

    /// All zero bits, for the board's machine slot (`Machine::placeholder`);
    /// [`Pipeline::rebuild`] makes it a pipeline.
    pub const fn zeroed() -> Self {
        Pipeline {
            planner: Planner::zeroed(),
            prep: Preparer::zeroed(),
            cfg: StepConfig::UNSET,
            comp: [0; AXES],
            burst: 0,
        }
    }

    /// [`Pipeline::new`], in place: the planner keeps its ring's storage
    /// ([`Planner::reset`]), so no second ring is built on the stack. The
    /// backlash state stays (the mechanism did not move; `$n=` waits for
    /// idle, so it agrees with [`Realtime::takeup`]).
    pub fn rebuild(&mut self, settings: Settings, tick_hz: u32) {
        self.planner.reset(settings);
        self.planner.set_tick_hz(tick_hz);
        self.cfg = StepConfig::new(&settings, tick_hz);
        self.prep = Preparer::new(settings, self.cfg);
    }

    /// The gateway: queue one move. The caller checks
    /// [`has_room`](Self::has_room) first (a full planner refuses it), and
    /// [`may_plan`](Self::may_plan) where it has more to queue.
    pub fn submit(&mut self, mv: Move) -> Result<(), PlanError> {
        self.burst = self.burst.saturating_add(1);
        self.submit_move(mv)
    }

    fn submit_move(&mut self, mv: Move) -> Result<(), PlanError> {
        match mv {
            Move::Line {
                end,
                speed,
                watch,
                line,
            } => {
                let speed = self.rotary_feed(&end, speed);
                if !self.compensating() {
                    return self.planner.push_line_mm(&end, speed, watch, line);
                }
                self.take_up(&end, line)?;
                let comp = self.comp;
                self.planner
                    .push_shifted(&end, &comp, speed, watch, line, None)
            }
            Move::Chord {
                end,
                speed,
                curve,
                line,
            } => {
                let speed = self.rotary_feed(&end, speed);
                if !self.compensating() {
                    return self.planner.push_chord(&end, speed, line, curve);
                }
                self.take_up(&end, line)?;
                let comp = self.comp;
                let watch = Watch::default();
                self.planner
                    .push_shifted(&end, &comp, speed, watch, line, Some(curve))
            }
            Move::Dwell { seconds, line } => {
                let ticks = dwell_ticks(seconds, self.cfg.tick_hz);
                self.planner.push_dwell(ticks, line)
            }
        }
    }

    /// RS274NGC's feed rule for rotary axes (`$376`), as LinuxCNC and
    /// grblHAL apply it: F is the speed along the linear axes' path, mm
    /// per minute, and the rotary axes take the move's time; a move of
    /// rotary axes alone takes F in degrees per minute along their own
    /// path. The planner's path is every axis's (its limits hold per
    /// axis), so a move that turns a rotary axis while a linear one moves
    /// is given as its time (`Speed::Time`, as G93 gives it): linear
    /// length / F. Every other move (no rotary axis set, or only one kind
    /// of axis moving) keeps its feed, so machines without `$376` plan
    /// exactly as before.
    fn rotary_feed(&self, end: &Pos, speed: Speed) -> Speed {
        let rotary = self.settings().rotary_axes;
        let Speed::Feed(f) = speed else {
            return speed;
        };
        if rotary == 0 {
            return speed;
        }
        // The planner's last end is the motor's (`push_shifted` adds the
        // backlash taken up); the move starts at the commanded one.
        let from = self.planner.commanded_mm();
        let axes = &self.settings().axes;
        let (mut linear, mut turned) = (0.0f32, false);
        for i in 0..AXES {
            let spm = axes[i].steps_per_mm;
            let d = end[i] - (from[i] - self.comp[i] as f32 / spm);
            // Under half a step is rounding (of the shift above, or of a
            // far coordinate), not a move of the axis.
            if libm::fabsf(d * spm) < 0.5 {
                continue;
            }
            if rotary & (1 << i) != 0 {
                turned = true;
            } else {
                linear += d * d;
            }
        }
        if !turned || linear <= 0.0 {
            return speed;
        }
        Speed::Time(crate::num::sqrt(linear) / f)
    }

    /// The next [`submit`](Self::submit) has a planner slot (two while
    /// backlash is compensated: a take-up may go first).
    pub fn has_room(&self) -> bool {
        let need = if self.compensating() { 2 } else { 1 };
        self.planner.len() + need <= N
    }

    /// Room, and the segment queue filled since the last
    /// [`PLAN_BURST_SCURVE`] moves in S-curve mode.
    pub fn may_plan(&self) -> bool {
        self.has_room()
            && (self.settings().profile != crate::settings::Profile::SCurve
                || self.burst < PLAN_BURST_SCURVE)
    }

    /// Backlash is set on some axis or still taken up (a path that only
    /// this can change: with `$160`-`$163` at 0 and nothing taken up,
    /// moves are planned exactly as without compensation).
    fn compensating(&self) -> bool {
        self.comp != [0; AXES] || self.settings().backlash_mm.iter().any(|&b| b > 0.0)
    }

    /// Motor steps minus commanded steps for axis `i` once it has moved
    /// towards positive (`positive`) or negative: 0 towards its homing
    /// direction, the backlash against it.
    fn comp_towards(&self, i: usize, positive: bool) -> i32 {
        let s = self.settings();
        let homes_positive = s.homing_dir_invert & (1 << i) == 0;
        if positive == homes_positive {
            return 0;
        }
        let b = libm::roundf(s.backlash_mm[i] * s.axes[i].steps_per_mm);
        let b = if b.is_finite() { b as i32 } else { 0 };
        if homes_positive {
            -b
        } else {
            b
        }
    }

    /// Queue the take-up a move to `end` needs on the axes it reverses
    /// (or moves for the first time since the slack changed side), and
    /// move `comp` by it.
    fn take_up(&mut self, end: &Pos, line: u32) -> Result<(), PlanError> {
        let target = self.planner.to_steps(end)?;
        let at = self.planner.position();
        let take: [i32; AXES] = core::array::from_fn(|i| {
            let d = i64::from(target[i]) - (i64::from(at[i]) - i64::from(self.comp[i]));
            if d == 0 {
                0
            } else {
                self.comp_towards(i, d > 0).wrapping_sub(self.comp[i])
            }
        });
        if take == [0; AXES] {
            return Ok(());
        }
        self.planner.push_takeup(&take, line)?;
        for (c, t) in self.comp.iter_mut().zip(take) {
            *c = c.wrapping_add(t);
        }
        Ok(())
    }

    /// Motor steps minus commanded steps per axis, as planned.
    pub fn backlash_comp(&self) -> [i32; AXES] {
        self.comp
    }

    pub fn settings(&self) -> &Settings {
        &self.planner.settings
    }
    pub fn step_config(&self) -> StepConfig {
        self.cfg
    }
    /// The planner, to read (traces, tests, the planner's free slots).
    pub fn planner(&self) -> &Planner<N> {
        &self.planner
    }
    /// The preparer, to read (traces, tests).
    pub fn prep(&self) -> &Preparer {
        &self.prep
    }

    /// Steps for a machine position, mm (rounded from the absolute value).
    pub fn to_steps(&self, mm: &Pos) -> Result<[i32; AXES], PlanError> {
        self.planner.to_steps(mm)
    }
    pub fn steps_to_mm(&self, steps: &[i32; AXES]) -> Pos {
        let s = &self.planner.settings;
        core::array::from_fn(|i| steps[i] as f32 / s.axes[i].steps_per_mm)
    }

    /// The machine is at `steps` (power-up, homing's pull-off, a test):
    /// the step interrupt's count and the plan start there. Call with
    /// nothing queued. Returns the position in mm.
    pub fn redefine(&mut self, rt: &Realtime, steps: &[i32; AXES]) -> Pos {
        rt.redefine_position(steps);
        self.planner.clear(self.motor(steps));
        self.steps_to_mm(steps)
    }

    /// Motor steps for a commanded (reported) step position.
    fn motor(&self, steps: &[i32; AXES]) -> [i32; AXES] {
        core::array::from_fn(|i| steps[i].wrapping_add(self.comp[i]))
    }

    /// Drop everything queued and take the stepper's position as truth:
    /// returns it, mm (the sequencer's next move starts there).
    pub fn flush(&mut self, rt: &Realtime) -> Pos {
        rt.bump_generation();
        self.prep.reset();
        let pos = rt.position();
        // What was planned but not loaded is gone: the take-up that ran.
        self.comp = rt.takeup();
        self.planner.clear(self.motor(&pos));
        rt.clear_trip();
        self.steps_to_mm(&pos)
    }

    /// Feed and rapid override, percent.
    pub fn set_overrides(&mut self, feed_pct: u8, rapid_pct: u8) {
        self.planner.set_overrides(feed_pct, rapid_pct);
    }

    /// Ramp the motion down and drop the rest (a probe's contact, a
    /// fault): unlike a hold, cycle start does not resume it.
    pub fn cancel_motion(&mut self) {
        self.prep.cancel_motion();
    }
    pub fn hold(&self) -> Hold {
        self.prep.hold()
    }
    pub fn cancelling(&self) -> bool {
        self.prep.cancelling()
    }
    /// Source line of the block prepared last.
    pub fn line(&self) -> u32 {
        self.prep.line()
    }

    /// A hold or cancel has come to rest: the preparer holds, the queue is
    /// empty and the step interrupt stopped.
    pub fn stopped(&self, rt: &Realtime, sink: &impl SegmentSink) -> bool {
        self.prep.hold() == Hold::Held && sink.is_empty() && rt.stepper_idle()
    }

    /// No motion left: nothing planned, prepared, queued for the step
    /// interrupt or being stepped (`drained` and an empty queue).
    /// The queue is read before the step interrupt's idle flag: the
    /// interrupt pops and loads a segment in one go, so one it takes
    /// between the two reads has cleared the flag by then and is not
    /// missed (the other order could see both idle).
    pub fn motion_idle(&self, rt: &Realtime, sink: &impl SegmentSink) -> bool {
        self.planner.is_empty() && self.prep.is_idle() && sink.is_empty() && rt.stepper_idle()
    }

    /// [`Self::motion_idle`] as far as the pipeline sees without the
    /// segment queue: the status report's Idle (it differs only while
    /// segments wait for a stopped step interrupt to load them).
    pub fn drained(&self, rt: &Realtime) -> bool {
        self.planner.is_empty() && self.prep.is_idle() && rt.stepper_idle()
    }

    /// Prepare segments for the step interrupt (see [`Preparer::fill`]).
    pub fn fill(&mut self, rt: &Realtime, sink: &mut impl SegmentSink) {
        self.prep.fill(&mut self.planner, rt, sink);
        self.burst = 0;
    }
}

/// Timer ticks of a dwell of `seconds` (finite, not negative), without
/// `f64` (soft-float on the board): whole seconds exactly, the fraction
/// through `f32`, within 6 ticks (63 ns at 96 MHz) of the exact product.
pub fn dwell_ticks(seconds: f32, tick_hz: u32) -> u64 {
    let s = seconds.max(0.0);
    let whole = s as u64;
    // Exact: an f32 minus its integer part.
    let frac = s - whole as f32;
    whole * u64::from(tick_hz) + (frac * tick_hz as f32) as u64
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod dwell_tests {
    use super::dwell_ticks;

    #[test]
    fn dwell_ticks_are_within_a_few_of_the_exact_product() {
        let hz = 96_000_000u32;
        assert_eq!(dwell_ticks(0.5, hz), 48_000_000);
        assert_eq!(dwell_ticks(0.0, hz), 0);
        assert_eq!(dwell_ticks(3.0, 48_000), 144_000);
        for i in 0..100_000u32 {
            let s = i as f32 * 0.012_345 + (i % 7) as f32 * 1_000.0;
            let exact = (f64::from(s) * f64::from(hz)) as i64;
            let got = dwell_ticks(s, hz) as i64;
            assert!((got - exact).abs() <= 6, "{s}: {got} vs {exact}");
        }
    }
}
