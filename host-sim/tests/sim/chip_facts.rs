//! The board's beliefs about the chip, checked where host-sim models a
//! peripheral (`firmware/CHIP.md`, `burin::chip`): the pulse-end DMA path
//! burin used up to 16ae6d1 (DMA1's memory port writing GPIOB) fails in the
//! model as it would on the chip, the path the boards use now works, and
//! the boot check turns a broken path into an alarm instead of a machine
//! whose position advances while nothing moves.

use burin::chip::dma::DmaPath;
use burin::chip::{Chip, HwFault};
use burin::command::{Command, Feed};
use host_sim::config::{MachineConfig, BOARD_PULSE_DMA};
use host_sim::engine::Sim;
use host_sim::record::Discard;

use crate::rig;
use rig::{origin, Rig};

/// A 10 mm move on X through the step driver, the pulse-end DMA on `path`:
/// (world steps, the stepper's steps).
fn move_x(path: DmaPath) -> (i64, i64) {
    let mut cfg = origin();
    cfg.interrupts.pulse_dma = (path, Chip::F411);
    let mut rec = Discard;
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        1,
        Command::Line {
            end: burin::pad([10.0, 0.0, 0.0, 0.0]),
            feed: Feed::PerMin(600.0),
        },
    );
    sim.run();
    (sim.world.steps[0], i64::from(sim.stepper.position()[0]))
}

#[test]
fn the_16ae6d1_pulse_end_moves_one_step_while_the_position_says_ten_mm() {
    let spm = MachineConfig::default().settings.axes[0].steps_per_mm;
    let want = (10.0 * spm).round() as i64;
    let (world, counted) = move_x(DmaPath::before_16ae6d1());
    assert_eq!(counted, want, "the stepper counts every step");
    assert_eq!(world, 1, "one rising edge, then the pin stays high");
    let (world, counted) = move_x(BOARD_PULSE_DMA);
    assert_eq!((world, counted), (want, want), "the boards' path");
}

#[test]
fn a_broken_pulse_path_is_an_alarm_at_boot_that_nothing_unlocks() {
    let mut cfg = origin();
    cfg.interrupts.pulse_dma = (DmaPath::before_16ae6d1(), Chip::F411);
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    assert_eq!(r.dev.sim.rt.hw_fault(), Some(HwFault::PulseEndPath));
    r.run(2);
    let boot = r.lines();
    assert!(boot.iter().any(|l| l == "ALARM:22"), "{boot:?}");
    assert!(
        boot.iter()
            .any(|l| l.starts_with("[MSG:hardware fault: step pulse DMA")),
        "{boot:?}"
    );
    assert_eq!(r.status().state, "Alarm");
    assert_ne!(r.cmd("$X"), ["[MSG:Caution: Unlocked]", "ok"]);
    assert_ne!(r.cmd("G1 X5 F600"), ["ok"]);
    r.run(50);
    assert_eq!(r.dev.sim.world.steps, [0; burin::AXES], "nothing moved");
    assert_eq!(r.status().state, "Alarm");
}

#[test]
fn a_path_the_table_allows_but_the_stream_breaks_is_caught_at_the_next_start() {
    // The boot test passes; then the stream fails (as TEIF would on a
    // stray bus error): the next move's start reads the flags and latches
    // the alarm before any pulse.
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    assert_eq!(r.dev.sim.rt.hw_fault(), None);
    r.lines();
    assert_eq!(r.cmd("G1 X1 F600"), ["ok"]);
    r.until_idle();
    let x = r.dev.sim.world.steps[0];
    assert!(x > 0);
    r.dev.sim.hw.dma = host_sim::engine::PulseDma::new(DmaPath::before_16ae6d1(), Chip::F411);
    r.dev.sim.hw.dma.request();
    let reply = r.cmd("G1 X2 F600");
    r.run(50);
    assert_eq!(r.dev.sim.rt.hw_fault(), Some(HwFault::PulseEndError));
    assert_eq!(reply[..2], ["ok", "ALARM:22"], "{reply:?}");
    assert_eq!(r.dev.sim.world.steps[0], x, "no pulse after the fault");
}
