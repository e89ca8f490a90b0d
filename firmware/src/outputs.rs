//! Spindle, coolant and stepper-enable outputs as plain state machines, so
//! the rules (GRBL's) are tested on the host and the firmware only copies
//! the result to its pins.
//!
//! [`Outputs`] follows the executed commands (`Note::Executed`: M3/M4/M5
//! with S, M7/M8/M9, M2/M30), in program order with motion, and turns
//! everything off on an alarm or a reset. [`Enable`] decides when the
//! stepper drivers are powered (`$1` idle delay).

use crate::command::{Command, SpindleDir};
use crate::settings::Settings;
use protocol::msg::accessory;

#[path = "outputs_laser.rs"]
mod laser;
pub use laser::{LaserQueue, LASER_QUEUE};

/// What the machine is doing, for laser mode (`$32`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// No step is being made (idle, dwell, hold completed).
    Stopped,
    /// A G0 move.
    Rapid,
    /// A G1/G2/G3 move at `ratio` of its programmed feed (1.0 when not known).
    Feed { ratio: f32 },
}

/// Spindle pin states, in hardware-free terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spindle {
    pub enable: bool,
    /// M4 (counter-clockwise): the direction pin is set.
    pub ccw: bool,
    /// PWM duty, 0.0-1.0.
    pub duty: f32,
}

/// Spindle and coolant state as the executed commands left it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    dir: SpindleDir,
    /// Programmed S, rpm (or laser power units).
    speed: f32,
    pub flood: bool,
    pub mist: bool,
    rpm_max: f32,
    rpm_min: f32,
    laser: bool,
    /// Spindle override, percent (0x99-0x9D): scales the programmed S
    /// for the pins and the status report, as GRBL's does.
    ov: u8,
    /// [`HELD_SPINDLE`] / [`HELD_COOLANT`]: off at the pins for a safety
    /// door or a spindle stop (0x9E) while the programmed state stays, so
    /// cycle start can restore it (`suspend`).
    held: u8,
}

/// [`Outputs::hold`] bits.
pub const HELD_SPINDLE: u8 = 1;
pub const HELD_COOLANT: u8 = 2;

impl Outputs {
    /// Everything off, the `$30`/`$31`/`$32` of `s`.
    pub fn new(s: &Settings) -> Self {
        let mut o = Outputs {
            dir: SpindleDir::Off,
            speed: 0.0,
            flood: false,
            mist: false,
            rpm_max: 0.0,
            rpm_min: 0.0,
            laser: false,
            ov: 100,
            held: 0,
        };
        o.configure(s);
        o
    }

    /// Takes new settings (`$30`, `$31`, `$32` may change while idle).
    pub fn configure(&mut self, s: &Settings) {
        self.rpm_max = s.spindle_max;
        self.rpm_min = s.spindle_min;
        self.laser = s.laser_mode;
    }

    /// Follows one executed command. Returns true when the outputs changed.
    pub fn apply(&mut self, cmd: &Command) -> bool {
        let before = *self;
        match *cmd {
            Command::Spindle { dir, speed } => {
                self.dir = dir;
                self.speed = if speed.is_finite() {
                    speed.max(0.0)
                } else {
                    0.0
                };
            }
            Command::Coolant { mist, flood } => {
                self.mist = mist;
                self.flood = flood;
            }
            // GRBL's program end stops the spindle and the coolant (the
            // interpreter also sends M5 for it; this does not rely on that).
            Command::ProgramEnd => self.all_off(),
            _ => {}
        }
        *self != before
    }

    /// Alarm, reset or e-stop: spindle stopped, coolant off (GRBL). The next
    /// M3/M8 must be programmed again.
    pub fn all_off(&mut self) {
        self.dir = SpindleDir::Off;
        self.speed = 0.0;
        self.flood = false;
        self.mist = false;
        self.held = 0;
    }

    /// Spindle override in percent (10-200).
    pub fn set_override(&mut self, percent: u8) {
        self.ov = percent;
    }

