//! Turning one move into a block: step counts, caps, the speed request,
//! the corner with the block before, and the merge with it.

use super::passes::CANCEL_WINDOW_S;
use super::*;

/// What a pushed block is besides its line: a chord of a curve, or a
/// backlash take-up ([`Block::takeup`]).
#[derive(Clone, Copy)]
pub(super) enum Piece {
    Line,
    Chord(Curve),
    TakeUp,
}

impl<const N: usize> Planner<N> {
    /// A move to `end` mm shifted by `shift` motor steps (backlash
    /// compensation, `motion::Pipeline`): the steps are `end`'s plus the
    /// shift, the geometry `end` plus the shift in mm, so the length and the
    /// corners are the commanded move's.
    pub fn push_shifted(
        &mut self,
        end: &Pos,
        shift: &[i32; AXES],
        speed: Speed,
        watch: Watch,
        line: u32,
        curve: Option<Curve>,
    ) -> Result<(), PlanError> {
        let mut target = self.to_steps(end)?;
        let mut mm = *end;
        for i in 0..AXES {
            target[i] = target[i]
                .checked_add(shift[i])
                .ok_or(PlanError::InvalidNumber)?;
            mm[i] += shift[i] as f32 / self.settings.axes[i].steps_per_mm;
        }
        let piece = curve.map_or(Piece::Line, Piece::Chord);
        self.push(target, &mm, speed, watch, line, piece)
    }

    /// A backlash take-up of `steps` on the axes that reverse: a rapid
    /// line (the axes' own rate and acceleration limits) from the end of
    /// the last block, flagged so that it is neither merged nor counted in
    /// the reported position.
    pub fn push_takeup(&mut self, steps: &[i32; AXES], line: u32) -> Result<(), PlanError> {
        let mut target = self.position;
        let mut mm = self.position_mm;
        for i in 0..AXES {
            target[i] = target[i]
                .checked_add(steps[i])
                .ok_or(PlanError::InvalidNumber)?;
            mm[i] += steps[i] as f32 / self.settings.axes[i].steps_per_mm;
        }
        let (speed, watch) = (Speed::Rapid, Watch::default());
        self.push(target, &mm, speed, watch, line, Piece::TakeUp)
    }

