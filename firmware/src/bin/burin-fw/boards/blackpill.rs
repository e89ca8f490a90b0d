//! Pin map of the WeAct Black Pill (STM32F411CEU6 and STM32F401CCU6 share
//! the 48-pin package and the board), which the README's wiring table mirrors.
//!
//! | function | pin | why there |
//! |---|---|---|
//! | X/Y/Z/A/B/C step | PB12/PB13/PB14/PB15/PB3/PB10 | all motion outputs on port B: one BSRR write per event; X-A sit together on one header |
//! | X/Y/Z/A/B/C dir | PB4/PB5/PB6/PB7/PB1/PB9 | port B |
//! | stepper enable (all) | PB8 | port B, so enable also goes through the step port; active low |
//! | spindle PWM | PA8 | TIM1_CH1, an advanced timer free of the step timer |
//! | spindle enable | PB0 | plain output |
//! | spindle direction | PA15 | plain output (JTDI at reset, see below) |
//! | flood / mist coolant | PA7 / PA9 | plain outputs |
//! | cycle start | PA0 | the on-board KEY button is wired to it: the board has a start button for free |
//! | feed hold | PA1 | |
//! | reset / e-stop | PA2 | |
//! | probe | PA3 | |
//! | X/Y/Z limit | PA4/PA5/PA6 | |
//!
//! Inputs have pull-ups; a switch closes to GND (active low; `$5`/`$6`
//! invert). PA0–PA6 are EXTI lines 0–6, all distinct, and cycle start, feed
//! hold, e-stop, probe and X limit get dedicated vectors (EXTI0–EXTI4).
//!
//! Why six axes fit only this way: every step and dir pin must sit on one
//! port (a step event is one BSRR store of the step pins, a direction event
//! one store of the dir pins and the step-off levels), and so must the
//! enable (the fault path's store). Port B has 15 pins on this package
//! (PB0-PB10, PB12-PB15; PB11 is VCAP); six step/dir pairs and the enable
//! take 13, PB2 (BOOT1) stays alone, and PB0 is left: the spindle enable,
//! the one output the fault path must cut in the same store as the drivers.
//! Spindle direction, flood and mist go to port A's last free pins:
//! PA15 and PB3 are JTDI and JTDO, released to GPIO by writing MODER
//! (RM0383/RM0368 §8.3.2; SWD on PA13/PA14 keeps working): PA15 has JTDI's
//! pull-up until configured (high = CCW, harmless for a direction), PB3 is
//! tri-stated until then. PA9 is USART1 TX, which only the ROM bootloader
//! uses (it listens on PA10, which stays alone for DFU); PA7 is the last
//! EXTI-capable pin, so A, B and C have no limit input (rotary axes rarely
//! have one; `$206`'s homing cycles, a nibble each, cannot name B or C).
//!
//! Left alone on purpose: PA11/PA12 (USB), PA13/PA14 (SWD), PC13 (LED),
//! PC14/PC15 (32 kHz crystal; these pins may not source current anyway),
//! PB2 (BOOT1), PA10 (USART1 RX: it needs to stay low for USB DFU).
//! PB11 does not exist on this package.
use super::super::outputs::EnablePin;
use super::super::step::{PortPins, StepPort};
use burin::seams::StepPins;
use burin::stepper::Switches;
use stm32f4xx_hal::{
    gpio::{
        gpioa, gpiob, gpioc, AnyPin, Edge, ExtiPin, Input, Output, PinState, Speed, PA0, PA1, PA11,
        PA12, PA2, PA3, PA4, PA5, PA6, PB0, PC13,
    },
    pac,
    prelude::*,
    rcc::Rcc,
    syscfg::SysCfg,
    timer::PwmChannel,
};

/// Step, direction and enable pin numbers on port B, one step/dir pair per
/// axis (`burin::AXES` of them: a new axis count needs its pins here).
pub const PORT_PINS: PortPins = PortPins {
    step: [12, 13, 14, 15, 3, 10],
    dir: [4, 5, 6, 7, 1, 9],
    enable: 8,
};

const _: () = assert!(
    PORT_PINS.is_valid(),
    "step port pins must be distinct and < 16"
);

/// Spindle PWM carrier; the duty cycle carries the speed.
const SPINDLE_PWM_HZ: u32 = 1_000;

/// Switch inputs (raw pins; polarity is applied by the caller).
pub struct Inputs {
    pub limit_x: PA4<Input>,
    pub limit_y: PA5<Input>,
    pub limit_z: PA6<Input>,
    pub probe: PA3<Input>,
    pub feed_hold: PA1<Input>,
    pub cycle_start: PA0<Input>,
    pub estop: PA2<Input>,
}

