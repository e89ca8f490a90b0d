//! burin's RTIC app (built only for thumbv7em-none-eabihf).
//!
//! Priorities, highest first, as DESIGN.md lays them out:
//! 4. `limit_x`, `limit_yz` (EXTI4, EXTI9_5), `estop` (EXTI2): a limit or
//!    e-stop edge acts in its interrupt, on the first edge, even while the
//!    step interrupt runs: hard-limit trip / reset in the `RT` atomics, and
//!    the stepper stops at its next event (`Realtime::hard_limit`,
//!    `halt_stepper`). Above the step timer because acting late is the one
//!    thing these must not do; each runs about 250-300 instructions, once
//!    per switch change (the line is masked until the contact settles), so
//!    the step timing pays nothing in normal running. The step interrupt's own
//!    IDR read at every event remains the guarantee that a closed limit
//!    stops pulses within one step event;
//! 3. `step` (TIM5): the core's step driver (`burin::stepper::driver`) on
//!    the segment queue's consumer: a rise (one BSRR write, next event
//!    computed while the pulse is high) and a fall per step, each at an
//!    absolute CC1 target of the free-running counter;
//! 2. `usb` (OTG_FS) or `usart` (USART1 on QEMU): bytes through the link's
//!    `RxSplitter` into the token ring (realtime bytes flag at once), reply
//!    bytes out of the TX ring;
//!    `cycle_start`, `feed_hold`, `probe` (EXTI0, EXTI1, EXTI3) share this
//!    level: they mask their line and record the edge; a hold raises its
//!    flag at once (like `!`), cycle start and the probe wait for the
//!    heartbeat to see the level settled (a start must not act on a
//!    glitch); both act through the session like `~`/`!`;
//! 1. `parse` (async software task): the device session (`burin::session`:
//!    parser, interpreter, executor) and `Machine::poll` (planner, segment
//!    preparer). It sleeps on a wake channel the other tasks signal.
//!    `heartbeat` (SysTick, 100 Hz) shares this level: LED, input debounce
//!    (`inputs.rs`), the clock of the stepper idle-disable timer. The parse
//!    task drives spindle, coolant and stepper enable (`outputs.rs`).
//!
//! `idle` feeds the watchdog and sleeps. It runs only when every task is
//! done, so a task that hogs the CPU starves the watchdog and the chip resets.
//! No RTIC resource is shared between priorities: every task owns its state
//! and the tasks meet only in lock-free spsc rings and atomic statics, so
//! nothing a higher task needs is ever behind a lower task's lock. Those
//! statics: `RT` and `FLAGS` here; `EDGES`, `INVERT`, `PINS` and `NOW_MS`
//! (inputs.rs: the input interrupts, the heartbeat and the parse task);
//! `PORT_OPENED` and `PORT_CLOSED` (usb.rs: USB interrupt to parse task);
//! `OFF_WORD` (fault.rs: the parse task's `$4` for the fault handler) and
//! `STEP_OFF` (pulse_end.rs: the step-off word DMA2 copies).
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(unsafe_op_in_unsafe_fn)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("burin-fw is firmware: build it with `cargo xtask build`");
}

// The app's modules live in `burin-fw/` beside this file; what differs per
// board is in `boards/` (one module per board, chosen by the Cargo feature).
#[cfg(target_os = "none")]
#[path = "burin-fw/boards/mod.rs"]
mod boards;
#[cfg(target_os = "none")]
#[path = "burin-fw/boot.rs"]
mod boot;
#[cfg(target_os = "none")]
#[path = "burin-fw/fault.rs"]
mod fault;
#[cfg(target_os = "none")]
#[path = "burin-fw/inputs.rs"]
mod inputs;
#[cfg(target_os = "none")]
#[path = "burin-fw/outputs.rs"]
mod outputs;
#[cfg(target_os = "none")]
#[path = "burin-fw/rings.rs"]
mod rings;
#[cfg(target_os = "none")]
#[path = "burin-fw/step.rs"]
mod step;
#[cfg(target_os = "none")]
#[path = "burin-fw/storage.rs"]
mod storage;

