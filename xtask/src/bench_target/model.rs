//! Cycles of executed Cortex-M4 instructions on the F411 and F401, from
//! the trace run's instruction stream (address, registers before it).
//!
//! The figures and their basis (ARM Cortex-M4 TRM r0p1 §3.3, table 3-1,
//! "Cortex-M4 instruction set summary", and its notes; RM0383 §3.4 and
//! RM0368 §3.4 for the flash and its ART accelerator; RM0383/RM0368 §6.2
//! clock tree and §2.1 bus matrix):
//!
//! - data processing, IT, CPS, MRS/MSR: 1 cycle;
//! - MUL, UMULL, SMULL, UMLAL, SMLAL 1, MLA and MLS 2 (TRM);
//! - UDIV/SDIV: 2 to 12, data-dependent and undocumented beyond that: the
//!   worst case, 12, is charged;
//! - LDR (single, any width): 2, or 1 when it follows another single load
//!   and its address does not use that load's result (TRM note: neighbouring
//!   loads pipeline their address and data phases; nothing pipelines after a
//!   store); LDRD 3;
//! - STR: 1 (the write buffer takes the data phase); STRD 2; a store or
//!   load on the system bus waits while the write buffer still holds a
//!   store to a slow peripheral (below);
//! - LDM/POP and STM/PUSH: 1 + N registers; VLDM/VSTM/VPUSH/VPOP 1 + N
//!   words; VLDR/VSTR 2 (3 for a D register);
//! - branches taken: 1 + P, P the pipeline refill, 1 to 3 (TRM): P = 2,
//!   3 when the target is a 32-bit instruction that is not word-aligned
//!   (its fetch needs two words); not taken 1; TBB/TBH 2 + P; a load into
//!   PC (POP {.., pc}, LDR pc) adds P as well;
//! - VFP: VADD/VSUB/VMUL/VCVT/VCMP/VMOV/VMRS/VNEG/VABS 1, VMOV of two core
//!   registers 2, VMLA/VMLS/VFMA/VFMS and their negations 3, VDIV/VSQRT 14;
//! - exception entry 12 and exit 12 (TRM §3.3.3, zero-wait memory; a
//!   tail-chain would be 6, but the step path is one interrupt per step,
//!   its two in the QEMU build are a pulse width apart). The vector read
//!   comes from flash: + the wait states (ART data cache assumed cold).
//!
//! Peripheral accesses, by the stand-in register's address (bench.rs
//! `regs`; real peripheral addresses are classed the same way):
//!
//! - APB: an AHB-APB bridge transfer is two PCLK cycles (AMBA APB: setup
//!   and access phase) plus one HCLK to cross the bridge: a read stalls
//!   `2 x HCLK/PCLK + 1` cycles beyond the LDR's own 2. APB1 runs at
//!   HCLK/2 on both boards (48 MHz of 96, 42 of 84; its limit is 50 MHz),
//!   so a TIM5 read costs 2 + 5 = 7; APB2 at HCLK (TIM1): 2 + 3 = 5. A
//!   store occupies the bus as long, in the write buffer: the core goes
//!   on, but its next system-bus access (SRAM stack and data included)
//!   waits until the store is through;
//! - AHB1 (GPIO): 2 cycles more than SRAM for a read (bus matrix and the
//!   port), a store keeps the bus 2 cycles.
//!
//! Flash (RM0383/RM0368 §3.4, ART accelerator): 3 wait states at 96 MHz
//! (F411, 2.7-3.6 V), 2 at 84 MHz (F401); a 128-bit line holds 4 to 8
//! instructions; the prefetch buffer reads the next line while the current
//! one executes; the instruction cache holds 64 lines of 128 bits, the data
//! cache (literal pools) 8. The assumption, because between two steps the
//! planner task runs thousands of instructions of its own and nothing shows
//! the step path's lines survive: every 16-byte line is cold at the
//! handler's entry. Within one handler run a line, once fetched, hits
//! (the handler touches far fewer than 64). So a taken branch (or the
//! entry) to a line not yet touched costs the wait states; a line reached
//! by running on costs what the prefetch has not hidden: the wait states
//! plus 1, minus the cycles spent since the previous line was entered; a
//! literal load from a line not yet read costs the wait states. The
//! "warm" figure assumes every line hits (no wait state at all).
//!
//! Only DWT.CYCCNT on a board settles any of this; the model is meant to
//! err high.
use std::collections::HashSet;

