//! Fault drills and boot levels on QEMU: the app boots with stored
//! `$2`/`$3`/`$4` inverts and then faults on purpose (a panic, a HardFault,
//! a stack overflow), each in its own QEMU run. QEMU's generic loader puts
//! the two request words in SRAM outside the linker's RAM
//! (`boards/qemu.rs`), so the image is the one the job test runs.
//!
//! What the drills read: the line the fault path prints on USART1 after its
//! stores (the stack pointer the fault came with, CFSR, TIM5's CR1/DIER),
//! and QEMU's log of stores to the peripherals it does not implement
//! (`-d unimp`: GPIOB and TIM1 are among them), which shows every GPIOB
//! and TIM1 store in order: the motion pins' levels from the first store
//! that makes them outputs, and the fault path's stores at the end.
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// Addresses and words `boards/qemu.rs` reads.
const DRILL_ADDR: u32 = 0x2001_FFFC;
const BOOT_ADDR: u32 = 0x2001_FFF8;
/// The stored inverts the drills boot with: `$2=5` (X and Z step pins
/// rest high), `$3=3`, `$4=1` (drivers enabled by a high level).
const STEP_INVERT: u32 = 0b0101;
const DIR_INVERT: u32 = 0b0011;
const BOOT_WORD: u32 = 0x5E77_0000 | STEP_INVERT | (DIR_INVERT << 4) | (1 << 8);

#[derive(Clone, Copy, Debug)]
pub enum Drill {
    Panic,
    HardFault,
    Overflow,
}

impl Drill {
    pub const ALL: [Drill; 3] = [Drill::Panic, Drill::HardFault, Drill::Overflow];
    fn word(self) -> u32 {
        0xFA17_0000
            + match self {
                Drill::Panic => 1,
                Drill::HardFault => 2,
                Drill::Overflow => 3,
            }
    }
}

/// QEMU's arguments for one drill: the request words and the store log.
pub fn args(drill: Drill, log: &Path) -> Vec<String> {
    vec![
        "-device".into(),
        format!(
            "loader,addr={DRILL_ADDR:#x},data={:#x},data-len=4",
            drill.word()
        ),
        "-device".into(),
        format!("loader,addr={BOOT_ADDR:#x},data={BOOT_WORD:#x},data-len=4"),
        "-d".into(),
        "unimp".into(),
        "-D".into(),
        log.display().to_string(),
    ]
}

/// The fault path's report line: `FAULT sp=… cfsr=… bfar=… tim5_cr1=… tim5_dier=…`.
#[derive(Debug, PartialEq)]
pub struct Report {
    pub sp: u32,
    pub cfsr: u32,
    pub tim5_cr1: u32,
    pub tim5_dier: u32,
}

pub fn report(text: &str) -> Option<Report> {
    let line = text.lines().find(|l| l.starts_with("FAULT "))?;
    let field = |name: &str| {
        line.split_whitespace()
            .find_map(|f| f.strip_prefix(name)?.strip_prefix('='))
            .and_then(|v| u32::from_str_radix(v, 16).ok())
    };
    Some(Report {
        sp: field("sp")?,
        cfsr: field("cfsr")?,
        tim5_cr1: field("tim5_cr1")?,
        tim5_dier: field("tim5_dier")?,
    })
}

/// CFSR bits (PM0214 §4.4.12): UsageFault UNDEFINSTR; MemManage DACCVIOL,
/// MSTKERR; BusFault PRECISERR, STKERR.
const UNDEFINSTR: u32 = 1 << 16;
const MEM_OR_BUS_STACK: u32 = (1 << 1) | (1 << 4) | (1 << 9) | (1 << 12);

/// Checks one drill's report and store log.
pub fn check(drill: Drill, r: &Report, log: &str) -> Result<()> {
    if r.tim5_cr1 & 1 != 0 || r.tim5_dier != 0 {
        bail!("{drill:?}: the step timer still runs after the fault: {r:?}");
    }
    match drill {
        Drill::Panic | Drill::HardFault if r.cfsr & UNDEFINSTR == 0 => {
            bail!("{drill:?}: not the udf HardFault: {r:?}")
        }
        Drill::Overflow if r.sp >= 0x2000_0000 || r.cfsr & MEM_OR_BUS_STACK == 0 => {
            bail!("overflow: the fault did not come from below SRAM: {r:?}")
        }
        _ => {}
    }
    let stores = stores(log);
    check_boot_levels(&stores)?;
    check_fault_stores(&stores)
}

/// One logged store to an unimplemented device.
#[derive(Debug, PartialEq)]
pub struct Store {
    pub device: String,
    pub offset: u32,
    pub value: u32,
}

