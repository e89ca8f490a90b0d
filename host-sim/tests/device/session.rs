//! The device session's GRBL text behaviour through the virtual device:
//! banner, `$` commands, status, check mode, jogging, soft reset and alarm,
//! realtime bytes while the line buffer is full. Deterministic: bytes go in
//! directly and virtual time advances in fixed steps.

use host_sim::record::Discard;
use protocol::client::grbl::{classify, TextEvent};

use crate::rig;

use rig::{origin, Rig};

#[test]
fn banner_info_settings_and_parser_state() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    assert!(r.lines().iter().any(|l| l.starts_with("Grbl 1.1h")));
    let info = r.cmd("$I");
    assert!(info[0].starts_with("[VER:1.1h.burin-"), "{info:?}");
    assert!(info[1].ends_with(",64,128]"), "{info:?}");
    assert_eq!(info.last().map(String::as_str), Some("ok"));
    let all = r.cmd("$$");
    assert!(all.iter().any(|l| l.starts_with("$100=")), "{all:?}");
    assert_eq!(r.cmd("$110=4000"), ["ok"]);
    assert_eq!(r.cmd("$110"), ["$110=4000.000", "ok"]);
    assert_eq!(r.cmd("$110=-5"), ["error:4"]);
    assert_eq!(
        r.cmd("$G"),
        ["[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]", "ok"]
    );
    assert_eq!(r.cmd("G91 G20"), ["ok"]);
    assert!(r.cmd("$G")[0].contains("G20 G91"));
    let bad = r.cmd("G1 X1 Q5");
    assert!(
        matches!(classify(&bad[0]), TextEvent::Error(n) if n > 0),
        "{bad:?}"
    );
    // A failed line leaves no trace: still G91 G20.
    assert!(r.cmd("$G")[0].contains("G20 G91"));
    assert_eq!(r.cmd(""), ["ok"]);
    assert_eq!(r.cmd("$Q"), ["error:3"]);
}

#[test]
fn status_report_fields_and_motion() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$10=3"), ["ok"]);
    assert_eq!(r.cmd("G10 L2 P1 X-100 Y-100 Z-10"), ["ok"]);
    assert_eq!(r.cmd("N7 G1 X5 Y5 Z-1 F600"), ["ok"]);
    r.run(20);
    let st = r.status();
    assert_eq!(st.state, "Run");
    assert!(
        st.bf.is_some() && st.line.is_some() && st.feed.unwrap_or(0.0) > 0.0,
        "{st:?}"
    );
    let st = r.until_idle();
    assert_eq!(st.mpos, rig::shown([-95.0, -95.0, -11.0, 0.0]));
    assert_eq!(st.bf, Some((64, 128)));
    assert_eq!(r.cmd("$10=0"), ["ok"]);
    let st = r.status();
    assert_eq!(st.wpos, rig::shown([5.0, 5.0, -1.0, 0.0]), "{st:?}");
}

#[test]
fn check_mode_interprets_without_moving() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$C"), ["[MSG:Enabled]", "ok"]);
    assert_eq!(r.status().state, "Check");
    assert_eq!(r.cmd("G1 X-50 F100"), ["ok"]);
    assert!(matches!(
        classify(&r.cmd("G2 X-5 R0")[0]),
        TextEvent::Error(_)
    ));
    r.run(50);
    let st = r.status();
    assert_eq!(st.mpos, rig::shown([0.0, 0.0, 0.0, 0.0]));
    // GRBL soft-resets as check mode ends: the banner follows the `ok`.
    assert_eq!(
        r.cmd("$C"),
        ["[MSG:Disabled]", "ok", "Grbl 1.1h ['$' for help]"]
    );
    assert_eq!(r.status().state, "Idle");
}

#[test]
fn jog_and_jog_cancel() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$J=G91 X-10 F1000"), ["ok"]);
    assert_eq!(r.status().state, "Jog");
    let st = r.until_idle();
    assert_eq!(st.mpos, rig::shown([-10.0, 0.0, 0.0, 0.0]));
    // No feed, or a word a jog may not carry: refused, nothing moves.
    assert_eq!(r.cmd("$J=G91 X-10"), ["error:16"]);
    assert_eq!(r.cmd("$J=G91 X-10 M3 F100"), ["error:16"]);
    // The job's modal state is untouched by the jog's G91.
    assert!(r.cmd("$G")[0].contains("G90"));
    // A long jog, cancelled: stops short, no alarm, position known.
    assert_eq!(r.cmd("$J=G90 X-200 F3000"), ["ok"]);
    r.run(100);
    r.send(&[0x85]);
    let st = r.until_idle();
    let x = st.mpos.as_ref().map_or(0.0, |p| p[0]);
    assert!(x < -10.0 && x > -200.0, "{st:?}");
    assert!(!r.lines().iter().any(|l| l.starts_with("ALARM")));
    assert_eq!(r.cmd("G1 X-20 F1000"), ["ok"]);
    let st = r.until_idle();
    assert_eq!(st.mpos, rig::shown([-20.0, 0.0, 0.0, 0.0]));
}