/// One clock configuration of a board.
#[derive(Clone, Copy, Debug)]
pub struct Chip {
    pub hz: f64,
    /// Flash wait states at `hz` (RM0383 table 6 / RM0368 table 6).
    pub ws: u32,
    /// HCLK / PCLK1 and HCLK / PCLK2.
    pub apb1_div: u32,
    pub apb2_div: u32,
    /// Every flash line hits the ART caches.
    pub warm: bool,
}

pub const F411: Chip = Chip {
    hz: 96.0e6,
    ws: 3,
    apb1_div: 2,
    apb2_div: 1,
    warm: false,
};
pub const F401: Chip = Chip {
    hz: 84.0e6,
    ws: 2,
    apb1_div: 2,
    apb2_div: 1,
    warm: false,
};

/// What a memory address is, for its cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Region {
    Flash,
    Sram,
    Apb1,
    Apb2,
    Ahb1,
    /// Core peripherals (SysTick, NVIC): no bus matrix.
    Core,
}

/// The region of `addr`: the bench's stand-in blocks by their roles
/// (TIM5 at 0x2001_F000, the GPIO port at 0x2001_F400, TIM1 at
/// 0x2001_F800), the chip's own map otherwise.
pub fn region(addr: u32) -> Region {
    match addr {
        0x2001_F000..=0x2001_F3FF => Region::Apb1,
        0x2001_F400..=0x2001_F7FF => Region::Ahb1,
        0x2001_F800..=0x2001_FBFF => Region::Apb2,
        0x0000_0000..=0x1FFF_FFFF => Region::Flash,
        0x2000_0000..=0x3FFF_FFFF => Region::Sram,
        0x4000_0000..=0x4000_FFFF => Region::Apb1,
        0x4001_0000..=0x4001_FFFF => Region::Apb2,
        0x4002_0000..=0x5FFF_FFFF => Region::Ahb1,
        _ => Region::Core,
    }
}

impl Chip {
    /// Cycles a read of `r` stalls beyond the load's own.
    fn read_stall(&self, r: Region) -> u32 {
        match r {
            Region::Apb1 => 2 * self.apb1_div + 1,
            Region::Apb2 => 2 * self.apb2_div + 1,
            Region::Ahb1 => 2,
            _ => 0,
        }
    }
    /// Cycles a store to `r` keeps the bus after it issued.
    fn write_busy(&self, r: Region) -> u32 {
        match r {
            Region::Apb1 => 2 * self.apb1_div + 1,
            Region::Apb2 => 2 * self.apb2_div + 1,
            Region::Ahb1 => 2,
            _ => 0,
        }
    }
    fn flash_ws(&self) -> u32 {
        if self.warm {
            0
        } else {
            self.ws
        }
    }
}

/// What the cost depends on, from the mnemonic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Alu(u32),
    Load {
        words: u32,
    },
    Store {
        words: u32,
    },
    LoadMulti,
    StoreMulti,
    Branch,
    TableBranch,
    /// VLDR/VSTR and VLDM/VSTM/VPUSH/VPOP.
    VLoad,
    VStore,
}

/// A disassembled instruction.
#[derive(Clone, Debug)]
pub struct Insn {
    /// Mnemonic without width (`.w`/`.n`), flag-setting `s` and condition.
    pub mnem: String,
    pub ops: String,
    pub size: u8,
    pub kind: Kind,
}

const CONDS: [&str; 16] = [
    "eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt", "le",
];

