//! Issue 15 through the virtual board: a soft reset behind a flood voids
//! it, realtime bytes never wait behind text, and the port keeps answering
//! after a hold and a flood.

use host_sim::record::Discard;

use crate::rig;

use rig::{origin, Rig};

fn job(lines: usize, line: &str) -> Vec<u8> {
    let mut v = Vec::new();
    for _ in 0..lines {
        v.extend_from_slice(line.as_bytes());
        v.push(b'\n');
    }
    v
}

/// Wait (in 2 ms rounds) for a held machine to stop.
fn until_held(r: &mut Rig) {
    for _ in 0..5000 {
        r.run(5);
        if r.status().state == "Hold:0" {
            return;
        }
    }
    panic!("never held");
}

/// Issue 15 item 4: `G1 X-50 F100`, `!`, 150 lines, 0x18 in one go, as the
/// board's USB interrupt receives them: banner, no `ok` for the flood, and
/// the machine never moves along Y.
#[test]
fn reset_after_a_flood_voids_the_flood() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-50 F100"), ["ok"]);
    r.send(b"!");
    until_held(&mut r);
    r.lines();
    let mut bytes = job(150, "G91 G1 Y-1 F1000");
    bytes.push(0x18);
    r.send(&bytes);
    r.run(20);
    let out = r.lines();
    assert!(out.iter().any(|l| l.starts_with("Grbl 1.1h")), "{out:?}");
    assert!(
        !out.iter().any(|l| l == "ok" || l.starts_with("ALARM")),
        "{out:?}"
    );
    r.run(500);
    let st = r.status();
    assert_eq!(st.state, "Idle", "{st:?}");
    let y = st.mpos.as_ref().map(|p| p[1]);
    assert_eq!(y, Some(0.0), "{st:?}");
    assert!(!r.lines().iter().any(|l| l == "ok"));
}

/// Issue 32: the virtual board takes what the board takes before it
/// pushes back (its token ring and `burin::link::RX_BACKLOG`), so the
/// flood tests here see the board's flow control.
#[test]
fn receive_window_is_the_boards() {
    use burin::link::{RX_BACKLOG, RX_RING, RX_RING_HOLDS, SNIFF};
    let cfg = origin();
    let mut rec = Discard;
    let r = Rig::new(&cfg, &mut rec);
    // The backlog's room keeps 2 + SNIFF for markers and a held frame
    // start; the ring holds what the board's spsc queue of RX_RING slots
    // holds.
    assert_eq!(RX_RING_HOLDS, RX_RING - 1);
    assert_eq!(r.dev.room(), RX_RING_HOLDS + RX_BACKLOG - 2 - SNIFF);
}

/// Issue 15 item 7: `!` behind 400 queued lines holds within one pass.
#[test]
fn hold_behind_queued_text_acts_at_once() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    let mut bytes = b"G1 X-50 F300\n".to_vec();
    bytes.extend(job(400, "G91 G1 Y-0.01 F300"));
    // More than the board's receive backlog (`burin::link::RX_BACKLOG`)
    // holds: the device takes what it has room for, the host sends the
    // rest as room frees (as a USB host does while the board NAKs).
    let mut sent = r.dev.receive(&bytes);
    assert!(sent < bytes.len(), "{sent}");
    for _ in 0..50 {
        r.run(1);
        sent += r.dev.receive(&bytes[sent..]);
    }
    assert_eq!(sent, bytes.len());
    let before = r.dev.sim.now();
    r.send(b"!");
    r.run(1);
    let st = r.status();
    assert!(st.state.starts_with("Hold"), "{st:?}");
    // Acted in the same 2 ms round it arrived in.
    assert!(r.dev.sim.now() - before <= 2 * u64::from(cfg.tick_hz) / 500);
}

