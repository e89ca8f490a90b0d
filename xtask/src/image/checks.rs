//! Checks on the linked ELF: the RTIC tasks are in the vector table, and
//! nothing pulled core's float text code in.
use super::{parse, read};
use anyhow::{bail, Context, Result};
use object::read::elf::ElfFile32;
use object::{Object, ObjectSection, ObjectSymbol};
use std::path::Path;

/// Interrupts that must reach RTIC tasks, with their STM32F4 IRQ numbers.
pub const RTIC_IRQS: [(&str, u32); 2] = [("TIM5", 50), ("OTG_FS", 67)];

/// Checks that the vector table sends [`RTIC_IRQS`] to their RTIC handlers,
/// not to cortex-m-rt's `DefaultHandler` (what an unbound interrupt gets).
pub fn check_vectors(elf: &Path) -> Result<()> {
    let bytes = read(elf)?;
    let file = parse(&bytes)?;
    let default = symbol(&file, "DefaultHandler")?;
    let table = file
        .section_by_name(".vector_table")
        .context("no .vector_table section")?;
    let data = table.data().context("reading .vector_table")?;
    for (name, irq) in RTIC_IRQS {
        let at = 4 * (16 + irq as usize);
        let entry =
            word(data, at).with_context(|| format!("vector table too short for IRQ {irq}"))?;
        if entry & !1 == default & !1 {
            bail!("IRQ {irq} ({name}) points at DefaultHandler: the RTIC task is not bound");
        }
        let handler = symbol(&file, name)?;
        if entry & !1 != handler & !1 {
            bail!("IRQ {irq} ({name}) points at {entry:#010x}, not at the `{name}` handler");
        }
        println!("  vector IRQ {irq:>2} {name:<6} -> {entry:#010x} (RTIC task), DefaultHandler {default:#010x}");
    }
    Ok(())
}

/// The board's machine slot (`Machine::placeholder`, 11 KB) is all zero
/// bits and so in `.bss`: in `.data` its load image costs as much flash.
/// A field whose constant is not zero (a float default, an `Option` whose
/// `None` is a niche value) moves it back silently; this says so.
pub fn check_machine_slot_in_bss(elf: &Path) -> Result<()> {
    let bytes = read(elf)?;
    let file = parse(&bytes)?;
    let slot = file
        .symbols()
        .find(|s| s.name().is_ok_and(|n| n.contains("machine_slot")))
        .context("no machine_slot symbol")?;
    let section = slot
        .section_index()
        .and_then(|i| file.section_by_index(i).ok())
        .context("machine_slot has no section")?;
    let name = section.name().unwrap_or("?");
    if name != ".bss" {
        bail!(
            "the machine slot ({} B) is in {name}, not .bss: `Machine::placeholder` is not \
             all zero bits, and its load image costs that much flash",
            slot.size()
        );
    }
    Ok(())
}

/// Thumb `cpsid i`.
const CPSID_I: u16 = 0xB672;

/// The fault and boot layout the board code relies on (`fault.rs`,
/// `memory-*.x`): the stack at the bottom of SRAM with the statics above
/// it (an overflow faults instead of overwriting them); `__pre_init` (run
/// before RAM is set up, e.g. after a DFU `:leave`) and our `HardFault`
/// (not cortex-m-rt's loop) each mask interrupts as their first instruction.
pub fn check_fault_layout(elf: &Path) -> Result<()> {
    let bytes = read(elf)?;
    let file = parse(&bytes)?;
    let (bottom, top) = (symbol(&file, "_stack_end")?, symbol(&file, "_stack_start")?);
    let statics = symbol(&file, "__sdata")?;
    if bottom != super::RAM_BASE || top > statics {
        bail!(
            "the stack {bottom:#010x}..{top:#010x} is not at the bottom of SRAM below the \
             statics ({statics:#010x}): an overflow would overwrite them"
        );
    }
    for name in ["__pre_init", "HardFault"] {
        let at = symbol(&file, name)? & !1;
        let first = halfword_at(&file, at).with_context(|| format!("no code at `{name}`"))?;
        if first != CPSID_I {
            bail!("`{name}` at {at:#010x} starts with {first:#06x}, not `cpsid i`");
        }
    }
    if file.symbol_by_name("HardFault_").is_some_and(|d| {
        symbol(&file, "HardFault").is_ok_and(|h| h & !1 == d.address() as u32 & !1)
    }) {
        bail!("HardFault is cortex-m-rt's default loop, not the fault path");
    }
    println!(
        "  stack {} B at {bottom:#010x}..{top:#010x} below the statics; __pre_init and \
         HardFault start with cpsid i",
        top - bottom
    );
    Ok(())
}

