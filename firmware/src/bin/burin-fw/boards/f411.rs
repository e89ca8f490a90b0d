//! WeAct Black Pill V3 with an STM32F411CEU6 (the default board).
use stm32f4xx_hal::{prelude::*, rcc::Config};

pub use super::blackpill::{closed_now, enable_exti, enable_pin, kill_aux, split, switches, Aux};

/// Human-readable board name for the startup log and `$I`.
pub const NAME: &str = "WeAct Black Pill STM32F411CEU6";

/// 25 MHz crystal -> PLL: VCO 384 MHz, /4 = 96 MHz core, /8 = 48 MHz USB.
/// 96 rather than the chip's 100 MHz maximum because USB needs an exact
/// 48 MHz from the same VCO. APB1 runs at 48 MHz, so TIM5 ticks at 96 MHz.
pub fn clocks() -> Config {
    Config::hse(25.MHz()).sysclk(96.MHz()).require_pll48clk()
}