/// Issue 15 item 7: after a hold and a 3.6 KB flood the device still
/// answers `?`, resumes on `~`, resets on 0x18, and a closed port takes
/// the unread flood with it.
#[test]
fn hold_and_flood_keep_the_port_alive() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-20 F300"), ["ok"]);
    r.send(b"!");
    until_held(&mut r);
    let flood = job(200, "G91 G1 Y-0.1 F300");
    assert!(flood.len() >= 3600);
    r.send(&flood);
    r.run(10);
    // The parse task takes the flood's lines first: the answer comes
    // within a few ms (three 2 ms rounds with the board's 255-token ring).
    assert!(r.status_within(5).state.starts_with("Hold"));
    r.send(b"~");
    r.run(5);
    assert_eq!(r.status_within(5).state, "Run");
    r.send(b"\x18");
    r.run(5);
    assert!(r.lines().iter().any(|l| l.starts_with("Grbl 1.1h")));
    // The flood again, then the port closes: what was not read is void.
    assert_eq!(r.cmd("$X"), ["[MSG:Caution: Unlocked]", "ok"]);
    r.send(b"!");
    r.send(&flood);
    r.run(5);
    let mut out = r.lines();
    r.dev.port_closed();
    r.run(5);
    r.send(b"~");
    for _ in 0..2000 {
        r.run(10);
        out.extend(r.lines());
    }
    let st = r.status();
    assert_eq!(st.state, "Idle");
    // Every acknowledged line ran; what the device had not read when the
    // port closed did not, and was never acknowledged.
    let oks = out.iter().filter(|l| *l == "ok").count();
    let ran = (-st.mpos.map(|p| p[1]).unwrap_or(0.0) / 0.1).round() as usize;
    assert!(oks > 0 && oks == ran, "{ran} {oks}");
}

/// Issue 15 item 5: a line right behind a soft reset, in the same write,
/// to an idle machine: banner, no alarm, and the move runs.
#[test]
fn line_right_behind_a_reset_runs() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.send(b"\x18G21 G90 G53 G0 X-8 Y-2\n");
    r.run(5);
    let out = r.lines();
    assert!(
        !out.iter()
            .any(|l| l.starts_with("ALARM") || l.starts_with("[MSG")),
        "{out:?}"
    );
    let banner = out.iter().position(|l| l.starts_with("Grbl 1.1h"));
    let ok = out.iter().position(|l| l == "ok");
    assert!(banner.is_some() && banner < ok, "{out:?}");
    let st = r.until_idle();
    assert_eq!(st.mpos, rig::shown([-8.0, -2.0, 0.0, 0.0]));
}

/// Issue 15 item 3: `Hold:1` while decelerating, `Hold:0` once stopped,
/// and `!` at rest is a finished hold at once.
#[test]
fn hold_substates_follow_grbl() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.send(b"!");
    r.run(1);
    assert_eq!(r.status().state, "Hold:0");
    r.send(b"~");
    r.run(1);
    assert_eq!(r.cmd("G1 X-50 F3000"), ["ok"]);
    r.run(100);
    r.send(b"!");
    r.run(1);
    assert_eq!(r.status().state, "Hold:1");
    until_held(&mut r);
}

fn frame(msg: &protocol::HostMsg) -> Vec<u8> {
    let mut out = [0u8; protocol::frame::MAX_WIRE];
    let n = protocol::frame::encode(msg, &mut out).expect("encode");
    out[..n].to_vec()
}

fn device_msgs(bytes: &[u8]) -> Vec<protocol::DeviceMsg> {
    bytes
        .split(|b| *b == 0)
        .filter(|f| !f.is_empty())
        .filter_map(|f| protocol::frame::decode(&mut f.to_vec()).ok())
        .collect()
}

/// Issue 15 item 5, framed: a `SoftReset` frame and a `Line` frame in one
/// write: the line is acknowledged, runs once, and no alarm is raised.
#[test]
fn framed_line_right_behind_a_reset_is_never_lost() {
    use protocol::{DeviceMsg, HostMsg, Rt};
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.dev.log = Some(Vec::new());
    let _ = r.dev.take_output();
    r.lines();
    let mut hello = vec![0u8];
    hello.extend(frame(&HostMsg::Hello {
        version: protocol::PROTOCOL_VERSION,
    }));
    r.send(&hello);
    r.run(2);
    let _ = r.dev.take_output();
    let text = protocol::LineText::from_slice(b"G21 G90 G53 G0 X-8 Y-2").expect("text");
    let mut bytes = frame(&HostMsg::Realtime(Rt::SoftReset));
    bytes.extend(frame(&HostMsg::Line { seq: 1, text }));
    r.send(&bytes);
    let mut out = Vec::new();
    for _ in 0..3000 {
        let t = r.dev.sim.now() + u64::from(cfg.tick_hz) / 500;
        r.dev.advance_to(t);
        out.extend(r.dev.take_output());
    }
    let msgs = device_msgs(&out);
    let acks = msgs
        .iter()
        .filter(|m| matches!(m, DeviceMsg::Ack { seq: 1, .. }))
        .count();
    // (A second `Ack` for the same line is the credit refresh.)
    assert!(acks >= 1, "{msgs:?}");
    assert!(
        !msgs.iter().any(|m| matches!(m, DeviceMsg::Alarm { .. })),
        "{msgs:?}"
    );
    assert_eq!(r.dev.log.as_deref(), Some(&[1u32][..]));
    let steps = r.dev.position_steps();
    assert!(steps[0] < 0 && steps[1] < 0, "{steps:?}");
}

