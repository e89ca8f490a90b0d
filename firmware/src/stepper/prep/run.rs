//! S-curve runs: one speed profile across several blocks.
//!
//! An S-curve profile starts and ends every block at zero acceleration.
//! On a curve cut into chords of a few tenths of a millimetre that leaves
//! each chord a ramp too short to change the speed much: a 10 mm circle
//! from rest took 2.61 s, against 1.36 s with trapezoids, the speed
//! climbing in a staircase of chord-long ramps. So the oldest block and
//! the blocks after it, up to the first junction that needs a corner
//! hold, are planned as one run: its ramps go on across the junctions,
//! and the acceleration returns to zero only where the run ends. The jerk
//! stays bounded across the junctions (the acceleration is continuous)
//! and no corner that needs a hold is crossed on a ramp.
//!
//! A run ends before a block that is not a line, watches other inputs,
//! or has a nominal speed more than 5 % away from the first block's
//! (`planner::joins`: an arc's chords differ by a little as their
//! direction turns the axes' rate caps; the run cruises at the lowest of
//! its blocks', so every block's cap holds in all of it), after
//! [`MAX_RUN`] blocks, and before the newest block in the ring: the
//! planner may still merge the next collinear move into that one
//! (`planner::merge`), and a run planned on its old length ran on at speed
//! into a corner it had planned as the end of the path (1,225 % of X's
//! acceleration on short_segments when the host took 145 µs a line).
//!
//! It is planned from the speed the tool has to the planned entry of the
//! block after it. The planner's forward pass reckons that entry with the
//! same kind of run (`planner::run`), counted from the last junction
//! that ends one; a run that starts elsewhere, or is cut short (fewer
//! blocks queued, the newest excluded), may not reach it and enters the
//! next block slower, which is always safe: every entry stays within what
//! the backward pass allows for stopping. The path acceleration is the
//! smallest of the run's blocks. Then each junction inside is checked on
//! the profile: if the run passes one faster than its limit
//! (`max_entry`), the run ends at that junction, at its planned entry, and
//! is planned again.

use super::{Hold, Preparer};
use crate::planner::ramp::PHASES;
use crate::planner::{
    joins, Block, BlockKind, Phase, Planner, Profile, Shape, CURVE_RUN_JERK, RUN_BLOCKS,
};

/// Most blocks after the running one that a run takes in: 16 chords of
/// 0.4 mm (a 10 mm radius at `$12` = 0.002) are 6.4 mm, more than a ramp
/// from rest to 50 mm/s takes at 500 mm/s² and 5000 mm/s³ (5 mm).
pub const MAX_RUN: usize = RUN_BLOCKS - 1;

impl Preparer {
    /// The running block's profile from where the tool is: over a run in
    /// S-curve mode (see the module doc), else to the next block's entry.
    /// Returns the profile, the shape it was planned with, the speed it
    /// ends at, and how many blocks after the running one it covers.
    pub(super) fn plan_run<const N: usize>(
        &self,
        pl: &Planner<N>,
        b: &Block,
    ) -> (Profile, Shape, f32, usize) {
        let base = self.shape();
        let mut r = 0;
        if base.jerk > 0.0 && self.hold == Hold::Running {
            while r < MAX_RUN {
                match pl.block(r + 1) {
                    Some(n) if joins(b, n) && pl.block(r + 2).is_some() => r += 1,
                    _ => break,
                }
            }
        }
        let rest = b.length - self.s_done;
        let hold0 = self.entry_hold_left();
        loop {
            let mut shape = base;
            let mut len = rest;
            let mut curve = b.curve_ar > 0.0;
            let mut cruise = b.nominal;
            for k in 1..=r {
                if let Some(n) = pl.block(k) {
                    shape.accel = shape.accel.min(n.accel);
                    len += n.length;
                    curve |= n.curve_ar > 0.0;
                    cruise = cruise.min(n.nominal);
                }
            }
            if r > 0 && curve {
                shape.jerk *= CURVE_RUN_JERK;
            }
            let (exit, exit_m) = match pl.block(r + 1) {
                Some(n) if n.kind == BlockKind::Line => (n.entry, n.hold_pre_m),
                _ => (0.0, 0.0),
            };
            // A trapezoid chord ramps at what its top speed allows.
            let shape = Profile::held_shape(&shape, self.v, cruise, exit, len, hold0);
            let p = Profile::plan_held(&shape, self.v, cruise, exit, len, hold0, exit_m);
            // The first junction inside that the profile passes too fast.
            let mut at = rest;
            let mut over = None;
            for k in 1..=r {
                let Some(n) = pl.block(k) else { break };
                if speed_at(&shape, &p, at) > n.max_entry * (1.0 + 1e-4) {
                    over = Some(k);
                    break;
                }
                at += n.length;
            }
            match over {
                Some(k) => r = k - 1,
                None => return (p, shape, exit, r),
            }
        }
    }

    /// Speed and distance into the profile at `tau` s into phase `phase`
    /// (the walk's own evaluation, shared with [`Preparer::s_after`]).
    pub(super) fn at(&self, phase: usize, tau: f32) -> (f32, f32) {
        phase_at(&self.pshape, &self.profile.phases[phase], tau)
    }

    /// Distance into the block after walking `dt` more seconds.
    pub(super) fn s_after(&self, dt: f32) -> f32 {
        let (phase, tau, s0, _) = self.walk_to(dt);
        if phase < PHASES {
            s0 + self.at(phase, tau).1
        } else {
            s0
        }
    }

    /// A walk step of `dt` cut short so that it ends on the block's end
    /// when a run goes on past it: the block's last steps are timed to
    /// that instant and the next block's from it.
    pub(super) fn clip_to_block(&self, dt: f32, length: f32) -> f32 {
        if self.run_blocks == 0 || self.hold_ramp || self.s_after(dt) < length {
            return dt;
        }
        let (mut lo, mut hi) = (0.0, dt);
        for _ in 0..32 {
            let mid = 0.5 * (lo + hi);
            if self.s_after(mid) >= length {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }
}

/// Speed and distance `tau` s into `ph` (a tail of a ramp when `t0 > 0`).
pub(super) fn phase_at(sh: &Shape, ph: &Phase, tau: f32) -> (f32, f32) {
    if ph.v0 == ph.v1 {
        (ph.v0, ph.v0 * tau)
    } else if ph.t0 > 0.0 {
        let (v, s) = sh.eval(ph.v0, ph.v1, ph.t0 + tau);
        (v, s - sh.eval(ph.v0, ph.v1, ph.t0).1)
    } else {
        sh.eval(ph.v0, ph.v1, tau)
    }
}

/// The profile's speed `d` mm from its start.
fn speed_at(sh: &Shape, p: &Profile, d: f32) -> f32 {
    let mut s0 = 0.0;
    for ph in &p.phases {
        if d <= s0 + ph.dist && ph.time > 0.0 {
            if ph.v0 == ph.v1 {
                return ph.v0;
            }
            let (mut lo, mut hi) = (0.0, ph.time);
            for _ in 0..24 {
                let mid = 0.5 * (lo + hi);
                if phase_at(sh, ph, mid).1 < d - s0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return phase_at(sh, ph, hi).0;
        }
        s0 += ph.dist;
    }
    p.exit_speed()
}
