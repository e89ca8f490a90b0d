//! `cargo xtask stream` as the person at the machine sees it: run in a
//! pseudo-terminal (expectrl) against `sim --pty`, a job with an operator
//! message and an M0 must show the message, stop with a prompt that says
//! which key continues, resume on that key, hold and resume on the hold
//! keys, and end where the job ends. Timeouts are generous and nothing is
//! timed: each step waits for the text the previous key must produce.

use expectrl::Session;
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

struct KillOnDrop(Child);
impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// 60 mm at 100 mm/min is 36 s of motion; at `--speed 4` that leaves
/// several seconds of wall time to hold it in, however loaded the machine.
const JOB: &str = "G21 G90 G94\n\
(MSG,insert the pen)\n\
G1 X5 F600\n\
M0\n\
G1 X60 F100\n\
G0 Y2\n";

#[test]
fn message_pause_key_hold_resume_and_end_position() {
    let exe = env!("CARGO_BIN_EXE_xtask");
    let dir = std::env::temp_dir().join(format!("burin-stream-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("pause.gcode"), JOB).expect("job file");
    let mut dev = KillOnDrop(
        Command::new(exe)
            .args(["sim", "--pty", "--speed", "4"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start the virtual device"),
    );
    let mut first = String::new();
    BufReader::new(dev.0.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .expect("device path line");
    let port = first.trim().to_string();
    assert!(port.starts_with("/dev/"), "device path, got {port:?}");

    let mut cmd = Command::new(exe);
    cmd.args(["stream", "pause.gcode", "--port", &port])
        .current_dir(&dir);
    let mut s = Session::spawn(cmd).expect("stream in a pty");
    s.set_expect_timeout(Some(Duration::from_secs(60)));
    let step = |s: &mut Session, what: &str| {
        if let Err(e) = s.expect(what) {
            panic!("waiting for {what:?}: {e}");
        }
    };
    step(&mut s, "pause.gcode:2: message: insert the pen");
    step(&mut s, "pause.gcode:4: paused: program pause (M0)");
    step(&mut s, "last message (pause.gcode:2): insert the pen");
    step(&mut s, "Enter, space or ~ continues");
    s.send("\r").expect("Enter");
    step(&mut s, "running again");
    // Now in the long move: space holds it, `~` resumes.
    s.send(" ").expect("space");
    step(&mut s, "paused: held from the keyboard");
    s.send("~").expect("~");
    step(&mut s, "running again");
    step(
        &mut s,
        "pause.gcode: finished: 6/6 lines sent, 0 error(s), 0 alarm(s)",
    );
    // The virtual machine starts at its configured Z; X and Y are the job's.
    step(&mut s, "WPos X60.000 Y2.000 Z");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without a terminal: no prompts, `--resume-pauses` goes on by itself,
/// errors read `FILE:LINE: error[CODE]: text` (the board's text), and the exit code says the
/// job ran to its end with rejected lines (1).
#[test]
fn without_a_terminal_pauses_resume_and_the_exit_code_tells() {
    let exe = env!("CARGO_BIN_EXE_xtask");
    let dir = std::env::temp_dir().join(format!("burin-stream-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(
        dir.join("pipe.gcode"),
        "G21 G90\n(MSG,hello)\nG1 X1\nM0\nG0 X3 Y1\n",
    )
    .expect("job file");
    let mut dev = KillOnDrop(
        Command::new(exe)
            .args(["sim", "--pty", "--speed", "100"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start the virtual device"),
    );
    let mut first = String::new();
    BufReader::new(dev.0.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .expect("device path line");
    let out = Command::new(exe)
        .args([
            "stream",
            "pipe.gcode",
            "--resume-pauses",
            "--port",
            first.trim(),
        ])
        .current_dir(&dir)
        .stdin(Stdio::null())
        .output()
        .expect("run the streamer");
    let text = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{text}");
    for want in [
        "pipe.gcode:2: message: hello",
        "pipe.gcode:3: error[",
        "pipe.gcode:4: paused: program pause (M0)",
        "continuing (--resume-pauses)",
        "pipe.gcode: finished: 5/5 lines sent, 1 error(s), 0 alarm(s)",
        "WPos X3.000 Y1.000",
    ] {
        assert!(text.contains(want), "{want:?} missing from:\n{text}");
    }
    // The board's own words for the error, not a placeholder.
    assert!(!text.contains("device error"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}
