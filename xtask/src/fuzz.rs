//! `cargo xtask fuzz [TARGET] [--time S]`: coverage-guided fuzzing of the
//! targets in `firmware/fuzz/` (cargo-fuzz + libFuzzer, nightly). Installs
//! cargo-fuzz when missing, seeds each target from `../shared/corpus` (when
//! present) and the project's own jobs and test data, runs one target at a
//! time and prints executions, exec/s, coverage and findings per target.
//! `cargo xtask ci` runs it briefly (`ci_step`): skipped without nightly or
//! cargo-fuzz, failed on a finding.

use anyhow::{bail, Context, Result};
use clap::Args;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use crate::util::root;

#[derive(Args)]
pub struct FuzzArgs {
    /// One target (default: all, as many at once as there are cores).
    target: Option<String>,
    /// Seconds per target.
    #[arg(long, default_value_t = 60)]
    time: u64,
    /// Stop after this many executions per target (libFuzzer -runs).
    #[arg(long)]
    runs: Option<u64>,
}

/// What one run of one target did.
struct Outcome {
    target: String,
    execs: u64,
    rate: u64,
    cov: String,
    finding: Option<String>,
    secs: f64,
}

pub fn run(a: &FuzzArgs) -> Result<i32> {
    let targets = pick(a.target.as_deref())?;
    if let Some(why) = missing_tools(true) {
        bail!("cannot fuzz: {why}");
    }
    let outs = fuzz_all(&targets, a.time, a.runs)?;
    Ok(i32::from(outs.iter().any(|o| o.finding.is_some())))
}

/// The CI step: a short run of every target, "skipped" without the tools.
pub fn ci_step(secs: u64) -> Result<()> {
    if let Some(why) = missing_tools(false) {
        eprintln!("fuzz: skipped ({why})");
        return Ok(());
    }
    let targets = pick(None)?;
    let outs = fuzz_all(&targets, secs, None)?;
    if outs.iter().any(|o| o.finding.is_some()) {
        bail!("the fuzzer found an invariant violation (see above)");
    }
    Ok(())
}

fn pick(target: Option<&str>) -> Result<Vec<&'static str>> {
    let all: Vec<&str> = host_sim::fuzz::TARGETS.iter().map(|t| t.0).collect();
    match target {
        None => Ok(all),
        Some(t) => match all.iter().find(|a| **a == t) {
            Some(a) => Ok(vec![a]),
            None => bail!("no fuzz target {t:?}; targets: {}", all.join(", ")),
        },
    }
}

/// `cargo` through rustup on nightly, outside this xtask's toolchain.
fn nightly_cargo() -> Command {
    let mut c = Command::new("cargo");
    c.env("RUSTUP_TOOLCHAIN", "nightly")
        .env_remove("CARGO")
        .env_remove("RUSTC")
        .env_remove("RUSTDOC")
        .env_remove("CARGO_TARGET_DIR")
        .current_dir(root().join("firmware"));
    c
}

