//! burin's RTIC app (built only for thumbv7em-none-eabihf): the tasks,
//! their priorities and what each owns. The work is elsewhere: the motion
//! core in the `burin` library, init's steps in `burin-fw/boot.rs`, the
//! parse task's pass in `pass.rs`, and whatever differs per board behind
//! `board::…` (`burin-fw/boards/`, one module per board).
//!
//! Priorities, highest first (DESIGN.md, Priorities, has the table):
//! 4. the limit and e-stop edges (`limit_x`, `limit_yz`, `estop`) act on
//!    the first edge, even while the step interrupt runs: acting late is
//!    the one thing these must not do. They run once per switch change (the
//!    line is masked until the contact settles), so the step timing pays
//!    nothing in normal running; the step interrupt's own IDR read at every
//!    event remains the guarantee that a closed limit stops pulses within
//!    one step event;
//! 3. `step` (TIM5): the core's step driver on the segment queue;
//! 2. the link (`usb`, or `usart` on QEMU) and the buttons' and probe's
//!    edges (`cycle_start`, `feed_hold`, `probe`);
//! 1. `parse` (async: session, planner, segment preparer, outputs), woken
//!    by the other tasks, and `heartbeat` (SysTick, 100 Hz: LED, input
//!    debounce, the clock of the stepper idle-disable timer).
//!
//! `idle` feeds the watchdog and sleeps. It runs only when every task is
//! done, so a task that hogs the CPU starves the watchdog and the chip resets.
//! No RTIC resource is shared between priorities (the link's, shared by
//! `usb` and `usart`, has one priority and no lock): every task owns its
//! state and the tasks meet only in lock-free spsc rings and atomic
//! statics, so nothing a higher task needs is ever behind a lower task's
//! lock. Those statics: `RT` and `FLAGS` here; `EDGES`, `INVERT`, `PINS`
//! and `NOW_MS` (inputs.rs: the input interrupts, the heartbeat and the
//! parse task); `PORT_OPENED` and `PORT_CLOSED` (usb.rs: USB interrupt to
//! parse task); `OFF_WORD` (fault.rs: the parse task's `$4` for the fault
//! handler) and `STEP_OFF` (pulse_end.rs: the step-off word DMA2 copies).
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(unsafe_op_in_unsafe_fn)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("burin-fw is firmware: build it with `cargo xtask build`");
}

// The app's modules, in `burin-fw/` beside this file (`fw` only gathers
// them under one cfg; `use fw::*` names them `crate::boot` and so on).
#[cfg(target_os = "none")]
#[path = "burin-fw"]
mod fw {
    pub mod boards;
    pub mod boot;
    pub mod fault;
    pub mod inputs;
    pub mod outputs;
    pub mod pass;
    pub mod rings;
    pub mod step;
}
#[cfg(target_os = "none")]
use fw::*;

#[cfg(target_os = "none")]
use defmt_rtt as _;

/// Realtime state shared by every priority (atomics only).
#[cfg(target_os = "none")]
static RT: burin::realtime::Realtime = burin::realtime::Realtime::new();
/// Realtime commands the link interrupt picked out of the byte stream.
#[cfg(target_os = "none")]
static FLAGS: burin::link::RtFlags = burin::link::RtFlags::new();

// USART6 is only a dispatcher: its pins (PA11/PA12) carry USB on this board.
#[cfg(target_os = "none")]
#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [USART6])]
mod app {
    use crate::boards::board;
    use crate::boot::{self as steps, HEARTBEAT_HZ};
    use crate::pass::{parse, Parse};
    use crate::rings::{PLANNER_BLOCKS, SEGMENT_SLOTS, TX_RING};
    use crate::step::StepTask;
    use burin::controller::Controller;
    use burin::executor::Machine;
    use burin::inputs::{self as inp, Debounce};
    use burin::link::{RxToken, RX_RING};
    use burin::stepper::Segment;
    use core::mem::MaybeUninit;
    use heapless::spsc::Queue;
    use rtic_sync::channel::{Receiver, Sender};
    use stm32f4xx_hal::gpio::{Output, PC13};
    use stm32f4xx_hal::{pac, watchdog::IndependentWatchdog};

    /// "Something changed, run the session": a one-slot channel, so any
    /// number of signals before the task runs cost one pass.
    type Wake = Sender<'static, (), 1>;
    type Store = board::Store;

    #[shared]
    struct Shared {
        /// The host link (`board::Link`) and its wake-up, for `usb` and
        /// `usart` alike: one priority, so no lock.
        #[lock_free]
        link: board::Link,
        #[lock_free]
        wake_link: Wake,
    }

