//! One job, three paths: the offline run (`cargo xtask sim FILE`, which
//! streams through the virtual board) and a GRBL sender on `sim --pty`'s
//! pseudo-terminal end on the same step; `cargo xtask qemu` checks the
//! third, the RTIC app itself, against the same offline figure. The job
//! has tool, spindle and coolant words on one line and an `M2` mid-file,
//! which the old offline runner got wrong (it dropped the rest of the job).

use std::io::{Read, Write};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use host_sim::config::MachineConfig;
use host_sim::offline::run_file;
use host_sim::record::Discard;
use protocol::client::grbl::parse_status;

const JOB: &str = include_str!("../../jobs/agree.gcode");

fn origin() -> MachineConfig {
    MachineConfig {
        start_position_mm: [0.0; burin::AXES],
        ..MachineConfig::default()
    }
}

#[test]
fn offline_runs_every_line_of_the_job() {
    let s = run_file(&origin(), JOB, &mut Discard);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    // G90 X5.0125, the G91 Y+4 after M2 (from Y-2), then the G18 arc to Z0.5.
    assert_eq!(s.final_position_steps, burin::pad([401, 160, 200, 0]));
    assert_eq!(s.lines, JOB.lines().count() as u32);
}

#[test]
fn a_rejected_line_is_an_error_with_its_file_line() {
    let job = "G21\nM3 S100 M8 T3\nG1 X1 F100 Q5\nG1 X2 F100\n";
    let s = run_file(&origin(), job, &mut Discard);
    assert_eq!(s.errors.len(), 1, "{:?}", s.errors);
    assert_eq!(s.errors[0].line, 3);
    assert!(s.errors[0].message.contains('Q'), "{:?}", s.errors);
    // The line after it still ran.
    assert_eq!(s.final_position_steps[0], 160);
}

/// The pty, as a sender sees it: open the device path, send-response
/// streaming (one line, wait for its `ok`), then `?` until idle.
#[test]
fn pty_ends_where_the_offline_run_ends() {
    let cfg = origin();
    let want = run_file(&cfg, JOB, &mut Discard).final_position_steps;
    let (tx, rx) = mpsc::channel();
    let dev_cfg = cfg.clone();
    // The device runs until the test process ends.
    std::thread::spawn(move || {
        let _ = host_sim::pty::run(&dev_cfg, 50.0, |path| {
            let _ = tx.send(path.to_string());
        });
    });
    let path = rx.recv_timeout(Duration::from_secs(10)).expect("pty path");
    let mut port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .expect("open pty");
    let mut reader = port.try_clone().expect("clone");
    let (btx, brx) = mpsc::channel::<Vec<u8>>();
    std::thread::spawn(move || {
        let mut buf = [0u8; 512];
        while let Ok(n @ 1..) = reader.read(&mut buf) {
            if btx.send(buf[..n].to_vec()).is_err() {
                break;
            }
        }
    });
    let mut text = String::new();
    // Read until `pat`; drop everything up to and including it, return
    // what came before it.
    let until = |text: &mut String, pat: &str| -> Option<String> {
        let end = Instant::now() + Duration::from_secs(20);
        while Instant::now() < end {
            if let Some(i) = text.find(pat) {
                let before = text[..i].to_string();
                text.drain(..i + pat.len());
                return Some(before);
            }
            if let Ok(b) = brx.recv_timeout(Duration::from_millis(50)) {
                text.push_str(&String::from_utf8_lossy(&b));
            }
        }
        None
    };
    // The banner once the port is open.
    assert!(
        until(&mut text, "Grbl 1.1h").is_some(),
        "no banner: {text:?}"
    );
    assert!(until(&mut text, "\r\n").is_some());
    for line in JOB.lines() {
        port.write_all(line.as_bytes()).expect("write");
        port.write_all(b"\n").expect("write");
        let before = until(&mut text, "ok\r\n");
        let before = before.unwrap_or_else(|| panic!("no ok for {line:?}: {text:?}"));
        assert!(!before.contains("error"), "{line:?}: {before:?}");
    }
    let spm = burin::pad([80.0f32, 80.0, 400.0, 80.0]);
    let end = Instant::now() + Duration::from_secs(30);
    let got = loop {
        port.write_all(b"?").expect("write");
        let _ = until(&mut text, "<").expect("no status");
        let body = until(&mut text, ">").expect("no status end");
        let st = parse_status(&format!("<{body}>")).expect("a status report");
        if st.state == "Idle" {
            let mpos = st.mpos.expect("MPos");
            break std::array::from_fn::<i64, { burin::AXES }, _>(|i| {
                // Axes the report leaves out (`$208`) stood at 0.
                (mpos.get(i).copied().unwrap_or(0.0) * spm[i]).round() as i64
            });
        }
        assert!(Instant::now() < end, "never idle: <{body}>");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(got, want, "pty vs offline (steps)");
}

/// A dwell longer than the stuck guard is progress (the step timer runs),
/// not a stuck board.
#[test]
fn offline_waits_out_a_long_dwell() {
    let s = run_file(&origin(), "G4 P1500\nG1 X1 F600\n", &mut Discard);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert!(s.job_time_s > 1500.0, "{}", s.job_time_s);
    assert_eq!(s.final_position_steps[0], 80);
}

/// An alarm stops the run and names the file line whose move raised it.
#[test]
fn offline_alarm_names_its_line() {
    let cfg = MachineConfig::default();
    let job = "G21\n$21=1\nG1 X5 F1000\nG1 Y-5\n";
    let s = run_file(&cfg, job, &mut Discard);
    assert_eq!(s.errors.len(), 1, "{:?}", s.errors);
    assert_eq!(
        (s.errors[0].line, s.errors[0].code),
        (3, 1),
        "{:?}",
        s.errors
    );
    assert!(s.errors[0].message.starts_with("ALARM:1"), "{:?}", s.errors);
    // Y never moved: the line after the alarm did not run.
    assert_eq!(s.final_position_steps[1], -80);
}
