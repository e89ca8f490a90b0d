//! S-curve runs: one speed profile across several blocks.
//!
//! An S-curve profile starts and ends every block at zero acceleration.
//! On a curve cut into chords of a few tenths of a millimetre that leaves
//! each chord a ramp too short to change the speed much: a 10 mm circle
//! from rest took 2.61 s, against 1.36 s with trapezoids, the speed
//! climbing in a staircase of chord-long ramps. So a profile may span
//! several blocks as one ramp: its acceleration goes on across the
//! junctions inside and returns to zero only where it ends, at the planned
//! entry of the block after it. The preparer plans, from where the tool
//! is, the first of these that fits:
//!
//! 1. **Free**: the blocks ahead up to the first corner that holds, of
//!    nominal speeds near the running block's, cruising at their least
//!    nominal speed and cut short before the first junction the profile
//!    would pass too fast (the runs of the first S-curve preparer).
//! 2. **The block alone**, where it runs faster than the run's caps: it
//!    leaves faster than the run's ramp would cross the junction, or a
//!    block of the run is long enough for a ramp of its own.
//! 3. **The rest of its run** (`planner::run`): no faster than the run's
//!    cap, so no junction inside needs a check, to the next run's first
//!    block. What the planner's backward pass promised besides the block
//!    alone, so it fits where the block alone does not (a chain of short
//!    chords: circle_small.ngc at 5000 mm/s³, 39.3 s before, 23.2 s).
//!
//! When none fits, a limit ahead fell after the plan that brought the tool
//! here (`planner::run` says how); the rest of the run then slows the
//! most, where one block's ramp barely slows at all.

use super::{Hold, Preparer};
use crate::planner::ramp::PHASES;
use crate::planner::{nominal_near, Block, BlockKind, Phase, Planner, Profile, RunAhead, Shape};

/// Most blocks a free run spans: each junction inside is checked on its
/// profile, by bisection.
const FREE_BLOCKS: usize = 17;

/// A profile over one or more blocks: the profile, the shape it was
/// planned with, the speed it ends at, and how many blocks after the
/// running one it covers.
type Plan = (Profile, Shape, f32, usize);

impl Preparer {
    /// The running block's profile from where the tool is: in S-curve
    /// mode over part or the rest of its run where one of those fits and
    /// is the faster (see the module doc), else to the next block's entry.
    pub(super) fn plan_run<const N: usize>(&self, pl: &Planner<N>, b: &Block) -> Plan {
        let rest = b.length - self.s_done;
        let hold0 = self.entry_hold_left();
        // The block alone.
        let base = self.shape();
        let (exit, exit_m) = exit_of(pl, 1);
        let shape = Profile::held_shape(&base, self.v, b.nominal, exit, rest, hold0);
        let alone = Profile::plan_held(&shape, self.v, b.nominal, exit, rest, hold0, exit_m);
        if base.jerk <= 0.0 || self.hold != Hold::Running {
            return (alone, shape, exit, 0);
        }
        if let Some(free) = self.plan_free(pl, b, rest, hold0) {
            return free;
        }
        let Some(run) = pl.run_ahead(b).filter(|r| r.extra > 0) else {
            return (alone, shape, exit, 0);
        };
        let cap = run.cap();
        let alone_fits = fits(&alone, exit);
        if alone_fits && (alone.phases[2].v0 > cap || self.outgrows(pl, b, &run, cap, rest)) {
            return (alone, shape, exit, 0);
        }
        // The rest of the run as one ramp, within its caps.
        let (run_exit, run_exit_m) = exit_of(pl, run.extra + 1);
        // Its corners' share at the fastest it runs: above the cap where a
        // limit fell under the tool (the fallback below).
        let top = cap.max(self.v);
        let run_shape = run.shape(&self.settings, top);
        let len = run.len - b.length + rest;
        let p = Profile::plan_held(&run_shape, self.v, top, run_exit, len, hold0, run_exit_m);
        if self.v <= cap * (1.0 + 1e-4) && fits(&p, run_exit) {
            return (p, run_shape, run_exit, run.extra);
        }
        // Neither fits: the tool is above what the planner now allows here,
        // a limit that fell after the plan that brought it here
        // (`planner::run`: an S ramp's length is not monotone in where it
        // ends, and a straight stretch's ramps take less, `planner::tube`).
        // One block's S ramp barely slows on a short chord (0.1 mm/s on
        // 0.7 mm at 2500 mm/s³), and a chain of them ran on at 81 mm/s into
        // a 14 mm/s corner; the run's one ramp slows the most, from above
        // its cap if need be.
        if !alone_fits && fits_better(&p, run_exit, &alone, exit) {
            return (p, run_shape, run_exit, run.extra);
        }
        (alone, shape, exit, 0)
    }

