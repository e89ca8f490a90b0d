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
//! 2. `usb` (OTG_FS, or `usart` on QEMU): bytes through the link's
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

// The app's modules live in `burin-fw/` beside this file.
#[cfg(target_os = "none")]
#[path = "burin-fw/boards/mod.rs"]
mod boards;
#[cfg(target_os = "none")]
#[path = "burin-fw/fault.rs"]
mod fault;
#[cfg(target_os = "none")]
#[path = "burin-fw/inputs.rs"]
mod inputs;
#[cfg(target_os = "none")]
#[path = "burin-fw/outputs.rs"]
mod outputs;
#[cfg(all(target_os = "none", not(feature = "board-qemu")))]
#[path = "burin-fw/pulse_end.rs"]
mod pulse_end;
#[cfg(target_os = "none")]
#[path = "burin-fw/rings.rs"]
mod rings;
#[cfg(all(target_os = "none", not(feature = "board-qemu")))]
#[path = "burin-fw/selfcheck.rs"]
mod selfcheck;
#[cfg(target_os = "none")]
#[path = "burin-fw/step.rs"]
mod step;
#[cfg(target_os = "none")]
#[path = "burin-fw/storage.rs"]
mod storage;
// The link: USB-CDC on the real boards, USART1 on QEMU (no OTG model).
#[cfg(all(target_os = "none", feature = "board-qemu"))]
#[path = "burin-fw/usart.rs"]
mod usart;
#[cfg(all(target_os = "none", not(feature = "board-qemu")))]
#[path = "burin-fw/usb.rs"]
mod usb;

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
    use crate::step::{StepHw, StepTask, Tim5};
    #[cfg(feature = "board-qemu")]
    use crate::usart::UsartLink as Link;
    #[cfg(not(feature = "board-qemu"))]
    use crate::usb::UsbLink as Link;
    use burin::controller::{Controller, Inputs};
    use burin::executor::Machine;
    use burin::inputs::{self as inp, Debounce};
    use burin::link::{RxToken, RX_RING};
    use burin::persist::Persist;
    use burin::session::{Device, Identity};
    use burin::settings::Settings;
    use burin::stepper::{Segment, Stepper};
    use core::mem::MaybeUninit;
    #[cfg(not(feature = "board-qemu"))]
    use core::sync::atomic::Ordering;
    use cortex_m::peripheral::syst::SystClkSource;
    use heapless::spsc::{Consumer, Producer, Queue};
    #[cfg(not(feature = "board-qemu"))]
    use protocol::usb_ids::{serial_from_uid, USB_SERIAL_LEN};
    use rtic_sync::channel::{Receiver, Sender};
    #[cfg(not(feature = "board-qemu"))]
    use stm32f4xx_hal::otg_fs::{UsbBus, UsbBusType, USB};
    use stm32f4xx_hal::{
        gpio::{Output, PC13},
        pac,
        prelude::*,
        syscfg::SysCfgExt,
        watchdog::IndependentWatchdog,
    };
    #[cfg(not(feature = "board-qemu"))]
    use usb_device::bus::UsbBusAllocator;

    /// The link's interrupt, pended by `parse` after it queues a reply.
    #[cfg(not(feature = "board-qemu"))]
    const LINK_IRQ: pac::Interrupt = pac::Interrupt::OTG_FS;
    #[cfg(feature = "board-qemu")]
    const LINK_IRQ: pac::Interrupt = crate::usart::IRQ;

    /// "Something changed, run the session": a one-slot channel, so any
    /// number of signals before the task runs cost one pass.
    type Wake = Sender<'static, (), 1>;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        driver: StepTask,
        wake_step: Wake,
        /// USB-CDC (`usb.rs`), or USART1 on QEMU (`usart.rs`). Two names
        /// because RTIC checks task locals before cfg removes a task.
        #[cfg(not(feature = "board-qemu"))]
        link: Link,
        #[cfg(not(feature = "board-qemu"))]
        wake_usb: Wake,
        #[cfg(feature = "board-qemu")]
        uart: Link,
        #[cfg(feature = "board-qemu")]
        wake_uart: Wake,
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
        #[cfg(not(feature = "board-qemu"))]
        ep_memory: [u32; 1024] = [0; 1024],
        #[cfg(not(feature = "board-qemu"))]
        usb_bus: Option<UsbBusAllocator<UsbBusType>> = None,
        #[cfg(not(feature = "board-qemu"))]
        serial: [u8; USB_SERIAL_LEN] = [0; USB_SERIAL_LEN],
        #[cfg(feature = "board-qemu")]
        ram_store: crate::storage::Mem = crate::storage::Mem::new(),
        #[cfg(not(feature = "board-qemu"))]
        backlog: burin::link::RxBacklog<{ crate::usb::BACKLOG }> = burin::link::RxBacklog::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let mut core = cx.core;

        // Clocks: HSE + PLL as the board file says (96 MHz on the F411),
        // from the reset state (a DFU `:leave` jumps here with the ROM
        // bootloader's PLL still running), after the regulator scale they
        // need (set while the PLL is off).
        #[cfg(not(feature = "board-qemu"))]
        clocks_to_reset_state(&dp.RCC);
        board::regulator(&dp.PWR, &dp.RCC);
        #[cfg(not(feature = "board-qemu"))]
        if !board::start_hse(&dp.RCC) {
            defmt::error!("the 25 MHz crystal did not start: blinking the LED on HSI");
            board::blink_no_crystal(dp.RCC, dp.GPIOC);
        }
        let mut rcc = dp.RCC.freeze(board::clocks());
        #[cfg(not(feature = "board-qemu"))]
        if !rcc.clocks.is_pll48clk_valid() {
            defmt::error!("USB clock is not 48 MHz: the port will not enumerate");
        }

        // Keep the debug probe (RTT logs) working through WFI, and stop the
        // watchdog while the core is halted at a breakpoint.
        dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());
        let watchdog = IndependentWatchdog::new(dp.IWDG);
        watchdog.stop_on_debug(&dp.DBGMCU, true);

        // Settings and offsets first: the pins' idle levels depend on them.
        #[cfg(not(feature = "board-qemu"))]
        let store = crate::storage::open(dp.FLASH);
        #[cfg(feature = "board-qemu")]
        let store = crate::storage::open(dp.FLASH, cx.local.ram_store);
        #[allow(unused_mut)]
        let (persist, mut boot) = load_settings(store);
        #[cfg(feature = "board-qemu")]
        board::boot_overrides(&mut boot.settings);
        let settings = boot.settings;
        crate::fault::publish(settings.enable_invert);

        // Pins: the board's map, everything in its safe state (outputs off,
        // drivers disabled): the step/dir/enable pins at their idle levels
        // under the stored `$2`/`$3`/`$4` from the store that makes them
        // outputs (`board::split`); `set_invert` below keeps them there.
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);
        let idle = board::Idle {
            step_invert: settings.step_invert,
            dir_invert: settings.dir_invert,
            enable_active_high: settings.enable_invert,
        };
        let mut pins = board::split(gpioa, gpiob, gpioc, dp.TIM1, &mut rcc, idle);
        pins.steppers.set_invert(
            settings.step_invert,
            settings.dir_invert,
            settings.enable_invert,
        );
        pins.aux.all_off();

        // Rings between the tasks, split once: producer and consumer each
        // go to the one task that uses that end.
        let (rx_send, rx_tokens) = cx.local.rx_ring.split();
        let (tx_bytes, tx_recv) = cx.local.tx_ring.split();
        let (segments, seg_recv) = cx.local.seg_ring.split();
        // USB: serial number from the 96-bit unique ID, then the CDC port.
        #[cfg(not(feature = "board-qemu"))]
        let serial = serial_from_uid(read_uid(), cx.local.serial);
        #[cfg(not(feature = "board-qemu"))]
        let usb = USB::new(
            (dp.OTG_FS_GLOBAL, dp.OTG_FS_DEVICE, dp.OTG_FS_PWRCLK),
            pins.usb_pins,
            &rcc.clocks,
        );
        #[cfg(not(feature = "board-qemu"))]
        let bus = &*cx
            .local
            .usb_bus
            .insert(UsbBus::new(usb, cx.local.ep_memory));
        #[cfg(not(feature = "board-qemu"))]
        let link = Link::new(bus, serial, rx_send, tx_recv, cx.local.backlog);
        // QEMU: USART1 at BAUD 8N1 (the first `-serial` of the machine).
        // Early in init: QEMU drops what the host sends before UE is set.
        #[cfg(feature = "board-qemu")]
        let uart = match dp
            .USART1
            .serial(pins.usart_pins, crate::usart::BAUD.bps(), &mut rcc)
        {
            Ok(serial) => Link::new(serial, rx_send, tx_recv),
            Err(_) => defmt::panic!("USART1 cannot run at {} baud", crate::usart::BAUD),
        };
        #[cfg(feature = "board-qemu")]
        let serial = "-";

        // Motion core: executor on the default settings, stepper with the
        // same pin timing, the step port with the same inverts.
        let timer = Tim5::new(dp.TIM5, &mut rcc);
        let tick_hz = burin::seams::StepTimer::tick_hz(&timer);
        // The step pulses end by TIM1 compare 2 and DMA2, at the idle
        // levels `set_invert` chose; the path is checked against the
        // chip's bus matrix and by one zero-effect transfer.
        #[cfg(not(feature = "board-qemu"))]
        let pulse = {
            let (word, bsrr) = pins.steppers.step_off_store();
            let tim1_clk = rcc.clocks.timclk2().raw();
            let (pulse, check) = crate::pulse_end::PulseEnd::new(
                dp.DMA2,
                &mut rcc,
                board::CHIP,
                bsrr,
                word,
                tim1_clk,
                tick_hz,
            );
            if let Err(fault) = check {
                defmt::error!("boot check: {}", fault.message());
                crate::RT.set_hw_fault(fault);
            }
            pulse
        };
        #[cfg(not(feature = "board-qemu"))]
        crate::selfcheck::clocks_and_timers(&mut core.DCB, &mut core.DWT, &rcc.clocks, &crate::RT);
        let cfg = burin::stepper::StepConfig::new(&settings, tick_hz);
        let steppers = pins.steppers;
        // Outputs: spindle, coolant, and the enable pin for the idle timer
        // (same `$4` polarity as the step port; both follow a `$4=` at once,
        // the step port in the step interrupt, this one in `Io::write`).
        let io = Io::new(pins.aux, board::enable_pin(settings.enable_invert));
        // Inputs: EXTI on both edges; the levels at power-up are settled.
        crate::inputs::publish(&settings);
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        let mut exti = dp.EXTI;
        let mut inputs = pins.inputs;
        board::enable_exti(&mut inputs, &mut syscfg, &mut exti);
        let debounce = Debounce::new(crate::inputs::SETTLE_MS, crate::inputs::active_now());
        // An e-stop already pressed at power-up latches the alarm too.
        crate::RT.set_estop(debounce.stable() & inp::ESTOP != 0);

        // The step timer stays stopped until `parse` queues segments.
        let driver = StepTask::new(
            StepHw {
                port: steppers,
                timer,
                #[cfg(not(feature = "board-qemu"))]
                pulse,
            },
            Stepper::new(cfg),
            seg_recv,
        );
        let (wake_step, wake) = rtic_sync::make_channel!((), 1);

        // Heartbeat: SysTick at HEARTBEAT_HZ from the core clock.
        let sysclk = rcc.clocks.sysclk().raw();
        start_heartbeat(&mut core.SYST, sysclk);

        // The session on the loaded settings; it tells the boot report
        // after the banner.
        let identity = Identity {
            board: board::NAME,
            caps: 0,
        };
        let controller = build_controller(cx.local.controller_slot, identity, persist, &boot);

        // The parse task prints the banner, then waits for a wake-up.
        if parse::spawn().is_err() {
            defmt::error!("parse task already running");
        }

        // Watchdog last, so the slow setup above cannot trip it.
        let mut watchdog = watchdog;
        watchdog.start(crate::WATCHDOG_MS.millis());

        defmt::info!(
            "burin {} on {} at {} Hz, USB serial {}",
            burin::VERSION,
            board::NAME,
            sysclk,
            serial
        );
        (
            Shared {},
            Local {
                driver,
                wake_step: wake_step.clone(),
                #[cfg(not(feature = "board-qemu"))]
                link,
                #[cfg(not(feature = "board-qemu"))]
                wake_usb: wake_step.clone(),
                #[cfg(feature = "board-qemu")]
                uart,
                #[cfg(feature = "board-qemu")]
                wake_uart: wake_step.clone(),
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
            },
        )
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

    /// The USB port: enumeration, bytes to the splitter, replies out.
    #[cfg(not(feature = "board-qemu"))]
    #[task(binds = OTG_FS, priority = 2, local = [link, wake_usb])]
    fn usb(cx: usb::Context) {
        if cx.local.link.service(&crate::FLAGS) {
            let _ = cx.local.wake_usb.try_send(());
        }
    }

    /// The same for the USART link (QEMU).
    #[cfg(feature = "board-qemu")]
    #[task(binds = USART1, priority = 2, local = [uart, wake_uart])]
    fn usart(cx: usart::Context) {
        if cx.local.uart.service(&crate::FLAGS) {
            let _ = cx.local.wake_uart.try_send(());
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
        #[cfg(feature = "board-qemu")]
        board::fault_drill();
        loop {
            #[cfg(not(feature = "board-qemu"))]
            let port_closed = crate::usb::PORT_CLOSED.swap(false, Ordering::AcqRel);
            #[cfg(feature = "board-qemu")]
            let port_closed = false;
            // A port open: the session decides (a reset with its banner
            // when nothing runs, before this pass answers any line of the
            // new client; nothing while a job runs).
            #[cfg(not(feature = "board-qemu"))]
            let port_opened = crate::usb::PORT_OPENED.swap(false, Ordering::AcqRel);
            #[cfg(feature = "board-qemu")]
            let port_opened = false;
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
            rtic::pend(LINK_IRQ);
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

    /// The session and controller, built straight into its static slot in
    /// a frame of its own.
    #[inline(never)]
    fn build_controller(
        slot: &'static mut MaybeUninit<Controller<crate::storage::Store>>,
        identity: Identity,
        persist: Persist<crate::storage::Store>,
        boot: &burin::persist::Loaded,
    ) -> &'static mut Controller<crate::storage::Store> {
        // One expression, both constructors inlined: the session (with the
        // O-word stage's 2 KiB capture buffer) is built in the slot, not
        // built on the stack and copied there.
        slot.write(Controller::new(
            Device::with_storage(identity, persist, Some(boot)),
            &boot.settings,
            crate::outputs::WAKE_MS,
        ))
    }

    /// HSI as the system clock and the PLL off, as after a reset (where
    /// this changes nothing). The HAL's clock setup writes PLLCFGR, which
    /// the chip ignores while the PLL runs, and the ROM bootloader that a
    /// DFU `:leave` comes from leaves its PLL on. HSI is the reset clock, so
    /// the waits end within its start-up time. (Not on QEMU: its RCC model
    /// never reports a clock ready, and nothing runs before the app there.)
    #[cfg(not(feature = "board-qemu"))]
    fn clocks_to_reset_state(rcc: &pac::RCC) {
        rcc.cr().modify(|_, w| w.hsion().set_bit());
        while rcc.cr().read().hsirdy().bit_is_clear() {}
        rcc.cfgr().modify(|_, w| w.sw().hsi());
        while !rcc.cfgr().read().sws().is_hsi() {}
        rcc.cr().modify(|_, w| w.pllon().clear_bit());
        while rcc.cr().read().pllrdy().bit_is_set() {}
    }

    /// SysTick at [`crate::HEARTBEAT_HZ`] from the core clock `sysclk`.
    fn start_heartbeat(syst: &mut cortex_m::peripheral::SYST, sysclk: u32) {
        syst.set_clock_source(SystClkSource::Core);
        // The reload register has 24 bits (16.7 M cycles, 0.17 s at 96 MHz).
        syst.set_reload((sysclk / crate::HEARTBEAT_HZ - 1).min(0x00FF_FFFF));
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();
    }

    /// Settings and offsets from the store, before the machine is built on
    /// them (flash sectors 1-2; RAM on QEMU, see storage.rs).
    fn load_settings(
        store: crate::storage::Store,
    ) -> (Persist<crate::storage::Store>, burin::persist::Loaded) {
        let mut persist = Persist::new(store, Settings::default());
        let boot = persist.load();
        if !boot.report.is_clean() {
            defmt::warn!(
                "settings: {} items defaulted, storage error: {}",
                boot.report.defaulted,
                boot.report.failed
            );
        }
        (persist, boot)
    }

    /// The chip's 96-bit unique ID, lowest address first.
    #[cfg(not(feature = "board-qemu"))]
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
}