fn reprap(line: &str) -> String {
    let x = line.bytes().fold(0u8, |x, b| x ^ b);
    format!("{line}*{x}")
}

/// Issue 15 item 2: a printcore session. `M110` sets the number, a lost
/// line is asked for again with `Resend:` (and `ok`), a bad checksum too,
/// and a line sent twice runs once.
#[test]
fn reprap_numbering_and_resend() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("N-1 M110 N-1*125"), ["ok"]);
    assert_eq!(r.cmd(&reprap("N0 G91 G1 X-1 F2000")), ["ok"]);
    let lost = r.cmd(&reprap("N2 G1 X-4"));
    assert_eq!(lost.len(), 3, "{lost:?}");
    assert!(lost[0].starts_with("Error:") && lost[1] == "Resend: 1" && lost[2] == "ok");
    let bad = r.cmd("N1 G1 X-2*1");
    assert!(
        bad[0].contains("checksum") && bad[1] == "Resend: 1",
        "{bad:?}"
    );
    assert_eq!(r.cmd(&reprap("N1 G1 X-2")), ["ok"]);
    assert_eq!(r.cmd(&reprap("N1 G1 X-2"))[1], "Resend: 2");
    assert_eq!(r.cmd(&reprap("N2 G1 X-4")), ["ok"]);
    let st = r.until_idle();
    assert_eq!(st.mpos, rig::shown([-7.0, 0.0, 0.0, 0.0]));
}

/// Issue 35 item 4: a line number of ten digits was refused as a checksum
/// mismatch and asked for again, for ever. Up to 2^31 - 1 runs (as in
/// Marlin); 2^31 gets an error and `ok` but no `Resend:`, so the host does
/// not send it again, and the next numbering works.
#[test]
fn reprap_numbers_up_to_2_pow_31_minus_1() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("M110 N2147483646"), ["ok"]);
    assert_eq!(r.cmd("N2147483647 G4 P0*87"), ["ok"]);
    let over = r.cmd(&reprap("N2147483648 G91 G1 X-1 F2000"));
    assert_eq!(over.len(), 2, "{over:?}");
    assert!(over[0].starts_with("Error:") && over[1] == "ok", "{over:?}");
    assert_eq!(r.cmd(&reprap("N-1 M110 N-1")), ["ok"]);
    assert_eq!(r.cmd(&reprap("N0 G91 G1 X-2 F2000")), ["ok"]);
    let st = r.until_idle();
    assert_eq!(
        st.mpos,
        rig::shown([-2.0, 0.0, 0.0, 0.0]),
        "the refused line did not run"
    );
}

/// Issue 15 item 3: a reset in motion prints `ALARM:3` once.
#[test]
fn reset_in_motion_alarms_once() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-100 F1000"), ["ok"]);
    r.run(50);
    r.send(&[0x18]);
    let mut out = Vec::new();
    for _ in 0..50 {
        r.run(2);
        out.extend(r.lines());
    }
    r.send(b"?");
    r.run(2);
    out.extend(r.lines());
    assert_eq!(
        out.iter().filter(|l| l.starts_with("ALARM")).count(),
        1,
        "{out:?}"
    );
}

/// Issue 15 item 3, issue 29 item 5: `$SLP` sleeps (drivers off, state
/// `Sleep`, motion and `~` refused, lines unanswered as GRBL's) until a
/// soft reset, which wakes it into alarm.
#[test]
fn sleep_until_reset() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$1=255"), ["ok"]);
    r.run(5);
    assert_eq!(r.dev.pins().map(|p| p.enable), Some(true));
    assert_eq!(r.cmd("$SLP"), ["[MSG:Sleeping]", "ok"]);
    r.run(5);
    assert_eq!(r.status().state, "Sleep");
    assert_eq!(r.dev.pins().map(|p| p.enable), Some(false));
    assert!(r.cmd("G0 X-1").is_empty());
    assert!(r.cmd("$X").is_empty());
    r.send(b"~");
    r.run(5);
    assert_eq!(r.status().state, "Sleep");
    r.send(b"\x18");
    r.run(5);
    let woke = r.lines();
    assert!(woke.iter().any(|l| l.starts_with("Grbl 1.1h")), "{woke:?}");
    assert!(
        woke.iter().any(|l| l == "[MSG:'$H'|'$X' to unlock]"),
        "{woke:?}"
    );
    assert_eq!(r.status().state, "Alarm");
    assert_eq!(r.cmd("$X"), ["[MSG:Caution: Unlocked]", "ok"]);
    assert_eq!(r.cmd("G0 X-1"), ["ok"]);
    assert_eq!(r.until_idle().mpos, rig::shown([-1.0, 0.0, 0.0, 0.0]));
    assert_eq!(r.dev.pins().map(|p| p.enable), Some(true));
}

