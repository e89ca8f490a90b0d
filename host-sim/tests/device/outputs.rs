//! The outputs as the board drives them, through the virtual board: the
//! controller's pin levels after each pass (spindle, coolant, stepper
//! enable with `$1`, laser mode), recorded where the board writes its
//! registers.

use crate::rig;

use host_sim::record::Discard;
use rig::{origin, Rig};

#[test]
fn spindle_and_coolant_follow_the_program() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    let p = r.dev.pins().expect("a pass ran");
    assert!(!p.spindle.enable && !p.flood && !p.mist, "{p:?}");
    // Tool, spindle and coolant words on one line.
    assert_eq!(r.cmd("T2 M3 S500 M8"), ["ok"]);
    r.run(2);
    let p = r.dev.pins().expect("pins");
    assert!(
        p.spindle.enable && !p.spindle.ccw && p.flood && !p.mist,
        "{p:?}"
    );
    // S500 of $30=1000 with $31=0: half duty.
    assert!((p.spindle.duty - 0.5).abs() < 1e-3, "{p:?}");
    assert_eq!(r.cmd("M4 S1000 M7"), ["ok"]);
    r.run(2);
    let p = r.dev.pins().expect("pins");
    assert!(p.spindle.enable && p.spindle.ccw && p.mist, "{p:?}");
    assert_eq!(p.spindle.duty, 1.0);
    assert_eq!(r.cmd("M5 M9"), ["ok"]);
    r.run(2);
    let p = r.dev.pins().expect("pins");
    assert!(!p.spindle.enable && !p.flood && !p.mist, "{p:?}");
}

#[test]
fn soft_reset_and_program_end_turn_everything_off() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    // M7 and M8 share a modal group: one per line (LinuxCNC).
    assert_eq!(r.cmd("M3 S300 M7"), ["ok"]);
    assert_eq!(r.cmd("M8"), ["ok"]);
    r.run(2);
    assert!(r.dev.pins().is_some_and(|p| p.spindle.enable && p.flood));
    r.send(&[0x18]);
    r.run(2);
    assert!(r.lines().iter().any(|l| l.starts_with("Grbl")), "no banner");
    let p = r.dev.pins().expect("pins");
    assert!(
        !p.spindle.enable && !p.flood && !p.mist,
        "after reset: {p:?}"
    );
    assert_eq!(r.cmd("M3 S300 M8"), ["ok"]);
    assert_eq!(r.cmd("M2"), ["ok"]);
    r.run(5);
    let p = r.dev.pins().expect("pins");
    assert!(!p.spindle.enable && !p.flood, "after M2: {p:?}");
}

/// `$1`: the drivers are on while steps run and go off `$1` ms after the
/// last one.
#[test]
fn drivers_disable_after_the_idle_delay() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$1=100"), ["ok"]);
    assert!(r.dev.pins().is_some_and(|p| !p.enable), "off at power-up");
    assert_eq!(r.cmd("G1 X2 F600"), ["ok"]);
    r.until_idle();
    r.run(100);
    let hz = f64::from(cfg.tick_hz);
    let secs = |t: u64| t as f64 / hz;
    let log = &r.dev.pin_log;
    let on = log.iter().position(|(_, p)| p.enable).expect("enabled");
    let off = log[on..].iter().find(|(_, p)| !p.enable).expect("disabled");
    let (on, off) = (secs(log[on].0), secs(off.0));
    // 2 mm at 10 mm/s: 0.2 s plus the ramps (about 20 ms), then 100 ms.
    assert!(
        off - on > 0.3 && off - on < 0.34,
        "enabled at {on:.3} s, disabled at {off:.3} s"
    );
    // `$1=255`: on for good.
    assert_eq!(r.cmd("$1=255"), ["ok"]);
    r.run(5);
    assert!(r.dev.pins().is_some_and(|p| p.enable));
}

/// Laser mode (`$32=1`): no beam while nothing moves, even with M3 on.
#[test]
fn laser_is_dark_while_stopped() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$32=1"), ["ok"]);
    assert_eq!(r.cmd("M3 S800"), ["ok"]);
    r.run(3);
    assert!(
        r.dev.pins().is_some_and(|p| !p.spindle.enable),
        "lit at rest"
    );
    assert_eq!(r.cmd("G1 X5 F600"), ["ok"]);
    r.run(20);
    let p = r.dev.pins().expect("pins");
    assert!(
        p.spindle.enable && (p.spindle.duty - 0.8).abs() < 1e-3,
        "{p:?}"
    );
    r.until_idle();
    assert!(
        r.dev.pins().is_some_and(|p| !p.spindle.enable),
        "lit after the move"
    );
}

