//! burin's RTIC app (built only for thumbv7em-none-eabihf).
//!
//! Priorities, highest first, as DESIGN.md lays them out:
//! 3. `step` (TIM5): one step event, one BSRR write, next period into ARR;
//! 2. `usb` (OTG_FS): the USB port, bytes in and out;
//! 1. `parse` (async software task): parse and plan; for now an echo.
//!    `heartbeat` (SysTick, 10 Hz) shares this level: LED, input watch.
//!
//! `idle` feeds the watchdog and sleeps. It runs only when every task is
//! done, so a task that hogs the CPU starves the watchdog and the chip resets.
//! No resource is shared between priorities: every task owns its state, so
//! nothing a higher task needs is ever behind a lower task's lock.
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
#[path = "burin-fw/step.rs"]
mod step;
// The link: USB-CDC on the real boards, USART1 on QEMU (no OTG model).
#[cfg(all(target_os = "none", feature = "board-qemu"))]
#[path = "burin-fw/usart.rs"]
mod usart;
#[cfg(all(target_os = "none", not(feature = "board-qemu")))]
#[path = "burin-fw/usb.rs"]
mod usb;

#[cfg(target_os = "none")]
use {defmt_rtt as _, panic_probe as _};

/// Step rate of the stand-in pulse train on X (see `step::FixedRate`).
#[cfg(target_os = "none")]
const DEMO_STEP_HZ: u32 = 1_000;
/// SysTick rate; the watchdog timeout must be several of these periods.
#[cfg(target_os = "none")]
const HEARTBEAT_HZ: u32 = 10;
/// Watchdog timeout. Idle feeds it at least every heartbeat (100 ms).
#[cfg(target_os = "none")]
const WATCHDOG_MS: u32 = 500;

// USART6 is only a dispatcher: its pins (PA11/PA12) carry USB on this board.
#[cfg(target_os = "none")]
#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [USART6])]
mod app {
    use crate::boards::board;
    use crate::step::{FixedRate, StepPort, Tim5};
    #[cfg(feature = "board-qemu")]
    use crate::usart::{Packet, RxReceiver, TxSender, UsartLink as Link, RX_PACKETS, TX_PACKETS};
    #[cfg(not(feature = "board-qemu"))]
    use crate::usb::{Packet, RxReceiver, TxSender, UsbLink as Link, RX_PACKETS, TX_PACKETS};
    #[cfg(not(feature = "board-qemu"))]
    use burin::usb_ids::{serial_from_uid, USB_SERIAL_LEN};
    use cortex_m::peripheral::syst::SystClkSource;
    #[cfg(not(feature = "board-qemu"))]
    use stm32f4xx_hal::otg_fs::{UsbBus, UsbBusType, USB};
    use stm32f4xx_hal::{
        gpio::{Output, PC13},
        pac,
        prelude::*,
        watchdog::IndependentWatchdog,
    };
    #[cfg(not(feature = "board-qemu"))]
    use usb_device::bus::UsbBusAllocator;

