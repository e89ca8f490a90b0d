//! Errors and alarms of the motion half of the core.
//!
//! Stable code table (never renumber; add at the end of a range):
//!
//! | range | what |
//! |---|---|
//! | 400–419 | a command refused before any step ran (nothing moved) |
//! | 420–439 | alarms: something happened while moving; the machine stops |

use core::fmt;

use crate::arc::ArcError;
use crate::planner::PlanError;

/// What went wrong in the motion core.
///
/// Tagged from 1, so that `Option<MachineError>`'s `None` is a zero byte
/// (the board's machine slot is all zero bits, `Machine::placeholder`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(u8)]
pub enum MachineError {
    /// 400: the move leaves the machine envelope on this axis.
    SoftLimit { axis: u8 } = 1,
    /// 401: this axis's max rate times its steps/mm exceeds `$201`; the move
    /// could not be stepped without losing steps, so it is refused.
    StepRateTooHigh { axis: u8 },
    /// 402: an arc with zero radius or a non-finite geometry.
    InvalidArc,
    /// 403: an arc or spline would need more chords than the core allows.
    TooManySegments,
    /// 404: one block would need more steps than the stepper's counters hold.
    MoveTooLong,
    /// 405: a coordinate, feed or time is not a finite number in range.
    InvalidNumber,
    /// 406: feed rate zero or negative.
    InvalidFeed,
    /// 407: the machine is in alarm; only homing and clear-alarm are accepted.
    InAlarm,
    /// 408: the command arrived while another was still being fed to the planner.
    Busy,
    /// 409: homing is disabled (`$22=0`) or no axis has a homing cycle.
    HomingDisabled,
    /// 410: G27 or soft limits need a homed machine.
    NotHomed,
    /// 411: G38.2/G38.4 probe started in the state it waits for.
    ProbeInitialState,
    /// 412: the feed is so slow that the dominant axis's steps would be
    /// further apart than the step driver times ([`crate::seams::MAX_PERIOD`],
    /// 11.2 s at 96 MHz). GRBL silently raises such feeds to its minimum of
    /// 1 mm/min; burin refuses instead, because a move that runs faster
    /// than programmed is worse than one that does not start: a feed like
    /// `F0.0001` is almost always a typo or a units mistake, and a refused
    /// line says so while nothing has moved yet.
    FeedTooSlow,
    /// 420: a limit switch closed during motion; position is lost.
    HardLimit { mask: u8 },
    /// 421: homing seek ended without finding this axis's switch.
    HomingNoSwitch { axis: u8 },
    /// 422: the switch was still closed after pull-off.
    HomingPullOff { axis: u8 },
    /// 423: G27 found this axis's switch further away than `$205` allows.
    VerifyHome { axis: u8, deviation_mm: f32 },
    /// 424: G38.2/G38.4 reached the end without contact (or release).
    ProbeNoContact,
    /// 425: soft reset during motion; position is lost.
    ResetDuringMotion,
    /// 426: the e-stop is pressed. Motion, homing and `$X` are refused
    /// until it is released.
    EStop,
    /// 427: a hardware path failed its check ([`crate::chip::HwFault`]):
    /// motion, homing and `$X` are refused until the chip is reset.
    HardwareFault { fault: crate::chip::HwFault },
    /// 428: a reset woke the machine from `$SLP`: the drivers were off, so
    /// the position is not trusted until `$X` or homing (GRBL's alarm
    /// state after sleep).
    Slept,
    /// 429: the safety door opened during homing (GRBL's alarm 7): the
    /// cycle ramps down and stops unfinished.
    HomingDoor,
}

impl MachineError {
    /// Stable numeric code.
    pub fn code(&self) -> u16 {
        use MachineError::*;
        match self {
            SoftLimit { .. } => 400,
            StepRateTooHigh { .. } => 401,
            InvalidArc => 402,
            TooManySegments => 403,
            MoveTooLong => 404,
            InvalidNumber => 405,
            InvalidFeed => 406,
            InAlarm => 407,
            Busy => 408,
            HomingDisabled => 409,
            NotHomed => 410,
            ProbeInitialState => 411,
            FeedTooSlow => 412,
            HardLimit { .. } => 420,
            HomingNoSwitch { .. } => 421,
            HomingPullOff { .. } => 422,
            VerifyHome { .. } => 423,
            ProbeNoContact => 424,
            ResetDuringMotion => 425,
            EStop => 426,
            HardwareFault { .. } => 427,
            Slept => 428,
            HomingDoor => 429,
        }
    }

