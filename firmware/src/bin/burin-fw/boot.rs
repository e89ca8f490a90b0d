//! `init`'s steps (`burin-fw.rs`), in the order it calls them. Each leaves
//! the outputs in their safe state (off, drivers disabled); the interrupts
//! stay masked until init returns. What differs per board is behind
//! `board::…` (`boards/mod.rs`).
use crate::boards::board;
use crate::outputs::Io;
use crate::step::{StepTask, Tim5};
use burin::controller::Controller;
use burin::inputs::{self as inp, Debounce};
use burin::persist::{Loaded, Persist};
use burin::session::{Device, Identity};
use burin::settings::Settings;
use burin::stepper::{Segment, Stepper};
use core::mem::MaybeUninit;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use heapless::spsc::Consumer;
use stm32f4xx_hal::{pac, prelude::*, rcc::Rcc, syscfg::SysCfgExt, watchdog::IndependentWatchdog};

type Store = board::Store;

/// SysTick rate; the watchdog timeout must be several of these periods.
pub const HEARTBEAT_HZ: u32 = 100;
/// Watchdog timeout, counted on the nominal 32 kHz LSI. Idle feeds it at
/// least every heartbeat (10 ms), but not while a settings write erases
/// flash with the CPU stalled: a migration erases both 16 KiB sectors back
/// to back, up to 0.8 s each (1.6 s). The LSI may run at 47 kHz (datasheet
/// maximum), which makes 4 s nominal at least 2.7 s real.
const WATCHDOG_MS: u32 = 4000;

/// Keeps the debug probe (RTT logs) working through WFI, and stops the
/// watchdog while the core is halted at a breakpoint. The watchdog is
/// started last (`start_watchdog`).
pub fn debug_and_watchdog(dbgmcu: &pac::DBGMCU, iwdg: pac::IWDG) -> IndependentWatchdog {
    dbgmcu.cr().modify(|_, w| w.dbg_sleep().set_bit());
    let watchdog = IndependentWatchdog::new(iwdg);
    watchdog.stop_on_debug(dbgmcu, true);
    watchdog
}

/// Settings and offsets from the store (flash sectors 1-2; RAM on QEMU,
/// see storage.rs), first: the pins' idle levels depend on them, and so
/// does the fault path's enable word.
pub fn load_settings(store: Store) -> (Persist<Store>, Loaded) {
    let mut persist = Persist::new(store, Settings::default());
    let mut boot = persist.load();
    if !boot.report.is_clean() {
        defmt::warn!(
            "settings: {} items defaulted, storage error: {}",
            boot.report.defaulted,
            boot.report.failed
        );
    }
    board::boot_overrides(&mut boot.settings);
    crate::fault::publish(boot.settings.enable_invert);
    (persist, boot)
}

/// Pins: the board's map, everything in its safe state (outputs off,
/// drivers disabled): the step/dir/enable pins at their idle levels under
/// the stored `$2`/`$3`/`$4` from the store that makes them outputs
/// (`board::split`); `set_invert` keeps them there.
pub fn pins(
    gpio: (pac::GPIOA, pac::GPIOB, pac::GPIOC),
    tim1: pac::TIM1,
    rcc: &mut Rcc,
    settings: &Settings,
) -> board::Board {
    let gpioa = gpio.0.split(rcc);
    let gpiob = gpio.1.split(rcc);
    let gpioc = gpio.2.split(rcc);
    let idle = board::Idle {
        step_invert: settings.step_invert,
        dir_invert: settings.dir_invert,
        enable_active_high: settings.enable_invert,
    };
    let mut pins = board::split(gpioa, gpiob, gpioc, tim1, rcc, idle);
    pins.steppers.set_invert(
        settings.step_invert,
        settings.dir_invert,
        settings.enable_invert,
    );
    pins.aux.all_off();
    pins
}

/// The step task: TIM5 free-running, the board's pulse end and boot
/// checks, the stepper on the stored pin timing, the step port with the
/// same inverts. The timer stays stopped until `parse` queues segments.
/// Returns the task and the step timer's tick rate.
pub fn step_task(
    (tim5, dma2, port): (pac::TIM5, pac::DMA2, crate::step::StepPort),
    core: &mut cortex_m::Peripherals,
    rcc: &mut Rcc,
    settings: &Settings,
    segments: Consumer<'static, Segment>,
) -> (StepTask, u32) {
    let timer = Tim5::new(tim5, rcc);
    let tick_hz = burin::seams::StepTimer::tick_hz(&timer);
    let hw = board::step_hw(port, timer, dma2, rcc);
    board::self_check(&mut core.DCB, &mut core.DWT, &rcc.clocks);
    let cfg = burin::stepper::StepConfig::new(settings, tick_hz);
    (StepTask::new(hw, Stepper::new(cfg), segments), tick_hz)
}

/// Outputs: spindle, coolant, and the enable pin for the idle timer (same
/// `$4` polarity as the step port; both follow a `$4=` at once, the step
/// port in the step interrupt, this one in `Io::write`).
pub fn outputs(aux: board::Aux, settings: &Settings) -> Io {
    Io::new(aux, board::enable_pin(settings.enable_invert))
}

/// Inputs: EXTI on both edges; the levels at power-up count as settled,
/// and an e-stop already pressed latches the alarm too.
pub fn inputs(
    mut inputs: board::Inputs,
    syscfg: pac::SYSCFG,
    mut exti: pac::EXTI,
    rcc: &mut Rcc,
    settings: &Settings,
) -> Debounce {
    crate::inputs::publish(settings);
    let mut syscfg = syscfg.constrain(rcc);
    board::enable_exti(&mut inputs, &mut syscfg, &mut exti);
    let debounce = Debounce::new(crate::inputs::SETTLE_MS, crate::inputs::active_now());
    crate::RT.set_estop(debounce.stable() & inp::ESTOP != 0);
    debounce
}

/// SysTick at [`HEARTBEAT_HZ`] from the core clock `sysclk`.
pub fn start_heartbeat(syst: &mut SYST, sysclk: u32) {
    syst.set_clock_source(SystClkSource::Core);
    // The reload register has 24 bits (16.7 M cycles, 0.17 s at 96 MHz).
    syst.set_reload((sysclk / HEARTBEAT_HZ - 1).min(0x00FF_FFFF));
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// The session and controller on the loaded settings (it tells the boot
/// report after the banner), built straight into its static slot in a
/// frame of its own.
#[inline(never)]
pub fn build_controller(
    slot: &'static mut MaybeUninit<Controller<Store>>,
    persist: Persist<Store>,
    boot: &Loaded,
) -> &'static mut Controller<Store> {
    let identity = Identity {
        board: board::NAME,
        caps: 0,
    };
    // One expression, both constructors inlined: the session (with the
    // O-word stage's 2 KiB capture buffer) is built in the slot, not
    // built on the stack and copied there.
    slot.write(Controller::new(
        Device::with_storage(identity, persist, Some(boot)),
        &boot.settings,
        crate::outputs::WAKE_MS,
    ))
}

/// The watchdog, last, so the slow setup before it cannot trip it; then
/// the boot line in the log.
pub fn start_watchdog(
    mut watchdog: IndependentWatchdog,
    sysclk: u32,
    serial: &str,
) -> IndependentWatchdog {
    watchdog.start(WATCHDOG_MS.millis());
    defmt::info!(
        "burin {} on {} at {} Hz, USB serial {}",
        burin::VERSION,
        board::NAME,
        sysclk,
        serial
    );
    watchdog
}
