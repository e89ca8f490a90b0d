//! `cargo xtask qemu`: the real RTIC app on QEMU's netduinoplus2 (STM32F405,
//! Cortex-M4F), built with `board-qemu` (HSI clocks, link on USART1 because
//! QEMU has no USB OTG model). The test talks to USART1 through QEMU's
//! stdin/stdout and kills QEMU when done. Also the QEMU plumbing that
//! `bench-target` shares.
use crate::{image, util};
use anyhow::{bail, Context, Result};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

mod drill;
mod stack;

/// Stack the F401 must keep unused at the QEMU run's deepest point. The
/// QEMU image has the F401's stack (memory-f405.x = memory-f401.x).
const MIN_HEADROOM: u32 = 8 * 1024;

const QEMU: &str = "qemu-system-arm";
const MACHINE: &str = "netduinoplus2";

/// Builds `bin` for the QEMU board (`<bin>-qemu.elf`).
pub fn build_bin(bin: &str, features: &[&str]) -> Result<PathBuf> {
    util::build_firmware(bin, Some(&features.join(",")), "qemu")
}

/// Installs QEMU's ARM system emulator when it is missing (Debian package
/// `qemu-system-arm`), as root only; otherwise says how.
pub fn ensure_installed() -> Result<()> {
    if util::have(QEMU) {
        return Ok(());
    }
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if !root {
        bail!("{QEMU} is missing: install it with `sudo apt-get install -y qemu-system-arm`");
    }
    let _lock = util::apt_lock();
    let install = || {
        util::run(
            Command::new("apt-get")
                .env("DEBIAN_FRONTEND", "noninteractive")
                .args(["install", "-y", "qemu-system-arm"]),
        )
    };
    if install().is_err() {
        util::run(Command::new("apt-get").arg("update"))?;
        install()?;
    }
    if !util::have(QEMU) {
        bail!("apt-get installed qemu-system-arm but {QEMU} is still not on PATH");
    }
    Ok(())
}

/// QEMU on the netduinoplus2 with `elf` loaded, semihosting on (output and
/// exit status of `cortex_m_semihosting`), no display, no monitor. USART1
/// (the first `-serial`) goes to stdin/stdout.
pub fn command(elf: &Path) -> Command {
    command_with_monitor(elf, None)
}

/// [`command`] with QEMU's monitor on the unix socket `monitor`, if given.
fn command_with_monitor(elf: &Path, monitor: Option<&Path>) -> Command {
    let mut cmd = Command::new(QEMU);
    cmd.args(["-M", MACHINE, "-display", "none", "-monitor"]);
    match monitor {
        Some(sock) => cmd.arg(format!("unix:{},server=on,wait=off", sock.display())),
        None => cmd.arg("none"),
    };
    cmd.args(["-semihosting-config", "enable=on,target=native"]);
    cmd.args(["-serial", "stdio", "-kernel"]);
    cmd.arg(elf);
    cmd
}

