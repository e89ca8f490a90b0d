//! Issue 35 item 2: an unlock acknowledged with `ok` means the next line is
//! judged unlocked, whatever the read boundaries. A character-counting
//! sender writes `$X` and the first job line in one go; the line must run,
//! in text and in framed mode, after every kind of alarm.

use host_sim::config::MachineConfig;
use host_sim::record::Discard;
use protocol::{DeviceMsg, HostMsg, Rt};

use crate::rig;

use rig::{line_frame, origin, Rig};

/// X of the machine position, mm.
fn x_of(r: &mut Rig) -> f32 {
    r.status().mpos.as_ref().map_or(f32::NAN, |p| p[0])
}

/// `$X` and a relative move in one write: both answered `ok`, and the
/// move runs from where the alarm left the machine.
fn unlock_and_move_in_one_write(r: &mut Rig) {
    r.alarm_holds(5);
    let x = x_of(r);
    r.send(b"$X\nG91 G0 X-2\n");
    r.run(5);
    assert_eq!(r.lines(), ["[MSG:Caution: Unlocked]", "ok", "ok"]);
    let st = r.until_idle();
    let got = st.mpos.as_ref().map_or(f32::NAN, |p| p[0]);
    assert!((got - (x - 2.0)).abs() < 1e-3, "X {x} -> {got}");
}

/// The case: a reset during motion (ALARM:3), then `$X` and a line.
#[test]
fn unlock_and_a_line_in_one_write_after_a_reset_in_motion() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-100 F1000"), ["ok"]);
    r.run(50);
    r.send(&[0x18]);
    r.run(5);
    let out = r.lines();
    assert!(out.iter().any(|l| l == "ALARM:3"), "{out:?}");
    unlock_and_move_in_one_write(&mut r);
}

/// A probe that never touches (ALARM:5), then `$X` and a line.
#[test]
fn unlock_and_a_line_in_one_write_after_a_failed_probe() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    // The plate is at Z -50: a probe to Z -5 ends without contact.
    assert_eq!(r.cmd("G38.2 Z-5 F600"), ["ok"]);
    let mut out = Vec::new();
    for _ in 0..100 {
        r.run(10);
        out.extend(r.lines());
        if out.iter().any(|l| l.starts_with("ALARM")) {
            break;
        }
    }
    assert!(out.iter().any(|l| l == "ALARM:5"), "{out:?}");
    unlock_and_move_in_one_write(&mut r);
}

/// Framed: the `$X` line and the next line in one burst, within the
/// credit window: the second line runs (no `Error` frame for it).
#[test]
fn framed_unlock_and_a_line_in_one_burst() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.dev.log = Some(Vec::new());
    let s = r.go_framed();
    r.send(&line_frame(s, "G1 X-100 F1000"));
    r.run_framed(50);
    r.send(&rig::frame(&HostMsg::Realtime(Rt::SoftReset)));
    let msgs = r.run_framed(10);
    assert!(
        msgs.iter()
            .any(|m| matches!(m, DeviceMsg::Alarm { code: 3 })),
        "{msgs:?}"
    );
    let x = r.dev.position_steps()[0];
    let mut burst = line_frame(s + 1, "$X");
    burst.extend(line_frame(s + 2, "G91 G0 X-2"));
    r.send(&burst);
    let mut msgs = Vec::new();
    for _ in 0..100 {
        msgs.extend(r.run_framed(10));
        if r.dev.idle() && r.dev.position_steps()[0] != x {
            break;
        }
    }
    assert!(
        !msgs.iter().any(|m| matches!(m, DeviceMsg::Error { .. })),
        "{msgs:?}"
    );
    assert_eq!(r.dev.log.as_deref(), Some(&[s, 0, s + 2][..]));
    // 2 mm at 80 steps/mm.
    assert_eq!(r.dev.position_steps()[0], x - 160);
}

/// `$H` in alarm, and a line in the same write: the line waits for the
/// homing cycle and runs after it (a guard: `$H` holds the next line back
/// until the cycle ends, so this passed before the fix too).
#[test]
fn home_and_a_line_in_one_write_after_an_alarm() {
    let mut cfg = MachineConfig::default();
    cfg.settings.homing_enable = true;
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-100 F1000"), ["ok"]);
    r.run(50);
    r.send(&[0x18]);
    r.run(5);
    assert!(r.lines().iter().any(|l| l == "ALARM:3"));
    r.send(b"$H\nG91 G0 X-2\n");
    let mut out = Vec::new();
    for _ in 0..10_000 {
        r.run(10);
        out.extend(r.lines());
        if r.dev.idle() && out.iter().filter(|l| *l == "ok").count() == 2 {
            break;
        }
    }
    assert_eq!(out, ["ok", "ok"]);
    let st = r.status();
    // X and Y home alike; then X moved 2 mm on.
    let p = st.mpos.unwrap_or_default();
    assert!((p[0] - (p[1] - 2.0)).abs() < 1e-3, "{p:?}");
}
