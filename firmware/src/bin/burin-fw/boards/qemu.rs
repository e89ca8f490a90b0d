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
use super::blackpill::PORT_PINS;
use super::usart::{UsartLink, BAUD};
use super::Periph;
use crate::step::{StepHw, StepPort, Tim5};
use burin::link::RxToken;
use burin::persist::{FlashMap, RamFlash};
use burin::seams::StepPins;
use cortex_m::peripheral::{DCB, DWT};
use heapless::spsc::{Consumer, Producer};
use stm32f4xx_hal::{
    gpio::{gpioa, gpiob, gpioc, Output, PA10, PA9, PC13},
    pac,
    prelude::*,
    rcc::{Clocks, Config, Rcc},
};

pub use super::blackpill::{
    enable_pin, kill_aux, outputs_off, outputs_off_word, stop_step_timer, Aux, Idle, Inputs,
};
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
    pub link_pins: (PA9, PA10),
}

/// The Black Pill's map (see `blackpill.rs`), with USART1 in place of USB;
/// the motion pins get their idle levels before they become outputs, as
/// there (QEMU's GPIO is unimplemented: `cargo xtask qemu` checks the
/// order of the stores in QEMU's log of them).
pub fn split(
    gpioa: gpioa::Parts,
    gpiob: gpiob::Parts,
    gpioc: gpioc::Parts,
    tim1: pac::TIM1,
    rcc: &mut Rcc,
    idle: Idle,
) -> Board {
    let _ = (
        gpiob.pb12.into_push_pull_output_in_state(idle.step(0)),
        gpiob.pb13.into_push_pull_output_in_state(idle.step(1)),
        gpiob.pb14.into_push_pull_output_in_state(idle.step(2)),
        gpiob.pb15.into_push_pull_output_in_state(idle.step(3)),
        gpiob.pb4.into_push_pull_output_in_state(idle.dir(0)),
        gpiob.pb5.into_push_pull_output_in_state(idle.dir(1)),
        gpiob.pb6.into_push_pull_output_in_state(idle.dir(2)),
        gpiob.pb7.into_push_pull_output_in_state(idle.dir(3)),
        gpiob.pb3.into_push_pull_output_in_state(idle.step(4)),
        gpiob.pb10.into_push_pull_output_in_state(idle.step(5)),
        gpiob.pb1.into_push_pull_output_in_state(idle.dir(4)),
        gpiob.pb9.into_push_pull_output_in_state(idle.dir(5)),
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
        // PA9 is the link's TX here: mist on a pin the F405 has spare
        // (QEMU models no GPIO; the fault path's PA7/PA9 store stands for it).
        mist: gpioc.pc6.into_push_pull_output().erase(),
    };
    aux.all_off();

    Board {
        steppers,
        inputs,
        aux,
        led: gpioc.pc13.into_push_pull_output(),
        link_pins: (gpioa.pa9, gpioa.pa10),
    }
}

/// Clocks: HSI only (QEMU models no regulator, and its RCC never reports
/// a clock ready).
pub fn start_clocks(rcc: pac::RCC, _pwr: &pac::PWR, gpioc: pac::GPIOC) -> (Rcc, pac::GPIOC) {
    (rcc.freeze(clocks()), gpioc)
}

/// The settings map's pages: two 4 KiB pages of RAM, the map's code path
/// (`storage.rs` on the boards) without persistence: nothing survives a
/// restart of QEMU.
pub type StoreMem = RamFlash<8192, 4096>;
/// The pages stay in init's static, lent to the map: held by value they
/// were 8 KB that init and the session moved on the stack, which the
/// board's flash handle is not.
pub type Store = FlashMap<&'static mut StoreMem>;

/// Settings in RAM: the flash controller stays unused (QEMU ignores it).
pub fn open_store(_flash: pac::FLASH, mem: &'static mut StoreMem) -> Store {
    FlashMap::new(mem)
}

/// The host link: USART1 (`usart.rs`), the machine's first `-serial`.
pub type Link = UsartLink;
/// The link's interrupt, pended by `parse` after it queues a reply.
pub const LINK_IRQ: pac::Interrupt = super::usart::IRQ;
/// USART1's registers.
pub type LinkHw = pac::USART1;

/// The peripherals init hands out, the link's being USART1.
pub fn take(dp: pac::Peripherals) -> Periph<LinkHw> {
    take_periph!(dp, dp.USART1)
}

/// The USART link needs no static of init's.
pub struct LinkMem;

impl LinkMem {
    pub const fn new() -> Self {
        LinkMem
    }
}

/// USART1 at `BAUD` 8N1. Early in init: QEMU drops what the host sends
/// before UE is set. No serial number: "-".
pub fn open_link(
    hw: LinkHw,
    pins: (PA9, PA10),
    rcc: &mut Rcc,
    _mem: &'static mut LinkMem,
    rx: Producer<'static, RxToken>,
    tx: Consumer<'static, u8>,
) -> (Link, &'static str) {
    match hw.serial(pins, BAUD.bps(), rcc) {
        Ok(serial) => (Link::new(serial, rx, tx), "-"),
        Err(_) => defmt::panic!("USART1 cannot run at {} baud", BAUD),
    }
}