/// Kills QEMU however a test ends.
struct Guard(Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `cmd` with piped stdio; stdout arrives on the returned channel.
fn spawn(mut cmd: Command) -> Result<(Guard, mpsc::Receiver<Vec<u8>>)> {
    eprintln!("$ {}", util::show(&cmd));
    cmd.stdin(Stdio::piped()).stdout(Stdio::piped());
    let mut child = cmd.spawn().with_context(|| format!("starting {QEMU}"))?;
    let mut stdout = child.stdout.take().context("QEMU stdout")?;
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = [0u8; 256];
        while let Ok(n @ 1..) = stdout.read(&mut buf) {
            if tx.send(buf[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    Ok((Guard(child), rx))
}

/// Runs `cmd` until the guest exits (semihosting `debug::exit`) and returns
/// its stdout; fails on a non-zero exit or after `timeout`.
pub fn run_to_exit(cmd: Command, timeout: Duration) -> Result<String> {
    let (mut guard, rx) = spawn(cmd)?;
    let end = Instant::now() + timeout;
    let mut out = Vec::new();
    loop {
        while let Ok(chunk) = rx.try_recv() {
            out.extend(chunk);
        }
        if let Some(status) = guard.0.try_wait()? {
            // The reader thread ends at EOF; collect what it still has.
            while let Ok(chunk) = rx.recv_timeout(Duration::from_millis(200)) {
                out.extend(chunk);
            }
            let text = String::from_utf8_lossy(&out).into_owned();
            if !status.success() {
                bail!("{QEMU} exited with {status}; output:\n{text}");
            }
            return Ok(text);
        }
        if Instant::now() > end {
            bail!(
                "{QEMU} still running after {timeout:?}; output so far:\n{}",
                String::from_utf8_lossy(&out)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Reads from `rx` into `seen` until `want` appears in it or `timeout`.
fn expect(
    rx: &mpsc::Receiver<Vec<u8>>,
    seen: &mut Vec<u8>,
    want: &[u8],
    timeout: Duration,
) -> bool {
    let end = Instant::now() + timeout;
    loop {
        if seen.windows(want.len()).any(|w| w == want) {
            return true;
        }
        let left = end.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return false;
        }
        if let Ok(chunk) = rx.recv_timeout(left) {
            seen.extend(chunk);
        }
    }
}

/// The job every path must agree on (`host-sim/tests/device/three_paths.rs` runs
/// it offline and over the pty): lines, arcs in two planes, a dwell,
/// tool/spindle/coolant words on one line and an `M2` mid-file.
const JOB: &str = include_str!("../../host-sim/jobs/agree.gcode");

/// Where the offline run (the virtual board, booted at machine zero like
/// the QEMU board) ends the job, in steps, and the steps per mm to read
/// `MPos` with.
fn offline_end() -> Result<([i64; burin::AXES], [f64; burin::AXES])> {
    let cfg = host_sim::config::MachineConfig {
        start_position_mm: [0.0; burin::AXES],
        ..Default::default()
    };
    let s = host_sim::offline::run_file(&cfg, JOB, &mut host_sim::record::Discard);
    if !s.errors.is_empty() {
        bail!(
            "the offline run of the agreement job failed: {:?}",
            s.errors
        );
    }
    let spm = std::array::from_fn(|i| f64::from(cfg.settings.axes[i].steps_per_mm));
    Ok((s.final_position_steps, spm))
}

/// The end-to-end test: boot the app, wait until its device session answers
/// `$I` over USART1, stream a job GRBL-style and check the final position
/// in the status report.
pub fn run() -> Result<i32> {
    let elf = build_bin("burin-fw", &["board-qemu"])?;
    ensure_installed()?;
    image::check_fault_layout(&elf)?;
    let (bottom, top) = image::stack_region(&elf)?;
    let dir = elf.parent().context("ELF path has no directory")?;
    let sock = dir.join("qemu-monitor.sock");
    let _ = std::fs::remove_file(&sock);
    let (mut guard, rx) = spawn(command_with_monitor(&elf, Some(&sock)))?;
    let mut stdin = guard.0.stdin.take().context("QEMU stdin")?;
    let mut seen = Vec::new();
    // QEMU's USART model drops bytes that arrive before the firmware has
    // enabled the peripheral, and boot time varies with the host's load:
    // ask again every half second until something answers.
    let end = Instant::now() + Duration::from_secs(20);
    let mut next_ask = Instant::now();
    loop {
        if Instant::now() >= next_ask {
            stdin.write_all(b"$I\n")?;
            stdin.flush()?;
            next_ask = Instant::now() + Duration::from_millis(500);
        }
        if contains(&seen, b"[VER:") {
            break;
        }
        let left = end.saturating_duration_since(Instant::now());
        if left.is_zero() {
            bail!(
                "no reply to `$I` within 20 s; USART1 said {:?}",
                String::from_utf8_lossy(&seen)
            );
        }
        if let Ok(chunk) = rx.recv_timeout(left.min(Duration::from_millis(100))) {
            seen.extend(chunk);
        }
    }
    // Let the answers to any repeated `$I` arrive before the real test.
    while let Ok(chunk) = rx.recv_timeout(Duration::from_millis(700)) {
        seen.extend(chunk);
    }
    // The boot's share of the peak (init's frames), before any job runs.
    let boot = stack::dump(&sock, bottom, top, &dir.join("qemu-stack-boot.bin"))?;
    println!(
        "stack_high_water_boot_bytes {}",
        stack::used(&boot, top - bottom)
    );
    let (want, spm) = offline_end()?;
    job_test(&mut stdin, &rx, &mut seen, want, spm)?;
    settings_test(&mut stdin, &rx, &mut seen)?;
    let region = stack::dump(&sock, bottom, top, &dir.join("qemu-stack.bin"))?;
    let used = stack::used(&region, top - bottom);
    let headroom = (top - bottom).saturating_sub(used);
    println!("stack_high_water_bytes {used}");
    println!("stack_region_bytes {}", top - bottom);
    println!("stack_headroom_bytes {headroom}");
    if headroom < MIN_HEADROOM {
        bail!(
            "the stack kept {headroom} of its {} bytes unused; the F401 needs {MIN_HEADROOM}",
            top - bottom
        );
    }
    println!(
        "qemu: the RTIC app ran host-sim/jobs/agree.gcode on {MACHINE} over USART1 \
         and ended on the offline run's step {want:?}"
    );
    if let Some(status) = guard.0.try_wait()? {
        bail!("{QEMU} exited by itself ({status})");
    }
    drop(guard);
    println!("qemu: QEMU stopped");
    drills(&elf, dir)?;
    Ok(0)
}

/// The fault drills (`qemu/drill.rs`), one QEMU run each.
fn drills(elf: &Path, dir: &Path) -> Result<()> {
    for d in drill::Drill::ALL {
        let log = dir.join(format!("qemu-drill-{d:?}.log"));
        let _ = std::fs::remove_file(&log);
        let mut cmd = command(elf);
        cmd.args(drill::args(d, &log));
        let said = drill::run_until_fault(cmd, Duration::from_secs(30))?;
        let report =
            drill::report(&said).with_context(|| format!("{d:?}: no fault line in {said:?}"))?;
        let stores = std::fs::read_to_string(&log)
            .with_context(|| format!("reading QEMU's store log {}", log.display()))?;
        drill::check(d, &report, &stores)?;
        println!(
            "drill {d:?}: outputs, drivers (under $4=1) and the step timer off; motion pins \
             at their $2/$3/$4 idle levels from boot; fault with sp={:#010x} cfsr={:#010x}",
            report.sp, report.cfsr
        );
    }
    Ok(())
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

/// Send-response streaming: one line, wait for its `ok`, next line. Then
/// `?` until the machine is idle, and compare `MPos`.
fn job_test(
    stdin: &mut impl Write,
    rx: &mpsc::Receiver<Vec<u8>>,
    seen: &mut Vec<u8>,
    want: [i64; burin::AXES],
    spm: [f64; burin::AXES],
) -> Result<()> {
    // The `$I` reply ends with its `ok`.
    if !expect(rx, seen, b"ok", Duration::from_secs(10)) {
        bail!(
            "`$I` got no ok; USART1 said {:?}",
            String::from_utf8_lossy(seen)
        );
    }
    for line in JOB.lines() {
        seen.clear();
        stdin.write_all(format!("{line}\n").as_bytes())?;
        stdin.flush()?;
        if !expect(rx, seen, b"ok", Duration::from_secs(10)) || contains(seen, b"error") {
            bail!(
                "`{line}` was not accepted: {:?}",
                String::from_utf8_lossy(seen)
            );
        }
        println!("sent: {line}");
    }
    // Poll `?` until the machine has run (a Run or Hold state was seen,
    // or it is already at the end) and is idle again.
    let end = Instant::now() + Duration::from_secs(60);
    let mut ran = false;
    let mut last = String::new();
    loop {
        seen.clear();
        stdin.write_all(b"?")?;
        stdin.flush()?;
        if expect(rx, seen, b">", Duration::from_secs(2)) {
            let text = String::from_utf8_lossy(seen).into_owned();
            if let Some(report) = text.split('<').nth(1).and_then(|r| r.split('>').next()) {
                last = report.to_string();
                ran |= report.starts_with("Run") || report.starts_with("Hold");
                if report.starts_with("Alarm") {
                    bail!("the machine is in alarm: <{report}>");
                }
                if report.starts_with("Idle") {
                    let pos = mpos(report).with_context(|| format!("no MPos in <{report}>"))?;
                    let mut steps: Vec<i64> = pos
                        .iter()
                        .zip(spm)
                        .map(|(p, s)| (p * s).round() as i64)
                        .collect();
                    // Axes past `$208` are not reported: the job leaves
                    // them at 0, so the offline run must end them there.
                    steps.resize(want.len(), 0);
                    if steps == want {
                        println!("status: <{report}> (saw Run: {ran}), steps {steps:?}");
                        return Ok(());
                    }
                    if ran {
                        bail!("job ended at <{report}> = steps {steps:?}, offline {want:?}");
                    }
                }
            }
        }
        if Instant::now() > end {
            bail!("the job did not finish within 60 s; last status <{last}>");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// `$n=` through the device session and its store (RAM on QEMU), read
/// back with `$$`.
fn settings_test(
    stdin: &mut impl Write,
    rx: &mpsc::Receiver<Vec<u8>>,
    seen: &mut Vec<u8>,
) -> Result<()> {
    for (line, want) in [("$110=4321", "ok"), ("$$", "$110=4321.000")] {
        seen.clear();
        stdin.write_all(format!("{line}\n").as_bytes())?;
        stdin.flush()?;
        if !expect(rx, seen, want.as_bytes(), Duration::from_secs(10)) {
            bail!(
                "`{line}`: no `{want}` in {:?}",
                String::from_utf8_lossy(seen)
            );
        }
    }
    println!("settings: $110=4321 stored and listed back");
    Ok(())
}

/// The numbers after `MPos:` in a status report body.
fn mpos(report: &str) -> Option<Vec<f64>> {
    let field = report.split('|').find_map(|f| f.strip_prefix("MPos:"))?;
    field.split(',').map(|v| v.trim().parse().ok()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The headroom the QEMU run measures is the F401's only while both
    /// images have the same stack region.
    #[test]
    fn the_qemu_image_has_the_f401_stack() {
        let stack = |file: &str| {
            let text = std::fs::read_to_string(crate::util::root().join("firmware").join(file))
                .expect("memory file");
            text.lines()
                .find(|l| l.trim_start().starts_with("STACK") && l.contains("ORIGIN"))
                .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
        };
        let f401 = stack("memory-f401.x");
        assert!(f401.is_some(), "memory-f401.x has no STACK region");
        assert_eq!(f401, stack("memory-f405.x"));
    }

    #[test]
    fn reads_mpos_from_a_grbl_report() {
        assert_eq!(
            mpos("Idle|MPos:3.000,4.000,0.000,0.000|FS:0,0"),
            Some(vec![3.0, 4.0, 0.0, 0.0])
        );
        assert_eq!(mpos("Idle|WPos:1,2,3"), None);
        assert_eq!(mpos("Idle|MPos:1,x,3"), None);
    }
}
