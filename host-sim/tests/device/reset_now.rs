//! A soft reset stops the step timer at once: during a move so slow that
//! its next step is seconds away, `0x18` then `$I` are answered within a
//! few milliseconds of virtual time, and no step follows the reset.

use crate::rig;

use host_sim::record::Discard;
use rig::{origin, Rig};

#[test]
fn reset_during_a_slow_move_is_answered_at_once() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    // 80 steps/mm at 0.08 mm/min: a step every 9.4 s.
    assert_eq!(r.cmd("G1 X1 F0.08"), ["ok"]);
    // Past the acceleration: well into the first interval.
    for _ in 0..1000 {
        r.run(100);
        if r.dev.position_steps()[0] >= 1 {
            break;
        }
    }
    let at = r.dev.position_steps();
    assert!(at[0] >= 1, "never stepped");
    assert!(r.dev.sim.rt.stepping(), "the timer should be running");
    r.send(&[0x18]);
    r.send(b"$I\n");
    // 10 rounds of 2 ms.
    r.run(10);
    let lines = r.lines();
    assert!(
        lines.iter().any(|l| l.starts_with("[VER:")),
        "no $I within 20 ms of the reset: {lines:?}"
    );
    assert!(!r.dev.sim.rt.stepping(), "the step timer still runs");
    r.run(50_000);
    assert_eq!(r.dev.position_steps(), at, "a step after the reset");
}
