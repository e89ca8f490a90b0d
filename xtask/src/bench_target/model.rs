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
/// 0x2001_F800), the chip's own map otherwise (`burin::chip`'s, the one
/// the board code is checked against; AHB2 costs as AHB1, anything off
/// the bus matrix as the core's own).
pub fn region(addr: u32) -> Region {
    use burin::chip::bus::Region as Map;
    match addr {
        0x2001_F000..=0x2001_F3FF => Region::Apb1,
        0x2001_F400..=0x2001_F7FF => Region::Ahb1,
        0x2001_F800..=0x2001_FBFF => Region::Apb2,
        _ => match burin::chip::Chip::F411.region(addr) {
            Map::Flash => Region::Flash,
            Map::Sram => Region::Sram,
            Map::Apb1 => Region::Apb1,
            Map::Apb2 => Region::Apb2,
            Map::Ahb1 | Map::Ahb2 => Region::Ahb1,
            Map::Other => Region::Core,
        },
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

mod insn;
use insn::{address, load_dests, reg_list};
pub use insn::{Insn, Kind};

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
mod tests;