impl Inputs {
    /// Routes PA0-PA6 to EXTI lines 0-6, both edges (a limit may be wired
    /// normally closed: `$5` decides which edge closes it). The NVIC
    /// vectors are unmasked by RTIC after init.
    pub fn enable_exti(&mut self, syscfg: &mut SysCfg, exti: &mut pac::EXTI) {
        macro_rules! line {
            ($($pin:ident),*) => {$(
                self.$pin.make_interrupt_source(syscfg);
                self.$pin.trigger_on_edge(exti, Edge::RisingFalling);
                self.$pin.clear_interrupt_pending_bit();
                self.$pin.enable_interrupt(exti);
            )*};
        }
        line!(
            limit_x,
            limit_y,
            limit_z,
            probe,
            feed_hold,
            cycle_start,
            estop
        );
    }
}

/// See [`Inputs::enable_exti`] (QEMU's board has no EXTI inputs).
pub fn enable_exti(inputs: &mut Inputs, syscfg: &mut SysCfg, exti: &mut pac::EXTI) {
    inputs.enable_exti(syscfg, exti);
}

/// Which inputs are pulled low (closed to GND) now, in one IDR read, as
/// `burin::inputs` bits: 0-2 X/Y/Z limit, 3 probe, 4 feed hold, 5 cycle
/// start, 6 reset/e-stop.
#[inline]
pub fn closed_now() -> u8 {
    // SAFETY: a single read of GPIOA's input data register, which has no
    // side effects; PA0..PA6 are inputs configured in `split`.
    let closed = !unsafe { (*pac::GPIOA::ptr()).idr().read().bits() };
    let bit = |pin: u32, to: u32| (((closed >> pin) & 1) << to) as u8;
    (((closed >> 4) & 0b111) as u8) | bit(3, 3) | bit(1, 4) | bit(0, 5) | bit(2, 6)
}

/// E-stop: spindle enable, PWM, flood and mist off in three stores, from
/// the e-stop interrupt, before the parse task hears of it.
pub fn kill_aux() {
    // SAFETY: BSRR is write-only set/reset: these stores only reset PB0
    // (spindle enable) and PA7/PA9 (flood, mist, see `Aux`) and touch no
    // other pin. CCR1 of TIM1 is the spindle PWM compare value; a single
    // store of 0 is the duty the parse task also writes for "off".
    unsafe {
        (*pac::GPIOB::ptr()).bsrr().write(|w| w.bits(AUX_OFF_B));
        (*pac::GPIOA::ptr()).bsrr().write(|w| w.bits(AUX_OFF_A));
        (*pac::TIM1::ptr()).ccr1().write(|w| w.bits(0));
    }
}

/// Spindle enable (PB0): the reset half of GPIOB's BSRR.
const AUX_OFF_B: u32 = 1 << 16;
/// Flood (PA7), mist (PA9): the reset half of GPIOA's BSRR. On QEMU's
/// board PA9 is USART1's TX in its alternate function, where ODR drives
/// nothing (RM0383 §8.3.7), so the same store is harmless there.
pub const AUX_OFF_A: u32 = (1 << (16 + 7)) | (1 << (16 + 9));

/// The fault path's GPIOB word: [`AUX_OFF_B`] and the stepper-enable pin
/// (PB8) at "drivers off" under `$4` (`enable_active_high`).
pub const fn outputs_off_word(enable_active_high: bool) -> u32 {
    let pin = PORT_PINS.enable as u32;
    AUX_OFF_B
        | if enable_active_high {
            1 << (pin + 16)
        } else {
            1 << pin
        }
}

/// TIM1_CCMR1 OC1M (bits 6:4): "force inactive" (0b100), RM0383 §12.4.7.
const OC1M_MASK: u32 = 0b111 << 4;
const OC1M_FORCE_INACTIVE: u32 = 0b100 << 4;

