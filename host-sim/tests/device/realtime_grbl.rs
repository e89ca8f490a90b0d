//! Issue 29 through the virtual board: GRBL 1.1's realtime state machine
//! (safety door, spindle stop, coolant toggles and `A:`, holds in dwells,
//! jog and hold, the spindle override in `FS:`, sleep, port open, `$C`,
//! `Ln:` and `$208`), each driven with the bytes a sender sends.

use host_sim::config::MachineConfig;
use host_sim::record::Discard;

use crate::rig;

use rig::{origin, Rig};

/// Run 2 ms rounds until the status state is `want` (at most `limit`).
fn until_state(r: &mut Rig, want: &str, limit: usize) {
    for _ in 0..limit {
        r.run(5);
        if r.status().state == want {
            return;
        }
    }
    panic!("never {want}: {:?}", r.status());
}

/// A machine cutting along X with the spindle and flood on, `$220` at
/// half a second.
fn cutting(r: &mut Rig) {
    r.lines();
    assert_eq!(r.cmd("$220=0.5"), ["ok"]);
    r.cutting();
}

/// Item 1: 0x84 holds (`Door:2` while stopping, `[MSG:Check Door]`),
/// then spindle and coolant go off (`Door:0` with no door switch);
/// `~` turns the spindle on (`Door:3`), waits `$220`, then the coolant
/// and the motion resume.
#[test]
fn safety_door_stops_outputs_and_resumes_after_the_spin_up_delay() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    cutting(&mut r);
    r.send(&[0x84]);
    r.run(1);
    let lines = r.lines();
    assert!(lines.iter().any(|l| l == "[MSG:Check Door]"), "{lines:?}");
    assert_eq!(r.status().state, "Door:2");
    assert!(
        r.spindle_on(),
        "the spindle turns until the hold has stopped"
    );
    until_state(&mut r, "Door:0", 1000);
    r.run(2);
    assert!(!r.spindle_on() && !r.flood_on());
    let st = r.status();
    assert_eq!(st.spindle, Some(0.0));
    let held_at = r.x();
    r.send(b"~");
    r.run(5);
    assert_eq!(r.status().state, "Door:3");
    assert!(r.spindle_on() && !r.flood_on(), "spindle first");
    r.run(150);
    assert_eq!(r.x(), held_at, "no motion before the spindle is up");
    r.run(150);
    assert!(r.flood_on(), "coolant after the delay");
    assert_ne!(r.x(), held_at, "and the motion");
    let st = r.until_idle();
    assert_eq!(st.mpos.map(|p| p[0]), Some(-50.0));
}

/// Item 1: with a door switch open, `~` does nothing (`Door:1`); once it
/// reads closed (`Door:0`) it resumes. A door from idle holds too.
#[test]
fn safety_door_resumes_only_with_the_door_closed() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    cutting(&mut r);
    r.dev.sim.rt.set_door_open(true);
    r.send(&[0x84]);
    until_state(&mut r, "Door:1", 1000);
    let held_at = r.x();
    r.send(b"~");
    r.run(400);
    assert_eq!(r.status().state, "Door:1");
    assert_eq!(r.x(), held_at);
    assert!(!r.spindle_on());
    r.dev.sim.rt.set_door_open(false);
    r.run(2);
    assert_eq!(r.status().state, "Door:0");
    r.send(b"~");
    let st = r.until_idle();
    assert_eq!(st.mpos.map(|p| p[0]), Some(-50.0));
    // From idle: the door holds the next line until `~`.
    r.send(&[0x84]);
    until_state(&mut r, "Door:0", 100);
    assert_eq!(
        r.cmd("$J=G91 X-1 F100"),
        ["error:8"],
        "no jog behind a door"
    );
    assert_eq!(r.cmd("G1 X-40 F600"), ["ok"]);
    r.run(200);
    assert_eq!(r.x(), -50.0, "nothing moves behind a door");
    r.send(b"~");
    let st = r.until_idle();
    assert_eq!(st.mpos.map(|p| p[0]), Some(-40.0));
}

/// Item 2: 0x9E in a hold stops the spindle and a second one restores it
/// (`[MSG:Restoring spindle]`); outside a hold it does nothing; `~` with
/// the spindle stopped restores it, waits, then resumes.
#[test]
fn spindle_stop_toggles_only_in_a_hold() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    cutting(&mut r);
    r.send(&[0x9E]);
    r.run(20);
    assert!(r.spindle_on(), "no spindle stop while running");
    r.send(b"!");
    until_state(&mut r, "Hold:0", 1000);
    r.send(&[0x9E]);
    r.run(5);
    assert!(!r.spindle_on() && r.flood_on(), "the spindle alone stops");
    assert_eq!(r.status().spindle, Some(0.0));
    r.lines();
    r.send(&[0x9E]);
    r.run(5);
    assert!(r.lines().iter().any(|l| l == "[MSG:Restoring spindle]"));
    assert!(r.spindle_on());
    r.send(&[0x9E]);
    r.run(5);
    assert!(!r.spindle_on());
    let held_at = r.x();
    r.lines();
    r.send(b"~");
    r.run(5);
    assert!(r.spindle_on());
    assert!(r.lines().iter().any(|l| l == "[MSG:Restoring spindle]"));
    r.run(150);
    assert_eq!(r.x(), held_at, "waits for the spindle");
    let st = r.until_idle();
    assert_eq!(st.mpos.map(|p| p[0]), Some(-50.0));
}

