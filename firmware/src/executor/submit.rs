//! Accepting commands: validation, soft limits, and feeding arcs, splines
//! and independent-rapid legs to the planner as it has room.

use super::*;

impl<const N: usize> Machine<N> {
    /// Accept one command. Call only when [`ready`](Self::ready).
    pub fn submit(
        &mut self,
        rt: &Realtime,
        cmd: &Command,
        line: u32,
        obs: &mut dyn FnMut(Note),
    ) -> Result<(), MachineError> {
        if !self.ready() {
            return Err(MachineError::Busy);
        }
        let allowed_in_alarm = matches!(
            cmd,
            Command::Home { .. } | Command::ClearAlarm | Command::Report(_) | Command::Message(_)
        );
        if self.alarm.is_some() && !allowed_in_alarm {
            return Err(MachineError::InAlarm);
        }
        if rt.estop() && matches!(cmd, Command::Home { .. } | Command::ClearAlarm) {
            return Err(MachineError::EStop);
        }
        if let Some(fault) = rt.hw_fault() {
            if matches!(cmd, Command::Home { .. } | Command::ClearAlarm) {
                return Err(MachineError::HardwareFault { fault });
            }
        }
        self.accept(rt, cmd, line, obs)
    }

    /// Runs or queues one command (a submitted one or a script's step).
    pub(super) fn accept(
        &mut self,
        rt: &Realtime,
        cmd: &Command,
        line: u32,
        obs: &mut dyn FnMut(Note),
    ) -> Result<(), MachineError> {
        let tol = self.motion.settings().arc_tolerance;
        match cmd {
            Command::Rapid { end } => {
                self.check_soft(end, end)?;
                if self.motion.settings().rapid_mode == RapidMode::Independent {
                    let (pts, n) = self.rapid_legs(end);
                    obs(Note::Move {
                        line,
                        start: self.commanded,
                        geometry: Geometry::Straight(end),
                    });
                    self.pending = Pending::Chords {
                        chords: Chords::Legs { pts, n, i: 0 },
                        speed: Speed::Rapid,
                        line,
                    };
                    return self.feed_chords(obs);
                }
                self.push_line(
                    end,
                    Speed::Rapid,
                    Watch::default(),
                    line,
                    PathKind::Rapid,
                    obs,
                )
            }
            Command::Line { end, feed } => {
                self.check_soft(end, end)?;
                let sp = Self::speed(*feed)?;
                self.push_line(end, sp, Watch::default(), line, PathKind::Feed, obs)
            }
            Command::Arc(a) => {
                let step = crate::arc::plane_step(&self.motion.settings().axes, a.plane);
                let ch = ArcChords::new(&self.commanded, a, tol, step)?;
                let (lo, hi) = ch.bounds();
                self.check_soft(&lo, &hi)?;
                let speed = self.chord_speed(a.feed, Chords::Arc(ch.clone()))?;
                obs(Note::Move {
                    line,
                    start: self.commanded,
                    geometry: Geometry::Arc(a),
                });
                self.pending = Pending::Chords {
                    chords: Chords::Arc(ch),
                    speed,
                    line,
                };
                self.feed_chords(obs)
            }
            Command::Spline(sp) => {
                let ch = SplineChords::new(&self.commanded, sp, tol)?;
                let (lo, hi) = ch.bounds();
                self.check_soft(&lo, &hi)?;
                let speed = self.chord_speed(sp.feed, Chords::Spline(ch.clone()))?;
                obs(Note::Move {
                    line,
                    start: self.commanded,
                    geometry: Geometry::Spline(sp),
                });
                self.pending = Pending::Chords {
                    chords: Chords::Spline(ch),
                    speed,
                    line,
                };
                self.feed_chords(obs)
            }
            Command::Dwell { seconds } => {
                if !(seconds.is_finite() && *seconds >= 0.0 && *seconds < 1.0e6) {
                    return Err(MachineError::InvalidNumber);
                }
                self.motion.submit(Move::Dwell {
                    seconds: *seconds,
                    line,
                })?;
                obs(Note::Stop {
                    line,
                    seconds: *seconds,
                });
                Ok(())
            }
            Command::Probe { end, feed, kind } => {
                self.check_soft(end, end)?;
                let speed = Self::speed(*feed)?;
                self.pending = Pending::ProbeWait {
                    end: *end,
                    speed,
                    kind: *kind,
                    line,
                };
                Ok(())
            }
            Command::Home { axes } => {
                let h = Homing::new(self.motion.settings(), *axes, false, line)?;
                self.pending = Pending::Homing(h);
                Ok(())
            }
            Command::VerifyHome { axes } => {
                let h = Homing::new(self.motion.settings(), *axes, true, line)?;
                if self.homed & h.axes() != h.axes() {
                    return Err(MachineError::NotHomed);
                }
                self.pending = Pending::Homing(h);
                Ok(())
            }
            Command::FeedOverride { percent } => {
                rt.set_feed_override(*percent);
                obs(Note::Executed { line, command: cmd });
                Ok(())
            }
            Command::Cycle(c) => {
                self.script = Some((script::Script::Cycle(c.steps(&self.commanded)), line));
                Ok(())
            }
            // A script's own ToolChange step is the hold (`run_pending`).
            Command::ToolChange { tool } if self.script.is_none() => {
                self.start_tool_change(*tool, line, obs);
                Ok(())
            }
            Command::ClearAlarm => {
                self.alarm = None;
                obs(Note::Executed { line, command: cmd });
                Ok(())
            }
            // Laser mode (GRBL's): a new S or M3/M4/M5 does not stop the
            // motion; the outputs apply it when its line's first segment
            // runs (`outputs::LaserQueue`).
            Command::Spindle { .. } if self.motion.settings().laser_mode => {
                obs(Note::Executed { line, command: cmd });
                Ok(())
            }
            Command::Aux { synced: false, .. } | Command::Message(_) | Command::Report(_) => {
                obs(Note::Executed { line, command: cmd });
                Ok(())
            }
            _ => {
                obs(Note::Stop { line, seconds: 0.0 });
                self.pending = Pending::Sync {
                    command: cmd.clone(),
                    line,
                };
                Ok(())
            }
        }
    }