    /// Turn the [`HELD_SPINDLE`] / [`HELD_COOLANT`] outputs off at the
    /// pins (`on`) or back to their programmed state.
    pub fn hold(&mut self, what: u8, on: bool) {
        if on {
            self.held |= what;
        } else {
            self.held &= !what;
        }
    }

    /// The outputs held off now.
    pub fn held(&self) -> u8 {
        self.held
    }

    /// The flood pin.
    pub fn flood_on(&self) -> bool {
        self.flood && self.held & HELD_COOLANT == 0
    }

    /// The mist pin.
    pub fn mist_on(&self) -> bool {
        self.mist && self.held & HELD_COOLANT == 0
    }

    /// The status report's `A:` bits ([`accessory`]) as the pins are now.
    pub fn accessories(&self) -> u8 {
        let spindle = match self.dir {
            _ if self.held & HELD_SPINDLE != 0 => 0,
            SpindleDir::Off => 0,
            SpindleDir::Cw => accessory::SPINDLE_CW,
            SpindleDir::Ccw => accessory::SPINDLE_CCW,
        };
        let flood = if self.flood_on() { accessory::FLOOD } else { 0 };
        let mist = if self.mist_on() { accessory::MIST } else { 0 };
        spindle | flood | mist
    }

    /// Laser mode (`$32=1`): spindle commands flow with the motion
    /// ([`LaserQueue`]).
    pub fn laser(&self) -> bool {
        self.laser
    }

    pub fn spindle_dir(&self) -> SpindleDir {
        self.dir
    }

    /// The spindle speed running now, rpm (0 while stopped or held): the
    /// status report's `FS:` second figure, which follows execution, not
    /// parsing, and includes the spindle override.
    pub fn speed(&self) -> f32 {
        match self.dir {
            SpindleDir::Off => 0.0,
            _ if self.held & HELD_SPINDLE != 0 => 0.0,
            _ => self.speed * f32::from(self.ov) / 100.0,
        }
    }

    /// The spindle pins for the current motion.
    ///
    /// Spindle mode: M3/M4 enable the spindle whatever the motion; S maps
    /// linearly from `[$31, $30]` rpm onto `(0, 1]` duty (S at or below
    /// `$31` gives the lowest duty that is still on, S at or above `$30`
    /// full duty; S0 is duty 0 with the enable on, as GRBL).
    ///
    /// Laser mode (`$32=1`), as GRBL 1.1: the laser fires only during
    /// G1/G2/G3 moves and is off on rapids. M3 is constant power; M4 scales
    /// power with the speed ratio (dynamic power). One difference: with M3
    /// the laser is also off while stopped (GRBL keeps it on between
    /// moves); a stopped laser burns a hole, and a G4 dot is not worth that.
    /// The motion comes from the segment the step interrupt runs
    /// (`Segment::cut`), and holds count as stopped.
    pub fn spindle(&self, motion: Motion) -> Spindle {
        let off = Spindle {
            enable: false,
            ccw: false,
            duty: 0.0,
        };
        if self.held & HELD_SPINDLE != 0 {
            return off;
        }
        let ccw = match self.dir {
            SpindleDir::Off => return off,
            SpindleDir::Cw => false,
            SpindleDir::Ccw => true,
        };
        let duty = self.duty();
        if !self.laser {
            return Spindle {
                enable: true,
                ccw,
                duty,
            };
        }
        let scale = match motion {
            Motion::Stopped | Motion::Rapid => return off,
            Motion::Feed { .. } if !ccw => 1.0,
            Motion::Feed { ratio } => crate::num::clamp(ratio, 0.0, 1.0),
        };
        Spindle {
            enable: true,
            ccw: false,
            duty: duty * scale,
        }
    }

    /// Duty of the programmed S, overridden, over the `$31`-`$30` range.
    fn duty(&self) -> f32 {
        /// Lowest duty that still turns a spindle on (GRBL's is 1/255).
        const MIN_DUTY: f32 = 1.0 / 256.0;
        let s = self.speed * f32::from(self.ov) / 100.0;
        if s <= 0.0 {
            return 0.0;
        }
        let span = self.rpm_max - self.rpm_min;
        // A NaN span (never from the settings table) counts as degenerate.
        if span.is_nan() || span <= 0.0 || s >= self.rpm_max {
            return 1.0;
        }
        crate::num::clamp((s - self.rpm_min) / span, MIN_DUTY, 1.0)
    }
}