/// QEMU's `unimplemented device write` lines, in order.
pub fn stores(log: &str) -> Vec<Store> {
    log.lines()
        .filter_map(|l| {
            let (device, rest) = l.split_once(": unimplemented device write")?;
            let num = |key: &str| {
                let v = rest.split(key).nth(1)?.split([',', ')']).next()?.trim();
                u32::from_str_radix(v.trim_start_matches("0x"), 16).ok()
            };
            Some(Store {
                device: device.trim().to_ascii_uppercase(),
                offset: num("offset ")?,
                value: num("value ")?,
            })
        })
        .collect()
}

fn is_gpiob(s: &Store) -> bool {
    s.device.ends_with("GPIOB")
}

/// The Black Pill's step and dir pins on GPIOB, X Y Z A B C
/// (`boards/blackpill.rs`' `PORT_PINS`).
const STEP_PINS: [u32; 6] = [12, 13, 14, 15, 3, 10];
const DIR_PINS: [u32; 6] = [4, 5, 6, 7, 1, 9];

/// Motion pins on GPIOB and their idle level under the drills' inverts:
/// step (`$2`), dir (`$3`), enable PB8 (off = low with `$4=1`).
fn idle_levels() -> Vec<(u32, bool)> {
    let mut pins = Vec::new();
    for axis in 0..6 {
        pins.push((STEP_PINS[axis], STEP_INVERT & (1 << axis) != 0));
        pins.push((DIR_PINS[axis], DIR_INVERT & (1 << axis) != 0));
    }
    pins.push((8, false));
    pins
}

/// From the store that makes a motion pin an output (MODER = 01) on,
/// until the fault path's own stores, the pin stays at its idle level; ODR
/// starts at 0 (its reset value) and BSRR stores move it.
pub fn check_boot_levels(stores: &[Store]) -> Result<()> {
    const BSRR: u32 = 0x18;
    let mut level = [false; 16];
    let mut output = [false; 16];
    let last_gpiob = stores.iter().rposition(is_gpiob).unwrap_or(0);
    for (i, s) in stores.iter().enumerate().filter(|(_, s)| is_gpiob(s)) {
        if i == last_gpiob {
            break; // the fault path's store, checked on its own
        }
        if s.offset == BSRR {
            // Set wins over reset in one BSRR store (RM0383 §8.4.7).
            for (pin, high) in level.iter_mut().enumerate() {
                if s.value & (1 << pin) != 0 {
                    *high = true;
                } else if s.value & (1 << (pin + 16)) != 0 {
                    *high = false;
                }
            }
        }
        if s.offset == 0 {
            for (pin, _) in idle_levels() {
                output[pin as usize] |= (s.value >> (2 * pin)) & 0b11 == 0b01;
            }
        }
        for (pin, idle) in idle_levels() {
            if output[pin as usize] && level[pin as usize] != idle {
                bail!(
                    "PB{pin} is an output at the wrong level ({}, idle is {}) after GPIOB \
                     store #{i} {s:?}",
                    level[pin as usize],
                    idle
                );
            }
        }
    }
    if idle_levels().iter().any(|&(pin, _)| !output[pin as usize]) {
        bail!("the log shows no MODER store making every motion pin an output");
    }
    Ok(())
}

/// The last GPIOB store is the fault path's: spindle enable (PB0) and
/// (with `$4=1`) the enable pin reset; the last GPIOA store resets flood
/// and mist (PA7, PA9); the last TIM1 stores put CCR1 to 0 and force OC1
/// inactive.
pub fn check_fault_stores(stores: &[Store]) -> Result<()> {
    const OFF: u32 = (1 << 16) | (1 << (16 + 8));
    const OFF_A: u32 = (1 << (16 + 7)) | (1 << (16 + 9));
    let gpiob = stores.iter().rfind(|s| is_gpiob(s));
    if gpiob.map(|s| (s.offset, s.value)) != Some((0x18, OFF)) {
        bail!("the last GPIOB store is {gpiob:?}, not the fault path's BSRR {OFF:#010x}");
    }
    let gpioa = stores.iter().rfind(|s| s.device.ends_with("GPIOA"));
    if gpioa.map(|s| (s.offset, s.value)) != Some((0x18, OFF_A)) {
        bail!("the last GPIOA store is {gpioa:?}, not the fault path's BSRR {OFF_A:#010x}");
    }
    let tim1: Vec<&Store> = stores
        .iter()
        .filter(|s| s.device.ends_with("TIM1") || s.device.ends_with("TIMER[1]"))
        .collect();
    let ccr1 = tim1.iter().rfind(|s| s.offset == 0x34).map(|s| s.value);
    let ccmr1 = tim1.iter().rfind(|s| s.offset == 0x18).map(|s| s.value);
    if ccr1 != Some(0) || ccmr1.is_none_or(|v| (v >> 4) & 0b111 != 0b100) {
        bail!(
            "TIM1 after the fault: CCR1 {ccr1:?}, CCMR1 {ccmr1:?} (want 0 and OC1M force inactive)"
        );
    }
    Ok(())
}