    /// Independent-axis rapid: every axis runs at its own max rate, so the
    /// move splits where each axis arrives (fastest first). Each leg is a
    /// straight block whose direction makes all its axes hit their max rate
    /// together; the legs stay inside the start/end box, so checking the end
    /// against soft limits is enough.
    fn rapid_legs(&self, end: &Pos) -> ([Pos; AXES], usize) {
        let start = self.commanded;
        let s = self.motion.settings();
        let rate: [f32; AXES] = core::array::from_fn(|i| s.axes[i].max_rate.max(1e-3) / 60.0);
        let time: [f32; AXES] = core::array::from_fn(|i| libm::fabsf(end[i] - start[i]) / rate[i]);
        let mut order: [usize; AXES] = core::array::from_fn(|i| i);
        order.sort_unstable_by(|a, b| time[*a].total_cmp(&time[*b]));
        let mut pts = [*end; AXES];
        let mut n = 0;
        let mut last_t = 0.0f32;
        for &k in &order {
            let tk = time[k];
            if tk <= last_t {
                continue;
            }
            last_t = tk;
            for i in 0..AXES {
                pts[n][i] = if time[i] <= tk {
                    end[i]
                } else {
                    start[i] + libm::copysignf(rate[i] * tk, end[i] - start[i])
                };
            }
            n += 1;
        }
        if n == 0 {
            pts[0] = *end;
            n = 1;
        }
        if let Some(p) = pts.get_mut(n - 1) {
            *p = *end;
        }
        (pts, n)
    }

    /// G93 arcs and splines: the whole curve takes `1/F` minutes, so every
    /// chord runs at the curve's length over that time.
    fn chord_speed(&self, feed: Feed, ch: Chords) -> Result<Speed, MachineError> {
        let sp = Self::speed(feed)?;
        let Speed::Time(t) = sp else { return Ok(sp) };
        let mut prev = self.commanded;
        let mut len = 0.0f32;
        let mut add = |p: Pos| {
            len += crate::num::sqrt(p.iter().zip(&prev).map(|(a, b)| (a - b) * (a - b)).sum());
            prev = p;
        };
        match ch {
            Chords::Arc(c) => c.for_each(&mut add),
            Chords::Spline(c) => c.for_each(&mut add),
            Chords::Legs { .. } => {}
        }
        if len <= 0.0 {
            return Err(MachineError::InvalidNumber);
        }
        Ok(Speed::Feed(len / t))
    }

    ///
    /// At most [`CHORDS_PER_CALL`] chords per call: a chord shorter than a
    /// step takes no planner slot, so "until the planner is full" alone
    /// could mean 2^24 chords (a many-turn helix of a radius under one
    /// step) and stall the task for seconds. The rest waits for the next
    /// poll; the device keeps answering meanwhile.
    pub(super) fn feed_chords(&mut self, obs: &mut dyn FnMut(Note)) -> Result<(), MachineError> {
        for _ in 0..CHORDS_PER_CALL {
            if !self.motion.may_plan() {
                break;
            }
            let Pending::Chords {
                chords,
                speed,
                line,
            } = &mut self.pending
            else {
                return Ok(());
            };
            let (speed, line) = (*speed, *line);
            let mut curve = Curve::default();
            let (next, kind) = match chords {
                Chords::Arc(c) => {
                    curve = c.curve();
                    (c.next(), PathKind::Arc)
                }
                Chords::Spline(c) => (c.next(), PathKind::Spline),
                Chords::Legs { pts, n, i } => {
                    let p = if *i < *n { pts.get(*i).copied() } else { None };
                    *i += 1;
                    (p, PathKind::Rapid)
                }
            };
            let Some(p) = next else {
                self.pending = Pending::None;
                return Ok(());
            };
            let mv = if kind == PathKind::Rapid {
                Move::Line {
                    end: p,
                    speed,
                    watch: Watch::default(),
                    line,
                }
            } else {
                Move::Chord {
                    end: p,
                    speed,
                    curve,
                    line,
                }
            };
            let pushed = self.motion.submit(mv);
            if let Err(e) = pushed {
                self.pending = Pending::None;
                return Err(e.into());
            }
            self.commanded = p;
            obs(Note::Path {
                line,
                kind,
                end: p,
                speed,
            });
        }
        Ok(())
    }
}
