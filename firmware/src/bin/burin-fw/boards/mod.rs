//! Board selection. Each board is one file here holding its pin map and its
//! clock tree, and one `memory-<board>.x` beside Cargo.toml; the app only
//! uses `board::…`. Adding a board (e.g. `board-qemu`, the netduinoplus2's
//! STM32F405 on HSI with the link on USART1) is a new file, a feature and a
//! memory file.
#[cfg(all(feature = "board-f411", feature = "board-f401"))]
compile_error!(
    "pick one board: the F411 is the default; for the F401 use \
     `--no-default-features --features board-f401`"
);
#[cfg(not(any(feature = "board-f411", feature = "board-f401")))]
compile_error!("no board selected: enable feature `board-f411` or `board-f401`");

mod blackpill;

#[cfg(feature = "board-f401")]
pub mod f401;
#[cfg(feature = "board-f401")]
pub use f401 as board;

#[cfg(all(feature = "board-f411", not(feature = "board-f401")))]
pub mod f411;
#[cfg(all(feature = "board-f411", not(feature = "board-f401")))]
pub use f411 as board;