    /// True for alarms (the machine stops and locks until cleared).
    pub fn is_alarm(&self) -> bool {
        self.code() >= 420
    }
}

/// The segmenter's errors keep the codes they had when it returned these
/// directly: 405, 402, 403.
impl From<ArcError> for MachineError {
    fn from(e: ArcError) -> Self {
        match e {
            ArcError::InvalidNumber => MachineError::InvalidNumber,
            ArcError::InvalidArc => MachineError::InvalidArc,
            ArcError::TooManySegments => MachineError::TooManySegments,
        }
    }
}

/// The planner's errors keep the codes they had when it returned these
/// directly: 408, 405, 404, 401, 406.
impl From<PlanError> for MachineError {
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::Full => MachineError::Busy,
            PlanError::InvalidNumber => MachineError::InvalidNumber,
            PlanError::MoveTooLong => MachineError::MoveTooLong,
            PlanError::StepRateTooHigh { axis } => MachineError::StepRateTooHigh { axis },
            PlanError::InvalidFeed => MachineError::InvalidFeed,
            PlanError::FeedTooSlow => MachineError::FeedTooSlow,
        }
    }
}

fn axis_name(axis: u8) -> char {
    crate::AXIS_NAMES.get(axis as usize).copied().unwrap_or('?')
}

impl fmt::Display for MachineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use MachineError::*;
        match *self {
            SoftLimit { axis } => write!(f, "move exceeds soft limit on {}", axis_name(axis)),
            StepRateTooHigh { axis } => {
                write!(
                    f,
                    "{} max rate needs more steps/s than $201 allows",
                    axis_name(axis)
                )
            }
            InvalidArc => f.write_str("invalid arc geometry"),
            TooManySegments => f.write_str("arc or spline needs too many segments"),
            MoveTooLong => f.write_str("move has too many steps for one block"),
            InvalidNumber => f.write_str("coordinate or time out of range"),
            InvalidFeed => f.write_str("feed rate must be positive"),
            InAlarm => f.write_str("machine is in alarm"),
            Busy => f.write_str("previous command still being planned"),
            HomingDisabled => f.write_str("homing is disabled"),
            NotHomed => f.write_str("machine is not homed"),
            ProbeInitialState => f.write_str("probe already in target state"),
            FeedTooSlow => f.write_str(
                "feed too slow: steps would be further apart than the step timer reaches",
            ),
            HardLimit { .. } => f.write_str("hard limit triggered; position lost"),
            HomingNoSwitch { axis } => write!(f, "homing: no switch found on {}", axis_name(axis)),
            HomingPullOff { axis } => write!(
                f,
                "homing: {} switch still closed after pull-off",
                axis_name(axis)
            ),
            VerifyHome { axis, deviation_mm } => {
                write!(f, "G27: {} home off by ", axis_name(axis))?;
                crate::num::write_fixed(f, deviation_mm, 3)?;
                f.write_str(" mm")
            }
            ProbeNoContact => f.write_str("probe: no contact"),
            ResetDuringMotion => f.write_str("reset during motion; position lost"),
            EStop => f.write_str("e-stop pressed; release it, then $X"),
            HardwareFault { fault } => {
                write!(
                    f,
                    "hardware fault: {}; reset or power-cycle",
                    fault.message()
                )
            }
            Slept => f.write_str("woke from sleep; $H or $X"),
            HomingDoor => f.write_str("safety door opened during homing"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The segmenter's and the planner's own errors reach the host with the
    /// codes they had when those modules returned `MachineError` directly.
    #[test]
    fn lower_errors_keep_their_codes() {
        let arc = [
            (ArcError::InvalidNumber, 405),
            (ArcError::InvalidArc, 402),
            (ArcError::TooManySegments, 403),
        ];
        for (e, code) in arc {
            assert_eq!(MachineError::from(e).code(), code, "{e:?}");
        }
        let plan = [
            (PlanError::Full, 408),
            (PlanError::InvalidNumber, 405),
            (PlanError::MoveTooLong, 404),
            (PlanError::StepRateTooHigh { axis: 2 }, 401),
            (PlanError::InvalidFeed, 406),
            (PlanError::FeedTooSlow, 412),
        ];
        for (e, code) in plan {
            assert_eq!(MachineError::from(e).code(), code, "{e:?}");
        }
        assert_eq!(
            MachineError::from(PlanError::StepRateTooHigh { axis: 2 }),
            MachineError::StepRateTooHigh { axis: 2 }
        );
    }
}
