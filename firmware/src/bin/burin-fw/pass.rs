//! The parse task's pass: one run of `burin::controller` (parser ->
//! interpreter -> planner -> segment preparer) on this board. Everything
//! it decides lives in the library; this carries the board's inputs in
//! and the controller's pin levels out.
use crate::boards::board;
use crate::outputs::Io;
use crate::rings::{TxRing, PLANNER_BLOCKS};
use burin::controller::{Controller, Inputs};
use burin::executor::Machine;
use burin::link::RxToken;
use burin::settings::Settings;
use burin::stepper::Segment;
use heapless::spsc::{Consumer, Producer};
use stm32f4xx_hal::pac;

type Store = board::Store;

/// The parse task's state, built by init.
pub struct Parse {
    pub rx_tokens: Consumer<'static, RxToken>,
    pub tx_bytes: Producer<'static, u8>,
    pub segments: Producer<'static, Segment>,
    /// A static of zero bits built at compile time (`Machine::placeholder`,
    /// in .bss), which `parse` rebuilds in place on the loaded settings
    /// before its first pass: `Machine::new` at run time built the whole
    /// machine (11 KB) as a temporary on the stack (the F401 has 20 KiB).
    pub machine: &'static mut Machine<PLANNER_BLOCKS>,
    /// What the machine is built on: the settings and the step timer's
    /// tick rate.
    pub boot: (Settings, u32),
    pub controller: &'static mut Controller<Store>,
    pub io: Io,
}

/// The parse task (declared in the app, `burin-fw.rs`): the machine built
/// on the loaded settings, the banner, then one pass per wake-up, for
/// good. One pass runs `burin::controller` with the board's inputs, writes
/// its pin levels, kicks the step interrupt if it has segments to start,
/// and pends the link's interrupt for the replies.
pub async fn parse(cx: crate::app::parse::Context<'_>) {
    let Parse {
        rx_tokens,
        tx_bytes,
        segments,
        machine,
        boot,
        controller,
        io,
    } = cx.local.parse;
    let wake = cx.local.wake;
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
