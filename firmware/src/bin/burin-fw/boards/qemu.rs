//! QEMU's `netduinoplus2` machine: an STM32F405 (Cortex-M4F like the F411)
//! that `cargo xtask qemu` runs the real app on.
//!
//! What QEMU models decides the differences from the Black Pill:
//! - RCC is a stub, so the clock tree stays on the 16 MHz HSI (waiting for
//!   a PLL lock would hang);
//! - there is no USB OTG model, so the link is USART1 (PA9/PA10, the pins
//!   the Black Pill leaves free for the same USART), the first `-serial`;
//! - GPIO is a stub (writes ignored, reads 0), TIM1 is unimplemented (reads
//!   0, writes ignored); TIM2–5, the USARTs and the NVIC are real.
//!
//! Everything else is the Black Pill's pin map, so the same code paths run.
use super::super::step::StepPort;
use super::blackpill::PORT_PINS;
use burin::seams::StepPins;
use stm32f4xx_hal::{
    gpio::{gpioa, gpiob, gpioc, Output, PinState, PA10, PA9, PC13},
    pac,
    prelude::*,
    rcc::{Config, Rcc},
};

pub use super::blackpill::{enable_pin, kill_aux, Aux, Inputs};
use burin::stepper::Switches;
use stm32f4xx_hal::syscfg::SysCfg;

/// GPIO reads 0 under QEMU, which would look like every switch closed:
/// all inputs count as open here.
pub fn closed_now() -> u8 {
    0
}

/// No edge interrupts: the pins never change under QEMU, and open is what
/// [`closed_now`] reports.
pub fn enable_exti(_inputs: &mut Inputs, _syscfg: &mut SysCfg, _exti: &mut pac::EXTI) {}

/// Limits and probe: open (see [`closed_now`]).
#[inline(always)]
pub fn switches() -> Switches {
    Switches::default()
}

/// Human-readable board name for the startup log and `$I`.
pub const NAME: &str = "QEMU netduinoplus2 (STM32F405)";

/// HSI only: 16 MHz core and timers.
pub fn clocks() -> Config {
    Config::hsi()
}

/// Spindle PWM carrier (TIM1 is not modelled; the writes go nowhere).
const SPINDLE_PWM_HZ: u32 = 1_000;

pub struct Board {
    pub steppers: StepPort,
    pub inputs: Inputs,
    pub aux: Aux,
    pub led: PC13<Output>,
    /// USART1 TX/RX.
    pub usart_pins: (PA9, PA10),
}

/// The Black Pill's map (see `blackpill.rs`), with USART1 in place of USB.
pub fn split(
    gpioa: gpioa::Parts,
    gpiob: gpiob::Parts,
    gpioc: gpioc::Parts,
    tim1: pac::TIM1,
    rcc: &mut Rcc,
) -> Board {
    let _ = (
        gpiob.pb12.into_push_pull_output(),
        gpiob.pb13.into_push_pull_output(),
        gpiob.pb14.into_push_pull_output(),
        gpiob.pb15.into_push_pull_output(),
        gpiob.pb4.into_push_pull_output(),
        gpiob.pb5.into_push_pull_output(),
        gpiob.pb6.into_push_pull_output(),
        gpiob.pb7.into_push_pull_output(),
        gpiob.pb8.into_push_pull_output_in_state(PinState::High),
    );
    // SAFETY: only forms the address of GPIOB's BSRR from the PAC's fixed
    // base pointer; no register is accessed here.
    let bsrr = unsafe { (*pac::GPIOB::ptr()).bsrr().as_ptr() };
    let mut steppers = StepPort::new(bsrr, PORT_PINS);
    steppers.set_enabled(false);

    let inputs = Inputs {
        limit_x: gpioa.pa4.into_pull_up_input(),
        limit_y: gpioa.pa5.into_pull_up_input(),
        limit_z: gpioa.pa6.into_pull_up_input(),
        probe: gpioa.pa3.into_pull_up_input(),
        feed_hold: gpioa.pa1.into_pull_up_input(),
        cycle_start: gpioa.pa0.into_pull_up_input(),
        estop: gpioa.pa2.into_pull_up_input(),
    };

    let (_, (ch1, ..)) = tim1.pwm_hz(SPINDLE_PWM_HZ.Hz(), rcc);
    let mut spindle_pwm = ch1.with(gpioa.pa8);
    spindle_pwm.set_duty(0);
    spindle_pwm.enable();
    let mut aux = Aux {
        spindle_pwm,
        spindle_enable: gpiob.pb0.into_push_pull_output(),
        spindle_dir: gpiob.pb1.into_push_pull_output(),
        flood: gpiob.pb9.into_push_pull_output(),
        mist: gpiob.pb10.into_push_pull_output(),
    };
    aux.all_off();

    Board {
        steppers,
        inputs,
        aux,
        led: gpioc.pc13.into_push_pull_output(),
        usart_pins: (gpioa.pa9, gpioa.pa10),
    }
}

/// The regulator as the clocks need it: nothing to do (QEMU models no regulator).
pub fn regulator(_pwr: &stm32f4xx_hal::pac::PWR, _rcc: &stm32f4xx_hal::pac::RCC) {}
