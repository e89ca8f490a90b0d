//! What the model knows of an instruction: its cost class from the
//! mnemonic, and the registers and address of a load or store.

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
pub(super) fn reg_list(ops: &str) -> (Vec<usize>, u32) {
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
pub(super) fn address(insn: &Insn, pc: u32, regs: &[u32; 16]) -> Option<(u32, Vec<usize>)> {
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
pub(super) fn load_dests(insn: &Insn) -> Vec<usize> {
    let head = insn.ops.split('[').next().unwrap_or("");
    head.split(',').filter_map(reg).collect()
}
