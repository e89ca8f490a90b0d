//! Stable numeric codes for the link's own errors and the alarms.
//!
//! Numbers below 100 follow GRBL 1.1's `error:N` meanings, so senders show
//! the right text; burin's own link errors start at 100. The G-code parser
//! and interpreter have their own codes in the same `u16` space (1, 2, 20-38
//! as GRBL, burin's from 60 up), which is why the wire carries a plain `u16`.

/// A link/system error code. `code()` is what `error:N` and the wire carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u16)]
pub enum Code {
    /// A number in a `$` command or setting value could not be read.
    BadNumber = 2,
    /// `$` command not recognised (also: unknown setting number).
    InvalidStatement = 3,
    /// A setting value was negative where that is not allowed.
    NegativeValue = 4,
    /// `$H` with homing disabled (`$22=0`).
    SettingDisabled = 5,
    /// The command needs the machine idle.
    NotIdle = 8,
    /// G-code refused while in alarm or jog state.
    Locked = 9,
    /// The line is longer than [`crate::MAX_LINE`] bytes; it was discarded.
    LineOverflow = 11,
    /// A `$J=` target outside the soft limits (`$20=1`): nothing moves.
    JogTravel = 15,
    /// A `$J=` line is not a valid jog.
    InvalidJog = 16,
    /// The command exists in GRBL but burin does not support it.
    Unsupported = 20,
    /// COBS framing broken (a code byte points past the frame end).
    FrameCorrupt = 100,
    /// CRC mismatch.
    FrameCrc = 101,
    /// Frame longer than [`crate::frame::MAX_FRAME`] bytes.
    FrameTooLong = 102,
    /// CRC good but the bytes are not a message of this protocol version.
    FrameDecode = 103,
    /// Sequence number ahead of the expected one: a line was lost.
    SeqGap = 104,
    /// A line arrived with no free line slot: the host exceeded its credits.
    FlowOverrun = 105,
    /// Input bytes were dropped because the receive ring was full.
    RxOverflow = 106,
    /// The host's protocol version is not supported.
    VersionMismatch = 107,
    /// A setting value is outside its allowed range.
    SettingRange = 110,
    /// A setting that takes whole numbers got a fraction.
    SettingNotInteger = 111,
    /// A mask setting has bits for axes that do not exist.
    SettingBadMask = 112,
    /// A settings write (`$n=`, `$RST=`) with the spindle or coolant on:
    /// the flash erase would stall the e-stop handler (M5 M9 first).
    OutputsOn = 113,
    /// `$201` above the step-rate ceiling of `$0` and the step path's
    /// cost, or a `$0` that makes the current `$201` impossible.
    StepRateCeiling = 114,
}

impl Code {
    /// Every code, for tables and tests.
    pub const ALL: [Code; 23] = [
        Code::BadNumber,
        Code::InvalidStatement,
        Code::NegativeValue,
        Code::SettingDisabled,
        Code::NotIdle,
        Code::Locked,
        Code::LineOverflow,
        Code::JogTravel,
        Code::InvalidJog,
        Code::Unsupported,
        Code::FrameCorrupt,
        Code::FrameCrc,
        Code::FrameTooLong,
        Code::FrameDecode,
        Code::SeqGap,
        Code::FlowOverrun,
        Code::RxOverflow,
        Code::VersionMismatch,
        Code::SettingRange,
        Code::SettingNotInteger,
        Code::SettingBadMask,
        Code::OutputsOn,
        Code::StepRateCeiling,
    ];

    /// The stable number.
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// The code with number `n`, if it is one of the link's.
    pub fn from_code(n: u16) -> Option<Code> {
        Code::ALL.into_iter().find(|c| c.code() == n)
    }

