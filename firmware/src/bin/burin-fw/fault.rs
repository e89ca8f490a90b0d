//! Safe faults: a panic, a HardFault and a stack overflow all end here.
//!
//! A stack overflow is a HardFault too: the stack sits at the bottom of
//! SRAM, below the statics (`memory-f4x1.x`), so a push past its end
//! leaves SRAM at 0x2000_0000 for the reserved space below it (RM0383 and
//! RM0368 §2.3, memory map), instead of overwriting the statics the way a
//! stack growing down onto them did. There, an MPU region without access
//! (set in `__pre_init` below) makes every access a MemManage fault,
//! escalated to the HardFault: the core's rule (PM0214 §4.2), so it does
//! not depend on how the bus answers reserved addresses. A frame larger
//! than the 32 KiB guard could still skip it; the largest is init's, about
//! 6.3 KB on the F401 image.
//!
//! Whatever went wrong, the first stores are the ones that keep people and
//! machines safe: spindle and laser PWM to 0 and forced inactive, spindle
//! enable and coolant low, stepper drivers to their `$4` "off" level; then
//! the step timer stops. These are plain stores to fixed register
//! addresses: nothing here formats, allocates, takes a lock or calls the
//! HAL, and the words are computed before the fault ([`publish`]). Then
//! the core waits for the watchdog (about 4 s, `WATCHDOG_MS`) or a probe.
//!
//! None of this is a safety function: the e-stop input, these handlers and
//! the watchdog are firmware. A real e-stop cuts the drivers' and the
//! spindle's power in hardware (README, Wiring).
use crate::boards::board;
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// The GPIOB BSRR word that turns spindle enable, flood and mist off and
/// puts the stepper-enable pin at its "drivers off" level under the
/// current `$4`. Boot value: `$4=0` (active-low enable, the default).
static OFF_WORD: AtomicU32 = AtomicU32::new(board::outputs_off_word(false));

/// Parse task (every pass) and init: the `$4` polarity the fault path
/// must use, as one precomputed word.
pub fn publish(enable_active_high: bool) {
    OFF_WORD.store(board::outputs_off_word(enable_active_high), Relaxed);
}

/// A panic turns the outputs and drivers off first, then formats
/// nothing: the message and the panic locations (build paths) cost
/// kilobytes of flash, and the debug probe's backtrace says where it
/// happened. `udf` raises the HardFault, whose handler stops the step
/// timer and waits for the watchdog (or the probe).
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // Masked first (one instruction, no memory access), so no interrupt
    // can turn a driver or the spindle back on between the stores.
    cortex_m::interrupt::disable();
    outputs_off();
    defmt::error!("panic");
    cortex_m::asm::udf()
}

/// Everything that moves or burns off: one GPIOB store, two TIM1 stores.
#[inline(always)]
pub fn outputs_off() {
    board::outputs_off(OFF_WORD.load(Relaxed));
}

/// The rest of a fault, after [`outputs_off`]: no more step interrupts,
/// the timer stopped, and wait (QEMU: report, see `boards/qemu.rs`).
fn stop(sp: u32) -> ! {
    outputs_off();
    board::stop_step_timer();
    board::report_fault(sp);
    loop {
        cortex_m::asm::wfi();
    }
}

/// Entered from `HardFault` below on a fresh stack; `sp` is the stack
/// pointer the fault came with (below SRAM after an overflow).
#[no_mangle]
extern "C" fn burin_hard_fault(sp: u32) -> ! {
    stop(sp)
}

// The HardFault vector (cortex-m-rt takes a global `HardFault` in place of
// its default loop). A HardFault from a stack overflow arrives with SP
// below SRAM, so the handler must not push before it moves SP: it masks
// interrupts, points MSP at the top of the stack (nothing returns from
// here, so what was there is dead) and only then enters Rust. No
// trampoline and no exception-frame argument: the probe reads those.
core::arch::global_asm!(
    ".section .text.HardFault,\"ax\",%progbits",
    ".global HardFault",
    ".type HardFault,%function",
    ".thumb_func",
    "HardFault:",
    "cpsid i",
    "mrs r0, msp",
    "ldr r1, =_stack_start",
    "msr msp, r1",
    "isb",
    "b {entry}",
    ".ltorg",
    ".size HardFault, . - HardFault",
    entry = sym burin_hard_fault,
);

// After a reset the core starts with interrupts enabled and nothing armed.
// After a DFU `:leave`, the ROM bootloader jumps here with its own SysTick
// and NVIC lines possibly still armed, and cortex-m-rt's set-vtor points
// them at this image's table before RAM is initialised: an interrupt then
// would run a handler on unzeroed statics. cortex-m-rt calls `__pre_init`
// first thing after VTOR: mask interrupts (RTIC unmasks them after init),
// stop SysTick, disable and unpend every NVIC line (RTIC enables its own),
// and clear a pending SysTick/PendSV. Then the stack guard below SRAM. No
// stack, no RAM.
core::arch::global_asm!(
    ".section .text.__pre_init,\"ax\",%progbits",
    ".global __pre_init",
    ".type __pre_init,%function",
    ".thumb_func",
    "__pre_init:",
    "cpsid i",
    // SYST_CSR: counter and its interrupt off.
    "ldr r0, =0xE000E010",
    "movs r1, #0",
    "str r1, [r0]",
    // NVIC_ICER0..7, then NVIC_ICPR0..7: all ones.
    "mvn r1, #0",
    "ldr r0, =0xE000E180",
    "movs r2, #8",
    "1:",
    "str r1, [r0, #0x100]",
    "str r1, [r0], #4",
    "subs r2, #1",
    "bne 1b",
    // SCB_ICSR: PENDSTCLR | PENDSVCLR.
    "ldr r0, =0xE000ED04",
    "ldr r1, =0x0A000000",
    "str r1, [r0]",
    // MPU (PM0214 §4.2): region 0 = the 32 KiB below SRAM, 0x1FFF_8000 to
    // 0x1FFF_FFFF, no access (RASR: XN, AP=000, SIZE=14, ENABLE), over the
    // default map (CTRL: PRIVDEFENA | ENABLE). The stack's overflow side
    // then faults by the core's own rule, whatever the bus does with the
    // reserved addresses. Nothing of the app lives there (the unique ID is
    // at 0x1FFF_7A10, below it).
    "ldr r0, =0xE000ED98",
    "movs r1, #0",
    "str r1, [r0]",
    "ldr r1, =0x1FFF8000",
    "str r1, [r0, #4]",
    "ldr r1, =0x1000001D",
    "str r1, [r0, #8]",
    "movs r1, #5",
    "str r1, [r0, #-4]",
    "dsb",
    "isb",
    "bx lr",
    ".ltorg",
    ".size __pre_init, . - __pre_init",
);
