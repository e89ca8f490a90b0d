//! The gateway's backlash compensation, at the planner: what a reversal
//! queues, and that nothing changes while `$160`-`$163` are 0.

use super::{Move, Pipeline};
use crate::planner::{Planner, Speed, Watch};
use crate::realtime::Realtime;
use crate::settings::Settings;

fn line(x: f32, y: f32) -> Move {
    Move::Line {
        end: crate::pad([x, y, 0.0, 0.0]),
        speed: Speed::Feed(20.0),
        watch: Watch::default(),
        line: 1,
    }
}

/// (target X, target Y, take-up) of every queued block.
fn blocks<const N: usize>(p: &Pipeline<N>) -> Vec<(i32, i32, bool)> {
    (0..p.planner().len())
        .filter_map(|k| p.planner().block(k))
        .map(|b| (b.target[0], b.target[1], b.takeup))
        .collect()
}

fn backlash(x: f32, y: f32) -> Settings {
    let mut s = Settings::default();
    s.backlash_mm[0] = x;
    s.backlash_mm[1] = y;
    s
}

#[test]
fn a_reversal_takes_up_the_backlash_first_and_shifts_what_follows() {
    // 80 steps/mm: 0.1 mm is 8 steps. The axes home towards positive
    // (`$23=0`): moving positive needs no take-up from power-up.
    let mut p = Pipeline::<16>::new(backlash(0.1, 0.1), 1_000_000);
    p.submit(line(10.0, 0.0)).unwrap();
    assert_eq!(blocks(&p), [(800, 0, false)]);
    // X reverses: 8 steps of take-up on X alone, then the move, 8 steps
    // further on the motor than commanded.
    p.submit(line(0.0, 5.0)).unwrap();
    assert_eq!(
        blocks(&p),
        [(800, 0, false), (792, 0, true), (-8, 400, false)]
    );
    assert_eq!(p.backlash_comp(), crate::pad([-8, 0, 0, 0]));
    // Y reverses, X goes on the same way: Y's take-up only.
    p.submit(line(-1.0, 0.0)).unwrap();
    assert_eq!(
        p.planner().block(3).map(|b| (b.target, b.takeup)),
        Some((crate::pad([-8, 392, 0, 0]), true))
    );
    assert_eq!(
        p.planner().block(4).map(|b| b.target),
        Some(crate::pad([-88, -8, 0, 0]))
    );
    // Both back to positive: the slack goes back to the homing side.
    p.submit(line(3.0, 3.0)).unwrap();
    assert_eq!(
        p.planner().block(5).map(|b| (b.target, b.takeup)),
        Some((crate::pad([-80, 0, 0, 0]), true))
    );
    assert_eq!(p.backlash_comp(), [0; crate::AXES]);
}

#[test]
fn homing_towards_negative_takes_up_the_other_way() {
    let mut s = backlash(0.1, 0.0);
    s.homing_dir_invert = 0b001;
    let mut p = Pipeline::<16>::new(s, 1_000_000);
    p.submit(line(-10.0, 0.0)).unwrap();
    assert_eq!(blocks(&p), [(-800, 0, false)]);
    p.submit(line(0.0, 0.0)).unwrap();
    assert_eq!(
        blocks(&p),
        [(-800, 0, false), (-792, 0, true), (8, 0, false)]
    );
}

/// `$160`-`$163` at 0: the gateway plans exactly what the planner alone
/// does (bench-motion's table and every trace stay as they were).
#[test]
fn without_backlash_the_gateway_plans_as_the_planner_alone() {
    let s = Settings::default();
    let mut p = Pipeline::<16>::new(s, 1_000_000);
    let mut alone = Planner::<16>::new(s);
    alone.set_tick_hz(1_000_000);
    for (x, y) in [(10.0, 0.0), (0.0, 5.0), (-1.0, 0.0), (3.0, 3.0)] {
        p.submit(line(x, y)).unwrap();
        alone
            .push_line_mm(
                &crate::pad([x, y, 0.0, 0.0]),
                Speed::Feed(20.0),
                Watch::default(),
                1,
            )
            .unwrap();
    }
    assert_eq!(p.planner().len(), alone.len());
    for k in 0..alone.len() {
        assert_eq!(p.planner().block(k), alone.block(k));
    }
    assert_eq!(p.has_room(), !alone.is_full());
}

/// A flush drops take-ups that never ran: the compensation comes back
/// from what the step interrupt loaded, and the plan restarts at the
/// reported position plus it.
#[test]
fn a_flush_keeps_the_take_up_that_ran() {
    let rt = Realtime::new();
    let mut p = Pipeline::<16>::new(backlash(0.1, 0.0), 1_000_000);
    p.submit(line(10.0, 0.0)).unwrap();
    p.submit(line(0.0, 0.0)).unwrap();
    assert_eq!(p.backlash_comp(), crate::pad([-8, 0, 0, 0]));
    // Nothing ran: no take-up either.
    assert_eq!(p.flush(&rt), [0.0; crate::AXES]);
    assert_eq!(p.backlash_comp(), [0; crate::AXES]);
    assert_eq!(p.planner().position(), [0; crate::AXES]);
    // The reversal is still ahead, so it is taken up again.
    p.submit(line(-1.0, 0.0)).unwrap();
    assert_eq!(blocks(&p), [(-8, 0, true), (-88, 0, false)]);
}

