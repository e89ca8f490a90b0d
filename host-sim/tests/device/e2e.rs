//! End to end through the virtual device, no pty: the protocol crate's
//! clients over an in-memory pipe, the firmware's link decoder and device
//! session, and the motion core in virtual time. Deterministic: the device
//! advances a fixed virtual step per round and the pipes never block.

use crate::common;

use host_sim::config::MachineConfig;
use host_sim::device_sim::VirtualDevice;
use host_sim::engine::run_job;
use host_sim::record::Discard;
use protocol::client::grbl::{GrblClient, Pacing, TextEvent};
use protocol::client::mem::MemPipe;
use protocol::client::{Client, ClientEvent};
use protocol::{DeviceMsg, Rt};
use std::io::{Read, Write};

const DEMO: &str = include_str!("../../jobs/demo.gcode");

/// Virtual time per round: 2 ms.
fn dt(cfg: &MachineConfig) -> u64 {
    u64::from(cfg.tick_hz) / 500
}

/// Device side of one round: take what the pipe has (as far as the link
/// has room), run, send the replies.
fn round(dev: &mut VirtualDevice, pipe: &mut MemPipe, pending: &mut Vec<u8>, step: u64) {
    let mut buf = [0u8; 256];
    if let Ok(n) = pipe.read(&mut buf) {
        pending.extend_from_slice(&buf[..n]);
    }
    let n = dev.receive(pending);
    pending.drain(..n);
    let t = dev.sim.now() + step;
    dev.advance_to(t);
    let out = dev.take_output();
    if !out.is_empty() {
        let _ = pipe.write_all(&out);
    }
}

fn expected_steps(cfg: &MachineConfig, job: &str) -> [i64; burin::AXES] {
    let s = run_job(cfg, job, &mut Discard);
    assert!(
        s.errors.is_empty(),
        "reference run has errors: {:?}",
        s.errors
    );
    s.final_position_steps
}

/// Stream `lines` framed; `cut` disconnects (dropping bytes in flight) after
/// that many lines were sent. Returns the device's execution log.
fn stream_framed(
    cfg: &MachineConfig,
    lines: &[&str],
    cut: Option<usize>,
) -> (Vec<u32>, [i32; burin::AXES]) {
    let mut rec = Discard;
    let mut dev = VirtualDevice::new(cfg, &mut rec);
    dev.log = Some(Vec::new());
    // The power-up banner went out before the host connected.
    let _ = dev.take_output();
    let (host, mut dpipe) = MemPipe::pair();
    let mut client = Client::new(host);
    client.set_resync_after(None);
    client.begin().expect("begin");
    let mut pending = Vec::new();
    let step = dt(cfg);
    let mut sent = 0usize;
    let mut cut = cut;
    let mut errors = Vec::new();
    for _round in 0..2_000_000 {
        while sent < lines.len() && client.can_send() {
            client.send_line(lines[sent].as_bytes()).expect("send");
            sent += 1;
        }
        if cut == Some(sent) {
            cut = None;
            // Cable pull: both directions lose what is in flight.
            dpipe.close();
            dev.port_closed();
            let (host, d2) = MemPipe::pair();
            dpipe = d2;
            pending.clear();
            client.reconnect(host).expect("reconnect");
            // A framed job that loses its port is held until told to go on.
            let mut held = false;
            for _ in 0..50 {
                round(&mut dev, &mut dpipe, &mut pending, step);
                held |= dev.sim.machine.state(&dev.sim.rt) == burin::executor::State::Hold;
            }
            let mut told = false;
            while let Some(ev) = client.poll().expect("poll") {
                told |= matches!(&ev, ClientEvent::Device(DeviceMsg::Msg(m)) if m.contains("Link lost"));
            }
            assert!(
                held && told,
                "no hold/report after the disconnect (held {held}, told {told})"
            );
            client.realtime(Rt::CycleStart).expect("resume");
        }
        round(&mut dev, &mut dpipe, &mut pending, step);
        while let Some(ev) = client.poll().expect("poll") {
            if let ClientEvent::Device(DeviceMsg::Error { .. } | DeviceMsg::Alarm { .. }) = ev {
                errors.push(ev);
            }
        }
        if sent == lines.len() && client.in_flight() == 0 && dev.idle() {
            break;
        }
    }
    assert!(errors.is_empty(), "device reported {errors:?}");
    assert_eq!(sent, lines.len());
    assert!(dev.idle(), "device never went idle");
    let pos = dev.position_steps();
    (dev.log.take().unwrap_or_default(), pos)
}

fn lines_of(job: &str) -> Vec<&str> {
    job.lines().collect()
}

#[test]
fn framed_demo_ends_where_run_job_ends() {
    let cfg = MachineConfig::default();
    let want = expected_steps(&cfg, DEMO);
    let (log, pos) = stream_framed(&cfg, &lines_of(DEMO), None);
    assert_eq!(pos.map(i64::from), want);
    assert!(!log.is_empty());
    assert!(
        log.windows(2).all(|w| w[0] <= w[1]),
        "commands out of order"
    );
}

