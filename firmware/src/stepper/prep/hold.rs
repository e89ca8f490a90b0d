//! Feed hold and motion cancel (probe contact): ramp down along the path.

use super::{Hold, Preparer};
use crate::planner::ramp::PHASES;
use crate::planner::{Phase, Profile};

impl Preparer {
    /// Ramp down to a stop and stay there until the executor flushes
    /// (probe contact). A feed hold already under way just carries on.
    pub fn cancel_motion(&mut self) {
        self.cancel = true;
        if self.hold == Hold::Running {
            self.begin_hold();
        }
    }

    /// A motion cancel is under way (not an operator hold).
    pub fn cancelling(&self) -> bool {
        self.cancel
    }

    pub(super) fn begin_hold(&mut self) {
        // `v` carries across block boundaries: between two blocks the
        // tool is still moving and the hold ramp starts in the next one.
        // So it does when the ramp would run past a corner (`plan_hold`).
        // A hold plans block by block (`plan_hold`): no run goes on.
        self.run_blocks = 0;
        if self.v > 1e-6 {
            self.hold = Hold::Decelerating;
            if self.active {
                self.plan_hold(true);
            }
        } else {
            self.hold = Hold::Held;
        }
    }

    /// Acceleration of the running profile now, mm/s² (signed).
    fn accel_now(&self) -> f32 {
        match self.profile.phases.get(self.phase) {
            Some(ph) if ph.v0 != ph.v1 => self.pshape.accel_at(ph.v0, ph.v1, ph.t0 + self.tau),
            _ => 0.0,
        }
    }

    /// The hold ramp from the current state (again at each new block, whose
    /// acceleration limit may differ). With S-curves the acceleration
    /// must first return to zero at the jerk limit (the speed still changes
    /// by `a²/2j` meanwhile): that is the second half of a symmetric ramp
    /// whose peak acceleration is the current one. A symmetric S ramp to
    /// zero follows. Trapezoids drop the acceleration at once. What is
    /// left of the entry corner's hold, for the speed now, comes first.
    ///
    /// A ramp that would run on past the block's end into a corner that
    /// needs a hold is not taken (returns false): it would turn the
    /// corner with no hold, each axis's velocity jumping on top of the
    /// ramps. The planned profile, which slows for the corner and holds
    /// it, runs on instead, and the hold ramp starts in the next block.
    /// Where the planned profile stops at the block's end anyway it is
    /// the hold's ramp: an S ramp, which first brings the acceleration
    /// back to zero, can take longer to stop than a profile already
    /// slowing down (one ran on past the end of a block planned to stop,
    /// into a corner at 17 mm/s where 3.95 was allowed). Past chords of a
    /// curve and straight on the ramp runs on, as it always did. A motion
    /// cancel (probe contact) always ramps at once. `planned`: the running
    /// profile is this block's (at a block's start it is the last one's).
    pub(super) fn plan_hold(&mut self, planned: bool) -> bool {
        // A stop from `v`: `v` is its top speed.
        let sh = self.shape().at_top(self.v);
        let a = if sh.jerk > 0.0 { self.accel_now() } else { 0.0 };
        let zero = Phase::default();
        let mut phases = [zero; PHASES];
        let mut v = self.v;
        let mut k = 0;
        let hold0 = self.entry_hold_left();
        if hold0 > 0.0 && v > 1e-3 && libm::fabsf(a) <= 1e-3 {
            phases[0] = Phase {
                v0: v,
                v1: v,
                time: hold0 / v,
                dist: hold0,
                t0: 0.0,
            };
            k = 1;
        }
        if libm::fabsf(a) > 1e-3 {
            let tj = libm::fabsf(a) / sh.jerk;
            let half = 0.5 * a * a / sh.jerk * if a < 0.0 { -1.0 } else { 1.0 };
            let (v0, v1) = (v - half, (v + half).max(0.0));
            let whole = 0.5 * (v0 + v1) * 2.0 * tj;
            phases[k] = Phase {
                v0,
                v1,
                time: tj,
                dist: (whole - sh.eval(v0, v1, tj).1).max(0.0),
                t0: tj,
            };
            v = v1;
            k += 1;
        }
        phases[k] = Phase {
            v0: v,
            v1: 0.0,
            time: sh.time(v),
            dist: sh.dist(v, 0.0),
            t0: 0.0,
        };
        let p = Profile { phases };
        let rest = self.block.map_or(0.0, |b| b.length - self.s_done);
        if p.total_dist() > rest + 1e-6 && !self.cancel {
            if planned && self.phase < PHASES && self.profile.exit_speed() <= 1e-6 {
                // The planned profile already stops at the block's end,
                // sooner than this ramp would (an S ramp that must first
                // bring a falling acceleration back to zero).
                self.hold_ramp = true;
                return true;
            }
            if self.exit_m > 0.0 {
                return false;
            }
        }
        self.set_profile(p);
        self.hold_ramp = true;
        true
    }

    /// An S-curve profile may only be replaced where acceleration is zero.
    pub(super) fn can_replan(&self) -> bool {
        self.settings.profile == crate::settings::Profile::Trapezoid
            || self.tau == 0.0
            || self.phase >= PHASES
            || self
                .profile
                .phases
                .get(self.phase)
                .is_some_and(|p| p.v0 == p.v1)
    }
}