/// Issue 15 item 3: `$208=3` reports three axes everywhere GRBL senders
/// read positions; 4 (the default) all four.
#[test]
fn reported_axes_follow_208() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$208"), ["$208=4", "ok"]);
    assert!(r.cmd("$I").iter().any(|l| l == "[AXS:4:XYZA]"));
    assert_eq!(r.cmd("$208=2"), ["error:110"]);
    assert_eq!(r.cmd("$208=3"), ["ok"]);
    let st = r.status();
    assert_eq!(st.mpos.map(|p| p.len()), Some(3));
    let params = r.cmd("$#");
    assert!(
        params.iter().any(|l| l == "[G54:0.000,0.000,0.000]"),
        "{params:?}"
    );
    assert!(
        params.iter().any(|l| l == "[PRB:0.000,0.000,0.000:0]"),
        "{params:?}"
    );
    assert!(r.cmd("$I").iter().any(|l| l == "[AXS:3:XYZ]"));
    assert_eq!(r.cmd("$10=0"), ["ok"]);
    assert_eq!(r.status().wpos.map(|p| p.len()), Some(3));
}

/// With `$208` at every axis the build drives, the status report, `$#`
/// and `$I` carry all of them, and a move of every axis ends on each.
#[test]
fn every_axis_reported_with_208_at_all() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    let all = burin::AXES;
    assert_eq!(r.cmd(&format!("$208={all}")), ["ok"]);
    let names: String = burin::AXIS_NAMES.iter().collect();
    let axs = format!("[AXS:{all}:{names}]");
    assert!(r.cmd("$I").contains(&axs), "{axs}");
    let want: Vec<f32> = (1..=all).map(|i| i as f32).collect();
    let words: String = burin::AXIS_NAMES
        .iter()
        .zip(&want)
        .map(|(c, v)| format!(" {c}{v}"))
        .collect();
    assert_eq!(r.cmd(&format!("G10 L2 P1{words}")), ["ok"]);
    let params = r.cmd("$#");
    let g54 = format!(
        "[G54:{}]",
        want.iter()
            .map(|v| format!("{v:.3}"))
            .collect::<Vec<_>>()
            .join(",")
    );
    assert!(params.contains(&g54), "{params:?}");
    assert_eq!(r.cmd("$10=0"), ["ok"]);
    assert_eq!(r.cmd(&format!("G90 G1{words} F2000")), ["ok"]);
    let st = r.until_idle();
    let two: Vec<f32> = want.iter().map(|v| 2.0 * v).collect();
    assert_eq!(st.wpos, Some(want), "{st:?}");
    assert_eq!(r.cmd("$10=1"), ["ok"]);
    assert_eq!(r.status().mpos, Some(two));
}

/// Issue 15 item 3: every port open gives the banner before the `ok` of a
/// line the client wrote at once; the old client's unread input gives the
/// new one nothing.
#[test]
fn pty_banner_on_every_open_before_any_ok() {
    use std::io::{Read, Write};
    use std::sync::mpsc;
    use std::time::{Duration, Instant};
    let cfg = origin();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = host_sim::pty::run(&cfg, 20.0, |path| {
            let _ = tx.send(path.to_string());
        });
    });
    let path = rx.recv_timeout(Duration::from_secs(10)).expect("pty path");
    for round in 0..3 {
        let mut port = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
            .expect("open pty");
        port.write_all(b"G91 G0 X-1\n").expect("write");
        let mut text = String::new();
        let end = Instant::now() + Duration::from_secs(10);
        let mut buf = [0u8; 256];
        while !text.contains("ok\r\n") && Instant::now() < end {
            if let Ok(n @ 1..) = port.read(&mut buf) {
                text.push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        }
        let banner = text.find("Grbl 1.1h");
        let ok = text.find("ok\r\n");
        assert!(
            banner.is_some() && ok.is_some() && banner < ok,
            "round {round}: {text:?}"
        );
        assert_eq!(text.matches("ok\r\n").count(), 1, "round {round}: {text:?}");
        // Leave unread input behind: it must not answer the next client.
        port.write_all(b"G4 P0.5\nG4 P0.5\n").expect("write");
        drop(port);
        // A pty shows a close only as a hangup while no client has it open:
        // the virtual board polls for it every millisecond, but a reopen
        // before its thread next runs hides the close (a loaded machine
        // starved it for over 100 ms). A USB port has no such race.
        std::thread::sleep(Duration::from_millis(1000));
    }
}
