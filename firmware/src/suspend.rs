//! Safety door and spindle stop: GRBL 1.1's suspend rules for the
//! spindle and coolant around a feed hold.
//!
//! A door (0x84, or a door switch's opening edge) holds the motion; once
//! it has stopped, spindle and coolant go off at the pins while their
//! programmed state stays. Cycle start resumes only with the door closed:
//! the spindle comes back first, then after the spin-up delay (`$220`)
//! the coolant, and only then the motion. A spindle stop (0x9E, only in
//! a hold) is the same without the coolant: a second 0x9E turns the
//! spindle back on, cycle start restores it and then resumes. GRBL waits
//! after a restore only for the door; burin waits for the spindle both
//! ways (a spindle that cuts before it is up to speed breaks tools).
//! The laser (`$32`) is dark in any hold already and needs no delay.
//!
//! No parking: GRBL's default configuration has none, and neither has
//! burin; the tool stays where the hold stopped it.

use crate::command::SpindleDir;
use crate::outputs::{Outputs, HELD_COOLANT, HELD_SPINDLE};
use crate::realtime::Realtime;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Off,
    /// The hold is still ramping down (`Door:2`).
    Stopping,
    /// Stopped, outputs held off (`Door:0` / `Door:1`).
    Stopped,
    /// The spindle is back on since `since` (ms); motion waits for the
    /// spin-up delay (`Door:3`), then resumes if `start`.
    Restoring {
        since: u32,
        start: bool,
    },
}

/// What a cycle start did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resume {
    /// The door is open, or a door's hold is still stopping: nothing.
    Refused,
    /// The motion resumes now (or after a restore already under way).
    Started,
    /// A stopped spindle comes back first (a spindle stop's restore is
    /// GRBL's `[MSG:Restoring spindle]`; `door` tells which).
    Restoring { door: bool },
}

/// The suspend state (a few bytes of RAM).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Suspend {
    phase: Phase,
    /// The suspension is a door's (else a spindle stop's).
    door: bool,
}

impl Default for Suspend {
    fn default() -> Self {
        Self::new()
    }
}

impl Suspend {
    pub const fn new() -> Self {
        Suspend {
            phase: Phase::Off,
            door: false,
        }
    }

    /// The door opened: hold, and stop spindle and coolant once stopped.
    /// Opened again while restoring, everything goes off again.
    pub fn door(&mut self, rt: &Realtime) {
        rt.feed_hold();
        // A spindle stop already stopped: the coolant goes off too.
        if !(self.door && self.phase == Phase::Stopped) {
            self.phase = Phase::Stopping;
        }
        self.door = true;
    }

    /// 0x9E during a hold (not a door's): stop the spindle once the hold
    /// is complete, or turn it back on. Returns true when it restores (the
    /// session says so, as GRBL's `[MSG:Restoring spindle]`).
    pub fn spindle_stop(&mut self, outputs: &mut Outputs, now_ms: u32) -> bool {
        if self.door {
            return false;
        }
        match self.phase {
            Phase::Off if outputs.spindle_dir() != SpindleDir::Off => {
                self.phase = Phase::Stopping;
                false
            }
            Phase::Stopping => {
                self.phase = Phase::Off;
                false
            }
            Phase::Stopped => {
                outputs.hold(HELD_SPINDLE, false);
                self.phase = Phase::Restoring {
                    since: now_ms,
                    start: false,
                };
                true
            }
            // Stopped again before the spin-up ended (a pending `~` with it).
            Phase::Restoring { .. } => {
                outputs.hold(HELD_SPINDLE, true);
                self.phase = Phase::Stopped;
                false
            }
            Phase::Off => false,
        }
    }

    /// Cycle start (`~`): resume now, or restore the outputs first. The
    /// door must read closed; before the hold has stopped a door's `~`
    /// does nothing (GRBL's).
    pub fn cycle_start(&mut self, rt: &Realtime, outputs: &mut Outputs, now_ms: u32) -> Resume {
        match self.phase {
            Phase::Off => rt.cycle_start(),
            Phase::Stopping if self.door => return Resume::Refused,
            // A spindle stop asked for before the hold completed: drop it.
            Phase::Stopping => {
                self.phase = Phase::Off;
                rt.cycle_start();
            }
            Phase::Stopped if self.door && rt.door_open() => return Resume::Refused,
            Phase::Stopped => {
                outputs.hold(HELD_SPINDLE, false);
                self.phase = Phase::Restoring {
                    since: now_ms,
                    start: true,
                };
                return Resume::Restoring { door: self.door };
            }
            Phase::Restoring { since, .. } => {
                self.phase = Phase::Restoring { since, start: true };
            }
        }
        Resume::Started
    }

