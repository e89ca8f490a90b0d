//! `cargo xtask senders`: real third-party senders against `sim --pty`.
//!
//! Installs them from their registries into caches kept between runs
//! (`install`) and drives each through its own code with a small script in
//! `xtask/senders/` that streams `xtask/senders/job.gcode` (lines and arcs)
//! and checks the final position from a `?` status report:
//!
//! * `grbl-streamer` (PyPI; character-counting GRBL 1.1 streamer): also a
//!   hold, a check of `Hold`, a resume and feed overrides mid-job (its
//!   own and a realtime +10 % in the UTF-8 form bCNC and cncjs send);
//! * printcore (PyPI `printrun`, installed without its GUI dependencies):
//!   RepRap numbering, `M110`, checksums, and one damaged line that burin
//!   must ask for again (`Resend:`);
//! * bCNC (Debian `bcnc`): its `Sender` and GRBL1 controller without the Tk
//!   window: hold (`Hold`, no motion), resume (`Run`), the override slider
//!   (`C2 90`/`C2 91` on the wire, `Ov:110`), its end-of-job purge (`!`,
//!   Ctrl-X) keeping the position, then a `$J=` jog cancelled with 0x85
//!   (`C2 85`) short of its target;
//! * cncjs (npm): its server in-process, driven through the socket.io API
//!   its web page uses: the same hold, resume, override and jog cancel.
//!
//! A sender whose registry is out of reach says "skipped: why" and passes:
//! CI never fails for the network's sake. A failing one prints its
//! exchange with the device (bytes both ways).

use anyhow::Result;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::util::{root, target_dir};

mod install;
pub use install::prepare;

/// Where the job ends (machine coordinates, mm).
const WANT: &str = "-40,-30,-1";
const TIMEOUT: Duration = Duration::from_secs(240);

/// Run one driver (`cmd` already names its script and cache; the port,
/// the job and the wanted position follow); `Ok(line)` on success,
/// `Err(line)` otherwise. On failure its stderr (the exchange with the
/// device, a traceback, or faulthandler's dump of where it blocked) is
/// printed too, so a red run says why.
fn drive(
    mut cmd: Command,
    slug: &str,
    port: &str,
    job: &Path,
) -> std::result::Result<String, String> {
    let err_path = target_dir().join("senders").join(format!("{slug}.stderr"));
    let err_file = std::fs::File::create(&err_path).map_err(|e| format!("stderr file: {e}"))?;
    let mut child = cmd
        .arg(port)
        .arg(job)
        .arg(WANT)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::from(err_file))
        .spawn()
        .map_err(|e| format!("spawn: {e}"))?;
    // Read as it comes: cncjs logs to stdout, more than a pipe holds.
    let mut out = child.stdout.take();
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        if let Some(out) = out.as_mut() {
            use std::io::Read;
            let _ = out.read_to_string(&mut text);
        }
        text
    });
    let end = Instant::now() + TIMEOUT;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Ok(status),
            Ok(None) if Instant::now() < end => std::thread::sleep(Duration::from_millis(100)),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                break Err(format!("timed out after {} s", TIMEOUT.as_secs()));
            }
        }
    };
    let text = reader.join().unwrap_or_default();
    let line = text.lines().last().unwrap_or("").to_string();
    let result = match status {
        Ok(s) if s.success() => Ok(line),
        Ok(s) if line.is_empty() => Err(format!("exited with {s}")),
        Ok(_) => Err(line.trim_start_matches("FAIL: ").to_string()),
        Err(e) => Err(e),
    };
    if result.is_err() {
        let err = std::fs::read_to_string(&err_path).unwrap_or_default();
        let tail: Vec<&str> = err.lines().rev().take(400).collect();
        for l in tail.iter().rev() {
            eprintln!("senders: {slug}: {l}");
        }
    }
    result
}

/// The senders, in the order they run, each with the command that drives
/// it or why it is skipped.
fn senders(ready: &install::Ready) -> Vec<(String, &'static str, Result<Command, String>)> {
    let dir = root().join("xtask").join("senders");
    let py = |script: &str| {
        ready.pypi.clone().map(|python| {
            let mut c = Command::new(python);
            c.arg("-u").arg(dir.join(script));
            c
        })
    };
    let bcnc = ready.bcnc.clone().map(|bcnc| {
        let mut c = Command::new(install::SYSTEM_PYTHON);
        c.arg("-u").arg(dir.join("bcnc_job.py")).arg(bcnc);
        c
    });
    let cncjs = ready.cncjs.clone().map(|npm| {
        let mut c = Command::new("node");
        c.arg(dir.join("cncjs_job.js")).arg(npm);
        c
    });
    vec![
        (
            "grbl-streamer 2.0.2".into(),
            "grbl_streamer",
            py("grbl_streamer_job.py"),
        ),
        (
            "printcore (printrun 2.2.0)".into(),
            "printcore",
            py("printcore_job.py"),
        ),
        ("bCNC (Debian bcnc)".into(), "bcnc", bcnc),
        (format!("cncjs {}", install::CNCJS), "cncjs", cncjs),
    ]
}

/// `cargo xtask senders`: install, then run.
pub fn run() -> Result<i32> {
    let t = Instant::now();
    let ready = install::prepare();
    eprintln!(
        "senders: installs checked in {:.1} s",
        t.elapsed().as_secs_f64()
    );
    run_with(&ready)
}

/// Run every installed sender against one virtual board.
pub fn run_with(ready: &install::Ready) -> Result<i32> {
    let cfg = host_sim::config::MachineConfig::default();
    let (tx, rx) = mpsc::channel();
    // The virtual board runs until this process ends.
    std::thread::spawn(move || {
        let _ = host_sim::pty::run(&cfg, 10.0, |path| {
            let _ = tx.send(path.to_string());
        });
    });
    let port = rx.recv_timeout(Duration::from_secs(10))?;
    let job = root().join("xtask").join("senders").join("job.gcode");
    let mut failed = 0;
    println!("| sender | result | s |\n|---|---|---|");
    for (name, slug, cmd) in senders(ready) {
        let t = Instant::now();
        let (mark, text) = match cmd {
            Err(why) => ("skipped".to_string(), why),
            Ok(cmd) => match drive(cmd, slug, &port, &job) {
                Ok(t) => ("pass".to_string(), t),
                Err(t) => {
                    failed += 1;
                    ("FAIL".to_string(), t)
                }
            },
        };
        let secs = t.elapsed().as_secs_f64();
        println!("| {name} | {mark}: {text} | {secs:.1} |");
        // Let the pty see the hangup before the next client opens it.
        std::thread::sleep(Duration::from_millis(300));
    }
    Ok(if failed == 0 { 0 } else { 1 })
}