/// Stepper driver enable: on before motion, off `$1` ms after the last
/// step (never with `$1 = 255`), on through a feed hold (the motors hold
/// the position to resume from), off on an alarm once stopped (GRBL).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Enable {
    idle_ms: u16,
    wake_ms: u16,
    state: EnState,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum EnState {
    Off,
    /// Powered since `since`; steps wait until `wake_ms` have passed.
    Waking {
        since: u32,
    },
    On,
    /// Stopped at `since`: off `idle_ms` later.
    Lingering {
        since: u32,
    },
}

/// `$1` value that keeps the drivers on for good.
pub const ALWAYS_ON: u16 = 255;

impl Enable {
    /// `idle_ms` is `$1`; `wake_ms` is how long a driver needs between
    /// enable and its first step (0 for most drivers). With `$1 = 255` the
    /// drivers are on from the start.
    pub fn new(idle_ms: u16, wake_ms: u16) -> Self {
        Enable {
            idle_ms,
            wake_ms,
            state: if idle_ms == ALWAYS_ON {
                EnState::On
            } else {
                EnState::Off
            },
        }
    }

    /// Takes a new `$1`.
    pub fn set_idle_ms(&mut self, idle_ms: u16) {
        self.idle_ms = idle_ms;
    }

    /// Advances the state at time `now` (ms, wrapping) and returns whether
    /// the drivers are enabled. `busy`: steps are queued or running;
    /// `hold`: a feed hold is on; `alarm`: the machine is in alarm.
    pub fn update(&mut self, now: u32, busy: bool, hold: bool, alarm: bool) -> bool {
        self.state = match self.state {
            _ if alarm && !busy => EnState::Off,
            // `$1=255` powers the drivers for good, also when it is set
            // while they are off (and again after an alarm has passed).
            EnState::Off if (busy || self.idle_ms == ALWAYS_ON) && self.wake_ms > 0 => {
                EnState::Waking { since: now }
            }
            EnState::Off if busy || self.idle_ms == ALWAYS_ON => EnState::On,
            EnState::Lingering { .. } if busy || hold || self.idle_ms == ALWAYS_ON => EnState::On,
            EnState::Waking { since } if now.wrapping_sub(since) >= u32::from(self.wake_ms) => {
                EnState::On
            }
            EnState::On if !busy && !hold && self.idle_ms == 0 => EnState::Off,
            EnState::On if !busy && !hold && self.idle_ms != ALWAYS_ON => {
                EnState::Lingering { since: now }
            }
            EnState::Lingering { since } if now.wrapping_sub(since) >= u32::from(self.idle_ms) => {
                EnState::Off
            }
            s => s,
        };
        self.enabled()
    }

    pub fn enabled(&self) -> bool {
        !matches!(self.state, EnState::Off)
    }

    /// Steps may start: the drivers are on and awake.
    pub fn may_step(&self) -> bool {
        matches!(self.state, EnState::On | EnState::Lingering { .. })
    }
}

/// The shells' write of the output pins, made safe against the e-stop: the
/// e-stop interrupt (above the task that writes the pins) turns spindle and
/// coolant off at once, but the pin levels the task is about to store were
/// computed before it fired. So the task stores them (`write`), then reads
/// the e-stop latch, which the interrupt sets before its own kill, and
/// kills again (`kill`) if it is set: whichever way the two interleave, the
/// last store is the kill. Returns whether it killed (the shell then forgets
/// what it wrote, so the next pass writes again).
pub fn write_then_recheck(
    rt: &crate::realtime::Realtime,
    write: impl FnOnce(),
    kill: impl FnOnce(),
) -> bool {
    write();
    let stopped = rt.estop();
    if stopped {
        kill();
    }
    stopped
}

#[cfg(test)]
#[path = "outputs_tests.rs"]
mod tests;
