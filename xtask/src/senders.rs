//! `cargo xtask senders`: real third-party senders against `sim --pty`.
//!
//! Installs them from PyPI into a cache venv (`target/senders/venv`, kept
//! between runs) and drives each with a small script in `xtask/senders/`
//! that streams `xtask/senders/job.gcode` (lines and arcs) and checks the
//! final position from a `?` status report:
//!
//! * `grbl-streamer` (PyPI; character-counting GRBL 1.1 streamer): also a
//!   hold, a check of `Hold`, a resume and feed overrides mid-job (its
//!   own and a realtime +10 % in the UTF-8 form bCNC and cncjs send);
//! * printcore (PyPI `printrun`, installed without its GUI dependencies):
//!   RepRap numbering, `M110`, checksums, and one damaged line that burin
//!   must ask for again (`Resend:`).
//!
//! When python3 or the registry is not there it says "skipped" and
//! succeeds: CI never fails for the network's sake.

use anyhow::Result;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::util::{root, target_dir};

/// Pinned versions (what the scripts were written against).
const PACKAGES: [(&str, &[&str]); 2] = [
    ("grbl-streamer", &["grbl-streamer==2.0.2", "pyserial==3.5"]),
    ("printrun", &["--no-deps", "printrun==2.2.0"]),
];

/// (name, package, script)
const SENDERS: [(&str, &str, &str); 2] = [
    (
        "grbl-streamer 2.0.2",
        "grbl-streamer",
        "grbl_streamer_job.py",
    ),
    ("printcore (printrun 2.2.0)", "printrun", "printcore_job.py"),
];

/// Where the job ends (machine coordinates, mm).
const WANT: &str = "-40,-30,-1";
const TIMEOUT: Duration = Duration::from_secs(240);

fn skipped(why: &str) -> Result<i32> {
    eprintln!("senders: skipped ({why})");
    Ok(0)
}

fn venv() -> Result<Option<PathBuf>> {
    let dir = target_dir().join("senders").join("venv");
    let python = dir.join("bin").join("python");
    if !python.exists() {
        std::fs::create_dir_all(target_dir().join("senders"))?;
        let ok = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&dir)
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        if !ok {
            return Ok(None);
        }
    }
    Ok(Some(python))
}

/// Install what is missing; false when the registry could not be reached
/// (or pip failed: the message says which).
fn install(python: &Path) -> bool {
    for (name, args) in PACKAGES {
        let have = Command::new(python)
            .args(["-m", "pip", "show", "-q", name])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        if have {
            continue;
        }
        let out = Command::new(python)
            .args([
                "-m",
                "pip",
                "install",
                "-q",
                "--disable-pip-version-check",
                "--timeout",
                "30",
            ])
            .args(args)
            .output();
        match out {
            Ok(o) if o.status.success() => {}
            Ok(o) => {
                let err = String::from_utf8_lossy(&o.stderr);
                eprintln!("senders: pip install {name}: {}", err.trim());
                return false;
            }
            Err(e) => {
                eprintln!("senders: pip: {e}");
                return false;
            }
        }
    }
    true
}

/// Run one driver script; `Ok(line)` on success, `Err(line)` otherwise.
/// On failure the script's stderr (a traceback, or faulthandler's dump of
/// where it blocked) is printed too, so a red run says why.
fn drive(
    python: &Path,
    script: &Path,
    port: &str,
    job: &Path,
) -> std::result::Result<String, String> {
    let err_path = target_dir().join("senders").join(format!(
        "{}.stderr",
        script
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("script")
    ));
    let err_file = std::fs::File::create(&err_path).map_err(|e| format!("stderr file: {e}"))?;
    let mut child = Command::new(python)
        .arg("-u")
        .arg(script)
        .arg(port)
        .arg(job)
        .arg(WANT)
        .stdout(Stdio::piped())
        .stderr(Stdio::from(err_file))
        .spawn()
        .map_err(|e| format!("spawn: {e}"))?;
    let end = Instant::now() + TIMEOUT;
    let result = loop {
        match child.try_wait() {
            Ok(Some(status)) => {
                let mut text = String::new();
                if let Some(mut out) = child.stdout.take() {
                    use std::io::Read;
                    let _ = out.read_to_string(&mut text);
                }
                let line = text.lines().last().unwrap_or("").to_string();
                break if status.success() {
                    Ok(line)
                } else if line.is_empty() {
                    Err(format!("exited with {status}"))
                } else {
                    Err(line.trim_start_matches("FAIL: ").to_string())
                };
            }
            Ok(None) if Instant::now() < end => std::thread::sleep(Duration::from_millis(100)),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                break Err(format!("timed out after {} s", TIMEOUT.as_secs()));
            }
        }
    };
    if result.is_err() {
        let err = std::fs::read_to_string(&err_path).unwrap_or_default();
        let tail: Vec<&str> = err.lines().rev().take(400).collect();
        for l in tail.iter().rev() {
            eprintln!("senders: {} stderr: {l}", script.display());
        }
    }
    result
}

pub fn run() -> Result<i32> {
    let Some(python) = venv()? else {
        return skipped("python3 -m venv failed");
    };
    if !install(&python) {
        return skipped("PyPI not reachable or the install failed");
    }
    let cfg = host_sim::config::MachineConfig::default();
    let (tx, rx) = mpsc::channel();
    // The virtual board runs until this process ends.
    std::thread::spawn(move || {
        let _ = host_sim::pty::run(&cfg, 10.0, |path| {
            let _ = tx.send(path.to_string());
        });
    });
    let port = rx.recv_timeout(Duration::from_secs(10))?;
    let dir = root().join("xtask").join("senders");
    let job = dir.join("job.gcode");
    let mut failed = 0;
    println!("| sender | result |\n|---|---|");
    for (name, _pkg, script) in SENDERS {
        let r = drive(&python, &dir.join(script), &port, &job);
        let (mark, text) = match &r {
            Ok(t) => ("pass", t.as_str()),
            Err(t) => {
                failed += 1;
                ("FAIL", t.as_str())
            }
        };
        println!("| {name} | {mark}: {text} |");
        // Let the pty see the hangup before the next client opens it.
        std::thread::sleep(Duration::from_millis(300));
    }
    Ok(if failed == 0 { 0 } else { 1 })
}