/// The fault path: spindle enable and drivers off in one GPIOB store
/// (`word` from [`outputs_off_word`]), coolant in one GPIOA store, then
/// the spindle/laser PWM forced low at once (CCR1 alone would wait for
/// the preloaded update). Register stores only: no HAL, nothing that can
/// fault on a sane chip.
#[inline(always)]
pub fn outputs_off(word: u32) {
    // SAFETY: BSRR is write-only set/reset; `word` names only PB0 and PB8
    // (`outputs_off_word`), `AUX_OFF_A` only PA7 and PA9. TIM1's CCR1 and
    // CCMR1 belong to the spindle PWM (channel 1); duty 0 and OC1M = force
    // inactive drive PA8 low now, whatever the preload holds. The RMW of
    // CCMR1 can race nothing: a fault runs with interrupts masked.
    unsafe {
        (*pac::GPIOB::ptr()).bsrr().write(|w| w.bits(word));
        (*pac::GPIOA::ptr()).bsrr().write(|w| w.bits(AUX_OFF_A));
        let tim1 = &*pac::TIM1::ptr();
        tim1.ccr1().write(|w| w.bits(0));
        tim1.ccmr1_output()
            .modify(|r, w| w.bits((r.bits() & !OC1M_MASK) | OC1M_FORCE_INACTIVE));
    }
}

/// The fault path, after [`outputs_off`]: no step interrupt, no counter
/// (so no compare event and no DMA request either).
#[inline(always)]
pub fn stop_step_timer() {
    // SAFETY: TIM5 is the step timer; DIER = 0 and CR1 = 0 stop its
    // interrupts and its counter. ICER is write-1-to-clear of TIM5's NVIC
    // line alone (IRQ 50: ICER1 bit 18).
    unsafe {
        let tim5 = &*pac::TIM5::ptr();
        tim5.dier().write(|w| w.bits(0));
        tim5.cr1().write(|w| w.bits(0));
        let irq = pac::Interrupt::TIM5 as u32;
        (*cortex_m::peripheral::NVIC::PTR).icer[(irq / 32) as usize].write(1 << (irq % 32));
    }
}

/// The stepper-enable pin on its own (PB8), for the idle-disable timer;
/// `active_high` is `$4` (default: active low).
pub fn enable_pin(active_high: bool) -> EnablePin {
    // SAFETY: only forms the address of GPIOB's BSRR from the PAC's fixed
    // base pointer; no register is accessed here.
    let bsrr = unsafe { (*pac::GPIOB::ptr()).bsrr().as_ptr() };
    EnablePin::new(bsrr, PORT_PINS.enable, active_high)
}

/// Limit and probe levels for the step interrupt, in one IDR read: bit set
/// = switch closed (pin low). `$5`/`$6` invert in the stepper.
#[inline(always)]
pub fn switches() -> Switches {
    // SAFETY: a single read of GPIOA's input data register, which has no
    // side effects; PA3..PA6 are inputs configured in `split`.
    let idr = unsafe { (*pac::GPIOA::ptr()).idr().read().bits() };
    let closed = !idr;
    Switches {
        limits: ((closed >> 4) & 0b111) as u8,
        probe: closed & (1 << 3) != 0,
    }
}

/// Spindle and coolant outputs. Direction and coolant are type-erased:
/// QEMU's board (`qemu.rs`) has USART1 on PA9 and puts mist elsewhere.
pub struct Aux {
    pub spindle_pwm: PwmChannel<pac::TIM1, 0>,
    pub spindle_enable: PB0<Output>,
    pub spindle_dir: AnyPin<Output>,
    pub flood: AnyPin<Output>,
    pub mist: AnyPin<Output>,
}

impl Aux {
    /// Spindle stopped, coolant off: the state after reset and after an alarm.
    pub fn all_off(&mut self) {
        self.spindle_pwm.set_duty(0);
        self.spindle_enable.set_low();
        self.spindle_dir.set_low();
        self.flood.set_low();
        self.mist.set_low();
    }
}

pub struct Board {
    pub steppers: StepPort,
    pub inputs: Inputs,
    pub aux: Aux,
    pub led: PC13<Output>,
    /// USB (OTG_FS DM/DP).
    pub link_pins: (PA11, PA12),
}

/// Idle levels of the motion outputs under the stored `$2`, `$3`, `$4`,
/// known before any of them becomes an output.
#[derive(Clone, Copy)]
pub struct Idle {
    /// `$2`: bit n set = axis n's step pin rests high.
    pub step_invert: u8,
    /// `$3`: bit n set = axis n's "positive" direction is high.
    pub dir_invert: u8,
    /// `$4`: drivers enabled by a high level (rest low); default low-active.
    pub enable_active_high: bool,
}

impl Idle {
    pub fn step(self, axis: u8) -> PinState {
        bit(self.step_invert, axis)
    }
    pub fn dir(self, axis: u8) -> PinState {
        bit(self.dir_invert, axis)
    }
    pub fn enable_off(self) -> PinState {
        level(!self.enable_active_high)
    }
}

fn bit(mask: u8, axis: u8) -> PinState {
    level(mask & (1 << axis) != 0)
}

fn level(high: bool) -> PinState {
    if high {
        PinState::High
    } else {
        PinState::Low
    }
}

