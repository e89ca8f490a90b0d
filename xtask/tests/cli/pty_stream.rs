//! The virtual device contract end to end, through real processes and a real
//! pseudo-terminal: `cargo xtask sim --pty` prints its device path first, and
//! `cargo xtask stream --port <path>` drives a job through it to the same
//! final position the offline simulator computes.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

struct KillOnDrop(Child);
impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn stream_demo_job_through_the_pty() {
    let exe = env!("CARGO_BIN_EXE_xtask");
    let mut dev = KillOnDrop(
        Command::new(exe)
            .args(["sim", "--pty", "--speed", "1000"])
            .current_dir(root())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start the virtual device"),
    );
    let mut first = String::new();
    BufReader::new(dev.0.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .expect("device path line");
    let path = first.trim().to_string();
    assert!(
        path.starts_with("/dev/"),
        "first line must be the device path, got {path:?}"
    );

    let out = Command::new(exe)
        .args(["stream", "host-sim/jobs/demo.gcode", "--port", &path])
        .current_dir(root())
        .output()
        .expect("run the streamer");
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "stream failed: {text}");
    // The offline simulator's final machine position for the same job.
    let job = std::fs::read_to_string(root().join("host-sim/jobs/demo.gcode")).expect("demo job");
    let cfg = host_sim::config::MachineConfig::default();
    let s = host_sim::engine::run_job(&cfg, &job, &mut host_sim::record::Discard);
    let p = s.final_position_mm;
    let want = format!("final MPos X{:.3} Y{:.3} Z{:.3}", p[0], p[1], p[2]);
    assert!(text.contains(&want), "expected {want}, got: {text}");
    std::thread::sleep(Duration::from_millis(10));
}