    /// Whether a block of the run is long enough, and allowed fast enough,
    /// for a ramp of its own to gain a tenth on the run's caps: one ramp
    /// over the run would cross it at the least corner's speed, where block
    /// by block runs faster (an S ramp over `L` from `v` gains about
    /// `j·(L/2v)²`). `cap`: the run's ([`RunAhead::cap`]).
    fn outgrows<const N: usize>(
        &self,
        pl: &Planner<N>,
        b: &Block,
        run: &RunAhead,
        cap: f32,
        rest: f32,
    ) -> bool {
        let j = run.shape(&self.settings, cap).jerk;
        let long = 2.0 * cap * crate::num::sqrt(0.1 * cap / j);
        let grows = |len: f32, n: &Block| len > long && n.nominal > 1.1 * cap;
        grows(rest, b)
            || (1..=run.extra)
                .filter_map(|k| pl.block(k))
                .any(|n| grows(n.length, n))
    }

    /// The blocks after the running one up to the first corner that holds
    /// (of nominal speeds near its own, at most a run's worth, and never
    /// the newest, which may still grow: `planner::merge`) as one ramp that
    /// cruises at their least nominal speed, cut short before the first
    /// junction inside it passes too fast, and taken only if it spans two
    /// blocks or more and ends no faster than planned. Where corners inside
    /// allow more than the least of them, this goes faster than the rest
    /// of the run within its caps.
    fn plan_free<const N: usize>(
        &self,
        pl: &Planner<N>,
        b: &Block,
        rest: f32,
        hold0: f32,
    ) -> Option<Plan> {
        let mut r = 0;
        while r + 1 < FREE_BLOCKS {
            let Some(n) = pl.block(r + 1) else { break };
            let free = n.kind == BlockKind::Line && n.hold_m <= 0.0 && n.hold_pre_m <= 0.0;
            let same = n.watch == b.watch && nominal_near(n.nominal, b.nominal);
            if !(free && same && pl.block(r + 2).is_some()) {
                break;
            }
            r += 1;
        }
        while r > 0 {
            // The blocks' least acceleration and nominal speed and their
            // length, as the rest of a run has them (no junction inside
            // holds, so the whole acceleration).
            let mut run = RunAhead::start(b);
            for k in 1..=r {
                run.block(pl.block(k)?);
            }
            // No corner inside holds: the cap leaves the ramp as it is.
            let shape = run.shape(&self.settings, run.cruise());
            let len = run.len - b.length + rest;
            let (exit, exit_m) = exit_of(pl, r + 1);
            let p = Profile::plan_held(&shape, self.v, run.cruise(), exit, len, hold0, exit_m);
            // The first junction inside that the profile passes too fast.
            let mut at = rest;
            let mut over = None;
            for k in 1..=r {
                let n = pl.block(k)?;
                if speed_at(&shape, &p, at) > n.max_entry * (1.0 + 1e-4) {
                    over = Some(k);
                    break;
                }
                at += n.length;
            }
            match over {
                Some(k) => r = k - 1,
                None if fits(&p, exit) => return Some((p, shape, exit, r)),
                None => return None,
            }
        }
        None
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

/// The planned entry of the `k`-th block from the oldest and its corner's
/// hold on the near side (none and a stop if it is not a line).
fn exit_of<const N: usize>(pl: &Planner<N>, k: usize) -> (f32, f32) {
    match pl.block(k) {
        Some(n) if n.kind == BlockKind::Line => (n.entry, n.hold_pre_m),
        _ => (0.0, 0.0),
    }
}

/// Whether a profile ends no faster than `exit`, give or take rounding.
fn fits(p: &Profile, exit: f32) -> bool {
    p.exit_speed() <= exit * (1.0 + 1e-4) + 1e-4
}

/// Whether `p` misses its `exit` by less than `q` misses its own.
fn fits_better(p: &Profile, exit: f32, q: &Profile, q_exit: f32) -> bool {
    p.exit_speed() - exit < q.exit_speed() - q_exit
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
