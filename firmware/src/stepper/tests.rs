//! The step event against the realtime flags the interrupts and the task
//! raise between two events.

use super::{Segment, StepConfig, Stepper, Switches};
use crate::planner::Watch;
use crate::realtime::{Realtime, Trip, SENSE_FLUSH};
use crate::settings::Settings;

fn segment(generation: u32) -> Segment {
    Segment {
        events: 100,
        period: 1000,
        amass: 0,
        new_block: true,
        steps: crate::pad([100, 0, 0, 0]),
        count: 100,
        dir_mask: 0,
        watch: Watch::default(),
        end_of_motion: true,
        generation,
        speed_mm_min: 600.0,
        cut: 0.0,
        line: 7,
        takeup: false,
    }
}

#[test]
fn hard_limit_from_an_interrupt_stops_the_next_event() {
    let rt = Realtime::new();
    let mut st = Stepper::new(StepConfig::new(&Settings::default(), 1_000_000));
    let mut queue = [
        Some(segment(rt.generation())),
        Some(segment(rt.generation())),
    ];
    let mut pop = || queue.iter_mut().find_map(Option::take);
    let open = Switches::default();
    assert!(st.on_event(&rt, &mut pop, || open).ticks > 0);
    assert!(st.on_event(&rt, &mut pop, || open).ticks > 0);
    let pos = rt.position();
    // The switch closed and bounced open again before the next event.
    rt.hard_limit(0b001);
    assert_eq!(rt.trip(), Trip::HardLimit);
    assert_eq!(rt.trip_mask(), 0b001);
    assert_eq!(rt.trip_position(), pos);
    let ev = st.on_event(&rt, &mut pop, || open);
    assert_eq!((ev.ticks, ev.step_mask), (0, 0), "no step after the trip");
    assert!(rt.stepper_idle());
    assert_eq!(rt.position(), pos);
}

#[test]
fn a_flush_stops_the_next_event_whatever_the_limits_setting_does() {
    let rt = Realtime::new();
    let mut st = Stepper::new(StepConfig::new(&Settings::default(), 1_000_000));
    let mut queue = [Some(segment(rt.generation()))];
    let mut pop = || queue.iter_mut().find_map(Option::take);
    let open = Switches::default();
    assert!(st.on_event(&rt, &mut pop, || open).ticks > 0);
    // A stale flag (no new generation) costs a look, not a stop, and
    // the look clears it.
    rt.raise_stale_flush();
    assert!(st.on_event(&rt, &mut pop, || open).ticks > 0);
    assert_eq!(rt.attention() & SENSE_FLUSH, 0);
    let pos = rt.position();
    // A flush, then the controller arms and disarms hard limits before
    // the next event: both only touch their own bit of the byte.
    rt.halt_stepper();
    rt.set_limits_armed(true);
    assert!(rt.limits_armed());
    rt.set_limits_armed(false);
    assert!(!rt.limits_armed());
    let ev = st.on_event(&rt, &mut pop, || open);
    assert_eq!((ev.ticks, ev.step_mask), (0, 0), "no step after the flush");
    assert_eq!(rt.position(), pos);
}

