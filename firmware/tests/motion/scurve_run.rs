//! S-curve runs (`stepper::prep::run`): the ramps go on across the chords
//! of a curve instead of starting each chord from zero acceleration.
use burin::planner::{Curve, Planner, Shape, Speed};
use burin::realtime::Realtime;
use burin::settings::{Profile, Settings};
use burin::stepper::prep::Preparer;
use burin::stepper::{Segment, StepConfig};
use heapless::spsc::Queue;

/// Path speed (mm/s) at the end of each of the first `blocks` blocks of a
/// 10 mm circle in 0.4 mm chords, from rest.
fn speeds_along_a_circle(blocks: usize) -> Vec<f32> {
    let settings = Settings {
        profile: Profile::SCurve,
        ..Settings::default()
    };
    let rt = Realtime::new();
    let mut p: Planner<64> = Planner::new(settings);
    let mut prep = Preparer::new(settings, StepConfig::new(&settings, 1_000_000));
    let n = 157;
    let curve = Curve {
        radius: 10.0,
        plane: 0b11,
    };
    for k in 1..=60 {
        let t = k as f32 / n as f32 * std::f32::consts::TAU;
        let end = burin::pad([10.0 - 10.0 * t.cos(), 10.0 * t.sin(), 0.0, 0.0]);
        p.push_chord(&end, Speed::Feed(50.0), k, curve).unwrap();
    }
    let mut q: Queue<Segment, 16> = Queue::new();
    let mut out = Vec::new();
    let mut last = 0.0;
    for _ in 0..100_000 {
        prep.fill(&mut p, &rt, &mut q);
        while let Some(s) = q.dequeue() {
            if s.new_block && s.events > 0 && out.len() < blocks && last > 0.0 {
                out.push(last);
            }
            if s.events > 0 {
                last = s.speed_mm_min / 60.0;
            }
        }
        if out.len() >= blocks {
            break;
        }
    }
    out
}

#[test]
fn s_curve_ramps_run_on_across_the_chords_of_a_curve() {
    let v = speeds_along_a_circle(12);
    assert_eq!(v.len(), 12);
    // A ramp per chord, each from zero acceleration, at the full 500
    // mm/s² (more than a chord's tangential share): an upper bound on the
    // old staircase.
    let sh = Shape {
        accel: 500.0,
        jerk: 5000.0,
        drop: 0.0,
    };
    let mut stair = 0.0;
    for _ in 0..8 {
        stair = sh.reach(stair, 0.4);
    }
    assert!(
        v[7] > 1.2 * stair,
        "after 8 chords at {:.1} mm/s, a ramp per chord reaches {stair:.1}: {v:?}",
        v[7]
    );
}
