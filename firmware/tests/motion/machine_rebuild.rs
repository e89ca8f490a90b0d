//! `$n=` rebuilds the machine in place (`Machine::rebuild`) instead of
//! building a second one on the stack: the rebuilt machine must be a new
//! one in everything but where it lives.

use burin::command::{Command, Feed};
use burin::executor::Machine;
use burin::realtime::Realtime;
use burin::settings::Settings;
use burin::stepper::{Segment, Switches};
use heapless::spsc::Queue;

fn segments(m: &mut Machine<16>, rt: &Realtime) -> Vec<Segment> {
    let cmds = [
        Command::Line {
            end: burin::pad([10.0, 5.0, 0.0, 0.0]),
            feed: Feed::PerMin(1200.0),
        },
        Command::Line {
            end: burin::pad([12.0, -3.0, 1.0, 0.0]),
            feed: Feed::PerMin(900.0),
        },
    ];
    for (i, c) in cmds.iter().enumerate() {
        m.submit(rt, c, i as u32 + 1, &mut |_| {}).expect("submit");
    }
    let mut out = Vec::new();
    let mut q: Queue<Segment, 16> = Queue::new();
    for _ in 0..10_000 {
        m.poll(rt, &mut q, Switches::default(), &mut |_| {});
        if q.is_empty() {
            break;
        }
        while let Some(s) = q.dequeue() {
            out.push(s);
        }
    }
    out
}

#[test]
fn a_rebuilt_machine_moves_as_a_new_one() {
    let a = Settings::default();
    let mut b = a;
    b.axes[0].max_accel = 123.0;
    b.axes[1].steps_per_mm = 160.0;
    b.junction_deviation = 0.05;

    let rt = Realtime::new();
    let mut used = Machine::<16>::new(a, 1_000_000);
    // Leave state behind: queued blocks, a commanded end, an override.
    used.submit(
        &rt,
        &Command::Line {
            end: burin::pad([3.0, 4.0, 0.0, 0.0]),
            feed: Feed::PerMin(600.0),
        },
        1,
        &mut |_| {},
    )
    .expect("submit");
    used.motion.set_overrides(150, 50);
    assert!(!used.motion.planner().is_empty());
    used.rebuild(b, 1_000_000);
    assert!(used.motion.planner().is_empty());

    let rt_new = Realtime::new();
    let mut fresh = Machine::<16>::new(b, 1_000_000);
    let from_fresh = segments(&mut fresh, &rt_new);
    let rt_used = Realtime::new();
    let from_used = segments(&mut used, &rt_used);
    assert!(from_fresh.len() > 10, "{} segments", from_fresh.len());
    assert_eq!(from_used, from_fresh);
    assert_eq!(used.settings(), fresh.settings());
    assert_eq!(used.commanded_position(), fresh.commanded_position());
}

/// The board's slot starts as `Machine::placeholder()` (a static built at
/// compile time) and `parse` rebuilds it in place on the stored settings:
/// it must then move exactly as `Machine::new` on those settings.
#[test]
fn a_rebuilt_placeholder_moves_as_a_new_machine() {
    static SLOT: std::sync::Mutex<Machine<16>> = std::sync::Mutex::new(Machine::placeholder());
    let mut b = Settings::default();
    b.axes[0].max_accel = 123.0;
    b.step_pulse_us = 5.0;
    let mut slot = SLOT.lock().expect("slot");
    slot.rebuild(b, 1_000_000);
    let mut fresh = Machine::<16>::new(b, 1_000_000);
    let from_fresh = segments(&mut fresh, &Realtime::new());
    assert!(from_fresh.len() > 10, "{} segments", from_fresh.len());
    assert_eq!(segments(&mut slot, &Realtime::new()), from_fresh);
    assert_eq!(slot.settings(), fresh.settings());
    assert_eq!(slot.step_config(), fresh.step_config());
}
