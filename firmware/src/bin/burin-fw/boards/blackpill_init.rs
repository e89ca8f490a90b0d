//! The Black Pills' side of the board interface (`mod.rs`) beyond the pin
//! map: the clock tree from a known state, the settings store on flash,
//! the USB-CDC link, the pulse-end DMA and the boot checks. The chip's own
//! constants (`clocks`, `regulator`, `CHIP`) come from `f411.rs` or
//! `f401.rs`, whichever is `board`.
use super::blackpill::{blink_no_crystal, start_hse};
use super::board::{clocks, regulator, CHIP};
use super::pulse_end::PulseEnd;
use super::usb::{UsbLink, BACKLOG, PORT_CLOSED, PORT_OPENED};
use super::Periph;
use crate::step::{StepHw, StepPort, Tim5};
use burin::link::{RxBacklog, RxToken};
use burin::seams::StepTimer;
use core::sync::atomic::Ordering;
use cortex_m::peripheral::{DCB, DWT};
use heapless::spsc::{Consumer, Producer};
use protocol::usb_ids::{serial_from_uid, USB_SERIAL_LEN};
use stm32f4xx_hal::gpio::{PA11, PA12};
use stm32f4xx_hal::otg_fs::{UsbBus, UsbBusType, USB};
use stm32f4xx_hal::rcc::{Clocks, Rcc};
use stm32f4xx_hal::{pac, prelude::*};
use usb_device::bus::UsbBusAllocator;

/// The host link: USB-CDC on OTG_FS (`usb.rs`).
pub type Link = UsbLink;
/// The link's interrupt, pended by `parse` after it queues a reply.
pub const LINK_IRQ: pac::Interrupt = pac::Interrupt::OTG_FS;
/// The OTG_FS peripheral's three register blocks.
pub type LinkHw = (pac::OTG_FS_GLOBAL, pac::OTG_FS_DEVICE, pac::OTG_FS_PWRCLK);

/// The peripherals init hands out, the link's being OTG_FS.
pub fn take(dp: pac::Peripherals) -> Periph<LinkHw> {
    take_periph!(dp, (dp.OTG_FS_GLOBAL, dp.OTG_FS_DEVICE, dp.OTG_FS_PWRCLK))
}

/// Clocks: HSE + PLL as the chip file says (96 MHz on the F411), from the
/// reset state (a DFU `:leave` jumps here with the ROM bootloader's PLL
/// still running), after the regulator scale they need (set while the PLL
/// is off). A dead crystal never returns: the LED blinks on HSI.
pub fn start_clocks(rcc: pac::RCC, pwr: &pac::PWR, gpioc: pac::GPIOC) -> (Rcc, pac::GPIOC) {
    clocks_to_reset_state(&rcc);
    regulator(pwr, &rcc);
    if !start_hse(&rcc) {
        defmt::error!("the 25 MHz crystal did not start: blinking the LED on HSI");
        blink_no_crystal(rcc, gpioc);
    }
    let rcc = rcc.freeze(clocks());
    if !rcc.clocks.is_pll48clk_valid() {
        defmt::error!("USB clock is not 48 MHz: the port will not enumerate");
    }
    (rcc, gpioc)
}

/// HSI as the system clock and the PLL off, as after a reset (where
/// this changes nothing). The HAL's clock setup writes PLLCFGR, which
/// the chip ignores while the PLL runs, and the ROM bootloader that a
/// DFU `:leave` comes from leaves its PLL on. HSI is the reset clock, so
/// the waits end within its start-up time. (Not on QEMU: its RCC model
/// never reports a clock ready, and nothing runs before the app there.)
fn clocks_to_reset_state(rcc: &pac::RCC) {
    rcc.cr().modify(|_, w| w.hsion().set_bit());
    while rcc.cr().read().hsirdy().bit_is_clear() {}
    rcc.cfgr().modify(|_, w| w.sw().hsi());
    while !rcc.cfgr().read().sws().is_hsi() {}
    rcc.cr().modify(|_, w| w.pllon().clear_bit());
    while rcc.cr().read().pllrdy().bit_is_set() {}
}

