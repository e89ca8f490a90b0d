//! Board selection and the board interface. The app (`burin-fw.rs`) only
//! uses `board::…`, and `board` is one of these modules, picked by the
//! Cargo feature:
//! - `f411` / `f401`: the WeAct Black Pill (`blackpill.rs`: pin map and
//!   register-level fault stores; `blackpill_init.rs`: clocks, USB link,
//!   flash store (`storage.rs`), pulse-end DMA, boot self-check), each
//!   file adding only its chip's constants (name, clock tree, regulator);
//! - `qemu`: QEMU's netduinoplus2 (`qemu.rs`): the same pin map on HSI,
//!   the link on USART1, settings in RAM.
//!
//! The contract every board module meets (same names, same signatures):
//!
//! | item | what |
//! |---|---|
//! | `NAME` | the board's name for the log and `$I` |
//! | `take(pac::Peripherals) -> Periph<LinkHw>` | the peripherals init hands out |
//! | `start_clocks(rcc, &pwr, gpioc) -> (Rcc, gpioc)` | clock tree and regulator |
//! | `Store`, `StoreMem`, `open_store`, `boot_overrides` | the settings store |
//! | `split(gpioa, gpiob, gpioc, tim1, rcc, Idle) -> Board` | the pin map, outputs safe (`Board`: `steppers`, `inputs`, `aux`, `led`, `link_pins`) |
//! | `Link`, `LINK_IRQ`, `LinkMem`, `open_link`, `port_events` | the host link |
//! | `step_hw(StepPort, Tim5, dma2, rcc) -> StepHw` | the step hardware |
//! | `self_check(dcb, dwt, clocks)` | boot checks of clocks and timers |
//! | `enable_exti`, `switches`, `closed_now` | the switch inputs |
//! | `enable_pin`, `kill_aux`, `outputs_off`, `outputs_off_word`, `stop_step_timer` | outputs, and the fault path's register stores |
//! | `fault_drill`, `report_fault` | QEMU's fault drills and fault report (no-ops on the boards) |
//!
//! Adding a board is a new module here, a feature and a `memory-<board>.x`.
#[cfg(any(
    all(feature = "board-f411", feature = "board-f401"),
    all(feature = "board-f411", feature = "board-qemu"),
    all(feature = "board-f401", feature = "board-qemu"),
))]
compile_error!(
    "pick one board: the F411 is the default; for another use \
     `--no-default-features --features board-f401` (or `board-qemu`)"
);
#[cfg(not(any(feature = "board-f411", feature = "board-f401", feature = "board-qemu")))]
compile_error!("no board selected: enable feature `board-f411`, `board-f401` or `board-qemu`");

use stm32f4xx_hal::pac;

/// The peripherals init uses, the same on every board, and the link's
/// (`L`: the board's own, OTG_FS or USART1).
pub struct Periph<L> {
    pub rcc: pac::RCC,
    pub pwr: pac::PWR,
    pub flash: pac::FLASH,
    pub gpioa: pac::GPIOA,
    pub gpiob: pac::GPIOB,
    pub gpioc: pac::GPIOC,
    pub tim1: pac::TIM1,
    pub tim5: pac::TIM5,
    pub dma2: pac::DMA2,
    pub syscfg: pac::SYSCFG,
    pub exti: pac::EXTI,
    pub iwdg: pac::IWDG,
    pub dbgmcu: pac::DBGMCU,
    pub link: L,
}

/// Moves the common peripherals out of `$dp` and the link's (`$link`, an
/// expression on `$dp`) into a [`Periph`].
macro_rules! take_periph {
    ($dp:ident, $link:expr) => {
        super::Periph {
            link: $link,
            rcc: $dp.RCC,
            pwr: $dp.PWR,
            flash: $dp.FLASH,
            gpioa: $dp.GPIOA,
            gpiob: $dp.GPIOB,
            gpioc: $dp.GPIOC,
            tim1: $dp.TIM1,
            tim5: $dp.TIM5,
            dma2: $dp.DMA2,
            syscfg: $dp.SYSCFG,
            exti: $dp.EXTI,
            iwdg: $dp.IWDG,
            dbgmcu: $dp.DBGMCU,
        }
    };
}

// The QEMU board borrows the map but has its own `split` (USART1, not USB).
#[cfg_attr(feature = "board-qemu", allow(dead_code))]
mod blackpill;

// The Black Pills' own hardware: USB link, pulse-end DMA, boot checks.
#[cfg(not(feature = "board-qemu"))]
mod blackpill_init;
#[cfg(not(feature = "board-qemu"))]
#[path = "../pulse_end.rs"]
pub mod pulse_end;
#[cfg(not(feature = "board-qemu"))]
#[path = "../selfcheck.rs"]
mod selfcheck;
#[cfg(not(feature = "board-qemu"))]
#[path = "../storage.rs"]
mod storage;
#[cfg(not(feature = "board-qemu"))]
#[path = "../usb.rs"]
mod usb;
// QEMU's link (no OTG model there).
#[cfg(feature = "board-qemu")]
#[path = "../usart.rs"]
mod usart;

#[cfg(feature = "board-f401")]
pub mod f401;
#[cfg(feature = "board-f401")]
pub use f401 as board;

#[cfg(all(feature = "board-f411", not(feature = "board-f401")))]
pub mod f411;
#[cfg(all(feature = "board-f411", not(feature = "board-f401")))]
pub use f411 as board;

#[cfg(all(
    feature = "board-qemu",
    not(any(feature = "board-f411", feature = "board-f401"))
))]
pub mod qemu;
#[cfg(all(
    feature = "board-qemu",
    not(any(feature = "board-f411", feature = "board-f401"))
))]
pub use qemu as board;
