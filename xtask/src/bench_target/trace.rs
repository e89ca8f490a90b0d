//! The trace run: bench-target under QEMU with every executed instruction
//! logged together with the registers before it, cut into step handler
//! invocations by the guest's markers, and the ELF's disassembly to tell
//! what each executed address is.
//!
//! How: `-d cpu,nochain` with one instruction per translation block
//! (`-singlestep` on QEMU 7.x, `-one-insn-per-tb` from 8.1) makes QEMU
//! dump R0-R15 before every instruction it runs; R15 is the PC. The
//! loader device writes a non-zero word at the stand-ins' trace flag, so
//! the guest runs only the step phases (`trace_run` in bench.rs). The
//! disassembler is `arm-none-eabi-objdump` (Debian's
//! binutils-arm-none-eabi, installed when missing and root) or any
//! `llvm-objdump`.
use super::model::Insn;
use crate::{qemu, util};
use anyhow::{bail, Context, Result};
use std::collections::HashMap;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// Address of the trace flag word in the stand-in window (bench.rs `regs`).
const TRACE_FLAG: u32 = 0x2001_FFFC;

/// One executed instruction: its address and the registers before it.
#[derive(Clone, Copy, Debug)]
pub struct Step {
    pub pc: u32,
    pub regs: [u32; 16],
}

/// One step handler run: the phase tag, its kind (1 a rise, 2 a fall)
/// and the instructions from the handler's first to its return.
#[derive(Debug)]
pub struct Invocation {
    pub tag: u32,
    pub kind: u32,
    pub steps: Vec<Step>,
    /// Where it returned to (the instruction after the last one).
    pub ret: u32,
}

/// The ELF's instructions by address and its function symbols.
pub struct Image {
    pub insns: HashMap<u32, Insn>,
    pub funcs: Vec<(u32, String)>,
}

impl Image {
    fn func(&self, name: &str) -> Result<u32> {
        self.funcs
            .iter()
            .find(|(_, n)| n == name)
            .map(|(a, _)| *a)
            .with_context(|| format!("no symbol `{name}` in the bench-target ELF"))
    }
}

/// The disassembler on PATH, installed (Debian `binutils-arm-none-eabi`)
/// when none is and this is root. `None`: none can be had (say skipped).
pub fn objdump() -> Option<String> {
    let llvm = || {
        std::iter::once("llvm-objdump".to_string())
            .chain((13..=22).rev().map(|v| format!("llvm-objdump-{v}")))
            .find(|t| util::have(t))
    };
    if util::have("arm-none-eabi-objdump") {
        return Some("arm-none-eabi-objdump".into());
    }
    if let Some(t) = llvm() {
        return Some(t);
    }
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if root {
        let install = || {
            util::run(
                Command::new("apt-get")
                    .env("DEBIAN_FRONTEND", "noninteractive")
                    .args(["install", "-y", "binutils-arm-none-eabi"]),
            )
        };
        if install().is_err() {
            let _ = util::run(Command::new("apt-get").arg("update"));
            let _ = install();
        }
    }
    util::have("arm-none-eabi-objdump").then(|| "arm-none-eabi-objdump".into())
}

/// Disassembles `elf` with `tool`.
pub fn disassemble(tool: &str, elf: &Path) -> Result<Image> {
    let out = Command::new(tool)
        .arg("-d")
        .arg(elf)
        .output()
        .with_context(|| format!("running {tool}"))?;
    if !out.status.success() {
        bail!("{tool} -d failed: {}", String::from_utf8_lossy(&out.stderr));
    }
    Ok(parse_disassembly(&String::from_utf8_lossy(&out.stdout)))
}