/// A USART has no port to open or close.
pub fn port_events() -> (bool, bool) {
    (false, false)
}

/// The step hardware: pins and TIM5 alone (QEMU's timer model has neither
/// compare channels nor DMA, so the step interrupt ends the pulses).
pub fn step_hw(port: StepPort, timer: Tim5, _dma2: pac::DMA2, _rcc: &mut Rcc) -> StepHw {
    StepHw { port, timer }
}

/// No boot checks: QEMU's clocks and timers are not the chip's.
pub fn self_check(_: &mut DCB, _: &mut DWT, _: &Clocks) {}

/// Fault drills (QEMU only): `cargo xtask qemu` sets this word with QEMU's
/// generic loader (`-device loader,addr=...,data=...`) to make the app
/// fault on purpose once `parse` runs; 0 (QEMU's RAM at reset) runs the
/// app normally. The address is outside the linker's RAM (memory-f405.x
/// leaves the top 4 KiB of SRAM out).
const DRILL_ADDR: usize = 0x2001_FFFC;
/// `panic!`, `udf` (a HardFault), or a recursion that overflows the stack.
const DRILL_PANIC: u32 = 0xFA17_0001;
const DRILL_HARD_FAULT: u32 = 0xFA17_0002;
const DRILL_OVERFLOW: u32 = 0xFA17_0003;

/// Runs the drill the loader asked for, if any (see [`DRILL_ADDR`]).
pub fn fault_drill() {
    // SAFETY: a word of SRAM that no Rust object occupies (see DRILL_ADDR).
    let word = unsafe { (DRILL_ADDR as *const u32).read_volatile() };
    match word {
        DRILL_PANIC => panic!("fault drill"),
        DRILL_HARD_FAULT => cortex_m::asm::udf(),
        DRILL_OVERFLOW => {
            let _ = overflow(0);
        }
        _ => {}
    }
}

/// Recurses with a 512-byte frame until the stack runs off SRAM.
#[inline(never)]
fn overflow(depth: u32) -> u32 {
    let mut frame = [0u8; 512];
    frame[depth as usize % 512] = depth as u8;
    core::hint::black_box(&mut frame);
    if depth < u32::MAX {
        overflow(depth + 1).wrapping_add(u32::from(frame[7]))
    } else {
        0
    }
}

/// The end of the fault path on QEMU, after the outputs and the step timer
/// are off: one line on USART1 (plain register polling) for `cargo xtask
/// qemu`: the stack pointer the fault came with, CFSR and BFAR (why), and
/// TIM5's CR1 and DIER (stopped?).
pub fn report_fault(sp: u32) {
    // SAFETY: reads of the fault status registers (SCB 0xE000_ED28 CFSR,
    // 0xE000_ED38 BFAR) and of TIM5; USART1 is the QEMU link, polled here
    // with interrupts masked, so nothing else drives it.
    unsafe {
        let cfsr = (0xE000_ED28 as *const u32).read_volatile();
        let bfar = (0xE000_ED38 as *const u32).read_volatile();
        let tim5 = &*pac::TIM5::ptr();
        let (cr1, dier) = (tim5.cr1().read().bits(), tim5.dier().read().bits());
        let usart = &*pac::USART1::ptr();
        let mut put = |b: u8| {
            while usart.sr().read().txe().bit_is_clear() {}
            usart.dr().write(|w| w.dr().bits(u16::from(b)));
        };
        for (name, value) in [
            ("\r\nFAULT sp=", sp),
            (" cfsr=", cfsr),
            (" bfar=", bfar),
            (" tim5_cr1=", cr1),
            (" tim5_dier=", dier),
        ] {
            name.bytes().for_each(&mut put);
            for shift in (0..8).rev() {
                put(b"0123456789abcdef"[(value >> (shift * 4)) as usize & 0xF]);
            }
        }
        b"\r\n".iter().for_each(|&b| put(b));
    }
}

/// Stored-settings stand-in for the drills: `cargo xtask qemu` boots them
/// with `$2`/`$3`/`$4` set (0x5E77 in the top half, then `$2` in bits 0-3,
/// `$3` in 4-7, `$4` in bit 8), as if the store held them, to check the
/// motion pins' levels from the first store on. Beside [`DRILL_ADDR`].
const BOOT_ADDR: usize = 0x2001_FFF8;

/// Applies the drill's stored inverts to `s`, if the loader set any.
pub fn boot_overrides(s: &mut burin::settings::Settings) {
    // SAFETY: a word of SRAM that no Rust object occupies (see DRILL_ADDR).
    let word = unsafe { (BOOT_ADDR as *const u32).read_volatile() };
    if word >> 16 == 0x5E77 {
        s.step_invert = (word & 0xF) as u8;
        s.dir_invert = ((word >> 4) & 0xF) as u8;
        s.enable_invert = word & (1 << 8) != 0;
    }
}
