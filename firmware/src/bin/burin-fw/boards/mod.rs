//! Board selection. Each board is one file here holding its pin map and its
//! clock tree, and one `memory-<board>.x` beside Cargo.toml; the app only
//! uses `board::…`. Adding a board (e.g. `board-qemu`, the netduinoplus2's
//! STM32F405 on HSI with the link on USART1) is a new file, a feature and a
//! memory file.
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

// The QEMU board borrows the map but has its own `split` (USART1, not USB).
#[cfg_attr(feature = "board-qemu", allow(dead_code))]
mod blackpill;

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
