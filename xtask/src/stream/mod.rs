//! `cargo xtask stream`: send a job to a board (or to `cargo xtask sim
//! --pty`) over the native protocol, for the person at the machine: what
//! it does (messages, errors, alarms with their `FILE:LINE`), why it waits
//! and which key continues, keys for hold/resume/overrides/reset, and the
//! time left from a simulation of the job on the board's own settings.
//!
//! One file line is one job line, so a sequence number maps straight back
//! to `FILE:LINE`. The board is found by its USB VID/PID through sysfs,
//! not libudev, so the tool needs no system libraries.
//!
//! Exit codes (scripts and CI): 0 the job ran to its end without errors;
//! 1 it ran to its end but lines were rejected (or the link failed);
//! 2 an alarm stopped it; 3 the operator reset (aborted) it; 130 Ctrl-C.

mod board;
mod eta;
mod job;
mod keys;
mod pause;
mod report;
mod run;
mod summary;
mod term;
mod timeline;

use anyhow::{Context, Result};
use protocol::client::Client;
use protocol::MachineState;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Duration;

#[derive(clap::Args)]
pub struct StreamArgs {
    /// G-code job to stream.
    #[arg(required_unless_present = "eta_report")]
    pub file: Option<PathBuf>,
    /// Serial port (e.g. /dev/ttyACM0, or the path `cargo xtask sim --pty`
    /// prints). Default: the board with burin's USB VID/PID.
    #[arg(long)]
    pub port: Option<String>,
    /// Run the job in the device's check mode ($C): interpret, no motion.
    #[arg(long)]
    pub check: bool,
    /// Without a terminal, continue by itself at program pauses (M0, M1,
    /// M6) instead of waiting for the board's cycle start.
    #[arg(long)]
    pub resume_pauses: bool,
    /// Do not simulate the job first (no ETA from motion).
    #[arg(long)]
    pub no_eta: bool,
    /// Measure the ETA: stream every job in DIR to a fresh `sim --pty
    /// --speed N` and print, at 10/50/90 % of each, the ETA shown against
    /// the real time left.
    #[arg(long, value_name = "DIR", hide = true)]
    pub eta_report: Option<PathBuf>,
    /// With --eta-report: the virtual board's speed.
    #[arg(long, default_value_t = 20.0, hide = true)]
    pub speed: f64,
}

/// How a stream ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    Done,
    Alarm,
    Reset,
    Interrupted,
}

pub fn run(a: StreamArgs) -> Result<i32> {
    if let Some(dir) = &a.eta_report {
        return report::run(dir, a.speed);
    }
    let Some(file) = &a.file else {
        anyhow::bail!("no job file given")
    };
    let name = file.display().to_string();
    let source = std::fs::read_to_string(file).with_context(|| format!("reading {name}"))?;
    let port = match &a.port {
        Some(p) => p.clone(),
        None => board::find_board()?,
    };
    let interactive = std::io::stdin().is_terminal() && std::io::stderr().is_terminal();
    let opts = Options {
        check: a.check,
        resume_pauses: a.resume_pauses,
        eta: !a.no_eta && !a.check,
        interactive,
        status_every: Duration::from_millis(50),
    };
    let (outcome, s) = stream_file(&port, job::Job::new(name, &source), &source, &opts)?;
    Ok(match outcome {
        Outcome::Done if s.errors == 0 => 0,
        Outcome::Done => 1,
        Outcome::Alarm => 2,
        Outcome::Reset => 3,
        Outcome::Interrupted => 130,
    })
}

pub struct Options {
    pub check: bool,
    pub resume_pauses: bool,
    pub eta: bool,
    pub interactive: bool,
    pub status_every: Duration,
}

/// Stream one job to the board on `port`; prints the summary.
pub fn stream_file(
    port_name: &str,
    job: job::Job,
    source: &str,
    o: &Options,
) -> Result<(Outcome, summary::Summary)> {
    let port = serialport::new(port_name, 115_200)
        .timeout(Duration::from_millis(2))
        .open_native()
        .with_context(|| format!("opening {port_name}"))?;
    let mut client = Client::new(port);
    let info = client
        .connect(Duration::from_secs(3))
        .with_context(|| format!("handshake on {port_name}"))?;
    eprintln!(
        "{port_name}: burin {} on {}, {} line slots, {} planner blocks",
        info.firmware, info.board, info.line_slots, info.planner_blocks
    );
    if let Some(st) = board::query_status(&mut client)? {
        if st.state == MachineState::Alarm {
            eprintln!("{port_name}: the machine is in alarm; home ($H) or unlock ($X) it first");
            let _ = client.request(&protocol::HostMsg::Bye);
            return Ok((Outcome::Alarm, summary::Summary::default()));
        }
    }
    let eta = if o.eta {
        let settings = board::read_settings(&mut client)?;
        let profile = timeline::Profile::simulate(source, &settings);
        eprintln!(
            "{}: simulated on the board's settings: {} of motion",
            job.name,
            run::clock(profile.total_s)
        );
        Some(eta::Eta::new(profile))
    } else {
        None
    };
    let ui = term::Ui::new(job.lines.len(), o.interactive);
    let mut s = run::Stream::new(client, &job, &ui, eta);
    s.check = o.check;
    s.resume_pauses = o.resume_pauses;
    s.status_every = o.status_every;
    let outcome = s.run();
    let outcome = match outcome {
        Ok(x) => x,
        Err(e) => {
            ui.bar.abandon();
            return Err(e.context(port_name.to_string()));
        }
    };
    let sum = summary::finish(s, outcome)?;
    ui.bar.finish_and_clear();
    drop(ui);
    sum.print(&job);
    Ok((outcome, sum))
}
