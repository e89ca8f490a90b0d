//! Switch inputs through the virtual board (`VirtualDevice::set_input`):
//! the e-stop, a limit that closes at rest and the panel's feed-hold and
//! cycle-start buttons, decided by `burin::inputs` as on the board.

use burin::inputs::{CYCLE_START, ESTOP, FEED_HOLD, LIMIT_X};
use host_sim::record::Discard;

use crate::rig::{origin, Rig};

#[test]
fn an_estop_stops_at_once_cuts_the_outputs_and_holds_the_alarm_until_released() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.cutting();
    r.dev.set_input(ESTOP, true);
    assert!(!r.spindle_on(), "the outputs are cut on the edge");
    let stopped = r.dev.position_steps();
    r.run(50);
    assert_eq!(r.dev.position_steps(), stopped, "a step after the e-stop");
    let st = r.status();
    assert_eq!(st.state, "Alarm");
    // GRBL's reset pin letter.
    assert_eq!(st.pins.as_deref(), Some("R"), "{st:?}");
    let out = r.cmd("$X");
    assert!(out.iter().any(|l| l.starts_with("error:")), "{out:?}");
    r.dev.set_input(ESTOP, false);
    r.run(5);
    let out = r.cmd("$X");
    assert!(
        out.iter().any(|l| l.starts_with("error:")),
        "before it settled: {out:?}"
    );
    r.run(20);
    assert_eq!(r.cmd("$X"), ["[MSG:Caution: Unlocked]", "ok"]);
}

#[test]
fn a_limit_closing_at_rest_alarms_only_with_hard_limits_on() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$21=0"), ["ok"]);
    r.dev.set_input(LIMIT_X, true);
    r.run(20);
    let st = r.status();
    assert_eq!(st.state, "Idle", "hard limits off");
    assert!(
        st.pins.as_deref().is_some_and(|p| p.contains('X')),
        "{st:?}"
    );
    r.dev.set_input(LIMIT_X, false);
    r.run(20);
    assert_eq!(r.status().pins, None);
    assert_eq!(r.cmd("$21=1"), ["ok"]);
    r.run(2);
    r.lines();
    r.dev.set_input(LIMIT_X, true);
    r.run(2);
    let lines = r.lines();
    assert!(lines.iter().any(|l| l == "ALARM:1"), "{lines:?}");
    assert_eq!(r.status().state, "Alarm");
}

#[test]
fn the_panel_buttons_hold_and_resume_and_a_glitch_resumes_nothing() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.cutting();
    r.dev.set_input(FEED_HOLD, true);
    r.run(1);
    assert!(r.status().state.starts_with("Hold"));
    r.dev.set_input(FEED_HOLD, false);
    r.run(300);
    assert_eq!(r.status().state, "Hold:0");
    let held = r.x();
    // 4 ms on the cycle-start line: shorter than the settle time.
    r.dev.set_input(CYCLE_START, true);
    r.run(2);
    r.dev.set_input(CYCLE_START, false);
    r.run(50);
    assert_eq!(r.status().state, "Hold:0");
    assert_eq!(r.x(), held);
    r.dev.set_input(CYCLE_START, true);
    r.run(15);
    assert_eq!(r.status().state, "Run");
    r.dev.set_input(CYCLE_START, false);
    r.run(50);
    assert!(r.x() < held, "resumed");
}
