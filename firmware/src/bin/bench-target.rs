//! On-target cost of the motion core's hot paths, run as real Cortex-M4F code
//! under `qemu-system-arm -M netduinoplus2 -icount shift=0` by
//! `cargo xtask bench-target`.
//!
//! How instructions are counted: with `-icount shift=0` QEMU advances its
//! virtual clock by exactly 2^0 = 1 ns per executed guest instruction, and
//! SysTick (core clock source) counts that virtual clock at the machine's
//! core frequency (168 MHz on netduinoplus2, so about 0.168 ticks per
//! instruction). Rather than trust that constant, the program calibrates: it
//! times a `subs`/`bne` loop written in assembly, run N times (exactly 2N
//! instructions), and divides. A metric is then
//! `(ticks − empty-measurement ticks) / ticks_per_insn / repetitions`. QEMU
//! counts instructions, not cycles.
//!
//! Cycles: the same ELF runs a second time with a word set at the stand-in
//! window's end (QEMU's loader device), and then only the step handler's
//! phases, with QEMU logging every instruction and the registers before
//! it; `cargo xtask bench-target` charges each executed instruction by
//! Cortex-M4 timings, bus and flash included (xtask/src/bench_target/).
//!
//! Output: one `name value` line per metric on the semihosting console, lines
//! starting with `#` are context; the exit status is 0 when all ran.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("bench-target runs under QEMU: use `cargo xtask bench-target`");
}

#[cfg(target_os = "none")]
#[path = "bench-target/bench.rs"]
mod bench;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn entry() -> ! {
    bench::run()
}

#[cfg(target_os = "none")]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    cortex_m_semihosting::hprintln!("# panic: {}", info);
    bench::exit(false)
}
