//! Work that waits for motion to finish: synced commands, probing, homing.

use super::*;

impl<const N: usize> Machine<N> {
    pub(super) fn run_pending(&mut self, rt: &Realtime, obs: &mut dyn FnMut(Note)) {
        match core::mem::replace(&mut self.pending, Pending::None) {
            Pending::None | Pending::Chords { .. } => {}
            // Finished by `poll` once the ramp-down has stopped.
            p @ Pending::ProbeStop { .. } => self.pending = p,
            Pending::Sync { command, line } => {
                match command {
                    Command::Pause { .. } => rt.feed_hold(),
                    Command::ToolChange { tool } => {
                        rt.feed_hold();
                        self.tool_event = Some(super::ToolEvent::Change { tool });
                    }
                    _ => {}
                }
                obs(Note::Executed {
                    line,
                    command: &command,
                });
            }
            Pending::ProbeWait {
                end,
                speed,
                kind,
                line,
            } => {
                let contact = self.switches.probe ^ self.planner.settings.probe_invert;
                let towards = matches!(kind, ProbeKind::Toward | ProbeKind::TowardNoError);
                let must = matches!(kind, ProbeKind::Toward | ProbeKind::Away);
                if contact == towards {
                    if must {
                        self.raise_alarm(rt, MachineError::ProbeInitialState, line, obs);
                    }
                    return;
                }
                let watch = Watch {
                    limits: 0,
                    probe: if towards { 1 } else { 2 },
                    homing: false,
                };
                match self.push_line(&end, speed, watch, line, PathKind::Probe, obs) {
                    Ok(()) => self.pending = Pending::ProbeRun { kind, line },
                    Err(e) => obs(Note::Error { line, error: e }),
                }
            }
            Pending::ProbeRun { kind, line } => {
                // The move ended without the probe tripping.
                let pos = self.commanded;
                self.probe_result = Some((pos, false));
                obs(Note::Probed {
                    line,
                    position: pos,
                    contact: false,
                });
                if matches!(kind, ProbeKind::Toward | ProbeKind::Away) {
                    self.raise_alarm(rt, MachineError::ProbeNoContact, line, obs);
                }
            }
            Pending::Homing(mut h) => {
                let line = h.line();
                let limits = self.switches.limits ^ self.planner.settings.limit_invert;
                let pos = rt.position();
                match h.step(&self.planner.settings, &pos, limits) {
                    Ok(homing::Action::Move {
                        target,
                        rate,
                        watch,
                    }) => {
                        let end = self.steps_to_mm(&target);
                        match self.push_line(
                            &end,
                            Speed::Feed(rate),
                            watch,
                            line,
                            PathKind::Home,
                            obs,
                        ) {
                            Ok(()) => self.pending = Pending::Homing(h),
                            Err(e) => self.raise_alarm(rt, e, line, obs),
                        }
                    }
                    Ok(homing::Action::Settle { seconds }) => {
                        let ticks = super::submit::dwell_ticks(seconds, self.cfg.tick_hz);
                        match self.planner.push_dwell(ticks, line) {
                            Ok(()) => self.pending = Pending::Homing(h),
                            Err(e) => self.raise_alarm(rt, e.into(), line, obs),
                        }
                    }
                    Ok(homing::Action::Redefine { position }) => {
                        rt.redefine_position(&position);
                        self.planner.clear(position);
                        self.commanded = self.steps_to_mm(&position);
                        self.pending = Pending::Homing(h);
                    }
                    Ok(homing::Action::Done { axes, verified }) => {
                        if !verified {
                            self.homed |= axes;
                            self.position_lost = false;
                            self.alarm = None;
                            obs(Note::Homed { axes });
                        }
                    }
                    Err(e) => {
                        if matches!(e, MachineError::VerifyHome { .. }) {
                            self.position_lost = true;
                        }
                        self.raise_alarm(rt, e, line, obs);
                    }
                }
            }
        }
    }
}
