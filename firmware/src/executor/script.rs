//! Commands that run as a sequence of others: a canned cycle (its moves,
//! dwells, spindle switches and G88's pause) and the manual tool change.
//!
//! The sequence is produced one command at a time as the planner has room
//! (a peck cycle has no bound on its moves) and each step goes through
//! [`Machine::accept`], so soft limits, syncing and holds are the ones
//! every other command gets. While a script runs the executor is not
//! [`ready`](Machine::ready): the commands after it wait in the session's
//! queue, nothing is dropped.
//!
//! The tool change (M6, `$211` >= 1): spindle off (synced with motion),
//! Z up to the tool-change Z, then X/Y to the tool-change position (the
//! axes `$215` names), then a feed hold that the operator ends with cycle
//! start; the host is told which tool to load ([`ToolEvent::Change`]).
//! With `$211=2` the machine then goes to the tool setter (`$216`,`$217`)
//! at the change Z, probes down (`$218` feed, `$219` travel; no contact is
//! alarm 5), and goes back up. The first tool measured after power-up is
//! the reference; each later one gets `its trip Z - the reference's` as
//! its length offset ([`ToolEvent::Length`], applied by the session as a
//! G43.1 Z would be). The machine stays where the change left it: the
//! program's next move starts there.

use super::*;
use crate::command::CycleSteps;
use crate::command::SpindleDir;

/// What the session tells the operator, or the interpreter, about M6.
/// Tagged from 1: `None` of an `Option` of it is zero (see `MachineError`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(u8)]
pub enum ToolEvent {
    /// Held at the tool-change position: load `tool`, then cycle start.
    Change { tool: u32 } = 1,
    /// The tool setter measured `tool`: its length offset is `z` mm.
    Length { tool: u32, z: f32 },
}

/// Tagged from 1: `None` of an `Option` of it is zero (see `MachineError`).
#[derive(Clone, Debug)]
#[repr(u8)]
pub(super) enum Script {
    Cycle(CycleSteps) = 1,
    Tool { tool: u32, stage: u8 },
}

/// One step of a tool change.
enum ToolStep {
    Cmd(Command),
    /// Read the setter probe's result.
    Measure,
    Skip,
}

impl<const N: usize> Machine<N> {
    /// Starts M6 as the settings say; `$211=0` only records the tool.
    pub(super) fn start_tool_change(&mut self, tool: u32, line: u32, obs: &mut dyn FnMut(Note)) {
        let cmd = Command::Tool { number: tool };
        obs(Note::Executed {
            line,
            command: &cmd,
        });
        if self.motion.settings().tool_change.mode > 0 {
            self.script = Some((Script::Tool { tool, stage: 0 }, line));
        }
    }

    fn tool_step(&mut self, tool: u32, stage: u8) -> Option<ToolStep> {
        let tc = self.motion.settings().tool_change;
        let mut at = self.commanded;
        let z = tc.position[2];
        Some(match stage {
            0 => ToolStep::Cmd(Command::Spindle {
                dir: SpindleDir::Off,
                speed: 0.0,
            }),
            1 if tc.axes & 0b100 != 0 => {
                at[2] = z;
                ToolStep::Cmd(Command::Rapid { end: at })
            }
            2 if tc.axes & 0b011 != 0 => {
                for (i, (a, p)) in at.iter_mut().zip(tc.position).take(2).enumerate() {
                    if tc.axes & (1 << i) != 0 {
                        *a = p;
                    }
                }
                ToolStep::Cmd(Command::Rapid { end: at })
            }
            1 | 2 => ToolStep::Skip,
            3 => ToolStep::Cmd(Command::ToolChange { tool }),
            _ if tc.mode < 2 => return None,
            4 => {
                at[0] = tc.setter[0];
                at[1] = tc.setter[1];
                ToolStep::Cmd(Command::Rapid { end: at })
            }
            5 => {
                at[2] -= tc.travel;
                ToolStep::Cmd(Command::Probe {
                    end: at,
                    feed: Feed::PerMin(tc.feed),
                    kind: ProbeKind::Toward,
                })
            }
            6 => ToolStep::Measure,
            7 => {
                at[2] = z;
                ToolStep::Cmd(Command::Rapid { end: at })
            }
            _ => return None,
        })
    }

    fn measure(&mut self, tool: u32) {
        let Some((p, true)) = self.probe_result() else {
            return;
        };
        let reference = *self.tool_reference.get_or_insert(p[2]);
        self.tool_event = Some(ToolEvent::Length {
            tool,
            z: p[2] - reference,
        });
    }

    /// Feeds the running script's steps while nothing else is pending.
    pub(super) fn run_script(&mut self, rt: &Realtime, obs: &mut dyn FnMut(Note)) {
        for _ in 0..CHORDS_PER_CALL {
            if !matches!(self.pending, Pending::None) || !self.motion.has_room() {
                return;
            }
            let Some((script, line)) = self.script.as_mut() else {
                return;
            };
            let line = *line;
            let cmd = match script {
                Script::Cycle(steps) => steps.next(),
                Script::Tool { tool, stage } => {
                    let (t, s) = (*tool, *stage);
                    *stage = s.saturating_add(1);
                    match self.tool_step(t, s) {
                        Some(ToolStep::Cmd(c)) => Some(c),
                        Some(ToolStep::Measure) => {
                            self.measure(t);
                            continue;
                        }
                        Some(ToolStep::Skip) => continue,
                        None => None,
                    }
                }
            };
            let Some(cmd) = cmd else {
                self.script = None;
                return;
            };
            if let Err(e) = self.accept(rt, &cmd, line, obs) {
                self.script = None;
                self.fault(e, line);
                return;
            }
        }
    }

    /// A tool change reached its hold, or the setter measured a tool.
    pub fn take_tool_event(&mut self) -> Option<ToolEvent> {
        self.tool_event.take()
    }
}
