//! Issue 35 item 3: a move refused after its line's `ok` stops the job.
//! A GRBL sender counts the `ok` and streams on; a `[MSG:…]` alone lets
//! the job run past the missing move. The stop is an alarm (soft limit:
//! `ALARM:2`, as GRBL), after a ramp down along the path, and nothing
//! behind the refused line runs.

use host_sim::record::Discard;
use protocol::codes::alarm;
use protocol::{DeviceMsg, HostMsg};

use crate::common;
use crate::rig;

use rig::{line_frame, origin, Rig};

/// Run until an `ALARM` line came (at most `rounds` rounds of 10).
fn until_alarm(r: &mut Rig, rounds: usize) -> Vec<String> {
    let mut out = Vec::new();
    for _ in 0..rounds {
        r.run(10);
        out.extend(r.lines());
        if out.iter().any(|l| l.starts_with("ALARM")) {
            break;
        }
    }
    out
}

/// A move along X is under way at F600; then the bad line and two more
/// lines arrive in one write. Returns the replies up to the alarm and
/// after it, and X where the move had got to when they arrived.
fn refused_mid_job(r: &mut Rig, bad: &str) -> (Vec<String>, f32) {
    r.lines();
    assert_eq!(r.cmd("G1 X-50 F600"), ["ok"]);
    r.run(100);
    let x0 = r.status().mpos.as_ref().map_or(f32::NAN, |p| p[0]);
    assert!(x0 < -0.5, "not moving yet: {x0}");
    r.send(format!("{bad}\nG1 Y-5 F600\nG1 Y-10\n").as_bytes());
    let mut out = until_alarm(r, 200);
    for _ in 0..20 {
        r.run(10);
        out.extend(r.lines());
    }
    (out, x0)
}

/// The machine stopped on the X move, never moved in Y, stays in alarm,
/// and `$X` unlocks it with its position known.
fn stopped_on_x(r: &mut Rig, x0: f32) {
    let st = r.status();
    assert_eq!(st.state, "Alarm", "{st:?}");
    let p = st.mpos.unwrap_or_default();
    assert_eq!(p[1], 0.0, "moved in Y: {p:?}");
    assert!(p[0] < x0 && p[0] > -50.0, "X {x0} -> {p:?}");
    r.alarm_holds(50);
    r.unlock_and_move_to(-5.0);
}

/// Soft limit found after the `ok`: `ALARM:2`, the lines behind it are
/// refused (`error:9`), Y never moves.
#[test]
fn late_soft_limit_raises_alarm_2_and_stops_the_stream() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    // Envelope X, Y in [-300, 0]: X-400 is outside.
    assert_eq!(r.cmd("$20=1"), ["ok"]);
    let (out, x0) = refused_mid_job(&mut r, "G1 X-400");
    println!("{out:?}");
    let msg = out
        .iter()
        .position(|l| l.starts_with("[MSG:line 2: error 400"));
    let alarm = out.iter().position(|l| l == "ALARM:2");
    assert!(msg.is_some() && alarm.is_some() && msg < alarm, "{out:?}");
    // The bad line's `ok`, then no `ok` for anything behind it.
    assert_eq!(out.iter().filter(|l| *l == "ok").count(), 1, "{out:?}");
    assert_eq!(out.iter().filter(|l| *l == "error:9").count(), 2, "{out:?}");
    stopped_on_x(&mut r, x0);
}

/// Feed too slow (412) found after the `ok`: the same stop, as burin's
/// `ALARM:21` (a line refused after its `ok`).
#[test]
fn late_feed_too_slow_raises_an_alarm_and_stops_the_stream() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    let (out, x0) = refused_mid_job(&mut r, "G1 X-60 F0.0001");
    let msg = out
        .iter()
        .position(|l| l.starts_with("[MSG:line 2: error 412"));
    let code = format!("ALARM:{}", alarm::LATE_ERROR);
    let alarm = out.iter().position(|l| *l == code);
    assert!(msg.is_some() && alarm.is_some() && msg < alarm, "{out:?}");
    assert_eq!(out.iter().filter(|l| *l == "ok").count(), 1, "{out:?}");
    assert_eq!(out.iter().filter(|l| *l == "error:9").count(), 2, "{out:?}");
    stopped_on_x(&mut r, x0);
}

/// A jog beyond the soft limits is not a job: it is refused before its
/// `ok` with GRBL's `error:15`, without an alarm.
#[test]
fn jog_beyond_the_soft_limits_is_error_15_without_alarm() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$20=1"), ["ok"]);
    r.send(b"$J=G91 X-400 F1000\n");
    r.run(20);
    let out = r.lines();
    assert_eq!(out, ["error:15"]);
    assert_eq!(r.status().state, "Idle");
    assert_eq!(r.cmd("G1 X-5 F1000"), ["ok"]);
    assert_eq!(r.until_idle().mpos, rig::shown([-5.0, 0.0, 0.0, 0.0]));
}