fn kind_of(m: &str, ops: &str) -> Option<Kind> {
    let vfp_single = |m: &str| {
        let base = m.split('.').next().unwrap_or(m);
        match base {
            "vadd" | "vsub" | "vmul" | "vnmul" | "vneg" | "vabs" | "vcmp" | "vcmpe" | "vmrs"
            | "vmsr" | "vcvt" | "vcvtr" | "vsel" => Some(1),
            "vmov" => Some(if ops.matches(',').count() >= 3 { 2 } else { 1 }),
            "vmla" | "vmls" | "vnmla" | "vnmls" | "vfma" | "vfms" | "vfnma" | "vfnms" => Some(3),
            "vdiv" | "vsqrt" => Some(14),
            _ => None,
        }
    };
    let base = m.split('.').next().unwrap_or(m);
    Some(match base {
        "b" | "bl" | "bx" | "blx" | "cbz" | "cbnz" => Kind::Branch,
        "tbb" | "tbh" => Kind::TableBranch,
        "ldr" | "ldrb" | "ldrh" | "ldrsb" | "ldrsh" | "ldrex" | "ldrexb" | "ldrexh" | "ldrt" => {
            Kind::Load { words: 1 }
        }
        "ldrd" => Kind::Load { words: 2 },
        "str" | "strb" | "strh" | "strex" | "strexb" | "strexh" | "strt" => {
            Kind::Store { words: 1 }
        }
        "strd" => Kind::Store { words: 2 },
        "ldm" | "ldmia" | "ldmfd" | "ldmdb" | "pop" => Kind::LoadMulti,
        "stm" | "stmia" | "stmea" | "stmdb" | "stmfd" | "push" => Kind::StoreMulti,
        "vldr" | "vldm" | "vldmia" | "vldmdb" | "vpop" => Kind::VLoad,
        "vstr" | "vstm" | "vstmia" | "vstmdb" | "vpush" => Kind::VStore,
        "mul" | "umull" | "smull" | "umlal" | "smlal" => Kind::Alu(1),
        "mla" | "mls" => Kind::Alu(2),
        "sdiv" | "udiv" => Kind::Alu(12),
        _ if base.starts_with('v') => Kind::Alu(vfp_single(m)?),
        _ => return None,
    })
}

/// Data processing and the rest that costs one cycle: recognised so an
/// unknown mnemonic can be reported rather than silently charged 1.
const ONE_CYCLE: &[&str] = &[
    "add", "adc", "sub", "sbc", "rsb", "mov", "movw", "movt", "mvn", "cmp", "cmn", "tst", "teq",
    "and", "orr", "orn", "eor", "bic", "lsl", "lsr", "asr", "ror", "rrx", "neg", "mul", "uxtb",
    "uxth", "sxtb", "sxth", "uxtab", "uxtah", "sxtab", "sxtah", "ubfx", "sbfx", "bfi", "bfc",
    "clz", "rbit", "rev", "rev16", "revsh", "adr", "it", "ite", "itt", "itte", "ittt", "itet",
    "itee", "iteee", "ittee", "ittte", "itett", "iteet", "itete", "ittet", "itttt", "nop", "cpsid",
    "cpsie", "mrs", "msr", "dmb", "dsb", "isb", "bkpt", "svc", "wfi", "wfe", "sev", "usat", "ssat",
    "qadd", "qsub", "sel", "uadd8", "usub8", "uqsub8", "uqadd8", "udf",
];

impl Insn {
    pub fn new(mnem: &str, ops: &str, size: u8) -> Self {
        let m = mnem.to_ascii_lowercase();
        let m = m
            .strip_suffix(".w")
            .or_else(|| m.strip_suffix(".n"))
            .unwrap_or(&m)
            .to_string();
        let known = |b: &str| kind_of(b, ops).is_some() || ONE_CYCLE.contains(&b);
        let mut candidates = vec![m.clone()];
        if let Some(b) = m.strip_suffix('s') {
            candidates.push(b.to_string());
        }
        for c in CONDS {
            if let Some(b) = m.strip_suffix(c) {
                candidates.push(b.to_string());
                if let Some(b2) = b.strip_suffix('s') {
                    candidates.push(b2.to_string());
                }
            }
        }
        let base = candidates
            .into_iter()
            .find(|b| !b.is_empty() && known(b))
            .unwrap_or(m);
        let kind = kind_of(&base, ops).unwrap_or(Kind::Alu(1));
        Insn {
            mnem: base,
            ops: ops.to_string(),
            size,
            kind,
        }
    }

    pub fn is_known(&self) -> bool {
        kind_of(&self.mnem, &self.ops).is_some() || ONE_CYCLE.contains(&self.mnem.as_str())
    }
}

/// A register name's number (`sp`, `lr`, `pc` and the GNU aliases too).
fn reg(name: &str) -> Option<usize> {
    let n = name.trim().trim_end_matches('!').to_ascii_lowercase();
    Some(match n.as_str() {
        "sp" => 13,
        "lr" => 14,
        "pc" => 15,
        "ip" => 12,
        "fp" => 11,
        "sl" => 10,
        "sb" => 9,
        _ => {
            let d: usize = n.strip_prefix('r')?.parse().ok()?;
            if d > 15 {
                return None;
            }
            d
        }
    })
}

