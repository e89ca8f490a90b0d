//! Switch inputs on EXTI: the interrupt halves (tiny, lock-free) and the
//! heartbeat's re-check (`burin::inputs::Debounce`). What an input does
//! (trip, e-stop, hold, start) is `burin::inputs::{on_edge, heartbeat}`'s
//! decision, the same in host-sim; this file only moves levels and masks.
//!
//! A line is masked in the NVIC, not in EXTI_IMR: NVIC's set/clear-enable
//! registers are one store each, while IMR is read-modify-write and shared
//! by every line, which would race between the interrupt priorities. The
//! flip side: EXTI9_5 carries both Y and Z limits and is masked for both.
//!
//! Who acts when:
//! - limits (EXTI4, EXTI9_5), e-stop (EXTI2) and feed hold (EXTI1) act in
//!   their interrupt on the first edge: hard-limit trip / reset / hold
//!   flag, then mask the line;
//! - cycle start (EXTI0) and the probe (EXTI3) only mask their line and
//!   leave the edge to the heartbeat, which acts once the level has
//!   settled;
//! - the heartbeat unmasks a line once `Debounce` says it settled.
use crate::boards::board;
use burin::inputs::{self as inp, Debounce};
use core::sync::atomic::{AtomicU16, AtomicU32, AtomicU8, Ordering::Relaxed};
use cortex_m::peripheral::NVIC;
use stm32f4xx_hal::pac::{self, Interrupt};

/// Settle time of every input. Switch contacts bounce for 1-5 ms; 20 ms
/// with a 10 ms re-check means two equal samples before a button acts.
pub const SETTLE_MS: u32 = 20;

/// Low byte: inputs whose edge interrupt fired and masked its line; high
/// byte: instant inputs whose interrupt saw them active and acted. One
/// word, so the heartbeat takes both halves of one interrupt together.
/// Bits as in `burin::inputs`.
static EDGES: AtomicU16 = AtomicU16::new(0);
/// The input inverts (`$5`, `$6`, `$14` as `burin::inputs::invert_mask`),
/// published by the parse task.
static INVERT: AtomicU8 = AtomicU8::new(0);
/// Debounced active inputs as `Pn:` bits, for the status report.
static PINS: AtomicU16 = AtomicU16::new(0);

/// Milliseconds since boot, as the heartbeat counts them (wrapping).
static NOW_MS: AtomicU32 = AtomicU32::new(0);

/// Heartbeat: advance the millisecond clock.
pub fn set_now(ms: u32) {
    NOW_MS.store(ms, Relaxed);
}

/// The heartbeat's millisecond clock (its resolution: one heartbeat).
pub fn now_ms() -> u32 {
    NOW_MS.load(Relaxed)
}

/// Parse task: the input inverts for the interrupts. Whether hard limits
/// are armed is the executor's call (`Realtime::limits_armed`).
pub fn publish(s: &burin::settings::Settings) {
    INVERT.store(
        inp::invert_mask(s.limit_invert, s.probe_invert, s.control_invert),
        Relaxed,
    );
}

/// Debounced inputs for `MotionPort::pins`.
pub fn report_pins() -> u16 {
    PINS.load(Relaxed)
}

/// Active inputs now (one IDR read, inverts applied).
pub fn active_now() -> u8 {
    inp::active(board::closed_now(), INVERT.load(Relaxed))
}

/// The NVIC vector of each input bit (0-2 X/Y/Z limit, 3 probe, 4 feed
/// hold, 5 cycle start, 6 e-stop) and its EXTI line (the pin number).
const VECTORS: [(Interrupt, u32); 7] = [
    (Interrupt::EXTI4, 4),
    (Interrupt::EXTI9_5, 5),
    (Interrupt::EXTI9_5, 6),
    (Interrupt::EXTI3, 3),
    (Interrupt::EXTI1, 1),
    (Interrupt::EXTI0, 0),
    (Interrupt::EXTI2, 2),
];

