//! Machine behaviour against simulated switches and probe: hard limits,
//! homing, G27, probing, soft limits, the step-rate ceiling.
use crate::common;
use burin::command::{Arc, ArcDir, Command, Feed, Plane, ProbeKind};
use common::*;
use host_sim::config::MachineConfig;
use host_sim::engine::Sim;

const ALL: u8 = 0;

fn home_and_check(sim: &mut Sim) {
    sim.push_command(1, Command::Home { axes: ALL });
    sim.run();
    assert!(sim.errors().is_empty(), "{:?}", sim.errors());
    assert!(!sim.machine.position_lost());
    assert_eq!(sim.machine.homed() & 0b111, 0b111);
    // Machine 0 is at the switch (world 0); pull-off leaves us at -1 mm.
    let pos = sim.rt.position();
    assert_eq!(
        &pos[..3],
        &[-80, -80, -400],
        "machine position after homing"
    );
    assert_eq!(
        &sim.world.steps[..3],
        &[-80, -80, -400],
        "world position after homing"
    );
}

#[test]
fn homing_seek_pulloff_locate() {
    let mut cfg = config_with_switches();
    cfg.start_position_mm = burin::pad([-50.0, -30.0, -12.0, 0.0]);
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    home_and_check(&mut sim);
    drop(sim);
    // Z homes alone first: no X/Y step before the last Z step of the first cycle.
    let first_xy = rec
        .events
        .iter()
        .position(|e| e.step_mask & 0b011 != 0)
        .unwrap();
    let z_moves_before = rec.events[..first_xy]
        .iter()
        .filter(|e| e.step_mask & 0b100 != 0)
        .count();
    assert!(z_moves_before > 12 * 400, "Z cycle must run first");
    check_pin_timing(rec.info.as_ref().unwrap(), &rec.events);
}

#[test]
fn homing_towards_negative_with_inverted_switch_pins() {
    let mut cfg = config_with_switches();
    cfg.settings.homing_dir_invert = 0b001; // X homes to its negative end
    cfg.settings.limit_invert = 0b111; // normally-closed switches
    cfg.settings.homing_order = 0x1; // X only
    cfg.limits[0] = Some(host_sim::config::LimitSwitch {
        trip_mm: -100.0,
        hysteresis_mm: 0.05,
    });
    cfg.start_position_mm = burin::pad([-20.0, 0.0, 0.0, 0.0]);
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(1, Command::Home { axes: ALL });
    sim.run();
    assert!(sim.errors().is_empty(), "{:?}", sim.errors());
    assert_eq!(sim.rt.position()[0], 80, "machine X = +pull-off");
    assert_eq!(sim.world.steps[0], -99 * 80, "1 mm off the switch at -100");
}

#[test]
fn homing_fails_without_switch() {
    let mut cfg = config_with_switches();
    cfg.limits[1] = None;
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(1, Command::Home { axes: ALL });
    sim.run();
    assert_eq!(sim.errors().len(), 1);
    assert_eq!(sim.errors()[0].code, 421, "{:?}", sim.errors());
    assert!(sim.machine.alarm().is_some());
}

#[test]
fn g27_verify_home_passes_then_alarms_on_lost_steps() {
    let mut cfg = config_with_switches();
    cfg.start_position_mm = burin::pad([-20.0, -20.0, -5.0, 0.0]);
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    home_and_check(&mut sim);
    sim.push_command(
        2,
        Command::Line {
            end: burin::pad([-30.0, -30.0, -5.0, 0.0]),
            feed: Feed::PerMin(2000.0),
        },
    );
    sim.push_command(3, Command::VerifyHome { axes: 0b011 });
    sim.run();
    assert!(
        sim.errors().is_empty(),
        "G27 on an intact machine: {:?}",
        sim.errors()
    );
    // The carriage slips 0.2 mm on X (a stall the core cannot see).
    sim.world.steps[0] -= 16;
    sim.push_command(
        4,
        Command::Line {
            end: burin::pad([-30.0, -30.0, -5.0, 0.0]),
            feed: Feed::PerMin(2000.0),
        },
    );
    sim.push_command(5, Command::VerifyHome { axes: 0b011 });
    sim.run();
    let e = sim.errors().last().cloned().unwrap();
    assert_eq!(e.code, 423, "{e:?}");
    assert!(e.message.contains("X"), "{e:?}");
    assert!(sim.machine.position_lost());
}