fn quiet_ok(c: &mut Command) -> bool {
    c.stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Why fuzzing cannot run here, if it cannot; installs cargo-fuzz when
/// missing (`install`: say so and try; CI tries too, quietly).
fn missing_tools(install: bool) -> Option<String> {
    if !quiet_ok(nightly_cargo().arg("--version")) {
        return Some("no nightly toolchain (rustup toolchain install nightly)".into());
    }
    if quiet_ok(nightly_cargo().args(["fuzz", "--version"])) {
        return None;
    }
    eprintln!("fuzz: cargo-fuzz missing, installing: cargo install cargo-fuzz --locked");
    let mut c = Command::new("cargo");
    c.args(["install", "cargo-fuzz", "--locked"])
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("CARGO");
    if !install {
        c.stdout(Stdio::null()).stderr(Stdio::null());
    }
    match c.status() {
        Ok(s) if s.success() => None,
        _ => Some(
            "cargo-fuzz is not installed and `cargo install cargo-fuzz --locked` failed \
             (no crates.io registry?)"
                .into(),
        ),
    }
}

fn fuzz_all(targets: &[&str], secs: u64, runs: Option<u64>) -> Result<Vec<Outcome>> {
    let t0 = Instant::now();
    build(targets)?;
    eprintln!("fuzz: built in {:.0} s", t0.elapsed().as_secs_f64());
    let mut seeds = Vec::new();
    for t in targets {
        seeds.push(crate::fuzz_seeds::write(t)?);
    }
    // libFuzzer runs on one core: as many targets at once as there are
    // cores, each for its full time (CI's 2 cores: 3 rounds, not 6).
    let order: Vec<usize> = (0..targets.len()).collect();
    let outs = host_sim::par::each_core(&order, |i| fuzz_one(targets[i], &seeds[i], secs, runs))
        .into_iter()
        .collect::<Result<Vec<Outcome>>>()?;
    eprintln!(
        "\n{:<16} {:>12} {:>9} {:>8} {:>7}  finding",
        "target", "execs", "exec/s", "cov", "secs"
    );
    for o in &outs {
        eprintln!(
            "{:<16} {:>12} {:>9} {:>8} {:>7.0}  {}",
            o.target,
            o.execs,
            o.rate,
            o.cov,
            o.secs,
            o.finding.as_deref().unwrap_or("none")
        );
    }
    Ok(outs)
}

fn build(targets: &[&str]) -> Result<()> {
    let mut c = nightly_cargo();
    c.args(["fuzz", "build", "--sanitizer", "none"]);
    if targets.len() == 1 {
        c.args(targets);
    }
    crate::util::run(&mut c)
}

fn fuzz_one(target: &str, seeds: &Path, secs: u64, runs: Option<u64>) -> Result<Outcome> {
    let fuzz = root().join("firmware/fuzz");
    let corpus = fuzz.join("corpus").join(target);
    std::fs::create_dir_all(&corpus)?;
    let mut c = nightly_cargo();
    c.args(["fuzz", "run", "--sanitizer", "none", target])
        .arg(&corpus)
        .arg(seeds)
        .arg("--")
        .arg(format!("-max_total_time={secs}"))
        .args(["-print_final_stats=1", "-timeout=20", "-rss_limit_mb=4096"])
        .arg(format!("-max_len={}", max_len(target)))
        .arg("-print_pcs=0");
    if let Some(r) = runs {
        c.arg(format!("-runs={r}"));
    }
    eprintln!(
        "\n== fuzz {target}: {secs} s ==\n$ {}",
        crate::util::show(&c)
    );
    let t = Instant::now();
    let out = c
        .stdout(Stdio::inherit())
        .stderr(Stdio::piped())
        .output()
        .context("could not start cargo fuzz")?;
    let log = String::from_utf8_lossy(&out.stderr);
    let tail: Vec<&str> = log.lines().rev().take(60).collect();
    let stat = |key: &str| {
        log.lines()
            .find_map(|l| {
                l.strip_prefix(key)
                    .map(|v| v.trim().parse::<u64>().unwrap_or(0))
            })
            .unwrap_or(0)
    };
    let cov = log
        .lines()
        .rev()
        .filter_map(|l| l.split("cov: ").nth(1))
        .find_map(|r| r.split_whitespace().next())
        .unwrap_or("?")
        .to_string();
    let finding = if out.status.success() {
        None
    } else {
        // One lock for the whole tail: another target may be printing.
        let mut err = std::io::stderr().lock();
        for l in tail.iter().rev() {
            let _ = writeln!(err, "{l}");
        }
        let art = log
            .lines()
            .find_map(|l| l.split("Test unit written to ").nth(1))
            .map(str::to_string);
        let lines: Vec<&str> = log.lines().collect();
        let why = lines
            .iter()
            .position(|l| l.contains("panicked at"))
            .and_then(|i| lines.get(i + 1))
            .map_or(String::new(), |l| format!("{l}; "));
        Some(match art {
            Some(a) => format!(
                "{why}{a} (minimise, in firmware/: cargo +nightly fuzz tmin -s none {target} {a}; keep it in \
                 firmware/fuzz/regressions/{target}/)"
            ),
            None => format!("{why}cargo fuzz exited {}", out.status),
        })
    };
    Ok(Outcome {
        target: target.to_string(),
        execs: stat("stat::number_of_executed_units:"),
        rate: stat("stat::average_exec_per_sec:"),
        cov,
        finding,
        secs: t.elapsed().as_secs_f64(),
    })
}

/// Longest input per target: the machine targets spend virtual time per
/// byte, so shorter inputs keep their rate up.
fn max_len(target: &str) -> usize {
    match target {
        "gcode_line" => 512,
        // protocol_frames fell from 47,000 to 8,000 exec/s at 4 KB inputs
        // (the client part allocates per message).
        "device" | "executor" | "protocol_frames" => 1024,
        _ => 4096,
    }
}

/// Where a target's generated seeds go (outside the repo's tracked files).
pub fn seed_dir(target: &str) -> PathBuf {
    root().join("firmware/fuzz/seeds").join(target)
}
