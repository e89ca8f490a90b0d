//! Speed-change math shared by the planner (how fast can a block be entered)
//! and the segment preparer (where is the tool at time t).
//!
//! Trapezoid: constant acceleration `a`.
//!
//! S-curve (burin's own, GRBL has none): each speed change is a symmetric
//! jerk-limited ramp. Acceleration rises at jerk `j` to at most `a`, holds,
//! and falls back to zero at `j`, so it is zero at every ramp end and block
//! junction. A ramp of `dv` takes `dv/a + a/j` when `dv ≥ a²/j`, otherwise
//! `2·sqrt(dv/j)`; because the ramp is point-symmetric its distance is
//! always `(v0 + v1)/2 · T`. The planner uses the same distance function for
//! look-ahead, so every planned speed is reachable by the S ramps and the
//! acceleration limit is kept exactly; the price is slower speed changes.

/// How speed changes: acceleration limit and, for S-curves, jerk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    /// mm/s²
    pub accel: f32,
    /// mm/s³; `0` means unlimited (trapezoid).
    pub jerk: f32,
    /// Trapezoid chords of a curve: a ramp whose top speed is `v` may
    /// accelerate at `accel − drop·v²` (`planner::curve`); 0 elsewhere.
    pub drop: f32,
}

impl Shape {
    /// The constant-acceleration shape of a profile whose top speed is
    /// `top`: the acceleration every speed up to it allows.
    pub fn at_top(&self, top: f32) -> Shape {
        Shape {
            accel: self.accel - self.drop * top * top,
            jerk: self.jerk,
            drop: 0.0,
        }
    }

    /// The top speed of a trapezoid from `v0` to `v1` (or as close as
    /// `len` allows) cruising at most at `vn`, with the acceleration its
    /// own top allows (`drop`). In squares (`w = v²`): the triangle's peak
    /// solves `2w − w0 − w1 = 2·len·(accel − drop·w)`; an exit out of
    /// reach ends at `w = (w0 + 2·len·accel)/(1 + 2·len·drop)`, which is
    /// then below the peak; an entry above both is the top itself.
    pub fn top(&self, v0: f32, vn: f32, v1: f32, len: f32) -> f32 {
        let (w0, w1, l) = (v0 * v0, v1 * v1, len.max(0.0));
        let peak = (w0 + w1 + 2.0 * l * self.accel) / (2.0 + 2.0 * l * self.drop);
        let reach = (w0 + 2.0 * l * self.accel) / (1.0 + 2.0 * l * self.drop);
        crate::num::sqrt((vn * vn).min(peak).min(reach).max(w0))
    }

    /// Duration of a speed change of `dv` (≥ 0).
    pub fn time(&self, dv: f32) -> f32 {
        let dv = dv.abs();
        let a = self.accel;
        if self.jerk <= 0.0 {
            dv / a
        } else if dv * self.jerk >= a * a {
            dv / a + a / self.jerk
        } else {
            2.0 * crate::num::sqrt(dv / self.jerk)
        }
    }

    /// Distance to change speed between `v0` and `v1`.
    pub fn dist(&self, v0: f32, v1: f32) -> f32 {
        0.5 * (v0 + v1) * self.time(v1 - v0)
    }

    /// Highest speed reachable from `v` (accelerating or, read backwards,
    /// decelerating) within `len` mm.
    pub fn reach(&self, v: f32, len: f32) -> f32 {
        let l = len.max(0.0);
        // With `drop`, the ramp's top is where it ends (read backwards,
        // where it starts): `x² − v² = 2·l·(accel − drop·x²)`.
        let trap = if self.drop > 0.0 {
            crate::num::sqrt((v * v + 2.0 * self.accel * l) / (1.0 + 2.0 * self.drop * l))
        } else {
            crate::num::sqrt(v * v + 2.0 * self.accel * l)
        };
        if self.jerk <= 0.0 {
            return trap;
        }
        // The S ramp is never faster than the trapezoid. Solved in closed
        // form (the passes call this for every block of a full ring: by
        // bisection an S-curve chord cost 500,000 instructions to plan),
        // then checked, and bisected only if rounding left it too far.
        let x = self.s_reach(v, len.max(0.0)).min(trap);
        let mut back = 1e-5;
        for _ in 0..3 {
            // A few ulps at least: where the ramp is short next to `v`,
            // `x − v` carries the rounding of `x`.
            let y = (x - ((x - v) * back).max(4.0 * f32::EPSILON * x)).max(v);
            if self.dist(v, y) <= len {
                return y;
            }
            back *= 10.0;
        }
        self.fitting(v, v, trap, len)
    }