/// A backlash take-up segment turns the motor (the step pins pulse) but
/// leaves the position alone: its steps go to `Realtime::takeup` as it
/// loads, and the motors' position (host-sim's view) counts them step by
/// step.
#[test]
fn take_up_steps_pulse_but_do_not_move_the_position() {
    let rt = Realtime::new();
    let mut st = Stepper::new(StepConfig::new(&Settings::default(), 1_000_000));
    let mut takeup = segment(rt.generation());
    takeup.takeup = true;
    takeup.events = 8;
    takeup.steps = crate::pad([8, 0, 0, 0]);
    takeup.count = 8;
    takeup.dir_mask = 0b001;
    let mut plain = segment(rt.generation());
    plain.new_block = true;
    plain.dir_mask = 0b001;
    let mut queue = [Some(takeup), Some(plain)];
    let mut pop = || queue.iter_mut().find_map(Option::take);
    let open = Switches::default();
    let mut pulses = 0;
    let mut motor = Vec::new();
    for _ in 0..8 {
        let ev = st.on_event(&rt, &mut pop, || open);
        pulses += u32::from(ev.step_mask & 1);
        motor.push(st.motor_position(&rt)[0]);
        assert_eq!(rt.position(), [0; crate::AXES], "the tool stands still");
    }
    // The direction event, then seven of the eight take-up steps.
    assert_eq!(pulses, 7);
    assert_eq!(rt.takeup(), crate::pad([-8, 0, 0, 0]));
    assert_eq!(motor, [0, -1, -2, -3, -4, -5, -6, -7]);
    // The last take-up step, then the plain segment counts again.
    for _ in 0..3 {
        st.on_event(&rt, &mut pop, || open);
    }
    assert_eq!(rt.position(), crate::pad([-2, 0, 0, 0]));
    assert_eq!(st.motor_position(&rt), crate::pad([-10, 0, 0, 0]));
}

/// A dropped event (the pulse-end path failed) gives back exactly what it
/// counted: nothing on a take-up's step, one step on a plain segment's.
#[test]
fn a_dropped_take_up_step_leaves_the_position_alone() {
    let rt = Realtime::new();
    let mut st = Stepper::new(StepConfig::new(&Settings::default(), 1_000_000));
    let mut takeup = segment(rt.generation());
    takeup.takeup = true;
    takeup.events = 4;
    takeup.steps = crate::pad([4, 0, 0]);
    takeup.count = 4;
    let mut plain = segment(rt.generation());
    plain.new_block = true;
    let mut queue = [Some(takeup), Some(plain)];
    let mut pop = || queue.iter_mut().find_map(Option::take);
    let open = Switches::default();
    let mut dropped = 0;
    for _ in 0..12 {
        let ev = st.on_event(&rt, &mut pop, || open);
        if ev.step_mask & 1 != 0 {
            let before = rt.position();
            st.take_back(&rt, &ev);
            let back = before[0] - rt.position()[0];
            assert!(back == 0 || back == 1, "took back {back}");
            dropped += back;
        }
    }
    // Every plain step was taken back again, no take-up step moved it.
    assert_eq!(rt.position(), [0; crate::AXES]);
    assert!(dropped > 0, "no plain step was dropped");
}

/// B and C step in the out-of-line path (`SENSE_EXTRA`): every step of a
/// segment moving them lands, with X's, and with hard limits armed a
/// closed switch still trips before the next step.
#[test]
fn b_and_c_step_out_of_line_and_still_trip_a_limit() {
    if crate::AXES < 6 {
        return;
    }
    let rt = Realtime::new();
    let mut st = Stepper::new(StepConfig::new(&Settings::default(), 1_000_000));
    let mut seg = segment(rt.generation());
    seg.steps = protocol::first_axes([100, 0, 0, 0, 50, 25]);
    seg.dir_mask = 1 << 5; // C negative
    let mut queue = [Some(seg), Some(seg)];
    let mut pop = || queue.iter_mut().find_map(Option::take);
    let open = Switches::default();
    let mut masks = 0u8;
    // A direction event (C turns negative), then the segment's 100.
    for _ in 0..101 {
        masks |= st.on_event(&rt, &mut pop, || open).step_mask;
    }
    assert_eq!(masks, 0b110001, "X, B and C stepped");
    assert_eq!(rt.position(), protocol::first_axes([100, 0, 0, 0, 50, -25]));
    rt.set_limits_armed(true);
    let closed = Switches {
        limits: 0b001,
        probe: false,
    };
    let ev = st.on_event(&rt, &mut pop, || closed);
    assert_eq!((ev.ticks, ev.step_mask), (0, 0), "tripped, no step");
    assert_eq!(rt.trip(), Trip::HardLimit);
}