/// GNU (`8000404:\tf000 f83c \tbl\t...`) and LLVM
/// (` 8000404: 00 f0 3c f8  \tbl\t...`) listings alike: the size is the
/// encoding's hex digits / 2, the mnemonic the next word, the operands
/// the rest up to a comment (`;` or `@`).
pub fn parse_disassembly(text: &str) -> Image {
    let mut insns = HashMap::new();
    let mut funcs = Vec::new();
    for line in text.lines() {
        if let Some((addr, rest)) = line.split_once(" <") {
            if let (Ok(a), Some(name)) = (
                u32::from_str_radix(addr.trim(), 16),
                rest.strip_suffix(">:"),
            ) {
                funcs.push((a, name.to_string()));
                continue;
            }
        }
        let Some((addr, rest)) = line.split_once(':') else {
            continue;
        };
        let Ok(addr) = u32::from_str_radix(addr.trim(), 16) else {
            continue;
        };
        if !line.starts_with(' ') && !line.starts_with('\t') {
            continue;
        }
        let mut digits = 0;
        let mut words = rest.split_whitespace().peekable();
        while let Some(w) = words.peek() {
            let hex = w.chars().all(|c| c.is_ascii_hexdigit());
            if hex && (w.len() == 2 || w.len() == 4) && digits < 8 {
                digits += w.len();
                words.next();
            } else {
                break;
            }
        }
        let Some(mnem) = words.next() else { continue };
        if digits == 0 || mnem.starts_with('.') || mnem.starts_with('<') {
            continue;
        }
        let ops: Vec<&str> = words.collect();
        let ops = ops.join(" ");
        let ops = ops
            .split([';', '@'])
            .next()
            .unwrap_or("")
            .trim()
            .to_string();
        insns.insert(addr, Insn::new(mnem, &ops, (digits / 2) as u8));
    }
    Image { insns, funcs }
}

/// QEMU's switch for one instruction per translation block.
fn one_insn_flag() -> Vec<&'static str> {
    let v = Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_default();
    let ver: Vec<u32> = v
        .split_whitespace()
        .nth(3)
        .unwrap_or("7.2")
        .split('.')
        .filter_map(|p| p.parse().ok())
        .collect();
    if ver.first().copied().unwrap_or(7) * 100 + ver.get(1).copied().unwrap_or(0) >= 801 {
        vec!["-one-insn-per-tb"]
    } else {
        vec!["-singlestep"]
    }
}

/// Runs the trace run of `elf` and cuts the log into the step handler's
/// invocations (kind 0, the untimed ones, dropped).
pub fn run(elf: &Path, image: &Image) -> Result<Vec<Invocation>> {
    let log = elf.with_extension("trace.log");
    let _ = std::fs::remove_file(&log);
    let mut cmd = qemu::command(elf);
    cmd.args(one_insn_flag());
    cmd.args(["-d", "cpu,nochain", "-D"]).arg(&log);
    cmd.arg("-device")
        .arg(format!("loader,addr={TRACE_FLAG:#x},data=1,data-len=4"));
    let out = qemu::run_to_exit(cmd, Duration::from_secs(300))?;
    if !out.contains("# trace run done") {
        bail!("the trace run did not finish: {out}");
    }
    let begin = image.func("burin_trace_begin")?;
    let end = image.func("burin_trace_end")?;
    let isrs: Vec<u32> = image
        .funcs
        .iter()
        .filter(|(_, n)| n.contains("5bench3isr") || n.contains("bench::isr"))
        .map(|(a, _)| *a)
        .collect();
    if isrs.is_empty() {
        bail!("no `bench::isr` function in the ELF");
    }
    let file = std::fs::File::open(&log).with_context(|| format!("opening {}", log.display()))?;
    let mut cut = Cutter::new(begin, end, isrs);
    let mut regs = [0u32; 16];
    for line in BufReader::new(file).lines() {
        let line = line?;
        if !line.starts_with('R') {
            continue;
        }
        let mut pc_seen = false;
        for field in line.split_whitespace() {
            let Some((name, value)) = field.split_once('=') else {
                continue;
            };
            let (Some(n), Ok(v)) = (
                name.strip_prefix('R').and_then(|n| n.parse::<usize>().ok()),
                u32::from_str_radix(value, 16),
            ) else {
                continue;
            };
            if n < 16 {
                regs[n] = v;
                pc_seen |= n == 15;
            }
        }
        if pc_seen {
            cut.push(Step { pc: regs[15], regs });
        }
    }
    let _ = std::fs::remove_file(&log);
    Ok(cut.done)
}