fn exti() -> &'static pac::exti::RegisterBlock {
    // SAFETY: EXTI's PR is the only register used through this reference;
    // it is write-1-to-clear, so each store touches only the lines whose
    // bits it sets, and each line is cleared by one context at a time (its
    // interrupt while unmasked, the heartbeat while masked).
    unsafe { &*pac::EXTI::ptr() }
}

/// Interrupt half, for the inputs in `mine` (the bits this vector serves):
/// acknowledges and masks the vector, records the edges for the heartbeat
/// and returns which of `mine` fired.
pub fn take_edges(irq: Interrupt, mine: u8) -> u8 {
    let lines = lines_of(mine);
    let pr = exti().pr().read().bits() & lines;
    // SAFETY: write-1-to-clear of this vector's own pending lines.
    exti().pr().write(|w| unsafe { w.bits(pr) });
    NVIC::mask(irq);
    let fired = VECTORS
        .iter()
        .enumerate()
        .filter(|(i, (_, line))| mine & (1 << i) != 0 && pr & (1 << line) != 0)
        .fold(0u8, |acc, (i, _)| acc | (1 << i));
    EDGES.fetch_or(u16::from(fired), Relaxed);
    fired
}

/// Interrupt half of an instant input (limits, e-stop, feed hold): takes
/// the vector's edges, then does what `burin::inputs::on_edge` decided
/// (a hard-limit trip while armed, the e-stop's stop and reset, the
/// hold). Returns whether to wake the parse task.
pub fn on_instant(irq: Interrupt, mine: u8) -> bool {
    let fired = take_edges(irq, mine);
    let acted = inp::on_edge(&crate::RT, fired, active_now(), &mut raise);
    EDGES.fetch_or(u16::from(acted.inputs) << 8, Relaxed);
    if acted.cut_outputs {
        board::kill_aux();
    }
    acted.wake
}

/// A realtime command from a switch, as if the host had sent it.
fn raise(cmd: protocol::Rt) {
    crate::FLAGS.raise(cmd);
}

fn lines_of(inputs: u8) -> u32 {
    VECTORS
        .iter()
        .enumerate()
        .filter(|(i, _)| inputs & (1 << i) != 0)
        .fold(0, |acc, (_, (_, line))| acc | (1 << line))
}

/// The heartbeat's input work at `now` (ms): takes the interrupts' edges,
/// lets `burin::inputs::heartbeat` re-check the masked inputs and act on
/// settled presses (buttons, and instant inputs whose interrupt read them
/// open: a bounce, acted on late rather than never), then unmasks the
/// lines that settled.
pub fn heartbeat(deb: &mut Debounce, now: u32) {
    let taken = EDGES.swap(0, Relaxed);
    let (edges, seen) = (taken as u8, (taken >> 8) as u8);
    // Pending bits of masked lines are stale: clear them before sampling,
    // so an edge after the sample stays pending and fires on unmask.
    let masked = deb.masked() | edges;
    // SAFETY: write-1-to-clear of lines whose vector is masked.
    exti().pr().write(|w| unsafe { w.bits(lines_of(masked)) });
    let (change, acted) =
        inp::heartbeat(&crate::RT, deb, edges, seen, active_now(), now, &mut raise);
    if acted.cut_outputs {
        board::kill_aux();
    }
    let still = deb.masked();
    for (i, (irq, _)) in VECTORS.iter().enumerate() {
        let shared = VECTORS
            .iter()
            .enumerate()
            .filter(|(_, (v, _))| v == irq)
            .fold(0u8, |acc, (j, _)| acc | (1 << j));
        if change.rearm & (1 << i) != 0 && still & shared == 0 {
            NVIC::unpend(*irq);
            // SAFETY: RTIC masks by priority (BASEPRI), never through the
            // NVIC enable bits, so unmasking breaks no critical section.
            unsafe { NVIC::unmask(*irq) };
        }
    }
    PINS.store(inp::report_pins(deb.stable()), Relaxed);
    if change.pressed | change.released != 0 {
        defmt::info!(
            "inputs active: {=u8:07b} (bit 0 X limit .. 6 e-stop)",
            deb.stable()
        );
    }
}