    #[local]
    struct Local {
        driver: StepTask,
        parse: Parse,
        wake: Receiver<'static, (), 1>,
        led: PC13<Output>,
        debounce: Debounce,
        watchdog: IndependentWatchdog,
        wake_step: Wake,
        wake_beat: Wake,
        wake_limit_x: Wake,
        wake_limit_yz: Wake,
        wake_estop: Wake,
        wake_hold: Wake,
    }

    #[init(local = [
        rx_ring: Queue<RxToken, RX_RING> = Queue::new(),
        tx_ring: Queue<u8, TX_RING> = Queue::new(),
        seg_ring: Queue<Segment, SEGMENT_SLOTS> = Queue::new(),
        machine_slot: Machine<PLANNER_BLOCKS> = Machine::placeholder(),
        controller_slot: MaybeUninit<Controller<Store>> = MaybeUninit::uninit(),
        link_mem: board::LinkMem = board::LinkMem::new(),
        store_mem: board::StoreMem = board::StoreMem::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let (p, mut core) = (board::take(cx.device), cx.core);
        // Clocks as the board says (a dead crystal blinks); the probe.
        let (mut rcc, gpioc) = board::start_clocks(p.rcc, &p.pwr, p.gpioc);
        let watchdog = steps::debug_and_watchdog(&p.dbgmcu, p.iwdg);
        // Settings first: the pins' idle levels depend on them.
        let store = board::open_store(p.flash, cx.local.store_mem);
        let (persist, boot) = steps::load_settings(store);
        let settings = boot.settings;
        // Pins, every output in its safe state.
        let pins = steps::pins((p.gpioa, p.gpiob, gpioc), p.tim1, &mut rcc, &settings);
        // Rings between the tasks, split once: each end goes to its task.
        let (rx_send, rx_tokens) = cx.local.rx_ring.split();
        let (tx_bytes, tx_recv) = cx.local.tx_ring.split();
        let (segments, seg_recv) = cx.local.seg_ring.split();
        // The host link (and the USB serial number, "-" on QEMU).
        let mem = cx.local.link_mem;
        let (link, serial) =
            board::open_link(p.link, pins.link_pins, &mut rcc, mem, rx_send, tx_recv);
        // Motion: the step task on TIM5, the board's pulse end and checks.
        let hw = (p.tim5, p.dma2, pins.steppers);
        let (driver, tick_hz) = steps::step_task(hw, &mut core, &mut rcc, &settings, seg_recv);
        // Outputs; inputs on EXTI, their power-up levels settled.
        let io = steps::outputs(pins.aux, &settings);
        let debounce = steps::inputs(pins.inputs, p.syscfg, p.exti, &mut rcc, &settings);
        let (wake_step, wake) = rtic_sync::make_channel!((), 1);
        // Heartbeat: SysTick from the core clock.
        let sysclk = rcc.clocks.sysclk().raw();
        steps::start_heartbeat(&mut core.SYST, sysclk);
        // The session; the parse task prints the banner, then waits.
        let controller = steps::build_controller(cx.local.controller_slot, persist, &boot);
        if parse::spawn().is_err() {
            defmt::error!("parse task already running");
        }
        let watchdog = steps::start_watchdog(watchdog, sysclk, serial);
        let parse = Parse {
            rx_tokens,
            tx_bytes,
            segments,
            machine: cx.local.machine_slot,
            boot: (settings, tick_hz),
            controller,
            io,
        };
        let wake_link = wake_step.clone();
        let local = Local {
            driver,
            parse,
            wake,
            led: pins.led,
            debounce,
            watchdog,
            wake_beat: wake_step.clone(),
            wake_limit_x: wake_step.clone(),
            wake_limit_yz: wake_step.clone(),
            wake_estop: wake_step.clone(),
            wake_hold: wake_step.clone(),
            wake_step,
        };
        (Shared { link, wake_link }, local)
    }

    /// Sleep until an interrupt; feed the watchdog every time through. (A
    /// stack overflow needs no check here: it faults, see `fault.rs`.)
    #[idle(local = [watchdog])]
    fn idle(cx: idle::Context) -> ! {
        loop {
            cx.local.watchdog.feed();
            cortex_m::asm::wfi();
        }
    }

    /// Step rises, falls and restarts (see `burin::stepper::driver`). The
    /// switches are one IDR read after each rise; a taken segment or a
    /// stop wakes `parse`.
    #[task(binds = TIM5, priority = 3, local = [driver, wake_step])]
    fn step(cx: step::Context) {
        if cx.local.driver.on_interrupt(&crate::RT) {
            let _ = cx.local.wake_step.try_send(());
        }
    }

    /// X limit (PA4): trips at once while armed motion runs.
    #[task(binds = EXTI4, priority = 4, local = [wake_limit_x])]
    fn limit_x(cx: limit_x::Context) {
        if crate::inputs::on_instant(pac::Interrupt::EXTI4, inp::LIMIT_X) {
            let _ = cx.local.wake_limit_x.try_send(());
        }
    }

    /// Y and Z limits (PA5, PA6) share EXTI9_5.
    #[task(binds = EXTI9_5, priority = 4, local = [wake_limit_yz])]
    fn limit_yz(cx: limit_yz::Context) {
        if crate::inputs::on_instant(pac::Interrupt::EXTI9_5, inp::LIMIT_Y | inp::LIMIT_Z) {
            let _ = cx.local.wake_limit_yz.try_send(());
        }
    }

    /// Reset / e-stop (PA2): pulses, spindle and coolant stop at once.
    #[task(binds = EXTI2, priority = 4, local = [wake_estop])]
    fn estop(cx: estop::Context) {
        if crate::inputs::on_instant(pac::Interrupt::EXTI2, inp::ESTOP) {
            let _ = cx.local.wake_estop.try_send(());
        }
    }

    /// Cycle start (PA0, the board's KEY): masked until the heartbeat
    /// has seen it settle.
    #[task(binds = EXTI0, priority = 2)]
    fn cycle_start(_: cycle_start::Context) {
        crate::inputs::take_edges(pac::Interrupt::EXTI0, inp::CYCLE_START);
    }

    /// Feed hold (PA1): acts on the first edge, as `!` from the host.
    #[task(binds = EXTI1, priority = 2, local = [wake_hold])]
    fn feed_hold(cx: feed_hold::Context) {
        if crate::inputs::on_instant(pac::Interrupt::EXTI1, inp::FEED_HOLD) {
            let _ = cx.local.wake_hold.try_send(());
        }
    }

    /// Probe (PA3): only its `Pn:` bit; probing itself is timed by the
    /// step interrupt's read at every event.
    #[task(binds = EXTI3, priority = 2)]
    fn probe(_: probe::Context) {
        crate::inputs::take_edges(pac::Interrupt::EXTI3, inp::PROBE);
    }

    /// The host link's interrupt: OTG_FS on the Black Pills (`usb`),
    /// USART1 on QEMU (`usart`); each board's peripheral raises only its
    /// own, the other vector stays silent. Bytes to the splitter, replies
    /// out.
    #[task(binds = OTG_FS, priority = 2, shared = [link, wake_link])]
    fn usb(cx: usb::Context) {
        serve_link(cx.shared.link, cx.shared.wake_link);
    }

    #[task(binds = USART1, priority = 2, shared = [link, wake_link])]
    fn usart(cx: usart::Context) {
        serve_link(cx.shared.link, cx.shared.wake_link);
    }

    fn serve_link(link: &mut board::Link, wake: &mut Wake) {
        if link.service(&crate::FLAGS) {
            let _ = wake.try_send(());
        }
    }

    // Parser -> interpreter -> planner -> segment preparer: one pass of
    // `burin::controller` per wake-up. The body is `pass::parse` (RTIC's
    // extern task).
    extern "Rust" {
        #[task(priority = 1, local = [parse, wake])]
        async fn parse(cx: parse::Context);
    }

    /// 100 Hz housekeeping: blink the LED at 1 Hz (alive), re-check the
    /// inputs whose edge interrupt masked them (`inputs::heartbeat`), and
    /// wake `parse` (status cadence, timeouts, the idle-disable timer).
    #[task(binds = SysTick, priority = 1, local = [led, debounce, wake_beat, ticks: u32 = 0])]
    fn heartbeat(cx: heartbeat::Context) {
        let ticks = cx.local.ticks;
        *ticks = ticks.wrapping_add(1);
        let now = ticks.wrapping_mul(1000 / HEARTBEAT_HZ);
        crate::inputs::set_now(now);
        if ticks.is_multiple_of(HEARTBEAT_HZ / 2) {
            cx.local.led.toggle();
        }
        crate::inputs::heartbeat(cx.local.debounce, now);
        let _ = cx.local.wake_beat.try_send(());
    }
}