    pub(super) fn push(
        &mut self,
        target: [i32; AXES],
        end_mm: &Pos,
        speed: Speed,
        watch: Watch,
        line: u32,
        piece: Piece,
    ) -> Result<(), PlanError> {
        let curve = match piece {
            Piece::Chord(c) => Some(c),
            Piece::Line | Piece::TakeUp => None,
        };
        let takeup = matches!(piece, Piece::TakeUp);
        if self.is_full() {
            return Err(PlanError::Full);
        }
        let s = &self.settings;
        let mut b = Block {
            target,
            watch,
            takeup,
            line,
            ..Block::EMPTY
        };
        let mut mm = [0.0f32; AXES];
        let mut len2 = 0.0;
        for i in 0..AXES {
            let spm = s.axes[i].steps_per_mm;
            if !(spm.is_finite() && spm > 0.0) {
                return Err(PlanError::InvalidNumber);
            }
            let d = target[i] as i64 - self.position[i] as i64;
            let ad = d.unsigned_abs();
            if ad > MAX_BLOCK_STEPS as u64 {
                return Err(PlanError::MoveTooLong);
            }
            b.steps[i] = ad as u32;
            if d < 0 {
                b.dir_mask |= 1 << i;
            }
            // Within MAX_BLOCK_STEPS, so an i32: one VCVT, where an i64
            // takes a library call (bench-target's plan_block_insns).
            mm[i] = d as i32 as f32 / s.axes[i].steps_per_mm;
            len2 += mm[i] * mm[i];
        }
        b.count = b.steps.iter().copied().max().unwrap_or(0);
        if b.count == 0 {
            return Ok(());
        }
        // The direction in steps sets the axes' shares (a Bresenham line
        // moves each axis in proportion); the commanded geometry sets the
        // length and the corners (see `Block::length`). A zero-length
        // commanded move that still rounds to a step keeps the step one.
        let len_steps = crate::num::sqrt(len2);
        let d: [f32; AXES] = core::array::from_fn(|i| end_mm[i] - self.position_mm[i]);
        let len_mm = crate::num::sqrt(d.iter().map(|v| v * v).sum());
        // Both ends round by at most half a step per axis, so the commanded
        // move is within a step per axis of the stepped one (and `f32`
        // rounding of far coordinates: 1.25 steps); a commanded
        // start that is further off (not where the steps are) is not
        // trusted.
        let near = (0..AXES).all(|i| libm::fabsf(d[i] - mm[i]) * s.axes[i].steps_per_mm <= 1.25);
        let (unit_mm, len_mm) = if near && len_mm.is_finite() && len_mm > 1e-6 {
            (d.map(|v| v / len_mm), len_mm)
        } else {
            (mm.map(|v| v / len_steps), len_steps)
        };
        b.length = len_mm;
        let mut unit = [0.0f32; AXES];
        let (mut cap, mut accel) = (f32::INFINITY, f32::INFINITY);
        for i in 0..AXES {
            unit[i] = mm[i] / len_steps;
            if b.steps[i] == 0 {
                continue;
            }
            let ax = &s.axes[i];
            let sane = |v: f32| v.is_finite() && v > 0.0;
            if !(sane(ax.max_rate) && sane(ax.max_accel) && sane(ax.steps_per_mm)) {
                return Err(PlanError::InvalidNumber);
            }
            if ax.max_rate / 60.0 * ax.steps_per_mm > s.max_step_rate_hz {
                return Err(PlanError::StepRateTooHigh { axis: i as u8 });
            }
            let u = unit[i].abs();
            cap = cap.min(ax.max_rate / 60.0 / u);
            accel = accel.min(ax.max_accel / u);
        }
        // Single intervals of minor axes, too (see `interval`).
        let cap = cap.min(interval::speed_cap(
            s,
            self.tick_hz,
            &b.steps,
            b.count,
            b.length,
        ));
        b.cap = cap;
        b.line_accel = accel;
        b.accel = accel;
        match curve.map(|c| (c, c.budget(s, &unit))) {
            Some((c, Some(cb))) => {
                (b.curve_ar, b.curve_an, b.curve_tangent) = (cb.ar, cb.an, cb.tangent);
                let v = self.curve_jerk_cap(c.radius);
                b.cap = b.cap.min(v);
                b.turn_at(v);
            }
            // Unknown radius: half the budget each way (the sum stays
            // within every axis limit).
            Some((_, None)) => b.accel = accel * 0.5,
            None => {}
        }
        match speed {
            Speed::Feed(v) if v > 0.0 && v.is_finite() => b.programmed = v,
            Speed::Time(t) if t > 0.0 && t.is_finite() => b.programmed = b.length / t,
            Speed::Rapid => {
                b.programmed = f32::INFINITY;
                b.rapid = true;
            }
            _ => return Err(PlanError::InvalidFeed),
        }
        // Steps further apart than the timer reaches cannot be timed by one
        // period. Refused here, before anything moved, rather than run
        // faster than programmed (see `FeedTooSlow`). At 100 % override:
        // a lower override is floored at this speed instead, so a job that
        // was accepted never fails halfway through.
        // Fewest dominant steps per second the step driver times.
        let min_step_hz = self.tick_hz as f32 / crate::seams::MAX_PERIOD as f32;
        b.floor = min_step_hz * b.length / b.count as f32;
        if b.programmed.min(b.cap) < b.floor {
            return Err(PlanError::FeedTooSlow);
        }
        b.nominal = self.nominal(&b);
        Self::curve_limits(&mut b, self.c_max());
        // Corners and curvature on the commanded geometry.
        // The turn across the previous chord, where a rule needs it.
        let line = &self.prev2_unit_mm;
        // A chord before the previous one (none after a stop).
        let before = line.iter().any(|&u| u != 0.0);
        let phi2 = if (self.pending & 1 != 0
            || self.settings.profile == crate::settings::Profile::SCurve)
            && before
        {
            Some(corner::angle(passes::dot(line, &unit_mm)))
        } else {
            None
        };
        let (corner, turn) = self.junction_speed(&unit_mm, len_mm, curve.is_some(), phi2);
        let limit = corner.limit();
        // Per axis: whether the corner turns it, and whether the turn
        // stays within rounding over this chord (one pass for both).
        let (mut turned, mut rounding) = (0u8, true);
        for (i, ax) in s.axes.iter().enumerate() {
            let d = libm::fabsf(unit_mm[i] - self.prev_unit_mm[i]);
            if d > 1e-6 {
                turned |= 1 << i;
                rounding &= corner::within_rounding(d, len_mm, ax);
            }
        }
        if self.prev_nominal <= 0.0 {
            turned = 0;
        }
        // A turn within rounding over this chord may be one that the next
        // chord takes back: its curvature rule waits for that chord
        // (`planner::cancel`). Until then the block is the newest, which
        // must stop within itself: `v² ≤ 2·accel·len`, under the rule's
        // `a·l/φ` wherever the turn is small enough for that.
        let pending = curve.is_none()
            && !takeup
            && rounding
            && turn.a > 0.0
            && turn.phi * 2.0 * b.accel * len_mm <= turn.a * turn.l
            && before
            && self.prev_curve.is_none();
        b.corner = if pending { corner.deviation } else { limit };
        b.jd = corner.jd;
        b.turn_at(corner.turn);
        b.junction = b.corner;
        let (quiet, release) = self.quiet_axes(&mut b, &unit);
        b.quiet = quiet;
        b.release = release & turned;
        self.release_pending |= b.release;
        // Both halves of the hold fit: the one before the corner in the
        // previous block, the one after it in this one.
        let room = self.prev_length.min(len_mm).min(b.length);
        // Axes still for a window before the corner, and whether this
        // block lasts one (one-sided holds, `passes`).
        let still = (0..AXES).fold(0u8, |m, i| {
            m | u8::from(self.still_time[i] >= CANCEL_WINDOW_S) << i
        });
        // Its corner, cap, acceleration and length are settled from here
        // on (the holds change neither): one square root for the three
        // uses below, where the still-time loop took one per idle axis.
        let min_time = b.min_time();
        let long = (still, min_time >= CANCEL_WINDOW_S);
        let (m, pair) = self.hold_factor(&unit_mm, len_mm, curve, limit, 0, long);
        // Where a helix's descent ends (`Pair::kink`) the axis across the
        // plane stops within the corner: a turn the curvature check reads
        // as a circle through the chords on both sides, at the slower
        // side's speed. The chord after keeps the corner's speed, so that
        // circle is run at most at the corner's curvature limit (a 0.4 mm
        // hole read Z 132 % of it, the flat chord at the curve's speed).
        if pair.kink && limit < b.cap {
            b.cap = limit;
            b.nominal = self.nominal(&b);
            Self::curve_limits(&mut b, self.c_max());
        }
        b.hold_fixed = if b.release != 0 {
            self.hold_factor(&unit_mm, len_mm, curve, limit, b.release, long)
                .0
        } else {
            m
        };
        b.set_corner(b.corner, m, room, self.prev_nominal);
        b.entry = if self.len == 0 { 0.0 } else { b.max_entry };
        let merged = b.junction.is_infinite() && self.merge(&b);
        // The corner before this one, if this one takes it back.
        let mut taken_back = self.len;
        if merged {
            let k = self.len - 1;
            self.at(k).quiet &= quiet;
            // The newest block goes straight on, longer: a pending corner
            // of its settles now (the stop within it bounds it no more).
            if self.pending & 1 != 0 {
                taken_back = self.release_taken_back(limit, phi2, None, before);
                self.pending &= !1;
            }
        } else {
            if curve.is_none() {
                taken_back = self.release_taken_back(limit, phi2, pair.net, before);
            }
            self.prev_given_up = 1.0 - pair.kept;
            self.prev_pulse_m = pair.pulse_m;
            self.pending = (self.pending << 1 | u8::from(pending)) & 3;
            self.prev_phi2 = phi2.unwrap_or(0.0);
            self.prev_turn = turn;
        }
        self.count_quiet(min_time, quiet);
        if !merged {
            self.prev2_unit_mm = self.prev_unit_mm;
        }
        self.prev_unit_mm = unit_mm;
        self.prev_curve = curve;
        // A merged block's cap is its whole line's (`merge`).
        self.prev_nominal = if merged {
            self.at(self.len - 1).nominal
        } else {
            b.nominal
        };
        self.prev_length = if merged {
            self.prev_length + len_mm
        } else {
            len_mm
        };
        for (i, t) in self.still_time.iter_mut().enumerate() {
            *t = if b.steps[i] == 0 { *t + min_time } else { 0.0 };
        }
        let start = self.position;
        self.position = target;
        self.position_mm = *end_mm;
        // S-curve runs (`planner::run`); in trapezoid mode every block is
        // its own.
        let scurve = self.settings.profile == crate::settings::Profile::SCurve;
        if merged {
            if scurve {
                self.regroup_newest();
            }
        } else {
            let k = self.len;
            b.run_pos = match k.checked_sub(1) {
                Some(j) if scurve => run::next_pos(self.at(j), &b),
                _ => 0,
            };
            *self.at(k) = b;
            self.len += 1;
        }
        let plain = curve.is_none() && !takeup;
        let tubed = self.extend_tube(start, len_mm, plain, merged);
        let released = self.release_quiet().min(taken_back).min(tubed);
        self.replan_to(false, released);
        Ok(())
    }
}