/// A job where every line is exactly one move, so the log must be 1..=n.
fn zigzag(n: usize) -> String {
    let mut s = String::from("G21 G90 G0 X-10 Y-10\n");
    for i in 0..n {
        let x = -10.0 - (i % 7) as f32;
        let y = -10.0 - (i % 5) as f32 * 0.5;
        s.push_str(&format!("G1 X{x:.1} Y{y:.1} F3000\n"));
    }
    s
}

#[test]
fn every_acked_line_executes_once_in_order_across_a_disconnect() {
    let cfg = MachineConfig::default();
    let job = zigzag(300);
    let lines = lines_of(&job);
    let want = expected_steps(&cfg, &job);
    for cut in [1, 7, 150, 299] {
        let (log, pos) = stream_framed(&cfg, &lines, Some(cut));
        let expect: Vec<u32> = (1..=lines.len() as u32).collect();
        assert_eq!(log, expect, "cut after {cut} lines");
        assert_eq!(pos.map(i64::from), want, "cut after {cut} lines");
    }
}

fn stream_text(
    cfg: &MachineConfig,
    job: &str,
    pacing: Pacing,
) -> ([i32; burin::AXES], usize, String) {
    let mut rec = Discard;
    let mut dev = VirtualDevice::new(cfg, &mut rec);
    dev.log = Some(Vec::new());
    let (host, mut dpipe) = MemPipe::pair();
    let mut client = GrblClient::new(host, pacing);
    let mut pending = Vec::new();
    let step = dt(cfg);
    let lines = lines_of(job);
    let (mut sent, mut oks, mut banner) = (0, 0, false);
    let mut last_status = String::new();
    let mut asked = false;
    for _round in 0..2_000_000 {
        while banner && sent < lines.len() && client.can_send(lines[sent]) {
            client.send_line(lines[sent]).expect("send");
            sent += 1;
        }
        round(&mut dev, &mut dpipe, &mut pending, step);
        while let Some(ev) = client.poll().expect("poll") {
            match ev {
                TextEvent::Banner(_) => banner = true,
                TextEvent::Ok => oks += 1,
                TextEvent::Error(n) => panic!("error:{n}"),
                TextEvent::Alarm(n) => panic!("ALARM:{n}"),
                TextEvent::Status(st) => {
                    last_status = format!("{st:?}");
                    if st.state == "Idle" && asked {
                        return (dev.position_steps(), oks, last_status);
                    }
                }
                TextEvent::Info(_) => {}
            }
        }
        if sent == lines.len() && oks == lines.len() && dev.idle() && !asked {
            client.realtime(b'?').expect("?");
            asked = true;
        }
    }
    panic!(
        "text stream did not finish: sent {sent}, ok {oks}, {last_status}; idle {} drained {} ready {} state {:?} now {} log {:?}",
        dev.sim.idle(),
        dev.controller.session.drained(),
        dev.sim.machine.ready(),
        dev.sim.machine.state(&dev.sim.rt),
        dev.sim.now(),
        dev.log.as_ref().map(|l| l.len())
    );
}

#[test]
fn text_char_counting_and_send_response_end_where_run_job_ends() {
    let cfg = MachineConfig::default();
    let want = expected_steps(&cfg, DEMO);
    for pacing in [Pacing::CharCounting, Pacing::SendResponse] {
        let (pos, oks, status) = stream_text(&cfg, DEMO, pacing);
        assert_eq!(oks, DEMO.lines().count());
        assert_eq!(pos.map(i64::from), want, "{pacing:?}");
        assert!(status.contains("Idle"), "{status}");
    }
}

/// Through the device session (not `run_job`): after G38.2 the machine
/// stops past the contact, and the interpreter must continue from there
/// (a relative move) while #5063 keeps the contact point.
#[test]
fn device_probe_then_relative_move_matches_run_job() {
    let mut cfg = common::config_with_switches();
    cfg.settings.g28_homes = true; // $210=1: the reference's G28 homes
    cfg.start_position_mm = burin::pad([-40.0, -40.0, -10.0, 0.0]);
    let job = "$H\nG90 G0 X-10 Y-10\nG38.2 Z-40 F600\nG91 G1 Z5 F500\nG90\nG1 X[#5061] F800\n";
    let reference = job.replacen("$H", "G28", 1);
    let want = expected_steps(&cfg, &reference);
    let (pos, oks, _) = stream_text(&cfg, job, Pacing::SendResponse);
    assert_eq!(oks, job.lines().count());
    assert_eq!(pos.map(i64::from), want);
    // The contact was at Z -20 mm (-8000 steps); Z ended 5 mm above the stop.
    assert!(
        want[2] < -8000 + 2000 && want[2] > -8000 + 2000 - 500,
        "{want:?}"
    );
}
