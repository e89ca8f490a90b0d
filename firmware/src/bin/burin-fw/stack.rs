//! Stack guard and high-water mark.
//!
//! cortex-m-rt paints the whole stack region, `_stack_end` (the top of the
//! static RAM) up to `_stack_start` (the top of RAM), with
//! `STACK_PAINT_VALUE` before `main` (its `paint-stack` feature). The stack
//! grows down towards the statics, so its lowest words are the guard:
//! `idle` checks them on every pass and resets the chip (pins back to their
//! reset state: outputs and drivers off) once a task's stack reached them,
//! before statics are overwritten further. `cargo xtask qemu` reads the
//! painted region after its run and prints how deep the stack went.
use cortex_m_rt::STACK_PAINT_VALUE;

/// Painted words at the bottom of the stack that must stay painted.
const GUARD_WORDS: usize = 16;

extern "C" {
    static _stack_end: u32;
}

/// The guard words are still painted.
pub fn intact() -> bool {
    let base = core::ptr::addr_of!(_stack_end);
    // SAFETY: `_stack_end` is cortex-m-rt's linker symbol for the lowest
    // stack address; the GUARD_WORDS above it lie inside the stack region,
    // which is always mapped RAM. Volatile reads only (another context's
    // stack may be there).
    (0..GUARD_WORDS).all(|i| unsafe { base.add(i).read_volatile() } == STACK_PAINT_VALUE)
}

/// Called by `idle` when [`intact`] fails: nothing on this chip can be
/// trusted any more, so start again from reset.
pub fn overflowed() -> ! {
    defmt::error!("stack overflow: the guard words were overwritten; resetting");
    cortex_m::peripheral::SCB::sys_reset()
}