/// The 16-bit word of loaded code at `addr`.
fn halfword_at(file: &ElfFile32<'_>, addr: u32) -> Option<u16> {
    file.sections().find_map(|s| {
        let start = u32::try_from(s.address()).ok()?;
        let off = addr.checked_sub(start)? as usize;
        let data = s.data().ok()?;
        let b = data.get(off..off + 2)?;
        Some(u16::from_le_bytes([b[0], b[1]]))
    })
}

pub(super) fn symbol(file: &ElfFile32<'_>, name: &str) -> Result<u32> {
    let sym = file
        .symbol_by_name(name)
        .with_context(|| format!("no symbol `{name}` in the ELF"))?;
    u32::try_from(sym.address()).context("symbol address beyond 32 bits")
}

pub(super) fn word(data: &[u8], at: usize) -> Option<u32> {
    let b = data.get(at..at + 4)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Symbol name parts of core's float parsing and printing. burin has its
/// own (`burin::num`); one stray `{}` of an f32, `str::parse::<f32>` or
/// `f32::clamp` (its assertion prints floats) links 10-25 KB of these.
const FLOAT_TEXT: [&str; 3] = ["flt2dec", "dec2flt", "float_to_decimal"];

/// Refuses an image that contains core's float parsing or printing.
pub fn check_no_float_text(elf: &Path) -> Result<()> {
    refuse_symbols(
        elf,
        float_text,
        "core's float text code",
        "use burin::num instead of float Display/FromStr/clamp",
    )
}

/// Fails, naming up to five of them, when the image has symbols `bad`
/// picks out.
fn refuse_symbols(elf: &Path, bad: fn(&str) -> bool, what: &str, advice: &str) -> Result<()> {
    let bytes = read(elf)?;
    let file = parse(&bytes)?;
    let found = matching(file.symbols().filter_map(|s| s.name().ok()), bad);
    if !found.is_empty() {
        bail!("{what} is linked in ({}): {advice}", found.join(", "));
    }
    Ok(())
}

fn matching<'a>(names: impl Iterator<Item = &'a str>, bad: fn(&str) -> bool) -> Vec<&'a str> {
    names.filter(|n| bad(n)).take(5).collect()
}

fn float_text(name: &str) -> bool {
    FLOAT_TEXT.iter().any(|part| name.contains(part))
}

/// Whether a symbol is soft-float `f64` arithmetic (compiler-builtins'
/// `__adddf3`, `__muldf3`, `__divdf3`, conversions and compares, under
/// their ARM EABI names too). The FPU is single precision: one `f64` in
/// the core (libm's `sinf`, `asinf` and `hypotf` compute in it) costs
/// 3-8 KB of these and tens of cycles per operation.
fn soft_double(name: &str) -> bool {
    let eabi = name.strip_prefix("__aeabi_");
    name.ends_with("df3")
        || name.contains("dfsf")
        || name.contains("sfdf")
        || eabi.is_some_and(|e| e.starts_with('d') && e != "dmb" || e.ends_with("2d"))
}

/// Refuses an image that computes in `f64`.
pub fn check_no_soft_double(elf: &Path) -> Result<()> {
    refuse_symbols(
        elf,
        soft_double,
        "soft-float f64 code",
        "keep the core in f32 (burin::num::trig, not libm's sinf/cosf/tanf/asinf/hypotf)",
    )
}

#[cfg(test)]
mod tests {
    use super::{float_text, matching, soft_double};

    fn float_text_symbols<'a>(names: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
        matching(names, float_text)
    }

    #[test]
    fn finds_soft_double_symbols() {
        for n in [
            "__adddf3",
            "__aeabi_dmul",
            "__aeabi_d2f",
            "__aeabi_f2d",
            "__truncdfsf2",
        ] {
            assert!(soft_double(n), "{n}");
        }
        for n in [
            "__aeabi_fmul",
            "__aeabi_uldivmod",
            "__aeabi_memcpy",
            "__floatuntisf",
            "sqrtf",
        ] {
            assert!(!soft_double(n), "{n}");
        }
    }

    #[test]
    fn finds_float_text_symbols_by_mangled_name() {
        let names = [
            "_ZN4core3num7flt2dec8strategy5grisu19format_shortest_opt17h1E",
            "_ZN5burin3num11write_fixed17h2E",
            "_ZN4core3num7dec2flt60_$LT$impl$u20$core..str..traits..FromStr$u20$for$u20$f32$GT$8from_str17h3E",
        ];
        let found = float_text_symbols(names.into_iter());
        assert_eq!(found.len(), 2);
        assert!(found.iter().all(|n| n.contains("core3num")));
    }
}
