//! The cycle model on hand-made instruction streams.
use super::*;
use std::collections::HashMap;

fn run(chip: &Chip, prog: &[(u32, &str, &str, u8)], trace: &[(u32, [u32; 16])], ret: u32) -> u64 {
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