#[test]
fn hard_limit_stops_at_once_and_loses_position() {
    let mut cfg = config_with_switches();
    cfg.settings.hard_limits = true;
    cfg.start_position_mm = burin::pad([-5.0, -5.0, -5.0, 0.0]);
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        1,
        Command::Line {
            end: burin::pad([10.0, -5.0, -5.0, 0.0]),
            feed: Feed::PerMin(1000.0),
        },
    );
    sim.push_command(
        2,
        Command::Line {
            end: burin::pad([10.0, -10.0, -5.0, 0.0]),
            feed: Feed::PerMin(1000.0),
        },
    );
    sim.run();
    // Line 2 was already planned: it is flushed, never run.
    assert_eq!(sim.world.steps[1], -400);
    sim.push_command(
        3,
        Command::Line {
            end: burin::pad([-10.0, -10.0, -5.0, 0.0]),
            feed: Feed::PerMin(1000.0),
        },
    );
    sim.run();
    assert_eq!(
        sim.errors().first().map(|e| (e.line, e.code)),
        Some((1, 420)),
        "{:?}",
        sim.errors()
    );
    assert!(sim.machine.position_lost());
    // The switch closes at world 0; the step after it is the last one.
    assert_eq!(
        sim.world.steps[0], 0,
        "stopped on the step that closed the switch"
    );
    let refused = sim.errors().iter().any(|e| (e.line, e.code) == (3, 407));
    assert!(refused, "line 3 refused in alarm: {:?}", sim.errors());
    // Homing clears the alarm and the lost flag.
    sim.push_command(4, Command::Home { axes: ALL });
    sim.run();
    assert!(!sim.machine.position_lost());
    assert!(sim.machine.alarm().is_none());
}

#[test]
fn probe_g38_2_contact_and_no_contact() {
    let cfg = config_with_switches();
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        1,
        Command::Probe {
            end: burin::pad([0.0, 0.0, -30.0, 0.0]),
            feed: Feed::PerMin(100.0),
            kind: ProbeKind::Toward,
        },
    );
    sim.run();
    let (pos, contact) = sim.probe_result().unwrap();
    assert!(contact);
    assert!(
        (pos[2] + 20.0).abs() <= 1.0 / 400.0 + 1e-4,
        "tripped at {pos:?}"
    );
    assert!(sim.errors().is_empty(), "{:?}", sim.errors());
    // Past the contact by the (tiny) ramp-down at 100 mm/min.
    let over = -8000 - sim.world.steps[2];
    assert!((0..40).contains(&over), "overtravel {over} steps");
    assert_eq!(sim.rt.position(), sim.world.steps.map(|s| s as i32));
    // Away from the plate: G38.4 until contact breaks.
    sim.push_command(
        2,
        Command::Probe {
            end: burin::pad([0.0, 0.0, -10.0, 0.0]),
            feed: Feed::PerMin(100.0),
            kind: ProbeKind::Away,
        },
    );
    sim.run();
    let (pos, contact) = sim.probe_result().unwrap();
    assert!(contact && pos[2] > -20.0 && pos[2] < -19.99, "{pos:?}");
    // G38.3 that never touches: no error; G38.2 that never touches: alarm.
    sim.push_command(
        3,
        Command::Probe {
            end: burin::pad([0.0, 0.0, -15.0, 0.0]),
            feed: Feed::PerMin(300.0),
            kind: ProbeKind::TowardNoError,
        },
    );
    sim.run();
    assert_eq!(sim.probe_result().map(|p| p.1), Some(false));
    assert!(sim.errors().is_empty());
    sim.push_command(
        4,
        Command::Probe {
            end: burin::pad([0.0, 0.0, -10.0, 0.0]),
            feed: Feed::PerMin(300.0),
            kind: ProbeKind::Toward,
        },
    );
    sim.run();
    assert_eq!(sim.errors().last().map(|e| e.code), Some(424));
}

/// A job with `cmds` on `cfg`: its errors (line, code) and each axis's
/// step count.
fn refusals(
    cfg: &MachineConfig,
    cmds: Vec<(u32, Command)>,
) -> (Vec<(u32, u16)>, [u32; burin::AXES]) {
    let mut rec = Collect::default();
    let mut sim = Sim::new(cfg, &mut rec);
    for (line, c) in cmds {
        sim.push_command(line, c);
    }
    sim.run();
    let codes = sim.errors().iter().map(|e| (e.line, e.code)).collect();
    drop(sim);
    assert!(rec.summary.is_none());
    let steps = rec.events.iter().fold([0; burin::AXES], |mut a, e| {
        for (i, c) in a.iter_mut().enumerate() {
            *c += (e.step_mask >> i & 1) as u32;
        }
        a
    });
    (codes, steps)
}