/// The status report's spindle figure is the spindle as it runs: `S500`
/// with `M3`, 0 after `M5` (the programmed S stays 500 in `$G`).
#[test]
fn status_spindle_follows_execution() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("M3 S500"), ["ok"]);
    r.run(2);
    assert_eq!(r.status().spindle, Some(500.0));
    assert_eq!(r.cmd("M5"), ["ok"]);
    r.run(2);
    assert_eq!(r.status().spindle, Some(0.0));
    assert!(r.cmd("$G")[0].contains("S500"));
}

/// One sample per round: running line, path speed, laser pins.
fn laser_samples(r: &mut Rig, rounds: usize) -> Vec<(u32, f32, bool, f32)> {
    let mut out = Vec::new();
    for _ in 0..rounds {
        r.run(1);
        let (speed, line) = r.dev.sim.rt.running();
        let p = r.dev.pins().expect("pins");
        let stepping = r.dev.sim.rt.stepping();
        let line = if stepping { line } else { 0 };
        out.push((line, speed, p.spindle.enable, p.spindle.duty));
        if r.dev.idle() {
            break;
        }
    }
    out
}

/// Issue 13 item 7: laser mode per segment, as the board drives the PWM:
/// dark on G0, M4 power with the segment's speed, a new S between G1
/// moves without a stop, dark once stopped.
#[test]
fn laser_power_follows_each_segment() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$32=1"), ["ok"]);
    // Lines 1-6 (text lines count from the first G-code line).
    r.send(b"M4 S1000\nG0 X5\nG1 X10 F600\nG1 X15 S500\nG0 X0\nM5\n");
    let samples = laser_samples(&mut r, 20_000);
    let of = |l: u32| samples.iter().filter(move |s| s.0 == l);
    assert!(of(2).count() > 0 && of(5).count() > 0, "{samples:?}");
    for s in of(2).chain(of(5)) {
        assert!(!s.2 && s.3 == 0.0, "lit on a rapid: {s:?}");
    }
    // M4: full power only at the programmed feed, less while ramping.
    for s in of(3).chain(of(4)) {
        assert!(s.2, "dark on a feed move: {s:?}");
        let full = if s.0 == 3 { 1.0 } else { 0.5 };
        let want = full * (s.1 / 600.0).min(1.0);
        assert!((s.3 - want).abs() < 0.02, "duty {} for {s:?}", want);
    }
    // Line 4 ramps down to the reversal at X15.
    assert!(of(4).any(|s| s.3 < 0.4), "no M4 scaling seen");
    assert!(of(3).any(|s| s.3 > 0.99), "never at full power");
    // S500 arrived between the two G1 moves without a stop at X10.
    let last3 = of(3).next_back().expect("line 3 ran");
    let first4 = of(4).next().expect("line 4 ran");
    assert!(
        last3.1 > 500.0 && first4.1 > 500.0,
        "stopped at the S change: {last3:?} {first4:?}"
    );
    assert!(of(4).any(|s| (s.3 - 0.5).abs() < 0.01));
    let p = r.dev.pins().expect("pins");
    assert!(!p.spindle.enable, "lit after the job: {p:?}");
}

/// A feed hold darkens the laser at once, while the machine still
/// decelerates, and cycle start lights it again.
#[test]
fn laser_is_dark_in_a_hold() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$32=1"), ["ok"]);
    assert_eq!(r.cmd("M3 S800 G1 X50 F1200"), ["ok"]);
    r.run(50);
    assert!(r.dev.pins().is_some_and(|p| p.spindle.enable));
    r.send(b"!");
    r.run(1);
    assert!(r.dev.sim.rt.stepping(), "stopped within a round");
    assert!(
        r.dev.pins().is_some_and(|p| !p.spindle.enable),
        "lit in a hold"
    );
    r.run(200);
    assert!(r.dev.pins().is_some_and(|p| !p.spindle.enable));
    r.send(b"~");
    r.run(20);
    assert!(
        r.dev
            .pins()
            .is_some_and(|p| p.spindle.enable && (p.spindle.duty - 0.8).abs() < 1e-3),
        "dark after resume"
    );
}