    /// The speed an S ramp from `v` ends at after exactly `len` mm.
    /// With the acceleration reaching `a` (`dv ≥ a²/j`):
    /// `len = (x² − v²)/2a + (x + v)·a/2j`, a quadratic in `x`. Below
    /// that, `len = (2v + d)·sqrt(d/j)` with `d = x − v`, which Newton's
    /// method solves from above (the cubic `(2v + d)²·d` is convex and
    /// increasing, so every step stays above the root), starting at the
    /// least of the upper bounds `a²/j`, `len²·j/4v²` and `cbrt(len²·j)`:
    /// from `a²/j` alone a dozen steps were not always enough.
    fn s_reach(&self, v: f32, len: f32) -> f32 {
        let (a, j) = (self.accel, self.jerk);
        let full = a * a / j;
        let c = v * full - v * v - 2.0 * a * len;
        let x = 0.5 * (crate::num::sqrt((full * full - 4.0 * c).max(0.0)) - full);
        if x - v >= full {
            return x;
        }
        let target = len * len * j;
        // Start at an upper bound near the root: the cubic is at least
        // `4v²·d` and at least `d³`.
        let mut d = full;
        if v > 0.0 {
            d = d.min(target / (4.0 * v * v));
        }
        if d > 2.0 * v {
            d = d.min(crate::num::cbrt(target));
        }
        for _ in 0..12 {
            let w = 2.0 * v + d;
            let f = w * w * d - target;
            if f <= 0.0 {
                break;
            }
            let step = f / (w * (2.0 * v + 3.0 * d));
            d -= step;
            if step <= 1e-7 * (v + d) {
                break;
            }
        }
        v + d.max(0.0)
    }