/// Each refusal stops the job where it is, as on the board
/// (`session::late`): nothing after it runs.
#[test]
fn soft_limits_refuse_before_any_step() {
    let mut cfg = config();
    cfg.settings.soft_limits = true;
    let line = |end| Command::Line {
        end,
        feed: Feed::PerMin(1000.0),
    };
    let into_x = (1, line(burin::pad([5.0, -5.0, 0.0, 0.0])));
    assert_eq!(
        refusals(&cfg, vec![into_x]),
        (vec![(1, 400)], [0; burin::AXES])
    );
    // Start and end inside, but the bulge crosses X = 0 (to X = +0.05).
    let bulge = Command::Arc(Arc {
        end: burin::pad([-20.0, -1.0, 0.0, 0.0]),
        center: [-10.0, -1.0],
        plane: Plane::XY,
        dir: ArcDir::Cw,
        turns: 0,
        feed: Feed::PerMin(1000.0),
    });
    let inside = (3, line(burin::pad([-1.0, -1.0, 0.0, 0.0])));
    let (codes, steps) = refusals(&cfg, vec![(2, bulge), inside.clone()]);
    assert_eq!(
        (codes, steps),
        (vec![(2, 400)], [0; burin::AXES]),
        "line 3 ran"
    );
    let over_the_top = Command::Arc(Arc {
        end: burin::pad([-21.0, -1.0, 0.0, 0.0]),
        center: [-11.0, -1.0],
        plane: Plane::XY,
        dir: ArcDir::Ccw, // over the top: Y up to +9
        turns: 0,
        feed: Feed::PerMin(1000.0),
    });
    // Line 3 started and ramped down along its path when line 4 was
    // refused (a fault's stop): X and Y moved alike, short of its 1 mm.
    let (codes, steps) = refusals(&cfg, vec![inside, (4, over_the_top)]);
    assert_eq!(codes, vec![(4, 400)]);
    assert!(
        steps[0] == steps[1] && steps[0] > 0 && steps[0] < 80,
        "{steps:?}"
    );
    assert!(steps[2..].iter().all(|&n| n == 0), "{steps:?}");
}

#[test]
fn step_rate_ceiling_is_an_error() {
    let mut cfg = config();
    cfg.settings.max_step_rate_hz = 5_000.0; // X needs 5000/60*80 = 6667 steps/s
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        7,
        Command::Line {
            end: burin::pad([1.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(100.0),
        },
    );
    sim.push_command(
        8,
        Command::Line {
            end: burin::pad([0.0, 0.0, 0.0, 10.0]),
            feed: Feed::PerMin(100.0),
        },
    );
    sim.run();
    assert_eq!(
        sim.errors()
            .iter()
            .map(|e| (e.line, e.code))
            .collect::<Vec<_>>(),
        vec![(7, 401)]
    );
    // The job stopped at the refusal: line 8 did not run either.
    assert_eq!(sim.rt.position(), burin::pad([0, 0, 0, 0]));
}

#[test]
fn soft_reset_mid_move_stops_and_flags_position() {
    let cfg = config();
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        1,
        Command::Line {
            end: burin::pad([100.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(3000.0),
        },
    );
    sim.input_at(cfg.tick_hz as u64, host_sim::engine::Input::Reset);
    sim.run();
    assert_eq!(sim.errors().last().map(|e| e.code), Some(425));
    assert!(sim.machine.position_lost());
    let x = sim.rt.position()[0];
    assert!(x > 0 && x < 8000, "stopped part way: {x}");
    // the core's idea of the position matches the steps that really ran
    assert_eq!(i64::from(x), sim.world.steps[0]);
}

/// G38.2 at 1000 mm/min: the trip point is recorded exactly, then Z ramps
/// down within its acceleration limit (no instant stop) and the machine
/// position is where it really stopped.
#[test]
fn probe_contact_ramps_down_within_accel() {
    let cfg = config_with_switches();
    let mut rec = Collect::default();
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        1,
        Command::Probe {
            end: burin::pad([0.0, 0.0, -30.0, 0.0]),
            feed: Feed::PerMin(1000.0),
            kind: ProbeKind::Toward,
        },
    );
    sim.run();
    assert!(sim.errors().is_empty(), "{:?}", sim.errors());
    let (pos, contact) = sim.probe_result().unwrap();
    assert!(contact);
    // The plate is at world step -8000: reported within 1 step of it.
    let trip_steps = pos[2] as f64 * 400.0;
    assert!(
        (trip_steps + 8000.0).abs() <= 1.0,
        "tripped at {trip_steps}"
    );
    // 16.7 mm/s at 100 mm/s² needs 1.39 mm (555 steps) to stop.
    let over = -8000 - sim.world.steps[2];
    assert!((500..900).contains(&over), "overtravel {over} steps");
    assert_eq!(sim.rt.position(), sim.world.steps.map(|s| s as i32));
    let stop = sim.machine.commanded_position();
    assert!((stop[2] * 400.0 - sim.world.steps[2] as f32).abs() < 0.5);
    assert!(sim.machine.alarm().is_none());
    // Motion goes on normally from the stop point.
    sim.push_command(
        2,
        Command::Line {
            end: burin::pad([0.0, 0.0, -10.0, 0.0]),
            feed: Feed::PerMin(600.0),
        },
    );
    sim.run();
    assert_eq!(sim.world.steps[2], -4000);
    drop(sim);
    let info = rec.info.as_ref().unwrap();
    let acc = check_max_accel(info, &rec.events, &[], 0.01);
    let probe_events: Vec<_> = rec
        .events
        .iter()
        .filter(|e| e.dir_mask & 0b100 != 0)
        .copied()
        .collect();
    let stop = check_stop_decel(info, &probe_events, 2, 2000);
    println!("probe stop: worst accel ratio {acc:.3}, stop ratio {stop:.3}");
    check_pin_timing(info, &rec.events);
}