/// Item 2: 0xA0 and 0xA1 toggle flood and mist at once, `$G` follows, and
/// the status report carries `A:` (S, C, F, M) as GRBL formats it.
#[test]
fn coolant_toggles_and_the_accessory_field() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.status().accessories, None);
    r.send(&[0xA0]);
    r.run(2);
    assert!(r.flood_on());
    assert_eq!(r.status().accessories.as_deref(), Some("F"));
    r.send(&[0xA1]);
    r.run(2);
    assert_eq!(r.status().accessories.as_deref(), Some("FM"));
    assert!(r.cmd("$G")[0].contains("M8"));
    assert_eq!(r.cmd("M4 S300"), ["ok"]);
    r.run(2);
    assert_eq!(r.status().accessories.as_deref(), Some("CFM"));
    assert_eq!(r.cmd("M3"), ["ok"]);
    r.send(&[0xA0]);
    r.run(2);
    assert!(!r.flood_on());
    assert_eq!(r.status().accessories.as_deref(), Some("SM"));
}

/// Items 3 and finding 6: `!` in a dwell is `Hold:0` at once, the dwell
/// pauses, the move queued behind it does not start, and `~` runs the
/// rest of the dwell and then the move.
#[test]
fn a_hold_pauses_a_dwell_and_what_waits_behind_it() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G4 P1"), ["ok"]);
    assert_eq!(r.cmd("G1 X-10 F600"), ["ok"]);
    r.run(100); // 0.2 s into the dwell
    r.send(b"!");
    r.run(1);
    assert_eq!(r.status().state, "Hold:0", "at once");
    r.run(1500); // 3 s: the dwell would be long over
    assert_eq!(r.status().state, "Hold:0");
    assert_eq!(r.x(), 0.0, "the move behind the dwell waits");
    r.send(b"~");
    r.run(300); // 0.6 s of the 0.8 s left
    assert_eq!(r.x(), 0.0, "the dwell's rest runs first");
    let st = r.until_idle();
    assert_eq!(st.mpos.map(|p| p[0]), Some(-10.0));
}

/// Item 3: a reset in a dwell, held or not, moves nothing and raises no
/// alarm (no `ALARM:3`, no unlock hint); the machine is idle after it.
#[test]
fn a_reset_in_a_dwell_raises_no_alarm() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    for hold in [true, false] {
        assert_eq!(r.cmd("G4 P3"), ["ok"]);
        assert_eq!(r.cmd("G1 X-10 F600"), ["ok"]);
        r.run(100);
        if hold {
            r.send(b"!");
            r.run(2);
        }
        r.send(&[0x18]);
        r.run(5);
        let out = r.lines();
        assert!(out.iter().any(|l| l.starts_with("Grbl 1.1h")), "{out:?}");
        assert!(!out.iter().any(|l| l.starts_with("ALARM")), "{out:?}");
        assert!(!out.iter().any(|l| l.contains("to unlock")), "{out:?}");
        assert_eq!(r.status().state, "Idle");
        assert_eq!(r.x(), 0.0);
    }
}

/// Item 4: a feed hold during a jog cancels and flushes it (back to
/// `Idle`, `~` resumes nothing).
#[test]
fn a_feed_hold_cancels_a_jog() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$J=G91 X-50 F1000"), ["ok"]);
    r.run(100);
    assert_eq!(r.status().state, "Jog");
    r.send(b"!");
    until_state(&mut r, "Idle", 1000);
    let stopped = r.x();
    assert!(stopped < 0.0 && stopped > -50.0, "{stopped}");
    r.send(b"~");
    r.run(200);
    assert_eq!(r.status().state, "Idle");
    assert_eq!(r.x(), stopped);
    assert!(!r.lines().iter().any(|l| l.starts_with("ALARM")));
}

/// Item 4: the spindle override reaches `FS:` and the spindle's duty.
#[test]
fn the_spindle_override_shows_in_fs_and_drives_the_pwm() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("M3 S500"), ["ok"]);
    r.run(2);
    let duty = r.dev.pins().map(|p| p.spindle.duty);
    assert_eq!(r.status().spindle, Some(500.0));
    r.send(&[0x9A]);
    r.run(2);
    let st = r.status();
    assert_eq!(st.spindle, Some(550.0), "{st:?}");
    assert_eq!(st.ov, Some((100, 100, 110)));
    let more = r.dev.pins().map(|p| p.spindle.duty);
    assert!(more > duty, "{duty:?} -> {more:?}");
}

