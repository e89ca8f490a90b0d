//! `$n=` reaches the step interrupt at once (issue 28, finding 2): the
//! firmware used to rebuild only the parse side, so the pins and the
//! stepper's switch reads kept their power-up `$0`/`$2`/`$3`/`$5` until a
//! reset. Each test here wires the virtual machine as the physical one is
//! (NC switches, reversed motors: `config::Wiring`), boots on the wrong
//! setting, corrects it with `$n=` and checks what the pins and the
//! carriage do next.

use host_sim::config::{MachineConfig, Wiring};
use host_sim::engine::Edge;
use host_sim::record::Discard;
use protocol::client::grbl::parse_status;

use crate::rig;

use rig::{origin, Rig};

/// Ticks per µs of the default machine (TIM5 at 96 MHz).
const TICKS_PER_US: u64 = 96;

/// The default machine, homing on, parked 10/10/5 mm off its switches
/// (they sit at machine 0, homing seeks towards positive).
fn homing_machine(wiring: Wiring) -> MachineConfig {
    let mut cfg = MachineConfig::default();
    cfg.settings.homing_enable = true;
    cfg.start_position_mm = burin::pad([-10.0, -10.0, -5.0, 0.0]);
    cfg.wiring = Some(wiring);
    cfg
}

/// Runs until the machine reports Idle or Alarm (a failed homing alarms):
/// that state and every other line received meanwhile.
fn settle(r: &mut Rig) -> (String, Vec<String>) {
    let mut seen = Vec::new();
    for _ in 0..20_000 {
        r.run(10);
        r.send(b"?");
        r.run(1);
        let lines = r.lines();
        let st = lines.iter().rev().find_map(|l| parse_status(l));
        seen.extend(lines.into_iter().filter(|l| !l.starts_with('<')));
        if let Some(st) = st.filter(|s| s.state == "Idle" || s.state == "Alarm") {
            return (st.state, seen);
        }
    }
    panic!("neither idle nor in alarm: {seen:?}");
}

/// `$H` to the end: homed without an alarm, machine zero at the switches
/// (the world's 0), so after the 1 mm pull-off the core and the carriage
/// agree on -1 mm for X, Y and Z.
fn home_and_check(r: &mut Rig) {
    r.send(b"$H\n");
    let (state, lines) = settle(r);
    assert_eq!(state, "Idle", "homing failed: {lines:?}");
    assert!(lines.iter().any(|l| l == "ok"), "{lines:?}");
    assert!(!lines.iter().any(|l| l.starts_with("ALARM")), "{lines:?}");
    let core = r.dev.position_steps();
    assert_eq!(&core[..3], &[-80, -80, -400], "machine position");
    assert_eq!(
        &r.dev.sim.world.steps[..3],
        &[-80, -80, -400],
        "carriage: machine zero must be at the switch"
    );
}

#[test]
fn dollar_5_for_nc_switches_then_homing_zeroes_at_the_switch() {
    // NC switches read active while open: on `$5=0` every limit reads
    // closed at power-up.
    let cfg = homing_machine(Wiring {
        limits_nc: 0b111,
        ..Wiring::default()
    });
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.dev.sim.world.switches().limits, 0b111, "open NC switches");
    assert_eq!(r.cmd("$5=7"), ["ok"]);
    // The seek must run to the switch, not trip at once on the old invert
    // (machine zero wherever the axis stood, reported as success).
    home_and_check(&mut r);
}

#[test]
fn dollar_3_for_reversed_motors_then_homing_seeks_the_new_way() {
    let cfg = homing_machine(Wiring {
        motors_reversed: 0b111,
        ..Wiring::default()
    });
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.dev.sim.record_edges();
    assert_eq!(r.cmd("$3=7"), ["ok"]);
    // At once, at rest: the direction pins of X, Y, Z high for "positive".
    let last = r.dev.sim.edges().last().copied();
    assert_eq!(
        last.map(|e| (e.step, e.dir_pins())),
        Some((0, 0b111)),
        "idle direction levels under $3=7: {last:?}"
    );
    let from = r.dev.sim.edges().len();
    home_and_check(&mut r);
    // The seek (Z first) left with Z's direction pin high: towards the
    // switch on this machine.
    let first = r.dev.sim.edges()[from..].iter().find(|e| e.step != 0);
    assert_eq!(
        first.map(|e| (e.step, e.dir_pins() & 0b100)),
        Some((0b100, 0b100))
    );
}