/// Two slots while compensating: a take-up never finds the ring full
/// after the gateway said there was room.
#[test]
fn room_means_room_for_a_take_up_too() {
    let mut p = Pipeline::<4>::new(backlash(0.1, 0.0), 1_000_000);
    let mut x = 0.0;
    while p.has_room() {
        x = if x > 0.0 { 0.0 } else { 10.0 };
        p.submit(line(x, 0.0)).unwrap();
    }
    assert!(p.planner().len() >= 3, "{}", p.planner().len());
}

/// `$376`: with A rotary, F is along X alone and A takes the move's time;
/// A alone keeps F (degrees per second here); without `$376` the path is
/// every axis's, as GRBL's.
#[test]
fn rotary_axes_take_the_linear_move_s_time() {
    let to = |x: f32, a: f32| Move::Line {
        end: crate::pad([x, 0.0, 0.0, a]),
        speed: Speed::Feed(10.0),
        watch: Watch::default(),
        line: 1,
    };
    let programmed = |p: &Pipeline<16>, k: usize| p.planner().block(k).map(|b| b.programmed);
    let mut s = Settings::default();
    s.axes[3].max_rate = 1.0e5;
    let mut plain = Pipeline::<16>::new(s, 1_000_000);
    plain.submit(to(10.0, 90.0)).unwrap();
    assert_eq!(programmed(&plain, 0), Some(10.0));

    s.set(376, 8.0).unwrap();
    let mut p = Pipeline::<16>::new(s, 1_000_000);
    // 10 mm of X at 10 mm/s: 1 s, so the 90.55 mm-or-degree path at 90.55.
    p.submit(to(10.0, 90.0)).unwrap();
    let v = programmed(&p, 0).unwrap();
    assert!((v - crate::num::sqrt(100.0 + 8100.0)).abs() < 1e-3, "{v}");
    // A alone: F in degrees per second along A.
    p.submit(to(10.0, 0.0)).unwrap();
    assert_eq!(programmed(&p, 1), Some(10.0));
    // X alone: unchanged.
    p.submit(to(0.0, 0.0)).unwrap();
    assert_eq!(programmed(&p, 2), Some(10.0));
}

/// The rotary rule measures the linear axes from the last commanded end,
/// not from the motor's: with backlash taken up on X (the planner's last
/// end 0.1 mm off the commanded one), a move of A alone keeps F.
#[test]
fn rotary_rule_measures_from_the_commanded_end_under_backlash() {
    let mut s = backlash(0.1, 0.0);
    s.set(376, 8.0).unwrap();
    let mut p = Pipeline::<16>::new(s, 1_000_000);
    let to = |x: f32, a: f32| Move::Line {
        end: crate::pad([x, 0.0, 0.0, a]),
        speed: Speed::Feed(10.0),
        watch: Watch::default(),
        line: 1,
    };
    // X towards negative: a take-up, and the motor 8 steps past X.
    p.submit(to(-5.0, 0.0)).unwrap();
    assert_eq!(p.backlash_comp()[0], -8);
    p.submit(to(-5.0, 30.0)).unwrap();
    let last = p
        .planner()
        .block(p.planner().len() - 1)
        .map(|b| b.programmed);
    assert_eq!(last, Some(10.0), "A alone: F in degrees per second");
}

/// In S-curve mode the planner takes at most `PLAN_BURST_SCURVE` moves
/// between two fills of the segment queue, however much room it has, so a
/// long run of planning never leaves the step interrupt without segments;
/// trapezoid mode fills its whole ring.
#[test]
fn s_curve_planning_stops_for_a_segment_fill_every_few_moves() {
    let scurve = Settings {
        profile: crate::settings::Profile::SCurve,
        ..Settings::default()
    };
    for (settings, burst) in [
        (scurve, usize::from(super::PLAN_BURST_SCURVE)),
        (Settings::default(), 64),
    ] {
        let mut p = Pipeline::<64>::new(settings, 1_000_000);
        let mut n = 0;
        while p.may_plan() {
            n += 1;
            p.submit(line(n as f32, (n % 2) as f32)).unwrap();
        }
        assert_eq!(n, burst, "{:?}", settings.profile);
        let rt = Realtime::new();
        let mut q: heapless::spsc::Queue<crate::stepper::Segment, 16> =
            heapless::spsc::Queue::new();
        p.fill(&rt, &mut q);
        assert!(p.may_plan() || !p.has_room());
        assert!(!q.is_empty(), "the fill queued segments");
    }
}