    /// The link's interrupt, pended by `parse` after it queues a reply.
    #[cfg(not(feature = "board-qemu"))]
    const LINK_IRQ: pac::Interrupt = pac::Interrupt::OTG_FS;
    #[cfg(feature = "board-qemu")]
    const LINK_IRQ: pac::Interrupt = crate::usart::IRQ;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        timer: Tim5,
        steppers: StepPort,
        pulses: FixedRate,
        /// USB-CDC (`usb.rs`), or USART1 on QEMU (`usart.rs`). Two names
        /// because RTIC checks task locals before cfg removes a task.
        #[cfg(not(feature = "board-qemu"))]
        link: Link,
        #[cfg(feature = "board-qemu")]
        uart: Link,
        rx: RxReceiver,
        tx: TxSender,
        led: PC13<Output>,
        inputs: board::Inputs,
        watchdog: IndependentWatchdog,
    }

    #[init(local = [
        #[cfg(not(feature = "board-qemu"))]
        ep_memory: [u32; 1024] = [0; 1024],
        #[cfg(not(feature = "board-qemu"))]
        usb_bus: Option<UsbBusAllocator<UsbBusType>> = None,
        #[cfg(not(feature = "board-qemu"))]
        serial: [u8; USB_SERIAL_LEN] = [0; USB_SERIAL_LEN],
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let mut core = cx.core;

        // Clocks: HSE + PLL as the board file says (96 MHz on the F411).
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

        // Pins: the board's map, everything in its safe state (outputs off,
        // drivers disabled).
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);
        let pins = board::split(gpioa, gpiob, gpioc, dp.TIM1, &mut rcc);
        let mut aux = pins.aux;
        aux.all_off();

        // Step timer: TIM5 at the timer clock, first event one half period
        // from now. Its interrupt is unmasked by RTIC when init returns.
        let mut timer = Tim5::new(dp.TIM5, &mut rcc);
        let pulses = FixedRate::new(
            crate::DEMO_STEP_HZ,
            burin::seams::StepTimer::tick_hz(&timer),
        );
        timer.start(pulses.first());

        // Channels between the USB interrupt and the parse task.
        let (rx_send, rx) = rtic_sync::make_channel!(Packet, RX_PACKETS);
        let (tx, tx_recv) = rtic_sync::make_channel!(Packet, TX_PACKETS);

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
        let link = Link::new(bus, serial, rx_send, tx_recv);
        // QEMU: USART1 at BAUD 8N1 (the first `-serial` of the machine).
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

        // Heartbeat: SysTick at HEARTBEAT_HZ from the core clock.
        let sysclk = rcc.clocks.sysclk().raw();
        core.SYST.set_clock_source(SystClkSource::Core);
        // The reload register has 24 bits (16.7 M cycles, 0.17 s at 96 MHz).
        core.SYST
            .set_reload((sysclk / crate::HEARTBEAT_HZ - 1).min(0x00FF_FFFF));
        core.SYST.clear_current();
        core.SYST.enable_interrupt();
        core.SYST.enable_counter();

        // The parse task waits on the RX channel from the start.
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
                timer,
                steppers: pins.steppers,
                pulses,
                #[cfg(not(feature = "board-qemu"))]
                link,
                #[cfg(feature = "board-qemu")]
                uart,
                rx,
                tx,
                led: pins.led,
                inputs: pins.inputs,
                watchdog,
            },
        )
    }

    /// Sleep until an interrupt; feed the watchdog every time through.
    #[idle(local = [watchdog])]
    fn idle(cx: idle::Context) -> ! {
        loop {
            cx.local.watchdog.feed();
            cortex_m::asm::wfi();
        }
    }

    /// One step event. The generator decides pins and the next period; this
    /// task only acknowledges the timer and lends it the two seams.
    #[task(binds = TIM5, priority = 3, local = [timer, steppers, pulses])]
    fn step(cx: step::Context) {
        let step::LocalResources {
            timer,
            steppers,
            pulses,
            ..
        } = cx.local;
        timer.clear_update();
        pulses.on_event(steppers, timer);
    }

    /// The USB port: enumeration, received packets to `parse`, replies out.
    #[cfg(not(feature = "board-qemu"))]
    #[task(binds = OTG_FS, priority = 2, local = [link])]
    fn usb(cx: usb::Context) {
        cx.local.link.service();
    }

    /// The same for the USART link (QEMU): bytes in, replies out.
    #[cfg(feature = "board-qemu")]
    #[task(binds = USART1, priority = 2, local = [uart])]
    fn usart(cx: usart::Context) {
        cx.local.uart.service();
    }

    /// Will run parser -> interpreter -> planner -> segment preparer. Until
    /// those land it echoes every packet back. After queueing a reply it
    /// pends OTG_FS, because an idle USB core raises no interrupt by itself.
    #[task(priority = 1, local = [rx, tx])]
    async fn parse(cx: parse::Context) {
        while let Ok(packet) = cx.local.rx.recv().await {
            if cx.local.tx.send(packet).await.is_err() {
                break;
            }
            rtic::pend(LINK_IRQ);
        }
        defmt::error!("link channel closed; parse task ends");
    }

    /// 10 Hz housekeeping: blink the LED at 1 Hz (alive) and log input
    /// changes, so the wiring can be checked switch by switch with a probe.
    #[task(binds = SysTick, priority = 1, local = [led, inputs, ticks: u32 = 0, last: u8 = 0])]
    fn heartbeat(cx: heartbeat::Context) {
        let heartbeat::LocalResources {
            led,
            inputs,
            ticks,
            last,
            ..
        } = cx.local;
        *ticks = ticks.wrapping_add(1);
        if *ticks % (crate::HEARTBEAT_HZ / 2) == 0 {
            led.toggle();
        }
        let closed = inputs.closed();
        if closed != *last {
            defmt::info!(
                "inputs closed: {=u8:07b} (bit 0 X limit .. 6 e-stop)",
                closed
            );
            *last = closed;
        }
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