/// Runs `cmd` (QEMU with [`args`]) until the fault line appears on USART1,
/// then stops it and returns what USART1 said.
pub fn run_until_fault(cmd: Command, timeout: Duration) -> Result<String> {
    let (guard, rx) = super::spawn(cmd)?;
    let end = Instant::now() + timeout;
    let mut seen = Vec::new();
    while !String::from_utf8_lossy(&seen).contains("tim5_dier=") || !seen.ends_with(b"\n") {
        let left = end.saturating_duration_since(Instant::now());
        if left.is_zero() {
            bail!(
                "no fault report within {timeout:?}; USART1 said {:?}",
                String::from_utf8_lossy(&seen)
            );
        }
        if let Ok(chunk) = rx.recv_timeout(left.min(Duration::from_millis(100))) {
            seen.extend(chunk);
        }
    }
    drop(guard);
    String::from_utf8(seen).context("USART1 output is not UTF-8")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(device: &str, offset: u32, value: u32) -> String {
        format!("{device}: unimplemented device write (size 4, offset 0x{offset:03x}, value 0x{value:08x})")
    }

    fn moder_all_outputs() -> String {
        let mut v = 0;
        for (pin, _) in idle_levels() {
            v |= 1 << (2 * pin);
        }
        w("GPIOB", 0, v)
    }

    #[test]
    fn reads_the_report_and_the_log() {
        let r = report("ok\r\nFAULT sp=1ffffff0 cfsr=00000082 bfar=1ffffff0 tim5_cr1=00000000 tim5_dier=00000000\r\n");
        assert_eq!(
            r,
            Some(Report {
                sp: 0x1fff_fff0,
                cfsr: 0x82,
                tim5_cr1: 0,
                tim5_dier: 0
            })
        );
        let log = [
            w("GPIOB", 0x18, 0x1000),
            "GPIOB: unimplemented device read (size 4, offset 0x000)".into(),
        ]
        .join("\n");
        assert_eq!(
            stores(&log),
            vec![Store {
                device: "GPIOB".into(),
                offset: 0x18,
                value: 0x1000
            }]
        );
    }

    #[test]
    fn boot_levels_catch_an_output_switched_before_its_level() {
        // Idle levels first (X, Z step high; X, Y dir high; enable low), then
        // the switch to outputs, then the fault path's store: passes.
        let idle = (1 << 12) | (1 << 14) | (1 << 4) | (1 << 5) | (1 << (8 + 16));
        let fault = w("GPIOB", 0x18, 0x0701_0000);
        let good = [w("GPIOB", 0x18, idle), moder_all_outputs(), fault.clone()].join("\n");
        assert!(check_boot_levels(&stores(&good)).is_ok());
        // The HAL's plain `into_push_pull_output` drives low first: X step
        // is an output at low, then raised (the edge a driver counts).
        let bad = [moder_all_outputs(), w("GPIOB", 0x18, idle), fault.clone()].join("\n");
        assert!(check_boot_levels(&stores(&bad)).is_err());
        // A later store of the default levels (no inverts) is caught too.
        let later = [
            w("GPIOB", 0x18, idle),
            moder_all_outputs(),
            w("GPIOB", 0x18, 1 << 8),
            fault,
        ]
        .join("\n");
        assert!(check_boot_levels(&stores(&later)).is_err());
    }

    #[test]
    fn fault_stores_must_come_last() {
        let ok = [
            w("GPIOB", 0x18, 0x0101_0000),
            w("GPIOA", 0x18, 0x0280_0000),
            w("TIM1", 0x34, 0),
            w("TIM1", 0x18, 0x48),
        ]
        .join("\n");
        assert!(check_fault_stores(&stores(&ok)).is_ok());
        // Drivers left on (PB8 not reset under `$4=1`).
        let on = [
            w("GPIOB", 0x18, 0x0001_0000),
            w("GPIOA", 0x18, 0x0280_0000),
            w("TIM1", 0x34, 0),
            w("TIM1", 0x18, 0x48),
        ]
        .join("\n");
        assert!(check_fault_stores(&stores(&on)).is_err());
        // Coolant left on (mist, PA9, not reset).
        let mist = [
            w("GPIOB", 0x18, 0x0101_0000),
            w("GPIOA", 0x18, 0x0080_0000),
            w("TIM1", 0x34, 0),
            w("TIM1", 0x18, 0x48),
        ]
        .join("\n");
        assert!(check_fault_stores(&stores(&mist)).is_err());
        // PWM only set to 0, not forced.
        let pwm = [
            w("GPIOB", 0x18, 0x0101_0000),
            w("GPIOA", 0x18, 0x0280_0000),
            w("TIM1", 0x34, 0),
            w("TIM1", 0x18, 0x68),
        ]
        .join("\n");
        assert!(check_fault_stores(&stores(&pwm)).is_err());
    }
}