#[cfg(target_os = "none")]
use defmt_rtt as _;

/// A panic turns the outputs and drivers off first (`fault.rs`), then
/// formats nothing: the message and the panic locations (build paths) cost
/// kilobytes of flash, and the debug probe's backtrace says where it
/// happened. `udf` raises the HardFault, whose handler stops the step
/// timer and waits for the watchdog (or the probe).
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // Masked first (one instruction, no memory access), so no interrupt
    // can turn a driver or the spindle back on between the stores.
    cortex_m::interrupt::disable();
    fault::outputs_off();
    defmt::error!("panic");
    cortex_m::asm::udf()
}

/// SysTick rate; the watchdog timeout must be several of these periods.
#[cfg(target_os = "none")]
const HEARTBEAT_HZ: u32 = 100;
/// Watchdog timeout, counted on the nominal 32 kHz LSI. Idle feeds it at
/// least every heartbeat (10 ms), but not while a settings write erases
/// flash with the CPU stalled: a migration erases both 16 KiB sectors back
/// to back, up to 0.8 s each (1.6 s). The LSI may run at 47 kHz (datasheet
/// maximum), which makes 4 s nominal at least 2.7 s real.
#[cfg(target_os = "none")]
const WATCHDOG_MS: u32 = 4000;

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
    use crate::outputs::Io;
    use crate::rings::{TxRing, PLANNER_BLOCKS, SEGMENT_SLOTS, TX_RING};
    use crate::step::StepTask;
    use burin::controller::{Controller, Inputs};
    use burin::executor::Machine;
    use burin::inputs::{self as inp, Debounce};
    use burin::link::{RxToken, RX_RING};
    use burin::settings::Settings;
    use burin::stepper::Segment;
    use core::mem::MaybeUninit;
    use heapless::spsc::{Consumer, Producer, Queue};
    use rtic_sync::channel::{Receiver, Sender};
    use stm32f4xx_hal::{
        gpio::{Output, PC13},
        pac,
        watchdog::IndependentWatchdog,
    };

    /// "Something changed, run the session": a one-slot channel, so any
    /// number of signals before the task runs cost one pass.
    type Wake = Sender<'static, (), 1>;

    #[shared]
    struct Shared {
        /// The host link (`board::Link`: USB-CDC, or USART1 on QEMU) and
        /// its wake-up, for `usb` and `usart` alike (one priority, so no
        /// lock).
        #[lock_free]
        link: board::Link,
        #[lock_free]
        wake_link: Wake,
    }

    #[local]
    struct Local {
        driver: StepTask,
        wake_step: Wake,
        wake: Receiver<'static, (), 1>,
        rx_tokens: Consumer<'static, RxToken>,
        tx_bytes: Producer<'static, u8>,
        segments: Producer<'static, Segment>,
        /// A static built at compile time (`Machine::placeholder`), which
        /// `parse` rebuilds in place on the loaded settings when it starts:
        /// `Machine::new` at run time built the whole machine (19.8 KB) as
        /// a temporary on the stack (the F401 has 20 KiB).
        machine: &'static mut Machine<PLANNER_BLOCKS>,
        /// What `parse` builds the machine on.
        boot: (Settings, u32),
        controller: &'static mut Controller<crate::storage::Store>,
        led: PC13<Output>,
        debounce: Debounce,
        io: Io,
        wake_beat: Wake,
        wake_limit_x: Wake,
        wake_limit_yz: Wake,
        wake_estop: Wake,
        wake_hold: Wake,
        watchdog: IndependentWatchdog,
    }

    #[init(local = [
        rx_ring: Queue<RxToken, RX_RING> = Queue::new(),
        tx_ring: Queue<u8, TX_RING> = Queue::new(),
        seg_ring: Queue<Segment, SEGMENT_SLOTS> = Queue::new(),
        machine_slot: Machine<PLANNER_BLOCKS> = Machine::placeholder(),
        controller_slot: MaybeUninit<Controller<crate::storage::Store>> = MaybeUninit::uninit(),
        link_mem: board::LinkMem = board::LinkMem::new(),
        store_mem: board::StoreMem = board::StoreMem::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let p = board::take(cx.device);
        let mut core = cx.core;
        // Clocks and regulator as the board says (a dead crystal blinks).
        let (mut rcc, gpioc) = board::start_clocks(p.rcc, &p.pwr, p.gpioc);
        let watchdog = crate::boot::debug_and_watchdog(&p.dbgmcu, p.iwdg);
        // Settings first: the pins' idle levels depend on them.
        let store = board::open_store(p.flash, cx.local.store_mem);
        let (persist, boot) = crate::boot::load_settings(store);
        let settings = boot.settings;
        // Pins, all in their safe state.
        let pins = crate::boot::pins((p.gpioa, p.gpiob, gpioc), p.tim1, &mut rcc, &settings);
        // Rings between the tasks, split once: each end goes to its task.
        let (rx_send, rx_tokens) = cx.local.rx_ring.split();
        let (tx_bytes, tx_recv) = cx.local.tx_ring.split();
        let (segments, seg_recv) = cx.local.seg_ring.split();
        // The host link (USB serial number, or "-" on QEMU).
        let (link, serial) = board::open_link(
            p.link,
            pins.link_pins,
            &mut rcc,
            cx.local.link_mem,
            rx_send,
            tx_recv,
        );
        // Motion: the step task on TIM5 and the board's pulse end.
        let dcb_dwt = (&mut core.DCB, &mut core.DWT);
        let (driver, tick_hz) = crate::boot::step_task(
            p.tim5,
            p.dma2,
            pins.steppers,
            dcb_dwt,
            &mut rcc,
            &settings,
            seg_recv,
        );
        // Outputs and inputs.
        let io = crate::boot::outputs(pins.aux, &settings);
        let debounce = crate::boot::inputs(pins.inputs, p.syscfg, p.exti, &mut rcc, &settings);
        let (wake_step, wake) = rtic_sync::make_channel!((), 1);
        // Heartbeat: SysTick at HEARTBEAT_HZ from the core clock.
        let sysclk = rcc.clocks.sysclk().raw();
        crate::boot::start_heartbeat(&mut core.SYST, sysclk);
        // The session; the parse task prints the banner, then waits.
        let controller = crate::boot::build_controller(cx.local.controller_slot, persist, &boot);
        if parse::spawn().is_err() {
            defmt::error!("parse task already running");
        }
        let watchdog = crate::boot::start_watchdog(watchdog);
        let (name, version) = (board::NAME, burin::VERSION);
        defmt::info!(
            "burin {} on {} at {} Hz, USB serial {}",
            version,
            name,
            sysclk,
            serial
        );
        let shared = Shared {
            link,
            wake_link: wake_step.clone(),
        };
        let local = Local {
            driver,
            wake_step: wake_step.clone(),
            wake,
            rx_tokens,
            tx_bytes,
            segments,
            machine: cx.local.machine_slot,
            boot: (settings, tick_hz),
            controller,
            led: pins.led,
            debounce,
            io,
            wake_limit_x: wake_step.clone(),
            wake_limit_yz: wake_step.clone(),
            wake_estop: wake_step.clone(),
            wake_hold: wake_step.clone(),
            wake_beat: wake_step,
            watchdog,
        };
        (shared, local)
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
        if crate::inputs::on_limit(pac::Interrupt::EXTI4, inp::LIMIT_X) {
            let _ = cx.local.wake_limit_x.try_send(());
        }
    }

    /// Y and Z limits (PA5, PA6) share EXTI9_5.
    #[task(binds = EXTI9_5, priority = 4, local = [wake_limit_yz])]
    fn limit_yz(cx: limit_yz::Context) {
        if crate::inputs::on_limit(pac::Interrupt::EXTI9_5, inp::LIMIT_Y | inp::LIMIT_Z) {
            let _ = cx.local.wake_limit_yz.try_send(());
        }
    }

    /// Reset / e-stop (PA2): pulses, spindle and coolant stop at once.
    #[task(binds = EXTI2, priority = 4, local = [wake_estop])]
    fn estop(cx: estop::Context) {
        if crate::inputs::on_estop() {
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
        if crate::inputs::on_feed_hold() {
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

    /// Parser -> interpreter -> planner -> segment preparer, one pass of
    /// `burin::controller` per wake-up; this task only carries its inputs
    /// in and its pin levels out.
    #[task(priority = 1, local = [wake, rx_tokens, tx_bytes, segments, machine, boot, controller, io])]
    async fn parse(cx: parse::Context) {
        let parse::LocalResources {
            wake,
            rx_tokens,
            tx_bytes,
            segments,
            machine,
            boot,
            controller,
            io,
            ..
        } = cx.local;
        machine.rebuild(boot.0, boot.1);
        let mut tx = TxRing {
            ring: tx_bytes,
            dropped: 0,
        };
        controller.hello(&mut tx);
        board::fault_drill();
        loop {
            // A port open: the session decides (a reset with its banner
            // when nothing runs, before this pass answers any line of the
            // new client; nothing while a job runs).
            let (port_closed, port_opened) = board::port_events();
            let input = Inputs {
                now_ms: crate::inputs::now_ms(),
                switches: board::switches(),
                pins: crate::inputs::report_pins(),
                port_closed,
                port_opened,
            };
            let io_rings = burin::controller::Io {
                rt: &crate::RT,
                flags: &crate::FLAGS,
                rx: &mut *rx_tokens,
                segments: &mut *segments,
                tx: &mut tx,
            };
            let pass = controller.pass(machine, io_rings, input, &mut |_| {});
            crate::inputs::publish(machine.settings());
            crate::fault::publish(machine.settings().enable_invert);
            io.write(&pass.pins);
            if pass.kick {
                rtic::pend(pac::Interrupt::TIM5);
            }
            // Replies out (an idle port raises no interrupt by itself).
            rtic::pend(board::LINK_IRQ);
            if tx.dropped > 0 {
                defmt::error!("{} reply bytes dropped", core::mem::take(&mut tx.dropped));
            }
            if wake.recv().await.is_err() {
                break;
            }
        }
        defmt::error!("wake channel closed; parse task ends");
    }

    /// 100 Hz housekeeping: blink the LED at 1 Hz (alive), wake `parse`
    /// (status cadence, timeouts, the idle-disable timer), and re-check the
    /// inputs whose edge interrupt masked them (`inputs::poll`): settled
    /// button presses become realtime commands through the same flags as
    /// `!` and `~` from the host.
    #[task(binds = SysTick, priority = 1, local = [led, debounce, wake_beat, ticks: u32 = 0])]
    fn heartbeat(cx: heartbeat::Context) {
        let heartbeat::LocalResources {
            led,
            debounce,
            wake_beat,
            ticks,
            ..
        } = cx.local;
        *ticks = ticks.wrapping_add(1);
        let now = ticks.wrapping_mul(1000 / crate::HEARTBEAT_HZ);
        crate::inputs::set_now(now);
        if *ticks % (crate::HEARTBEAT_HZ / 2) == 0 {
            led.toggle();
        }
        let change = crate::inputs::poll(debounce, now);
        if change.pressed & inp::FEED_HOLD != 0 {
            crate::FLAGS.raise(protocol::Rt::FeedHold);
        }
        if change.pressed & inp::CYCLE_START != 0 {
            crate::FLAGS.raise(protocol::Rt::CycleStart);
        }
        // Instant inputs whose interrupt read them open (a bounce) and
        // that settled closed: act now, late rather than never.
        if change.pressed & inp::ESTOP != 0 {
            crate::inputs::estop();
        }
        crate::inputs::limits_closed(change.pressed);
        // The e-stop level for the machine's alarm latch, once settled (its
        // edge interrupt set it already on the first edge).
        if debounce.masked() & inp::ESTOP == 0 {
            crate::RT.set_estop(debounce.stable() & inp::ESTOP != 0);
        }
        if change.pressed | change.released != 0 {
            defmt::info!(
                "inputs active: {=u8:07b} (bit 0 X limit .. 6 e-stop)",
                debounce.stable()
            );
        }
        let _ = wake_beat.try_send(());
    }
}