/// Framed: the refused line's `Error`, then the alarm; the lines behind it
/// (acknowledged into line slots) never reach the executor.
#[test]
fn framed_late_soft_limit_alarms_and_drops_the_lines_behind() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.dev.log = Some(Vec::new());
    let s = r.go_framed();
    r.send(&rig::frame(&HostMsg::SetSetting { n: 20, value: 1.0 }));
    r.send(&line_frame(s, "G1 X-50 F600"));
    r.run_framed(100);
    let mut burst = line_frame(s + 1, "G1 X-400");
    burst.extend(line_frame(s + 2, "G1 Y-5"));
    burst.extend(line_frame(s + 3, "G1 Y-10"));
    r.send(&burst);
    let mut msgs = Vec::new();
    for _ in 0..50 {
        msgs.extend(r.run_framed(10));
    }
    let err = msgs
        .iter()
        .position(|m| matches!(m, DeviceMsg::Error { seq: Some(q), code: 400, .. } if *q == s + 1));
    let alarm = msgs.iter().position(|m| {
        matches!(
            m,
            DeviceMsg::Alarm {
                code: alarm::SOFT_LIMIT
            }
        )
    });
    assert!(err.is_some() && alarm.is_some() && err < alarm, "{msgs:?}");
    assert_eq!(r.dev.log.as_deref(), Some(&[s][..]));
    assert_eq!(r.dev.position_steps()[1], 0);
}

/// A fault the executor finds on its own, after the command was accepted:
/// the probe move is planned only once the motion before it has stopped,
/// and its feed is refused then. It used to be dropped without a word and
/// the job went on.
#[test]
fn probe_move_refused_when_planned_stops_the_job() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.send(b"G38.2 Z-10 F0.0001\nG0 X-5\n");
    let out = until_alarm(&mut r, 100);
    let msg = out
        .iter()
        .position(|l| l.starts_with("[MSG:line 1: error 412"));
    let code = format!("ALARM:{}", alarm::LATE_ERROR);
    let alarm = out.iter().position(|l| *l == code);
    assert!(msg.is_some() && alarm.is_some() && msg < alarm, "{out:?}");
    r.run(20);
    let mut out = out;
    out.extend(r.lines());
    // The probe line's `ok`; the move behind it is refused.
    assert_eq!(out.iter().filter(|l| *l == "ok").count(), 1, "{out:?}");
    assert_eq!(out.iter().filter(|l| *l == "error:9").count(), 1, "{out:?}");
    assert_eq!(r.status().mpos, rig::shown([0.0, 0.0, 0.0, 0.0]));
}

/// A canned cycle's step refused by the soft limits (its R plane is above
/// the envelope): the cycle stops as `ALARM:2` instead of being cut short
/// without a word while the job goes on.
#[test]
fn canned_cycle_step_outside_the_soft_limits_stops_the_job() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$20=1"), ["ok"]);
    r.send(b"G90 G0 Z-20\nG98 G81 X-10 Y-10 Z-30 R10 F300\nG80 G0 X-20\n");
    let out = until_alarm(&mut r, 500);
    let msg = out
        .iter()
        .position(|l| l.starts_with("[MSG:line 2: error 400"));
    let alarm = out.iter().position(|l| l == "ALARM:2");
    assert!(msg.is_some() && alarm.is_some() && msg < alarm, "{out:?}");
    // The cycle runs after the move before it, so the line behind it was
    // acknowledged already: dropped, it never runs.
    r.run(200);
    let p = r.status().mpos.unwrap_or_default();
    assert!(p[0] >= -10.0, "{p:?}");
    assert_eq!(r.status().state, "Alarm");
}

/// The ramp down before the alarm is not a feed hold: cycle start during
/// it resumes nothing, and the alarm comes.
#[test]
fn cycle_start_does_not_resume_the_stop() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$20=1"), ["ok"]);
    assert_eq!(r.cmd("G1 X-50 F3000"), ["ok"]);
    r.run(100);
    r.send(b"G1 X-400\n");
    r.run(1);
    let st = r.status();
    assert_eq!(st.state, "Run", "still ramping down: {st:?}");
    r.send(b"~");
    let out = until_alarm(&mut r, 100);
    assert!(out.iter().any(|l| l == "ALARM:2"), "{out:?}");
    let x = r.status().mpos.map_or(f32::NAN, |p| p[0]);
    assert!(x > -25.0, "ran on after ~: {x}");
    r.run(100);
    assert_eq!(r.status().mpos.map_or(f32::NAN, |p| p[0]), x);
}

/// The stop is a ramp at the axis's acceleration, not a halt: the steps
/// before it decelerate within `$120`, and the alarm's position is where
/// the steps ended.
#[test]
fn the_stop_decelerates_and_keeps_the_position() {
    let cfg = origin();
    let mut rec = common::Collect::default();
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$20=1"), ["ok"]);
    assert_eq!(r.cmd("G1 X-50 F3000"), ["ok"]);
    r.run(200);
    r.send(b"G1 X-400\n");
    let out = until_alarm(&mut r, 100);
    assert!(out.iter().any(|l| l == "ALARM:2"), "{out:?}");
    r.run(50);
    let steps = r.dev.position_steps();
    let st = r.status();
    drop(r);
    let info = rec.info.clone().expect("run info");
    let worst = common::check_stop_decel(&info, &rec.events, 0, 200);
    println!("stop: worst distance/bound {worst:.3}");
    let x = st.mpos.map_or(f32::NAN, |p| p[0]);
    assert_eq!(x, steps[0] as f32 / 80.0);
    assert!(x < -5.0 && x > -50.0, "{x}");
}