/// Rise-to-fall time of every pulse in `edges`, ticks.
fn widths(edges: &[Edge]) -> Vec<u64> {
    let mut out = Vec::new();
    let mut rose = None;
    for e in edges {
        match (rose, e.step) {
            (None, s) if s != 0 => rose = Some(e.tick),
            (Some(t), 0) => {
                out.push(e.tick - t);
                rose = None;
            }
            _ => {}
        }
    }
    out
}

#[test]
fn a_raised_dollar_0_widens_the_next_pulses() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.dev.sim.record_edges();
    assert_eq!(r.cmd("G1 X1 F600"), ["ok"]);
    assert_eq!(r.until_idle().state, "Idle");
    let before = widths(r.dev.sim.edges());
    assert_eq!(before.len(), 80);
    assert!(before.iter().all(|&w| w < 10 * TICKS_PER_US), "{before:?}");
    // A 10 µs pulse needs the step rate under the one ceiling first
    // (10 + 1 + 10 µs a step: 47.6 kHz at most).
    assert_eq!(r.cmd("$0=10"), ["error:114"]);
    assert_eq!(r.cmd("$201=40000"), ["ok"]);
    assert_eq!(r.cmd("$0=10"), ["ok"]);
    let from = r.dev.sim.edges().len();
    assert_eq!(r.cmd("G1 X0 F600"), ["ok"]);
    assert_eq!(r.until_idle().state, "Idle");
    let after = widths(&r.dev.sim.edges()[from..]);
    assert_eq!(after.len(), 80);
    let short = after.iter().filter(|&&w| w < 10 * TICKS_PER_US).count();
    assert_eq!(short, 0, "pulses shorter than $0=10 µs: {after:?}");
}

#[test]
fn dollar_2_moves_the_idle_step_level_at_once() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.dev.sim.record_edges();
    assert_eq!(r.cmd("$2=1"), ["ok"]);
    // No motion yet: X's step pin rests high now.
    let edges = r.dev.sim.edges().to_vec();
    assert_eq!(
        edges
            .iter()
            .map(|e| (e.step, e.step_pins()))
            .collect::<Vec<_>>(),
        [(0, 1)],
        "{edges:?}"
    );
    // Pulses are low-going from then on and end at the high rest level.
    assert_eq!(r.cmd("G1 X1 F600"), ["ok"]);
    assert_eq!(r.until_idle().state, "Idle");
    let edges = &r.dev.sim.edges()[1..];
    let rises: Vec<_> = edges.iter().filter(|e| e.step != 0).collect();
    assert_eq!(rises.len(), 80);
    assert!(rises.iter().all(|e| e.step_pins() & 1 == 0), "{rises:?}");
    assert_eq!(edges.last().map(|e| e.step_pins() & 1), Some(1));
    // `$4` reaches the enable pin's writer in the same pass.
    assert_eq!(r.dev.pins().map(|p| p.enable_invert), Some(false));
    assert_eq!(r.cmd("$4=1"), ["ok"]);
    assert_eq!(r.dev.pins().map(|p| p.enable_invert), Some(true));
}

/// Ticks from each direction store to the first rise after it.
fn setups(edges: &[Edge]) -> Vec<u64> {
    let mut out = Vec::new();
    let mut dir = edges.first().map_or(0, |e| e.dir);
    let mut changed = None;
    for e in edges {
        if e.dir != dir {
            dir = e.dir;
            changed = Some(e.tick);
        }
        if e.step != 0 {
            if let Some(t) = changed.take() {
                out.push(e.tick - t);
            }
        }
    }
    out
}

#[test]
fn a_raised_dollar_200_holds_the_step_after_a_reversal() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G1 X1 F600"), ["ok"]);
    assert_eq!(r.until_idle().state, "Idle");
    r.dev.sim.record_edges();
    assert_eq!(r.cmd("$200=20"), ["ok"]);
    assert_eq!(r.cmd("G1 X0 F600"), ["ok"]);
    assert_eq!(r.until_idle().state, "Idle");
    let s = setups(r.dev.sim.edges());
    assert_eq!(s.len(), 1, "one reversal: {s:?}");
    assert!(s[0] >= 20 * TICKS_PER_US, "direction setup {} ticks", s[0]);
}