    /// One pass: hold the outputs off once the motion has stopped, keep a
    /// door's hold on, finish a restore after `delay_ms` (0 when the
    /// spindle is off or a laser).
    pub fn update(&mut self, rt: &Realtime, outputs: &mut Outputs, now_ms: u32, delay_ms: u32) {
        match self.phase {
            Phase::Off => {}
            Phase::Stopping => {
                if self.door {
                    rt.feed_hold();
                }
                if rt.at_rest() {
                    let what = if self.door {
                        HELD_SPINDLE | HELD_COOLANT
                    } else {
                        HELD_SPINDLE
                    };
                    outputs.hold(what, true);
                    self.phase = Phase::Stopped;
                }
            }
            // A jog cancel's flush clears the hold flag: the door keeps it.
            Phase::Stopped => {
                if self.door {
                    rt.feed_hold();
                }
            }
            Phase::Restoring { since, start } => {
                let spinning = outputs.speed() > 0.0 && !outputs.laser();
                let wait = if spinning { delay_ms } else { 0 };
                if now_ms.wrapping_sub(since) >= wait {
                    outputs.hold(HELD_COOLANT, false);
                    self.phase = Phase::Off;
                    self.door = false;
                    if start {
                        rt.cycle_start();
                    }
                }
            }
        }
    }

    /// Reset or alarm: nothing held, nothing to restore.
    pub fn clear(&mut self, outputs: &mut Outputs) {
        *self = Suspend::new();
        outputs.hold(HELD_SPINDLE | HELD_COOLANT, false);
    }

    /// A door is open or being dealt with: the status report's `Door:n`
    /// (2 stopping, 1 stopped with the door open, 0 ready to resume,
    /// 3 restoring).
    pub fn door_substate(&self, rt: &Realtime) -> Option<u8> {
        if !self.door {
            return None;
        }
        Some(match self.phase {
            Phase::Off | Phase::Stopping => 2,
            Phase::Stopped => u8::from(rt.door_open()),
            Phase::Restoring { .. } => 3,
        })
    }

    /// Something is suspended (a door, or a spindle stop in a hold).
    pub fn active(&self) -> bool {
        self.phase != Phase::Off
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::Command;
    use crate::settings::Settings;

    fn spinning() -> Outputs {
        let mut o = Outputs::new(&Settings::default());
        o.apply(&Command::Spindle {
            dir: SpindleDir::Cw,
            speed: 1000.0,
        });
        o.apply(&Command::Coolant {
            mist: false,
            flood: true,
        });
        o
    }

    #[test]
    fn a_door_reopened_while_restoring_stops_everything_again() {
        let rt = Realtime::new();
        let mut o = spinning();
        let mut s = Suspend::new();
        s.door(&rt);
        assert_eq!(s.door_substate(&rt), Some(2));
        s.update(&rt, &mut o, 0, 4000);
        assert_eq!(s.door_substate(&rt), Some(0));
        assert_eq!(o.accessories(), 0, "spindle and coolant off");
        assert_eq!(
            s.cycle_start(&rt, &mut o, 10),
            Resume::Restoring { door: true }
        );
        assert_eq!(s.door_substate(&rt), Some(3));
        s.update(&rt, &mut o, 3000, 4000);
        assert!(o.spindle(crate::outputs::Motion::Stopped).enable);
        assert!(!o.flood_on(), "coolant waits for the spin-up");
        s.door(&rt);
        s.update(&rt, &mut o, 3500, 4000);
        assert_eq!(s.door_substate(&rt), Some(0));
        assert_eq!(o.accessories(), 0);
        assert!(rt.hold_requested(), "the door keeps its hold");
    }

    #[test]
    fn a_spindle_stop_before_the_hold_completes_is_dropped_by_cycle_start() {
        let rt = Realtime::new();
        rt.set_running(600.0, 1, 0.0);
        rt.set_stepper_idle(false);
        let mut o = spinning();
        let mut s = Suspend::new();
        assert!(!s.spindle_stop(&mut o, 0));
        s.update(&rt, &mut o, 0, 4000);
        assert!(s.active(), "still moving: nothing held yet");
        assert!(o.spindle(crate::outputs::Motion::Stopped).enable);
        assert_eq!(s.cycle_start(&rt, &mut o, 5), Resume::Started);
        assert!(!s.active());
        rt.set_stepper_idle(true);
        s.update(&rt, &mut o, 10, 4000);
        assert!(o.spindle(crate::outputs::Motion::Stopped).enable);
    }
}