/// Item 5: asleep, lines get no reply (GRBL reads nothing); a reset wakes
/// the machine into alarm with the unlock hint.
#[test]
fn sleep_answers_nothing_and_wakes_into_alarm() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$SLP"), ["[MSG:Sleeping]", "ok"]);
    assert_eq!(r.cmd("G0 X-1"), Vec::<String>::new());
    r.send(&[0x18]);
    r.run(5);
    let out = r.lines();
    assert!(
        out.iter().any(|l| l == "[MSG:'$H'|'$X' to unlock]"),
        "{out:?}"
    );
    assert!(!out.iter().any(|l| l.starts_with("ALARM")), "{out:?}");
    assert_eq!(r.status().state, "Alarm");
    assert_eq!(r.x(), 0.0, "the line sent while asleep never ran");
    r.unlock_and_move_to(-2.0);
}

/// Finding 1, item 6: a port open at rest is a reset (check mode off,
/// modal state back to defaults), so its banner is true.
#[test]
fn a_port_open_at_rest_resets_as_a_dtr_reset() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$C"), ["[MSG:Enabled]", "ok"]);
    assert_eq!(r.cmd("G91 G20"), ["ok"]);
    r.dev.port_closed();
    r.run(2);
    r.dev.port_opened();
    r.run(2);
    let out = r.lines();
    assert_eq!(out, ["Grbl 1.1h ['$' for help]"]);
    assert_eq!(r.status().state, "Idle", "check mode is off");
    let gc = r.cmd("$G");
    assert!(gc[0].contains("G21") && gc[0].contains("G90"), "{gc:?}");
}

/// Item 6: a port open while a job runs resets nothing and sends no
/// banner; the job finishes.
#[test]
fn a_port_open_while_running_keeps_the_job_and_sends_no_banner() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-20 F600"), ["ok"]);
    r.run(50);
    r.dev.port_closed();
    r.run(2);
    r.dev.port_opened();
    r.run(2);
    assert!(r.lines().is_empty());
    assert_eq!(r.status().state, "Run");
    let st = r.until_idle();
    assert_eq!(st.mpos.map(|p| p[0]), Some(-20.0));
}

/// Item 6: reopened in alarm, the banner comes with the unlock hint.
#[test]
fn a_port_open_in_alarm_shows_the_unlock_message() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X-20 F600"), ["ok"]);
    r.run(100);
    r.send(&[0x18]);
    r.run(5);
    assert!(r.lines().iter().any(|l| l == "ALARM:3"));
    r.dev.port_closed();
    r.run(2);
    r.dev.port_opened();
    r.run(2);
    assert_eq!(
        r.lines(),
        ["Grbl 1.1h ['$' for help]", "[MSG:'$H'|'$X' to unlock]"]
    );
    assert_eq!(r.status().state, "Alarm");
}

/// Item 6: `$C` off is GRBL's soft reset: banner after the `ok`, modal
/// state back to defaults.
#[test]
fn check_mode_off_resets_with_a_banner() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$C"), ["[MSG:Enabled]", "ok"]);
    assert_eq!(r.cmd("G20"), ["ok"]);
    assert_eq!(
        r.cmd("$C"),
        ["[MSG:Disabled]", "ok", "Grbl 1.1h ['$' for help]"]
    );
    assert!(r.cmd("$G")[0].contains("G21"));
}

/// Item 7: `Ln:` is the line's N word when it has one.
#[test]
fn ln_reports_the_n_word() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("N100 G1 X-20 F600"), ["ok"]);
    r.run(50);
    assert_eq!(r.status().line, Some(100));
    assert_eq!(r.cmd("G1 X-10"), ["ok"]);
    let st = r.until_idle();
    assert_eq!(st.mpos.map(|p| p[0]), Some(-10.0));
}

/// Item 7: `$208` defaults to the axes the machine file describes: the
/// XYZ machines report three axes, the default (with A) four.
#[test]
fn reported_axes_default_to_the_machine() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/machines/");
    for (file, axes) in [("grbl_match.toml", 3.0), ("default.toml", 4.0)] {
        let cfg = MachineConfig::load(format!("{dir}{file}")).expect("machine file");
        assert_eq!(cfg.settings.get(208), Some(axes), "{file}");
    }
}

/// Item 1: the door during homing ends the cycle with GRBL's `ALARM:7`.
#[test]
fn a_door_during_homing_is_alarm_7() {
    let mut cfg = origin();
    cfg.settings.homing_enable = true;
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.send(b"$H\n");
    r.run(50);
    assert_eq!(r.status().state, "Home");
    r.send(&[0x84]);
    let mut out = Vec::new();
    for _ in 0..500 {
        r.run(5);
        out.extend(r.lines());
        if out.iter().any(|l| l.starts_with("ALARM")) {
            break;
        }
    }
    assert!(out.iter().any(|l| l == "ALARM:7"), "{out:?}");
    r.run(50);
    r.alarm_holds(100);
}
