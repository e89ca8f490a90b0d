//! WeAct Black Pill V3 with an STM32F411CEU6 (the default board): the
//! Black Pill's map and setup (`blackpill.rs`, `blackpill_init.rs`) with
//! this chip's constants.
use stm32f4xx_hal::{pac, prelude::*, rcc::Config};

pub use super::blackpill::*;
pub use super::blackpill_init::*;

/// Received tokens the link holds while the token ring is full: the
/// size host-sim models (`burin::link::RX_BACKLOG`, 8 KiB).
pub const RX_BACKLOG: usize = burin::link::RX_BACKLOG;

/// Human-readable board name for the startup log and `$I`.
pub const NAME: &str = "WeAct Black Pill STM32F411CEU6";

/// The chip facts this board's code is checked against (`burin::chip`).
pub const CHIP: burin::chip::Chip = burin::chip::Chip::F411;

/// 25 MHz crystal -> PLL: VCO 384 MHz, /4 = 96 MHz core, /8 = 48 MHz USB.
/// 96 rather than the chip's 100 MHz maximum because USB needs an exact
/// 48 MHz from the same VCO. APB1 runs at 48 MHz, so TIM5 ticks at 96 MHz.
pub fn clocks() -> Config {
    Config::hse(25.MHz()).sysclk(96.MHz()).require_pll48clk()
}

/// The regulator for 96 MHz: voltage scale 1. Scale 2, the reset value of
/// `PWR_CR.VOS`, is rated to 84 MHz only (RM0383, PWR_CR), and the HAL's
/// clock setup never writes it. VOS may change only while the PLL is off,
/// so this runs before `freeze`; it takes effect when the PLL starts.
pub fn regulator(pwr: &pac::PWR, rcc: &pac::RCC) {
    rcc.apb1enr().modify(|_, w| w.pwren().set_bit());
    // The enable needs two APB1 cycles before PWR answers: read it back.
    let _ = rcc.apb1enr().read();
    pwr.cr().modify(|_, w| w.vos().scale1());
}