/// Cuts the instruction stream at the markers.
struct Cutter {
    begin: u32,
    end: u32,
    isrs: Vec<u32>,
    tag: Option<u32>,
    current: Option<Invocation>,
    finished: Option<Invocation>,
    done: Vec<Invocation>,
}

impl Cutter {
    fn new(begin: u32, end: u32, isrs: Vec<u32>) -> Self {
        Cutter {
            begin,
            end,
            isrs,
            tag: None,
            current: None,
            finished: None,
            done: Vec::new(),
        }
    }

    fn push(&mut self, s: Step) {
        if let Some(inv) = &mut self.current {
            if s.pc == inv.ret {
                self.finished = self.current.take();
            } else {
                inv.steps.push(s);
            }
            return;
        }
        if s.pc == self.begin {
            self.tag = Some(s.regs[0]);
            self.finished = None;
        } else if s.pc == self.end {
            if let Some(mut inv) = self.finished.take() {
                inv.kind = s.regs[0];
                if inv.kind != 0 {
                    self.done.push(inv);
                }
            }
            self.tag = None;
        } else if let Some(tag) = self.tag {
            if self.isrs.contains(&s.pc) && self.finished.is_none() {
                self.current = Some(Invocation {
                    tag,
                    kind: 0,
                    steps: vec![s],
                    ret: s.regs[14] & !1,
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_gnu_and_llvm_listings() {
        let gnu = "08000400 <foo>:\n 8000400:\tb580      \tpush\t{r7, lr}\n 8000402:\tf000 f83c \tbl\t8000480 <bar>\n 8000406:\t4a02      \tldr\tr2, [pc, #8]\t; (8000410 <foo+0x10>)\n";
        let llvm = "08000400 <foo>:\n 8000400: 80 b5        \tpush\t{r7, lr}\n 8000402: 00 f0 3c f8  \tbl\t0x8000480 <bar> @ imm = #120\n 8000406: 02 4a        \tldr\tr2, [pc, #8]\n";
        for text in [gnu, llvm] {
            let img = parse_disassembly(text);
            assert_eq!(img.funcs, vec![(0x0800_0400, "foo".to_string())]);
            assert_eq!(img.insns[&0x0800_0400].size, 2);
            assert_eq!(img.insns[&0x0800_0402].size, 4);
            assert_eq!(img.insns[&0x0800_0402].mnem, "bl");
            assert_eq!(img.insns[&0x0800_0406].ops, "r2, [pc, #8]");
        }
    }

    #[test]
    fn cuts_at_the_markers() {
        let step = |pc, r0, lr| {
            let mut regs = [0; 16];
            regs[0] = r0;
            regs[14] = lr;
            regs[15] = pc;
            Step { pc, regs }
        };
        let mut c = Cutter::new(0x100, 0x200, vec![0x300]);
        for s in [
            step(0x100, 3, 0),    // begin(3)
            step(0x50, 0, 0),     // harness
            step(0x300, 0, 0x55), // isr entry, returns to 0x54
            step(0x302, 0, 0x55), // isr
            step(0x54, 0, 0),     // back in the harness
            step(0x200, 1, 0),    // end(1): kept
            step(0x100, 3, 0),    // begin(3)
            step(0x300, 0, 0x55), // isr
            step(0x54, 0, 0),     // back
            step(0x200, 0, 0),    // end(0): dropped
        ] {
            c.push(s);
        }
        assert_eq!(c.done.len(), 1);
        assert_eq!(c.done[0].tag, 3);
        assert_eq!(c.done[0].kind, 1);
        assert_eq!(c.done[0].steps.len(), 2);
        assert_eq!(c.done[0].ret, 0x54);
    }
}
