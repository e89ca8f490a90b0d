//! `cargo xtask sim`: run a job on the host simulator (the firmware's own
//! motion core under a virtual timer), or only check it with `--check`.

use anyhow::{Context, Result};
use host_sim::config::MachineConfig;
use host_sim::outputs::{simulate, Outputs};
use std::path::PathBuf;

/// The bundled demo job, run when no file is given.
const DEMO: &str = include_str!("../../host-sim/jobs/demo.gcode");

#[derive(clap::Args)]
pub struct SimArgs {
    /// G-code job (default: the bundled demo, host-sim/jobs/demo.gcode).
    pub file: Option<PathBuf>,
    /// Machine description (TOML); default: host-sim/machines/default.toml's values.
    #[arg(long, value_name = "FILE")]
    pub machine: Option<PathBuf>,
    /// Parse and interpret only, no motion: one `FILE:LINE:COL: error[CODE]: message` per error.
    #[arg(long)]
    pub check: bool,
    /// With --check: also print each emitted command as one JSON object per line.
    #[arg(long, requires = "check")]
    pub dump: bool,
    /// Write the run summary as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Write a CSV trace `tick,X,Y,Z,A` (one row per step event).
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Write the step/dir pins as a VCD waveform.
    #[arg(long, value_name = "FILE")]
    pub vcd: Option<PathBuf>,
    /// Draw commanded vs stepped path and the velocity profile as SVG.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Run a virtual device on a pseudo-terminal instead of a job: prints the
    /// device path (e.g. /dev/pts/7) as the first line, then runs until killed.
    /// Speaks GRBL text and the native protocol, like the board's USB port.
    #[arg(long, conflicts_with_all = ["file", "check", "json", "trace", "vcd", "plot"])]
    pub pty: bool,
    /// With --pty: run N times faster than real time.
    #[arg(long, value_name = "N", default_value_t = 1.0, requires = "pty")]
    pub speed: f64,
}

pub fn run(a: SimArgs) -> Result<i32> {
    if a.pty {
        let cfg = match &a.machine {
            Some(p) => MachineConfig::load(p).map_err(|e| anyhow::anyhow!("{e}"))?,
            None => MachineConfig::default(),
        };
        host_sim::pty::run(&cfg, a.speed, |path| {
            use std::io::Write;
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "{path}");
            let _ = out.flush();
        })?;
        return Ok(0);
    }
    let (name, source) = match &a.file {
        Some(p) => (
            p.display().to_string(),
            std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?,
        ),
        None => ("host-sim/jobs/demo.gcode".to_string(), DEMO.to_string()),
    };
    let cfg = match &a.machine {
        Some(p) => MachineConfig::load(p).map_err(|e| anyhow::anyhow!("{e}"))?,
        None => MachineConfig::default(),
    };
    if a.check {
        let mut out = std::io::stdout().lock();
        let errors = host_sim::check::check_file(&name, &source, a.dump, &cfg.settings, &mut out)?;
        if errors > 0 {
            eprintln!("{name}: {errors} error(s)");
            return Ok(1);
        }
        return Ok(0);
    }
    let outputs = Outputs {
        json: a.json,
        trace: a.trace,
        vcd: a.vcd,
        plot: a.plot,
    };
    let summary = simulate(&cfg, &source, &name, &outputs)?;
    host_sim::report::print_summary(std::io::stdout().lock(), &cfg.run_info(), &summary, &name)?;
    for (label, path) in [
        ("json", &outputs.json),
        ("trace", &outputs.trace),
        ("vcd", &outputs.vcd),
        ("plot", &outputs.plot),
    ] {
        if let Some(p) = path {
            println!("  wrote {label:<6} {}", p.display());
        }
    }
    Ok(if summary.errors.is_empty() { 0 } else { 1 })
}