/// Configures every pin of the map and hands them out grouped by user.
/// The step, direction and enable pins get their idle level (`idle`) in
/// ODR before MODER makes them outputs (`into_push_pull_output_in_state`
/// writes BSRR first): with `$2` a step pin never passes through low, a
/// rising edge a driver would count, and with `$4=1` the drivers are
/// never enabled for the cycles between the switch and the first store.
pub fn split(
    gpioa: gpioa::Parts,
    gpiob: gpiob::Parts,
    gpioc: gpioc::Parts,
    tim1: pac::TIM1,
    rcc: &mut Rcc,
    idle: Idle,
) -> Board {
    // Motion outputs: configured here, then driven only through StepPort's
    // BSRR writes. The typed pins are dropped on purpose: nothing else can
    // obtain them again, so StepPort has the port bits to itself.
    let _ = (
        gpiob
            .pb12
            .into_push_pull_output_in_state(idle.step(0))
            .speed(Speed::Medium),
        gpiob
            .pb13
            .into_push_pull_output_in_state(idle.step(1))
            .speed(Speed::Medium),
        gpiob
            .pb14
            .into_push_pull_output_in_state(idle.step(2))
            .speed(Speed::Medium),
        gpiob
            .pb15
            .into_push_pull_output_in_state(idle.step(3))
            .speed(Speed::Medium),
        gpiob
            .pb4
            .into_push_pull_output_in_state(idle.dir(0))
            .speed(Speed::Medium),
        gpiob
            .pb5
            .into_push_pull_output_in_state(idle.dir(1))
            .speed(Speed::Medium),
        gpiob
            .pb6
            .into_push_pull_output_in_state(idle.dir(2))
            .speed(Speed::Medium),
        gpiob
            .pb7
            .into_push_pull_output_in_state(idle.dir(3))
            .speed(Speed::Medium),
        gpiob
            .pb3
            .into_push_pull_output_in_state(idle.step(4))
            .speed(Speed::Medium),
        gpiob
            .pb10
            .into_push_pull_output_in_state(idle.step(5))
            .speed(Speed::Medium),
        gpiob
            .pb1
            .into_push_pull_output_in_state(idle.dir(4))
            .speed(Speed::Medium),
        gpiob
            .pb9
            .into_push_pull_output_in_state(idle.dir(5))
            .speed(Speed::Medium),
        gpiob.pb8.into_push_pull_output_in_state(idle.enable_off()),
    );
    // SAFETY: only forms the address of GPIOB's BSRR from the PAC's fixed
    // base pointer; no register is accessed here.
    let bsrr = unsafe { (*pac::GPIOB::ptr()).bsrr().as_ptr() };
    let mut steppers = StepPort::new(
        bsrr,
        PORT_PINS,
        idle.step_invert,
        idle.dir_invert,
        idle.enable_active_high,
    );
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
        spindle_dir: gpioa.pa15.into_push_pull_output().erase(),
        flood: gpioa.pa7.into_push_pull_output().erase(),
        mist: gpioa.pa9.into_push_pull_output().erase(),
    };
    aux.all_off();

    Board {
        steppers,
        inputs,
        aux,
        led: gpioc.pc13.into_push_pull_output(),
        link_pins: (gpioa.pa11, gpioa.pa12),
    }
}

/// Polls of `HSERDY` before the crystal counts as dead: about 100 ms on
/// the 16 MHz HSI (a poll is a few cycles), 50 times the 2 ms start-up
/// the datasheets give for a 25 MHz crystal.
const HSE_POLLS: u32 = 400_000;

/// Starts the 25 MHz crystal with a time limit (the HAL's clock setup
/// waits for it forever); false if it never became ready.
pub fn start_hse(rcc: &pac::RCC) -> bool {
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    (0..HSE_POLLS).any(|_| rcc.cr().read().hserdy().bit_is_set())
}

/// No crystal: run on the internal HSI and blink the LED (PC13) at 4 Hz
/// for good, instead of hanging dark. The watchdog is not started yet, so
/// this is what the board shows until it is power-cycled or reflashed.
pub fn blink_no_crystal(rcc: pac::RCC, gpioc: pac::GPIOC) -> ! {
    let mut rcc = rcc.freeze(stm32f4xx_hal::rcc::Config::hsi());
    let mut led = gpioc.split(&mut rcc).pc13.into_push_pull_output();
    let eighth_s = rcc.clocks.sysclk().raw() / 8;
    loop {
        led.toggle();
        cortex_m::asm::delay(eighth_s);
    }
}