/// Registers of a `{..}` list and how many words they are (D registers 2).
fn reg_list(ops: &str) -> (Vec<usize>, u32) {
    let inner = ops
        .split_once('{')
        .and_then(|(_, r)| r.split_once('}'))
        .map(|(l, _)| l)
        .unwrap_or("");
    let mut regs = Vec::new();
    let mut words = 0;
    for item in inner.split(',') {
        let item = item.trim();
        let (a, b) = item.split_once('-').unwrap_or((item, item));
        let (a, b) = (a.trim(), b.trim());
        let width = if a.starts_with('d') { 2 } else { 1 };
        let num = |s: &str| {
            s.trim_start_matches(['r', 's', 'd'])
                .parse::<u32>()
                .ok()
                .or_else(|| reg(s).map(|r| r as u32))
        };
        match (num(a), num(b)) {
            (Some(x), Some(y)) if y >= x => {
                words += (y - x + 1) * width;
                if width == 1 && !a.starts_with('s') {
                    regs.extend((x..=y).map(|r| r as usize));
                }
            }
            _ => words += width,
        }
        if let Some(r) = reg(a) {
            if !regs.contains(&r) && a == b {
                regs.push(r);
            }
        }
    }
    regs.dedup();
    (regs, words)
}

/// The address a single load or store accesses, from the registers before
/// it, and the registers the address uses.
fn address(insn: &Insn, pc: u32, regs: &[u32; 16]) -> Option<(u32, Vec<usize>)> {
    let (_, rest) = insn.ops.split_once('[')?;
    let (inner, after) = rest.split_once(']')?;
    let parts: Vec<&str> = inner.split(',').map(str::trim).collect();
    let base = reg(parts.first()?)?;
    let mut used = vec![base];
    let base_val = if base == 15 {
        (pc + 4) & !3
    } else {
        regs[base]
    };
    // Post-indexed (`[rn], #4`): the access is at rn itself.
    if after.trim_start().starts_with(',') {
        return Some((base_val, used));
    }
    let mut addr = base_val;
    if let Some(off) = parts.get(1) {
        if let Some(imm) = off.strip_prefix('#') {
            let imm = imm.trim();
            let v = if let Some(h) = imm.strip_prefix("0x").or_else(|| imm.strip_prefix("-0x")) {
                i64::from_str_radix(h, 16).ok()? * if imm.starts_with('-') { -1 } else { 1 }
            } else {
                imm.parse::<i64>().ok()?
            };
            addr = (i64::from(base_val) + v) as u32;
        } else if let Some(r) = reg(off) {
            used.push(r);
            let shift = parts
                .get(2)
                .and_then(|s| s.strip_prefix("lsl"))
                .and_then(|s| s.trim().strip_prefix('#'))
                .and_then(|s| s.trim().parse::<u32>().ok())
                .unwrap_or(0);
            addr = base_val.wrapping_add(regs[r] << shift);
        }
    }
    Some((addr, used))
}

/// Destination registers of a single load (the operands before `[`).
fn load_dests(insn: &Insn) -> Vec<usize> {
    let head = insn.ops.split('[').next().unwrap_or("");
    head.split(',').filter_map(reg).collect()
}

/// The cost of one handler run on `chip`: `steps` are the executed
/// instructions with the registers before each, `ret` where it returned.
/// `unknown` collects mnemonics the model does not know (charged 1).
pub fn handler_cycles(
    chip: &Chip,
    steps: &[(u32, [u32; 16])],
    ret: u32,
    insn: impl Fn(u32) -> Option<Insn>,
    unknown: &mut HashSet<String>,
) -> u64 {
    handler_detail(chip, steps, ret, insn, unknown, &mut Vec::new())
}

