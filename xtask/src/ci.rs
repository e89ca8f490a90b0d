//! `cargo xtask ci`: every check, in the order docs/testing.md lists. CI runs
//! exactly this (`.ci/run`), so a green local run means a green CI run.

use crate::util::{cargo, ensure_target, run, TARGET};
use anyhow::Result;
use std::time::Instant;

/// Seconds each fuzz target runs in CI (6 targets; the budget is tight).
const FUZZ_CI_SECS: u64 = 15;

pub fn run_all() -> Result<i32> {
    let started = Instant::now();
    // The senders' installs (PyPI, apt, npm: mostly waiting on the network)
    // run beside the builds; the senders step joins them.
    let senders_ready = std::thread::spawn(|| {
        let t = Instant::now();
        (crate::senders::prepare(), t.elapsed())
    });
    step("toolchain: thumb target", ensure_target)?;
    step("cargo fmt --check", || {
        run(cargo().args(["fmt", "--all", "--check"]))
    })?;
    step("clippy (host crates)", || {
        run(cargo().args([
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ]))
    })?;
    for board in crate::image::Board::ALL {
        step(&format!("clippy (firmware, {TARGET}, {board})"), || {
            run(cargo()
                .args([
                    "clippy", "-p", "firmware", "--target", TARGET, "--lib", "--bins",
                ])
                .args(board.cargo_features())
                .args(["--", "-D", "warnings"]))
        })?;
    }
    step(
        &format!("clippy (firmware, {TARGET}, qemu + bench-target)"),
        || {
            run(cargo()
                .args(["clippy", "-p", "firmware", "--target", TARGET, "--bins"])
                .args([
                    "--no-default-features",
                    "--features",
                    "board-qemu,bench-target",
                ])
                .args(["--", "-D", "warnings"]))
        },
    )?;
    // Docs are part of the product: a broken intra-doc link fails here.
    step("cargo doc (-D warnings)", || {
        run(cargo()
            .args(["doc", "--workspace", "--no-deps"])
            .env("RUSTDOCFLAGS", "-D warnings"))
    })?;
    step(
        "minimum Rust version: no package used needs newer (cargo metadata)",
        crate::msrv::check,
    )?;
    // The corpus tests run in their own step below, visibly.
    step("host tests", || {
        run(cargo().args(["test", "--workspace", "--", "--skip", "corpus_"]))
    })?;
    for board in crate::image::Board::ALL {
        step(&format!("firmware image + size budget ({board})"), || {
            crate::image::ci_check(board)
        })?;
    }
    step("corpus conformance (../shared/corpus)", corpus)?;
    // Fetches LinuxCNC's rs274 from Debian into target/ the first time;
    // says "skipped" when that is not possible.
    step("rs274 conformance (LinuxCNC): cargo xtask rs274", || {
        crate::rs274::run(true)
    })?;
    // Skipped (not failed) without nightly or cargo-fuzz; fails on a finding.
    step(
        &format!("fuzz: every target {FUZZ_CI_SECS} s (cargo xtask fuzz)"),
        || crate::fuzz::ci_step(FUZZ_CI_SECS),
    )?;
    step(
        "firmware under QEMU (netduinoplus2): cargo xtask qemu",
        || match crate::qemu::run()? {
            0 => Ok(()),
            code => anyhow::bail!("qemu test exited {code}"),
        },
    )?;
    // The on-target goals (issue 28): red when one is missed, naming it.
    step(
        "on-target goals under QEMU: cargo xtask bench-target",
        crate::bench_target::ci_step,
    )?;
    step(
        "third-party senders on sim --pty: cargo xtask senders",
        || {
            let (ready, took) = senders_ready
                .join()
                .map_err(|_| anyhow::anyhow!("the senders' installs panicked"))?;
            eprintln!(
                "senders: installs took {:.1} s beside the steps before",
                took.as_secs_f64()
            );
            match crate::senders::run_with(&ready)? {
                0 => Ok(()),
                code => anyhow::bail!("senders check exited {code}"),
            }
        },
    )?;
    eprintln!(
        "\n== ci: all checks passed in {:.0} s ==",
        started.elapsed().as_secs_f64()
    );
    Ok(0)
}

/// The third-party corpus is not in the repo; it sits beside the clone when
/// there is one. Its checks print a line per file, so they run visible here.
fn corpus() -> Result<()> {
    let dir = crate::util::root().join("../shared/corpus");
    if !dir.is_dir() {
        eprintln!("corpus conformance: skipped ({} not found)", dir.display());
        return Ok(());
    }
    // `--workspace`, as in the host-test step: the same features, so the
    // test binaries built there are reused instead of rebuilt. The suites
    // holding them: firmware/tests/gcode (conformance.rs) and
    // host-sim/tests/sim (corpus.rs).
    run(cargo().args([
        "test",
        "--workspace",
        "--test",
        "gcode",
        "--test",
        "sim",
        "--",
        "corpus_",
        "--nocapture",
    ]))
}

/// Run one named step, timing it, so a CI log reads as a list of checks.
fn step(name: &str, f: impl FnOnce() -> Result<()>) -> Result<()> {
    eprintln!("\n== ci: {name} ==");
    let t = Instant::now();
    let r = f();
    match &r {
        Ok(()) => eprintln!("== ci: {name}: ok ({:.1} s) ==", t.elapsed().as_secs_f64()),
        Err(e) => eprintln!("== ci: {name}: FAILED: {e:#} =="),
    }
    r
}