/// The flash store needs no RAM of init's (QEMU's keeps its pages there).
pub struct StoreMem;

impl StoreMem {
    pub const fn new() -> Self {
        StoreMem
    }
}

/// Settings on flash sectors 1-2 (`storage.rs`).
pub use super::storage::Store;

/// Opens the settings store on flash (`storage.rs`).
pub fn open_store(flash: pac::FLASH, _mem: &'static mut StoreMem) -> Store {
    super::storage::open(flash)
}

/// What the store holds is what boots (QEMU's drills override it).
pub fn boot_overrides(_: &mut burin::settings::Settings) {}

/// init's statics the USB link lives on.
pub struct LinkMem {
    ep_memory: [u32; 1024],
    usb_bus: Option<UsbBusAllocator<UsbBusType>>,
    serial: [u8; USB_SERIAL_LEN],
    backlog: RxBacklog<BACKLOG>,
}

impl LinkMem {
    pub const fn new() -> Self {
        LinkMem {
            ep_memory: [0; 1024],
            usb_bus: None,
            serial: [0; USB_SERIAL_LEN],
            backlog: RxBacklog::new(),
        }
    }
}

/// USB: serial number from the 96-bit unique ID, then the CDC port.
/// Returns the link and the serial number.
pub fn open_link(
    hw: LinkHw,
    pins: (PA11, PA12),
    rcc: &mut Rcc,
    mem: &'static mut LinkMem,
    rx: Producer<'static, RxToken>,
    tx: Consumer<'static, u8>,
) -> (Link, &'static str) {
    let LinkMem {
        ep_memory,
        usb_bus,
        serial,
        backlog,
    } = mem;
    let serial = serial_from_uid(read_uid(), serial);
    let usb = USB::new(hw, pins, &rcc.clocks);
    let bus = &*usb_bus.insert(UsbBus::new(usb, ep_memory));
    (Link::new(bus, serial, rx, tx, backlog), serial)
}

/// The chip's 96-bit unique ID, lowest address first.
fn read_uid() -> [u32; 3] {
    const UID: *const u32 = 0x1FFF_7A10 as *const u32;
    // SAFETY: 0x1FFF_7A10..0x1FFF_7A1C is the factory-programmed,
    // always-readable unique device ID of every STM32F4 (RM0383 §24.1).
    unsafe {
        [
            UID.read_volatile(),
            UID.add(1).read_volatile(),
            UID.add(2).read_volatile(),
        ]
    }
}

/// Port closed, port opened (USB interrupt to the parse task), each taken
/// once.
pub fn port_events() -> (bool, bool) {
    (
        PORT_CLOSED.swap(false, Ordering::AcqRel),
        PORT_OPENED.swap(false, Ordering::AcqRel),
    )
}

/// The step hardware: the pulses end by TIM1 compare 2 and DMA2, at the
/// idle levels `set_invert` chose; the path is checked against the chip's
/// bus matrix and by one zero-effect transfer.
pub fn step_hw(port: StepPort, timer: Tim5, dma2: pac::DMA2, rcc: &mut Rcc) -> StepHw {
    let (word, bsrr) = port.step_off_store();
    let tim1_clk = rcc.clocks.timclk2().raw();
    let tick_hz = timer.tick_hz();
    let (pulse, check) = PulseEnd::new(dma2, rcc, CHIP, bsrr, word, tim1_clk, tick_hz);
    if let Err(fault) = check {
        defmt::error!("boot check: {}", fault.message());
        crate::RT.set_hw_fault(fault);
    }
    StepHw { port, timer, pulse }
}

/// Boot checks of the clock tree and the timers (`selfcheck.rs`).
pub fn self_check(dcb: &mut DCB, dwt: &mut DWT, clocks: &Clocks) {
    super::selfcheck::clocks_and_timers(dcb, dwt, clocks, &crate::RT);
}

/// Fault drills are QEMU's alone.
pub fn fault_drill() {}

/// The fault path's report is QEMU's alone (a debug probe reads the
/// registers on a board).
#[inline(always)]
pub fn report_fault(_sp: u32) {}
