//! Invariant checks for the coverage-guided fuzz targets (`firmware/fuzz/`,
//! `cargo xtask fuzz`). Each target is one `pub fn NAME(data: &[u8])` that
//! panics when an invariant breaks, so the libFuzzer targets are thin
//! wrappers and the stable test `host-sim/tests/device/fuzz_regressions.rs` replays
//! every saved failing input (`firmware/fuzz/regressions/<target>/*`) with
//! no fuzzer.
//!
//! Invariants that fail today for a reason another issue owns are kept
//! but gated by the `KNOWN_*` constants below (false: not checked), so the
//! targets still run usefully; turn one on when its issue is fixed.

mod device;
pub mod envelope;
mod executor;
mod gcode;
mod protocol;
mod settings;

pub use device::device;
pub use executor::{executor, small_machine};
pub use gcode::{gcode_line, gcode_program};
pub use protocol::protocol_frames;
pub use settings::settings;

/// Issue 15: realtime bytes in their UTF-8 two-byte form (`C2 xx`) are
/// not yet recognised by the link. The device target always sends them;
/// when true it also checks that an override in that form leaves nothing
/// in the line buffer (a `$I` right behind it is answered).
pub const CHECK_UTF8_REALTIME: bool = true;

/// Issue 15: after a soft reset with a full receive ring, old input may
/// still run, and a line right behind a reset may be acked and dropped.
/// When true, the device target checks "no motion after 0x18 until new
/// input asks for it" and "acknowledged lines are not lost" across resets
/// taken with a full ring.
pub const CHECK_RESET_WITH_FULL_RING: bool = true;

/// A soft reset taken while the receive ring ended inside a framed
/// session's `Bye` (the rest still in the backlog) left the line assembler
/// framed while the splitter was back in text, so the next text line was
/// never answered (found 2026-11-24, fixed in `LineAssembler::flush_reset`;
/// input in `firmware/fuzz/regressions/device/`). When true, the device
/// target checks the after-reset `$I` in that state too.
pub const CHECK_MODE_AFTER_RESET: bool = true;

/// A target's check: panics on a broken invariant.
pub type Target = fn(&[u8]);

/// Issue 15: a line sent right behind 0x18 (in the same USB packet or
/// before the task took the reset) may be acked and then dropped, or not
/// answered at all: `$I` sent at once after a reset during motion got no
/// reply (regression `device/reset-then-info`). When false, the device
/// target waits for the reset's banner before it sends `$I`.
pub const CHECK_LINE_RIGHT_AFTER_RESET: bool = true;

/// Issue 15: after a soft reset during motion (ALARM:3) the session reads
/// input again only once the stepper has taken its next event; in a slow
/// move that is seconds away (a wait segment; F1 on 5 steps/mm: 8-20 s of
/// virtual time before `$I` was answered; regressions
/// `device/reset-then-info*`). When false, the device target allows
/// `RESET_BOUND_SLOW_MS` (46 s) instead of `RESET_BOUND_MS` (50 ms).
pub const CHECK_PROMPT_AFTER_RESET: bool = true;

/// Every target, by name (the fuzz crate's binaries, the regression test
/// and `cargo xtask fuzz` use this list).
pub const TARGETS: &[(&str, Target)] = &[
    ("gcode_line", gcode_line),
    ("gcode_program", gcode_program),
    ("protocol_frames", protocol_frames),
    ("settings", settings),
    ("device", device),
    ("executor", executor),
];

/// A target by name.
pub fn target(name: &str) -> Option<Target> {
    TARGETS.iter().find(|t| t.0 == name).map(|t| t.1)
}

/// Reads fuzz input as a stream of small decisions; reads past the end
/// give zeros, so every input is a complete program.
pub(crate) struct Bytes<'a> {
    data: &'a [u8],
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { data }
    }
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    pub fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }
    pub fn u16(&mut self) -> u16 {
        u16::from(self.u8()) | u16::from(self.u8()) << 8
    }
    pub fn u32(&mut self) -> u32 {
        u32::from(self.u16()) | u32::from(self.u16()) << 16
    }
    /// Up to `max` bytes (length from the next byte).
    pub fn take(&mut self, max: usize) -> &'a [u8] {
        let n = usize::from(self.u8()).min(max).min(self.data.len());
        let (a, b) = self.data.split_at(n);
        self.data = b;
        a
    }
    /// The rest of the input.
    pub fn rest(&mut self) -> &'a [u8] {
        std::mem::take(&mut self.data)
    }
    /// One of `items` (the first when the input has run out).
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        let i = usize::from(self.u8()) % items.len().max(1);
        items[i]
    }
}
