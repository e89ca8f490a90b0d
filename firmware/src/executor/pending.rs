//! Work that waits for motion to finish: synced commands, probing, homing,
//! and the stop after a fault.

use super::*;

impl<const N: usize> Machine<N> {
    /// An error found after its line was acknowledged (issue 35): a
    /// command refused when it reached the executor, or a chord, probe move
    /// or script step refused later. The sender has counted the `ok` and
    /// streams on, so the job must stop here, not skip the command: the
    /// motion ramps down along its path (a motion cancel, which cycle
    /// start does not resume; the position stays exact), then everything
    /// queued is dropped and `e` becomes the alarm (`poll`). Nothing is
    /// accepted meanwhile ([`Machine::ready`] is false). The session takes
    /// the fault with [`Machine::take_fault`] to report it; in alarm, or
    /// with a stop already under way, it is only reported.
    pub fn fault(&mut self, e: MachineError, line: u32) {
        self.fault = Some((e, line));
        if self.alarm.is_some() || matches!(self.pending, Pending::Fault { .. }) {
            return;
        }
        self.script = None;
        self.pending = Pending::Fault { error: e, line };
        self.motion.cancel_motion();
    }

    /// A fault's ramp has stopped: its error becomes the alarm.
    pub(super) fn end_fault(
        &mut self,
        rt: &Realtime,
        sink: &impl SegmentSink,
        obs: &mut dyn FnMut(Note),
    ) {
        let Pending::Fault { error, line } = self.pending else {
            return;
        };
        if self.motion.stopped(rt, sink) {
            // Position exact (it ramped down): an operator hold asked for
            // meanwhile goes with the job.
            rt.clear_hold();
            self.raise_alarm(rt, error, line, obs);
        }
    }

    /// The last fault and its line, once.
    pub fn take_fault(&mut self) -> Option<(MachineError, u32)> {
        self.fault.take()
    }

    pub(super) fn run_pending(&mut self, rt: &Realtime, obs: &mut dyn FnMut(Note)) {
        match core::mem::replace(&mut self.pending, Pending::None) {
            Pending::None | Pending::Chords { .. } => {}
            // Finished by `poll` once the ramp-down has stopped.
            p @ (Pending::ProbeStop { .. } | Pending::Fault { .. }) => self.pending = p,
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
                let contact = self.switches.probe ^ self.motion.settings().probe_invert;
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
                    Err(e) => self.fault(e, line),
                }
            }
            Pending::ProbeRun { kind, line } => {
                // The move ended without the probe tripping.
                let pos = self.commanded;
                self.probed = Probed::At(pos, false);
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
                let limits = self.switches.limits ^ self.motion.settings().limit_invert;
                let pos = rt.position();
                match h.step(self.motion.settings(), &pos, limits) {
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
                        match self.motion.submit(Move::Dwell { seconds, line }) {
                            Ok(()) => self.pending = Pending::Homing(h),
                            Err(e) => self.raise_alarm(rt, e.into(), line, obs),
                        }
                    }
                    Ok(homing::Action::Redefine { position }) => {
                        self.commanded = self.motion.redefine(rt, &position);
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
