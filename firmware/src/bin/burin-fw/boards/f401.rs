//! WeAct Black Pill V1.3/V3 with an STM32F401CCU6. Same package and board
//! as the F411 one, so it shares the Black Pill pin map; only the clock
//! tree and the memory sizes differ (the setup is `blackpill_init.rs`).
use stm32f4xx_hal::{prelude::*, rcc::Config};

pub use super::blackpill::*;
pub use super::blackpill_init::*;

/// Human-readable board name for the startup log and `$I`.
pub const NAME: &str = "WeAct Black Pill STM32F401CCU6";

/// The chip facts this board's code is checked against (`burin::chip`).
pub const CHIP: burin::chip::Chip = burin::chip::Chip::F401;

/// 25 MHz crystal -> PLL: VCO 336 MHz, /4 = 84 MHz core (the chip's
/// maximum), /7 = 48 MHz USB. APB1 runs at 42 MHz, so TIM5 ticks at 84 MHz.
pub fn clocks() -> Config {
    Config::hse(25.MHz()).sysclk(84.MHz()).require_pll48clk()
}

/// The regulator as the clocks need it: nothing to do (84 MHz is within scale 2, the reset value of `PWR_CR.VOS` (RM0368)).
pub fn regulator(_pwr: &stm32f4xx_hal::pac::PWR, _rcc: &stm32f4xx_hal::pac::RCC) {}

/// Received tokens the link holds while the token ring is full: 2048
/// (4 KiB), half the F411's. The F401's statics had 44 KiB (its 64 KiB
/// SRAM less a 20 KiB stack), and six axes took 2.2 KB more than that
/// left; their wider arrays also deepened the stack (7,956 B of 20 KiB
/// left unused, under the 8 KiB floor), so the stack took 1 KiB of the
/// room this made (memory-f401.x: 21 KiB stack, 43 KiB statics).
/// What it costs: a sender that writes without counting (no GRBL
/// character counting, no credits) sees USB NAKs 4 KiB of text sooner;
/// realtime bytes still act on arrival, and nothing is lost. host-sim
/// models the F411's 4096.
pub const RX_BACKLOG: usize = burin::link::RX_BACKLOG / 2;