#[test]
fn reset_while_moving_alarms_then_banner_and_unlock() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-100 F1000"), ["ok"]);
    r.run(50);
    r.send(&[0x18]);
    r.run(2);
    let out = r.lines();
    let alarm = out.iter().position(|l| l == "ALARM:3");
    let banner = out.iter().position(|l| l.starts_with("Grbl 1.1h"));
    assert!(
        alarm.is_some() && banner.is_some() && alarm < banner,
        "{out:?}"
    );
    r.alarm_holds(50);
    assert_eq!(r.cmd("G1 X-5"), ["error:9"]);
    r.unlock_and_move_to(-5.0);
}

/// The e-stop pin: its interrupt latches the level in `Realtime` and
/// raises a soft reset, as the board does. The machine stays in alarm,
/// refusing motion, `$X` and `$H`, until the e-stop is released.
#[test]
fn estop_latches_the_alarm_until_released() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-100 F1000"), ["ok"]);
    r.run(50);
    r.dev.sim.rt.set_estop(true);
    r.send(&[0x18]);
    r.run(2);
    let out = r.lines();
    assert!(out.iter().any(|l| l == "ALARM:10"), "{out:?}");
    assert!(
        !out.iter().any(|l| l == "ALARM:3"),
        "one alarm, the e-stop's: {out:?}"
    );
    r.alarm_holds(50);
    assert_eq!(r.cmd("$X"), ["error:9"]);
    assert_eq!(r.cmd("$H"), ["error:9"]);
    assert_eq!(r.cmd("G1 X-5 F1000"), ["error:9"]);
    r.run(10);
    assert_eq!(r.status().state, "Alarm");
    // Released: unlock works and the machine moves again.
    r.dev.sim.rt.set_estop(false);
    r.run(2);
    r.unlock_and_move_to(-5.0);
}

/// A limit switch closing at rest (the board's limit interrupt, `$21=1`)
/// raises alarm 1 as GRBL does; nothing moves, `$X` unlocks.
#[test]
fn hard_limit_at_rest_alarms() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-5 F1000"), ["ok"]);
    let before = r.until_idle().mpos;
    r.dev.sim.rt.hard_limit(0b001);
    r.run(2);
    let out = r.lines();
    assert!(out.iter().any(|l| l == "ALARM:1"), "{out:?}");
    let st = r.status();
    assert_eq!(st.state, "Alarm");
    assert_eq!(st.mpos, before);
    assert_eq!(r.cmd("G1 X-6"), ["error:9"]);
    r.unlock_and_move_to(-6.0);
}

/// Pressed at power-up there is no edge: the level alone latches the alarm.
#[test]
fn estop_pressed_at_power_up_alarms() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.dev.sim.rt.set_estop(true);
    r.run(2);
    let out = r.lines();
    assert!(out.iter().any(|l| l == "ALARM:10"), "{out:?}");
    assert_eq!(r.status().state, "Alarm");
    assert_eq!(r.cmd("G0 X-1"), ["error:9"]);
}

#[test]
fn reset_in_a_finished_hold_keeps_the_position_without_alarm() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-100 F1000"), ["ok"]);
    r.run(50);
    r.send(b"!");
    r.run(200);
    let st = r.status();
    assert_eq!(st.state, "Hold:0");
    r.send(&[0x18]);
    r.run(5);
    let out = r.lines();
    assert!(!out.iter().any(|l| l.starts_with("ALARM")), "{out:?}");
    assert!(out.iter().any(|l| l.starts_with("Grbl 1.1h")), "{out:?}");
    let after = r.status();
    assert_eq!(after.state, "Idle");
    assert_eq!(after.mpos, st.mpos);
    assert_eq!(r.cmd("G1 X-5 F1000"), ["ok"]);
    assert_eq!(r.until_idle().mpos, rig::shown([-5.0, 0.0, 0.0, 0.0]));
}

#[test]
fn realtime_bytes_act_while_the_line_buffer_is_full() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    // Far more lines than the queues hold; the link fills and pushes back.
    let mut job = String::new();
    for i in 0..400 {
        job.push_str(&format!("G1 X-{}.5 F3000\n", i % 10));
    }
    // Like a character-counting sender: never more than the 128-byte
    // window unprocessed. The device stops taking lines once its queues
    // are full; the window then stays full.
    let mut rest = job.as_bytes();
    let mut full_rounds = 0;
    while !rest.is_empty() && full_rounds < 20 {
        let room = 120usize.saturating_sub(r.dev.rx_pending());
        let n = rest.iter().take(room).count();
        r.send(&rest[..n]);
        rest = &rest[n..];
        r.run(1);
        full_rounds = if r.dev.rx_pending() >= 100 {
            full_rounds + 1
        } else {
            0
        };
    }
    assert!(
        !rest.is_empty() && r.dev.rx_pending() >= 100,
        "the line buffer never filled"
    );
    // Status, hold and overrides still get through at once.
    r.send(b"!");
    // Two override steps, each handled before the next arrives.
    r.send(&[0x91]);
    r.run(1);
    r.send(&[0x91]);
    r.run(200);
    let st = r.status();
    assert_eq!(st.state, "Hold:0", "{st:?}");
    assert_eq!(st.ov.map(|o| o.0), Some(120));
    r.send(b"~");
    r.run(5);
    assert_eq!(r.status().state, "Run");
}