/// [`handler_cycles`], and each instruction's address and cycles (its
/// fetch stall included) in `each`.
pub fn handler_detail(
    chip: &Chip,
    steps: &[(u32, [u32; 16])],
    ret: u32,
    insn: impl Fn(u32) -> Option<Insn>,
    unknown: &mut HashSet<String>,
    each: &mut Vec<(u32, u64)>,
) -> u64 {
    let ws = chip.flash_ws();
    // Exception entry and exit; the vector read from flash.
    let mut t: u64 = 12 + u64::from(ws);
    let mut wb_free: u64 = 0;
    let mut lines: HashSet<u32> = HashSet::new();
    let mut dlines: HashSet<u32> = HashSet::new();
    let mut line_entered: u64 = t;
    let mut prev_load: Option<Vec<usize>> = None;
    let mut taken_into = true;
    for (i, (pc, regs)) in steps.iter().enumerate() {
        let t0 = t;
        let Some(ins) = insn(*pc) else {
            unknown.insert(format!("<no instruction at {pc:#x}>"));
            t += 1;
            continue;
        };
        if !ins.is_known() {
            unknown.insert(ins.mnem.clone());
        }
        let next = steps.get(i + 1).map(|s| s.0).unwrap_or(ret);
        let taken = next != pc + u32::from(ins.size);
        // Fetch: each 16-byte line this instruction occupies.
        for line in [pc >> 4, (pc + u32::from(ins.size) - 1) >> 4] {
            if lines.insert(line) {
                let stall = if taken_into {
                    u64::from(ws)
                } else {
                    (u64::from(ws) + 1).saturating_sub(t - line_entered)
                };
                t += stall;
                line_entered = t;
            }
            taken_into = false;
        }
        let refill = |target: u32| -> u64 {
            let wide = insn(target).is_some_and(|t| t.size == 4);
            if wide && !target.is_multiple_of(4) {
                3
            } else {
                2
            }
        };
        // System-bus accesses wait for the write buffer (`wb_free`).
        let mut this_load = None;
        let cost: u64 = match ins.kind {
            Kind::Alu(c) => u64::from(c) + if taken { refill(next) } else { 0 },
            Kind::Branch | Kind::TableBranch => {
                let base = if ins.kind == Kind::TableBranch { 2 } else { 1 };
                base + if taken { refill(next) } else { 0 }
            }
            Kind::Load { words } => {
                let (addr, used) = address(&ins, *pc, regs).unwrap_or((0x2000_0000, vec![]));
                let r = region(addr);
                let pipelined = words == 1
                    && prev_load
                        .as_ref()
                        .is_some_and(|d| !used.iter().any(|u| d.contains(u)));
                let mut c = if words == 2 {
                    3
                } else if pipelined {
                    1
                } else {
                    2
                };
                if r == Region::Flash {
                    if dlines.insert(addr >> 4) {
                        c += u64::from(ws);
                    }
                } else {
                    c += wb_free.saturating_sub(t);
                }
                c += u64::from(chip.read_stall(r));
                this_load = Some(load_dests(&ins));
                if taken {
                    c += refill(next);
                }
                c
            }
            Kind::Store { words } => {
                let (addr, _) = address(&ins, *pc, regs).unwrap_or((0x2000_0000, vec![]));
                let r = region(addr);
                let c = u64::from(words) + wb_free.saturating_sub(t);
                wb_free = t + c + u64::from(chip.write_busy(r));
                c
            }
            Kind::LoadMulti | Kind::StoreMulti | Kind::VLoad | Kind::VStore => {
                let (regs_in, words) = reg_list(&ins.ops);
                let words = if ins.ops.contains('{') {
                    words
                } else if ins.ops.trim_start().starts_with('d') {
                    2
                } else {
                    1
                };
                let mut c = 1 + u64::from(words) + wb_free.saturating_sub(t);
                if regs_in.contains(&15) && taken {
                    c += refill(next);
                }
                c
            }
        };
        prev_load = this_load;
        t += cost;
        if taken {
            taken_into = true;
        }
        each.push((*pc, t - t0));
    }
    // Exception exit.
    t + 12
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn run(
        chip: &Chip,
        prog: &[(u32, &str, &str, u8)],
        trace: &[(u32, [u32; 16])],
        ret: u32,
    ) -> u64 {
        let map: HashMap<u32, Insn> = prog
            .iter()
            .map(|(a, m, o, s)| (*a, Insn::new(m, o, *s)))
            .collect();
        let mut unknown = HashSet::new();
        let c = handler_cycles(chip, trace, ret, |a| map.get(&a).cloned(), &mut unknown);
        assert!(unknown.is_empty(), "{unknown:?}");
        c
    }

    fn at(pc: u32, r0: u32) -> (u32, [u32; 16]) {
        let mut regs = [0; 16];
        regs[0] = r0;
        regs[1] = 0x2000_0100;
        (pc, regs)
    }

    const WARM: Chip = Chip { warm: true, ..F411 };

    #[test]
    fn mnemonics_lose_width_flags_and_condition() {
        assert_eq!(Insn::new("adds.w", "r0, #1", 4).mnem, "add");
        assert_eq!(
            Insn::new("ldrne", "r0, [r1]", 2).kind,
            Kind::Load { words: 1 }
        );
        assert_eq!(Insn::new("bne.w", "0x8000", 4).kind, Kind::Branch);
        assert_eq!(Insn::new("bls", "0x8000", 2).kind, Kind::Branch);
        assert_eq!(Insn::new("pop.w", "{r4, r5, pc}", 4).kind, Kind::LoadMulti);
        assert!(!Insn::new("frob", "", 2).is_known());
    }

    #[test]
    fn consecutive_loads_pipeline_unless_dependent() {
        // ldr r2,[r1]; ldr r3,[r1,#4]: 2 + 1. ldr r1,[r1]; ldr r3,[r1]: 2 + 2.
        let prog = [
            (0x100, "ldr", "r2, [r1]", 2),
            (0x102, "ldr", "r3, [r1, #4]", 2),
        ];
        let indep = run(&WARM, &prog, &[at(0x100, 0), at(0x102, 0)], 0x104);
        let prog = [
            (0x100, "ldr", "r1, [r1]", 2),
            (0x102, "ldr", "r3, [r1, #4]", 2),
        ];
        let dep = run(&WARM, &prog, &[at(0x100, 0), at(0x102, 0)], 0x104);
        assert_eq!(indep, 24 + 3);
        assert_eq!(dep, 24 + 4);
    }

    #[test]
    fn apb1_reads_stall_and_stores_hold_the_next_access() {
        // ldr r2, [r0] with r0 at the TIM5 stand-in: 2 + 5 on the F411.
        let prog = [(0x100, "ldr", "r2, [r0, #0x24]", 2)];
        let c = run(&WARM, &prog, &[at(0x100, 0x2001_F000)], 0x102);
        assert_eq!(c, 24 + 7);
        // str to APB1 then str to SRAM: 1, then waits 5 for the bus, + 1.
        let prog = [(0x100, "str", "r2, [r0]", 2), (0x102, "str", "r2, [r1]", 2)];
        let c = run(
            &WARM,
            &prog,
            &[at(0x100, 0x2001_F010), at(0x102, 0x2001_F010)],
            0x104,
        );
        assert_eq!(c, 24 + 1 + 5 + 1);
        // The same stores to SRAM: 1 + 1.
        let c = run(
            &WARM,
            &prog,
            &[at(0x100, 0x2000_0000), at(0x102, 0x2000_0000)],
            0x104,
        );
        assert_eq!(c, 24 + 2);
    }

    #[test]
    fn taken_branches_refill_and_cold_lines_cost_wait_states() {
        // b to 0x120 (16-bit target): 1 + 2; then a nop.
        let prog = [(0x100, "b", "0x120", 2), (0x120, "nop", "", 2)];
        let trace = [at(0x100, 0), at(0x120, 0)];
        assert_eq!(run(&WARM, &prog, &trace, 0x122), 24 + 3 + 1);
        // Cold: the entry line and the target line cost 3 each, the
        // vector read 3 more.
        assert_eq!(run(&F411, &prog, &trace, 0x122), 24 + 3 + 3 + 3 + 3 + 1);
        // A not-taken conditional branch: 1.
        let prog = [(0x100, "bne", "0x120", 2), (0x102, "nop", "", 2)];
        assert_eq!(
            run(&WARM, &prog, &[at(0x100, 0), at(0x102, 0)], 0x104),
            24 + 2
        );
    }

    #[test]
    fn pops_with_pc_and_pushes() {
        let prog = [
            (0x100, "push", "{r4, r5, r7, lr}", 2),
            (0x102, "pop", "{r4, r5, r7, pc}", 2),
        ];
        let c = run(&WARM, &prog, &[at(0x100, 0), at(0x102, 0)], 0x200);
        assert_eq!(c, 24 + 5 + 5 + 2);
    }
}
