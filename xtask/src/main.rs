//! `cargo xtask …`: the project's one entry point for checks, images,
//! flashing, simulation and streaming.

mod bench_motion;
mod bench_target;
mod ci;
mod flash;
mod fuzz;
mod fuzz_seeds;
mod image;
mod imports;
mod msrv;
mod qemu;
mod rs274;
mod senders;
mod sim;
mod stream;
mod util;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "cargo xtask",
    about = "burin build, test, flash, sim and stream tasks"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Every check CI runs: fmt, clippy, tests, firmware images, size budget, corpus.
    Ci,
    /// Build the release firmware image and print its flash and RAM use.
    Build(image::BuildArgs),
    /// Build and flash the firmware (probe-rs, or DFU with --dfu).
    Flash(flash::FlashArgs),
    /// Run a G-code job on the host simulator (no file: the bundled demo).
    Sim(sim::SimArgs),
    /// Stream a job to a board (or to `sim --pty`).
    Stream(stream::StreamArgs),
    /// Run the real RTIC app on QEMU's netduinoplus2 and check its serial link.
    Qemu,
    /// Count the hot paths' Cortex-M4 instructions under QEMU (-icount shift=0).
    BenchTarget,
    /// Motion benchmark: job time vs the time-optimal bound and the axis limits (simulated time).
    BenchMotion(bench_motion::BenchMotionArgs),
    /// Real third-party senders (grbl-streamer, printcore, bCNC, cncjs) against `sim --pty`.
    Senders,
    /// Coverage-guided fuzzing (cargo-fuzz, nightly): all targets or one.
    Fuzz(fuzz::FuzzArgs),
    /// Compare the interpreter's end points with LinuxCNC's rs274 (corpus + own programs).
    /// Check the burin library's import rule: no module cycle, lib.rs order.
    Imports,
    Rs274 {
        /// Fetch rs274 from Debian into target/rs274 if it is not there.
        #[arg(long)]
        install: bool,
    },
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.cmd {
        Cmd::Ci => ci::run_all(),
        Cmd::Build(a) => image::run(&a),
        Cmd::Flash(a) => flash::run(&a),
        Cmd::Sim(a) => sim::run(a),
        Cmd::Stream(a) => stream::run(a),
        Cmd::Qemu => qemu::run(),
        Cmd::BenchTarget => bench_target::run(),
        Cmd::BenchMotion(a) => bench_motion::run(a),
        Cmd::Senders => senders::run(),
        Cmd::Fuzz(a) => fuzz::run(&a),
        Cmd::Imports => imports::run(),
        Cmd::Rs274 { install } => rs274::run(install).map(|()| 0),
    };
    match result {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::exit(1);
        }
    }
}
