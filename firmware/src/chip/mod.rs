//! What the STM32F411 and STM32F401 are, as far as the board code relies
//! on it: the memory map and bus matrix ([`bus`]), the DMA requests and
//! paths ([`dma`]), and the boot self-checks that confirm on the chip what
//! no model can ([`self_test`], [`judge_rate`]). `firmware/CHIP.md` is the
//! table of these facts with their reference-manual sections; this module
//! is its executable part, shared by the board and host-sim, so a wrong
//! belief about the chip fails a host test instead of a machine.

pub mod bus;
pub mod dma;

use dma::StreamFlags;

/// The two supported chips.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Chip {
    /// STM32F411CEU6 (WeAct Black Pill 3.x): RM0383, errata ES0287.
    F411,
    /// STM32F401CCU6 (Black Pill 1.x/2.x): RM0368, errata ES0299.
    F401,
}

/// A hardware path that failed, found at boot or by the step path's error
/// flags. Any of these would leave a machine whose position and status
/// advance while nothing moves, so each latches an alarm that neither
/// `$X` nor `$H` clears ([`crate::realtime::Realtime::set_hw_fault`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HwFault {
    /// The pulse-end DMA path is one the chip cannot run
    /// ([`dma::DmaPath::check`]); found before it was enabled.
    PulseEndPath = 1,
    /// The boot test request did not complete, or raised an error flag.
    PulseEndSelfTest = 2,
    /// The pulse-end stream raised an error flag, or was disabled by the
    /// hardware, while running.
    PulseEndError = 3,
    /// The step timer does not count at the rate the step timing assumes.
    StepTimer = 4,
    /// The pulse-end timer does not count at the rate the pulse width
    /// assumes.
    PulseTimer = 5,
    /// The system clock is not the crystal-locked PLL the timing assumes.
    Clock = 6,
}

impl HwFault {
    /// From the code [`HwFault::code`] gives (0 and unknown codes: none).
    pub const fn from_code(code: u8) -> Option<HwFault> {
        use HwFault::*;
        Some(match code {
            1 => PulseEndPath,
            2 => PulseEndSelfTest,
            3 => PulseEndError,
            4 => StepTimer,
            5 => PulseTimer,
            6 => Clock,
            _ => return None,
        })
    }

    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The operator's message: what failed and what it means.
    pub const fn message(self) -> &'static str {
        match self {
            HwFault::PulseEndPath => {
                "step pulse DMA path not possible on this chip: motors would not turn"
            }
            HwFault::PulseEndSelfTest => {
                "step pulse DMA failed its boot test: motors would not turn"
            }
            HwFault::PulseEndError => "step pulse DMA error while running: steps lost",
            HwFault::StepTimer => "step timer (TIM5) not counting at its clock: step timing wrong",
            HwFault::PulseTimer => {
                "pulse timer (TIM1) not counting at its clock: pulse width wrong"
            }
            HwFault::Clock => "system clock not on the crystal PLL: timing wrong",
        }
    }
}

/// The pulse-end hardware as the boot test drives it: the board's TIM1 and
/// DMA2 registers, host-sim's DMA model.
pub trait PulseEndHw {
    /// Raise the stream's request once by software (TIM1_EGR.CC2G), with
    /// the step pins at rest: the transfer rewrites the step-off word,
    /// which changes no pin.
    fn request_once(&mut self);
    /// The stream's flags now.
    fn flags(&self) -> StreamFlags;
    /// Clear the stream's transfer-complete flag (and the others).
    fn clear_flags(&mut self);
}

/// Polls of the flags before a test transfer counts as lost. A transfer
/// takes a few bus cycles; a poll is several.
pub const SELF_TEST_POLLS: u32 = 1000;

/// The boot test of the pulse-end path: one zero-effect transfer must
/// complete without an error flag and leave the circular stream enabled.
pub fn self_test(hw: &mut impl PulseEndHw) -> Result<(), HwFault> {
    hw.clear_flags();
    hw.request_once();
    for _ in 0..SELF_TEST_POLLS {
        let f = hw.flags();
        if f.failed() {
            break;
        }
        if f.complete {
            hw.clear_flags();
            return Ok(());
        }
    }
    hw.clear_flags();
    Err(HwFault::PulseEndSelfTest)
}

/// The pulse-end path at boot, as both shells run it: the path must be
/// one the chip can run ([`dma::DmaPath::check`]), and a zero-effect
/// transfer on the enabled stream must complete ([`self_test`]).
pub fn check_pulse_end(
    path: &dma::DmaPath,
    chip: Chip,
    hw: &mut impl PulseEndHw,
) -> Result<(), HwFault> {
    path.check(chip).map_err(|_| HwFault::PulseEndPath)?;
    self_test(hw)
}

/// A timer counts at the rate the code assumes: over one measurement,
/// `ticks` of the timer against `cycles` of the core clock, expected
/// `timer_hz` / `core_hz`. Off by more than 5 % is a wrong prescaler or
/// clock tree (a stopped timer reads 0).
pub fn judge_rate(cycles: u32, ticks: u32, timer_hz: u32, core_hz: u32) -> bool {
    if cycles == 0 || core_hz == 0 {
        return false;
    }
    let expected = u64::from(cycles) * u64::from(timer_hz) / u64::from(core_hz);
    let got = u64::from(ticks) * 20;
    got >= expected * 19 && got <= expected * 21
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Model {
        flags: StreamFlags,
        works: bool,
    }

    impl PulseEndHw for Model {
        fn request_once(&mut self) {
            if self.works {
                self.flags.complete = true;
            } else {
                self.flags.transfer_error = true;
                self.flags.enabled = false;
            }
        }
        fn flags(&self) -> StreamFlags {
            self.flags
        }
        fn clear_flags(&mut self) {
            self.flags.complete = false;
            self.flags.transfer_error = false;
        }
    }

    #[test]
    fn the_boot_test_tells_a_working_stream_from_a_broken_one() {
        let on = StreamFlags {
            enabled: true,
            ..Default::default()
        };
        let mut good = Model {
            flags: on,
            works: true,
        };
        assert_eq!(self_test(&mut good), Ok(()));
        let mut bad = Model {
            flags: on,
            works: false,
        };
        assert_eq!(self_test(&mut bad), Err(HwFault::PulseEndSelfTest));
        // A stream that never completes (no request reaches it) fails too.
        struct Deaf(StreamFlags);
        impl PulseEndHw for Deaf {
            fn request_once(&mut self) {}
            fn flags(&self) -> StreamFlags {
                self.0
            }
            fn clear_flags(&mut self) {}
        }
        assert_eq!(self_test(&mut Deaf(on)), Err(HwFault::PulseEndSelfTest));
    }

    #[test]
    fn rates() {
        // TIM5 at 96 MHz against a 96 MHz core: equal counts.
        assert!(judge_rate(96_000, 96_000, 96_000_000, 96_000_000));
        // A timer at half its assumed clock (APB1 without its x2).
        assert!(!judge_rate(96_000, 48_000, 96_000_000, 96_000_000));
        // TIM1 with prescaler 2: 48 MHz.
        assert!(judge_rate(96_000, 48_100, 48_000_000, 96_000_000));
        assert!(!judge_rate(96_000, 0, 48_000_000, 96_000_000));
    }

    #[test]
    fn fault_codes_round_trip() {
        for c in 1..=6 {
            let f = HwFault::from_code(c).unwrap();
            assert_eq!(f.code(), c);
            assert!(!f.message().is_empty());
        }
        assert_eq!(HwFault::from_code(0), None);
    }
}