    /// One-line explanation for operators (the streamer prints it).
    pub const fn message(self) -> &'static str {
        match self {
            Code::BadNumber => "bad number format",
            Code::InvalidStatement => "invalid $ statement or unknown setting",
            Code::NegativeValue => "value must not be negative",
            Code::SettingDisabled => "homing is disabled ($22=0)",
            Code::NotIdle => "command needs the machine idle",
            Code::Locked => "locked by alarm or jog state",
            Code::LineOverflow => "line too long, discarded",
            Code::JogTravel => "jog target exceeds machine travel",
            Code::InvalidJog => "invalid jog command",
            Code::Unsupported => "unsupported command",
            Code::FrameCorrupt => "corrupt frame",
            Code::FrameCrc => "frame checksum mismatch",
            Code::FrameTooLong => "frame too long",
            Code::FrameDecode => "frame is not a valid message",
            Code::SeqGap => "sequence gap: line lost, resend",
            Code::FlowOverrun => "no free line slot: host exceeded credits",
            Code::RxOverflow => "receive buffer overflow, input dropped",
            Code::VersionMismatch => "protocol version not supported",
            Code::SettingRange => "setting value out of range",
            Code::SettingNotInteger => "setting needs a whole number",
            Code::SettingBadMask => "mask names axes that do not exist",
            Code::OutputsOn => "no flash write with spindle or coolant on (M5 M9 first)",
            Code::StepRateCeiling => {
                "step rate beyond the ceiling of the pulse width and the CPU (lower $201 or $0)"
            }
        }
    }
}

/// Alarm codes (`ALARM:N`), GRBL 1.1 numbering.
pub mod alarm {
    /// Hard limit switch hit; position lost.
    pub const HARD_LIMIT: u16 = 1;
    /// Target outside soft limits; the move was not started.
    pub const SOFT_LIMIT: u16 = 2;
    /// Reset while moving; position may be lost.
    pub const ABORT_CYCLE: u16 = 3;
    /// Probe not in the expected state before probing.
    pub const PROBE_FAIL_INITIAL: u16 = 4;
    /// Probe did not touch within the move.
    pub const PROBE_FAIL_CONTACT: u16 = 5;
    /// Homing: reset during the cycle.
    pub const HOMING_FAIL_RESET: u16 = 6;
    /// Homing: door opened during the cycle.
    pub const HOMING_FAIL_DOOR: u16 = 7;
    /// Homing: pull-off did not clear the switch.
    pub const HOMING_FAIL_PULLOFF: u16 = 8;
    /// Homing: switch not found within the search distance.
    pub const HOMING_FAIL_APPROACH: u16 = 9;
    /// E-stop pressed (grblHAL's number): the machine stays in alarm
    /// until it is released.
    pub const ESTOP: u16 = 10;
    /// Host link lost while running (burin): the machine was held.
    pub const LINK_LOST: u16 = 20;
    /// A line was refused after its `ok` (burin): the machine ramped down
    /// and stopped, nothing queued behind the line runs. The `[MSG:…]` (the
    /// `Error` frame) before the alarm names the line and the error; a soft
    /// limit is [`SOFT_LIMIT`] instead, as in GRBL.
    pub const LATE_ERROR: u16 = 21;
    /// A hardware path failed its boot check or raised an error while
    /// running (burin): pulses may not reach the drivers. Only a reset of
    /// the board clears it.
    pub const HARDWARE_FAULT: u16 = 22;
    /// Woken from `$SLP` by a reset (burin's number for GRBL's alarm state
    /// after sleep, which has none: text mode prints no `ALARM:` line).
    pub const SLEPT: u16 = 23;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_round_trip() {
        for (i, a) in Code::ALL.iter().enumerate() {
            assert_eq!(Code::from_code(a.code()), Some(*a));
            assert!(!a.message().is_empty());
            for b in &Code::ALL[i + 1..] {
                assert_ne!(a.code(), b.code());
            }
        }
        assert_eq!(Code::LineOverflow.code(), 11);
        assert_eq!(Code::FrameCrc.code(), 101);
        assert_eq!(Code::from_code(999), None);
    }
}