    /// The largest speed in `lo..=hi` that a ramp from `v` ends at within
    /// `len` mm, by bisection (`lo` when none does); the ramp's distance
    /// must grow towards `hi` there.
    fn fitting(&self, v: f32, mut lo: f32, mut hi: f32, len: f32) -> f32 {
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if self.dist(v, mid) <= len {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The fastest speed at the far end of a block of `len` mm whose near
    /// end runs at `known`, when each end holds its speed for a corner:
    /// `known²·m_known/2` mm at the near end, `x²·m_other/2` at the far
    /// one (`planner::passes` explains the holds). Read forwards it is the
    /// fastest exit from an entry, backwards the fastest entry that still
    /// slows to an exit. Below `known` only when the far end cannot even
    /// hold `known` (the pass the other way then lowers `known`).
    pub fn reach_held(&self, known: f32, len: f32, m_known: f32, m_other: f32) -> f32 {
        let v = known;
        let avail = (len - 0.5 * m_known * v * v).max(0.0);
        if m_other <= 0.0 {
            return self.reach(v, avail);
        }
        let half = 0.5 * m_other;
        if half * v * v > avail {
            return crate::num::sqrt(avail / half);
        }
        if self.jerk <= 0.0 {
            // x²·m/2 + (x² − v²)/2a = avail. With `drop`, solved at the
            // acceleration the first answer's speed allows: the second
            // answer is slower, so its own allows more.
            let solve = |a: f32| {
                let k = 0.5 / a;
                crate::num::sqrt((avail + k * v * v) / (half + k))
            };
            let x = solve(self.accel);
            if self.drop <= 0.0 {
                return x;
            }
            return solve(self.accel - self.drop * x * x);
        }
        let (mut lo, mut hi) = (v, self.reach(v, avail));
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if half * mid * mid + self.dist(v, mid) <= avail {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The speed to slow to from `v` within `len` mm when `target` is out
    /// of reach: the fastest one at or below `target` that fits, else (not
    /// even a stop fits) the slowest one above it.
    ///
    /// An S ramp's distance is not monotone in where it ends: from
    /// 83 mm/s (500 mm/s², 5000 mm/s³) a stop takes 11.1 mm and a ramp
    /// down to 28 mm/s 11.7 mm, since the ramp's fixed `a/j` runs at a
    /// higher mean speed. A block whose exit rose while it cruised can so
    /// miss the new exit but still fit a stop: it used to stop dead in the
    /// middle of a straight run; it now ends at the fastest speed below
    /// the exit that fits (10 mm/s there). For a trapezoid a stop never
    /// fits when `target` does not, and this is the slowest reachable speed.
    pub fn reach_down_to(&self, v: f32, target: f32, len: f32) -> f32 {
        if self.dist(v, 0.0) > len {
            return self.reach_down(v, len);
        }
        self.fitting(v, 0.0, crate::num::clamp(target, 0.0, v), len)
    }

    /// Lowest speed reachable when slowing from `v` within `len` mm.
    pub fn reach_down(&self, v: f32, len: f32) -> f32 {
        if self.jerk <= 0.0 {
            return crate::num::sqrt((v * v - 2.0 * self.accel * len.max(0.0)).max(0.0));
        }
        if self.dist(v, 0.0) <= len {
            return 0.0;
        }
        let (mut lo, mut hi) = (0.0, v);
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if self.dist(v, mid) <= len {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }

    /// Acceleration `tau` seconds into a ramp from `v0` to `v1` (signed).
    pub fn accel_at(&self, v0: f32, v1: f32, tau: f32) -> f32 {
        let dv = v1 - v0;
        let total = self.time(dv);
        if total <= 0.0 {
            return 0.0;
        }
        let sg = if dv < 0.0 { -1.0 } else { 1.0 };
        if self.jerk <= 0.0 {
            return dv / total;
        }
        let tau = crate::num::clamp(tau, 0.0, total);
        let j = self.jerk;
        let tj = if dv.abs() * j >= self.accel * self.accel {
            self.accel / j
        } else {
            crate::num::sqrt(dv.abs() / j)
        };
        sg * j * tau.min(tj).min(total - tau)
    }

    /// Speed and distance `tau` seconds into a ramp from `v0` to `v1`.
    pub fn eval(&self, v0: f32, v1: f32, tau: f32) -> (f32, f32) {
        let dv = v1 - v0;
        let sg = if dv < 0.0 { -1.0 } else { 1.0 };
        let total = self.time(dv);
        let tau = crate::num::clamp(tau, 0.0, total);
        if self.jerk <= 0.0 || total <= 0.0 {
            let a = if total > 0.0 { dv / total } else { 0.0 };
            return (v0 + a * tau, v0 * tau + 0.5 * a * tau * tau);
        }
        let j = self.jerk;
        let adv = dv.abs();
        let (tj, ta) = if adv * j >= self.accel * self.accel {
            (self.accel / j, adv / self.accel - self.accel / j)
        } else {
            (crate::num::sqrt(adv / j), 0.0)
        };
        if tau < tj {
            let v = v0 + sg * j * tau * tau / 2.0;
            let s = v0 * tau + sg * j * tau * tau * tau / 6.0;
            return (v, s);
        }
        if tau < tj + ta {
            let ap = j * tj;
            let v1a = v0 + sg * j * tj * tj / 2.0;
            let s1 = v0 * tj + sg * j * tj * tj * tj / 6.0;
            let u = tau - tj;
            return (v1a + sg * ap * u, s1 + v1a * u + sg * ap * u * u / 2.0);
        }
        // Last jerk phase, written backwards from the end (point symmetry).
        let w = total - tau;
        let d = 0.5 * (v0 + v1) * total;
        (
            v1 - sg * j * w * w / 2.0,
            d - (v1 * w - sg * j * w * w * w / 6.0),
        )
    }
}

/// One phase of a profile: a ramp or a cruise between two speeds.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Phase {
    pub v0: f32,
    pub v1: f32,
    pub time: f32,
    pub dist: f32,
    /// The phase starts this far (s) into the ramp from `v0` to `v1`; `dist`
    /// and `time` count from there. Nonzero only for a hold that must first
    /// bring a running S-curve acceleration back to zero.
    pub t0: f32,
}

impl Phase {
    /// `Phase::default()`, as a constant.
    pub const ZERO: Phase = Phase {
        v0: 0.0,
        v1: 0.0,
        time: 0.0,
        dist: 0.0,
        t0: 0.0,
    };
}

/// Phases of a [`Profile`].
pub const PHASES: usize = 5;

/// Speed over the rest of a block: up to five phases (the entry corner's
/// hold, change to the peak, cruise, change to the exit speed, the exit
/// corner's hold).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Profile {
    pub phases: [Phase; PHASES],
}

impl Profile {
    /// `Profile::default()`, as a constant.
    pub const ZERO: Profile = Profile {
        phases: [Phase::ZERO; PHASES],
    };
}

impl Profile {
    /// Plan `len` mm starting at `v0`, cruising at most at `vn`, ending at
    /// `v1` (or as close as the distance allows).
    pub fn plan(shape: &Shape, v0: f32, vn: f32, v1: f32, len: f32) -> Profile {
        let len = len.max(0.0);
        let vn = vn.max(1e-6);
        let ramp = |a: f32, b: f32| Phase {
            v0: a,
            v1: b,
            time: shape.time(b - a),
            dist: shape.dist(a, b),
            t0: 0.0,
        };
        // A phase of no length at speed `v` (keeps the boundary speeds).
        let at = |v: f32| Phase {
            v0: v,
            v1: v,
            ..Phase::default()
        };
        let mut v1 = v1.min(vn);
        // Entry too fast to reach the exit speed: slow down as much as possible.
        if v0 > v1 && shape.dist(v0, v1) > len {
            v1 = shape.reach_down_to(v0, v1, len);
            return Profile {
                phases: [at(v0), ramp(v0, v1), at(v1), at(v1), at(v1)],
            };
        }
        // Entry too slow to reach the exit speed: speed up as much as possible.
        if v1 > v0 && shape.dist(v0, v1) > len {
            v1 = shape.reach(v0, len).min(v1);
            return Profile {
                phases: [at(v0), ramp(v0, v1), at(v1), at(v1), at(v1)],
            };
        }
        let (up, down) = (shape.dist(v0, vn), shape.dist(vn, v1));
        let peak = if up + down <= len {
            vn
        } else if shape.jerk <= 0.0 && v0 <= vn {
            let a = shape.accel;
            crate::num::sqrt(((2.0 * a * len + v0 * v0 + v1 * v1) / 2.0).max(0.0)).min(vn)
        } else {
            // Entered above the cruise speed (an override drop): S ramps via
            // `vn` may not fit, so bisect a plateau between the exit speed
            // (one direct ramp, which fits) and `vn`.
            let lo0 = if v0 > vn { v1 } else { v0.max(v1) };
            let (mut lo, mut hi) = (lo0, vn);
            for _ in 0..24 {
                let mid = 0.5 * (lo + hi);
                if shape.dist(v0, mid) + shape.dist(mid, v1) <= len {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let a = ramp(v0, peak);
        let c = ramp(peak, v1);
        let cruise_len = (len - a.dist - c.dist).max(0.0);
        let b = Phase {
            v0: peak,
            v1: peak,
            time: cruise_len / peak.max(1e-6),
            dist: cruise_len,
            t0: 0.0,
        };
        Profile {
            phases: [at(v0), a, b, c, at(v1)],
        }
    }

    /// [`Profile::plan`] with the corners' holds: `hold0` mm at `v0` first
    /// (cut to what `len` leaves), and at the end the exit corner's hold
    /// for the speed the block really leaves at, `x²·m1/2` mm at `x`.
    /// Planned for the asked exit `v1`; when the ramp cannot reach it (an
    /// entry slower than planned), the hold shrinks to the slower corner
    /// and the ramp gets the rest, so a hold never crawls: its time is at
    /// most `x·m1/2` (it took 10⁴ s at a near-zero exit speed). When the
    /// ramp cannot come down to `v1` and still hold it, the block leaves
    /// slower than asked, at the fastest corner speed it can hold.
    pub fn plan_held(
        shape: &Shape,
        v0: f32,
        vn: f32,
        v1: f32,
        len: f32,
        hold0: f32,
        m1: f32,
    ) -> Profile {
        let len = len.max(0.0);
        let hold0 = Self::entry_hold(v0, hold0, len);
        let rest = len - hold0;
        let target = v1.min(vn).max(0.0);
        let mut hold1 = (0.5 * target * target * m1.max(0.0)).min(rest);
        let mut p = Profile::plan(shape, v0, vn, v1, rest - hold1);
        let exit = p.exit_speed();
        if hold1 > 0.0 && exit < target {
            hold1 = (0.5 * exit * exit * m1).min(rest);
            p = Profile::plan(shape, v0, vn, v1, rest - hold1);
        } else if hold1 > 0.0 && exit > target * (1.0 + 1e-4) {
            // Too fast to come down to the corner and still hold it: the
            // exit became known late (a starved planner), when the block
            // was already slowing to stop at its end, and the hold costs
            // more than stopping does (`m > 1/a`). Arriving above the
            // corner speed would be a jump at the corner; a slower corner
            // holds for less, so slow further, to a stop if need be (a
            // stop always fits: it was planned). Entering the next block
            // slower than planned is always safe.
            //
            // Or it cannot even stop here: a feed override drop lowered
            // the exit below anything this block can reach. Then it leaves
            // at the slowest speed it can still hold its corner at (the
            // hold costs less than the speed it saves, `m < 1/a`); with no
            // hold at the exit the corner's velocity change came on top of
            // the slow-down (Z at 110 % in Cereal's curves after a drop to
            // 30 %). If no hold fits at all (or a stop planned to end
            // right here misses by rounding), it slows as much as it can.
            let fits = |x: f32| shape.dist(v0, x) + 0.5 * x * x * m1 <= rest;
            let bisect = |mut lo: f32, mut hi: f32, below_fits: bool| {
                for _ in 0..24 {
                    let mid = 0.5 * (lo + hi);
                    if fits(mid) == below_fits {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                if below_fits {
                    lo
                } else {
                    hi
                }
            };
            let x = if fits(0.0) {
                // The fastest corner speed that fits, up to the asked one.
                bisect(0.0, target, true)
            } else if fits(v0) {
                // The slowest one that fits.
                bisect(0.0, v0, false)
            } else {
                0.0
            };
            hold1 = (0.5 * x * x * m1).min(rest);
            p = Profile::plan(shape, v0, vn, x, rest - hold1);
        }
        let cruise = |v: f32, dist: f32| Phase {
            v0: v,
            v1: v,
            time: if dist > 0.0 { dist / v.max(1e-6) } else { 0.0 },
            dist,
            t0: 0.0,
        };
        let exit = p.exit_speed();
        p.phases[0] = cruise(v0, hold0);
        p.phases[PHASES - 1] = cruise(exit, hold1);
        p
    }

    /// The entry hold [`Profile::plan_held`] keeps of `hold0` on `len`
    /// mm entered at `v0`. A hold at (nearly) no speed would never end: a
    /// corner passed that slowly has nothing to hold.
    fn entry_hold(v0: f32, hold0: f32, len: f32) -> f32 {
        if v0 > 1e-3 {
            hold0.max(0.0).min(len.max(0.0))
        } else {
            0.0
        }
    }

    /// The constant-acceleration shape [`Profile::plan_held`] is to be
    /// given for the same arguments, and the preparer's walk evaluated
    /// with: with `drop`, the acceleration of the top over all the length
    /// the entry hold leaves, which is at or above every peak `plan_held`
    /// may plan there (its exit hold only shortens the ramps, its
    /// fallbacks only lower the exit).
    pub fn held_shape(shape: &Shape, v0: f32, vn: f32, v1: f32, len: f32, hold0: f32) -> Shape {
        if shape.drop <= 0.0 {
            return *shape;
        }
        let rest = len.max(0.0) - Self::entry_hold(v0, hold0, len);
        shape.at_top(shape.top(v0, vn, v1, rest))
    }

    pub fn total_dist(&self) -> f32 {
        self.phases.iter().map(|p| p.dist).sum()
    }

    pub fn exit_speed(&self) -> f32 {
        self.phases
            .iter()
            .rev()
            .find(|p| p.time > 0.0)
            .map_or(self.phases[PHASES - 1].v1, |p| p.v1)
    }
}
