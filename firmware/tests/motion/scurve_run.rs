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

/// A chain of 0.02 mm chords, straight but for a tenth of a degree per
/// chord, at F3000: the planner's entries after 400 chords, the oldest
/// popped as they would run, with a full ring queued.
fn entries_along_short_chords(profile: Profile) -> Vec<f32> {
    let settings = Settings {
        profile,
        ..Settings::default()
    };
    let mut p: Planner<64> = Planner::new(settings);
    let (mut x, mut y, mut dir) = (0.0f32, 0.0f32, 0.0f32);
    for k in 1..=400u32 {
        if p.is_full() {
            p.pop();
        }
        dir += 0.1f32.to_radians();
        x += 0.02 * dir.cos();
        y += 0.02 * dir.sin();
        p.push_line_mm(
            &burin::pad([x, y, 0.0, 0.0]),
            Speed::Feed(50.0),
            Default::default(),
            k,
        )
        .unwrap();
    }
    (0..p.len()).map(|k| p.block(k).unwrap().entry).collect()
}

/// The backward pass reckons a run's rest as one S ramp (`planner::run`):
/// with a ramp per chord, each from zero acceleration, the 64 chords
/// queued (1.3 mm) stop from 4.6 mm/s, where one ramp over each run of
/// 17 stops from about twice that.
#[test]
fn a_ring_of_short_chords_stops_in_a_ramp_per_run() {
    let e = entries_along_short_chords(Profile::SCurve);
    let sh = Shape {
        accel: 500.0,
        jerk: 5000.0,
        drop: 0.0,
    };
    let mut chain = 0.0;
    for _ in 1..e.len() {
        chain = sh.reach(chain, 0.02);
    }
    assert!(
        e[1] > 1.6 * chain,
        "entry of the second chord {:.2} mm/s, a ramp per chord stops from {chain:.2}: {e:?}",
        e[1]
    );
    // Never above what a trapezoid with the same acceleration allows.
    let t = entries_along_short_chords(Profile::Trapezoid);
    assert!(
        e.iter().zip(&t).all(|(s, t)| *s <= *t * 1.0001),
        "{e:?} {t:?}"
    );
}

/// Runs are fixed as blocks are queued, but a block that grows by a merge
/// (`planner::merge`) leaves a run it no longer belongs in: the 0.025 mm
/// steps of short_segments.ngc merge into one 25 mm line, which had stayed
/// in the run of the short block before it and so at that one's speed
/// (its Y leg at 11 % of the rate limit; 3.26 s became 5.46 s).
#[test]
fn a_block_grown_by_merges_leaves_a_run_it_no_longer_fits() {
    let settings = Settings {
        profile: Profile::SCurve,
        ..Settings::default()
    };
    let mut p: Planner<64> = Planner::new(settings);
    let mut line = 0;
    let mut push = |p: &mut Planner<64>, x: f32, y: f32| {
        line += 1;
        p.push_line_mm(
            &burin::pad([x, y, 0.0, 0.0]),
            Speed::Feed(423.0),
            Default::default(),
            line,
        )
        .unwrap();
    };
    for k in 1..=40 {
        push(&mut p, 0.0254 * k as f32, 0.0);
    }
    for k in 1..=40 {
        push(&mut p, 1.016, 0.0254 * k as f32);
    }
    let mut grown = 0;
    for k in 1..p.len() {
        let (a, b) = (p.block(k - 1).unwrap(), p.block(k).unwrap());
        if b.length > 0.5 {
            grown += 1;
        }
        if b.run_pos != 0 && b.length > 0.1 {
            assert!(
                burin::planner::nominal_near(a.nominal, b.nominal),
                "block {k} ({:.3} mm at {:.1} mm/s) in the run of one at {:.1} mm/s",
                b.length,
                b.nominal,
                a.nominal
            );
        }
    }
    assert!(grown >= 1, "no move merged");
}

/// A run's corners take their share of each of the meter's windows, not
/// of one window for the whole run (`planner::run`): a pen plotter's
/// 0.26 mm strokes turning 0.1 rad each (a radius of 2.6 mm) hold a
/// little at every corner, and summed over a run of 17 the holds capped
/// it at 1.5 mm/s, far below the 20.8 the blocks alone enter at, so no
/// run counted. Its turns keep half the jerk: `v ≤ cbrt(j·r²/2)`.
#[test]
fn a_plotter_run_counts_its_corners_per_window() {
    let mut settings = Settings {
        profile: Profile::SCurve,
        jerk: 5000.0,
        junction_deviation: 0.01,
        ..Settings::default()
    };
    for ax in &mut settings.axes[..2] {
        (ax.steps_per_mm, ax.max_rate, ax.max_accel) = (80.0, 5000.0, 500.0);
    }
    let mut p: Planner<64> = Planner::new(settings);
    let (mut x, mut y, mut dir) = (0.0f32, 0.0f32, 0.0f32);
    for k in 1..=300u32 {
        if p.is_full() {
            p.pop();
        }
        dir += 0.1;
        x += 0.26 * dir.cos();
        y += 0.26 * dir.sin();
        p.push_line_mm(
            &burin::pad([x, y, 0.0, 0.0]),
            Speed::Feed(2500.0 / 60.0),
            Default::default(),
            k,
        )
        .unwrap();
    }
    let b: Vec<_> = (0..p.len()).map(|k| *p.block(k).unwrap()).collect();
    // The old cap: 0.1 of one 50 ms window for the holds of a whole run.
    let held: f32 = b[1..17]
        .iter()
        .map(|b| 0.5 * (b.hold_m + b.hold_pre_m))
        .sum();
    assert!(held > 0.0, "the corners hold: {held}");
    let old_cap = 0.1 * 0.05 / held;
    let turn_cap = (0.5f32 * 5000.0 * 2.6 * 2.6).cbrt();
    let e = b[8].entry;
    // The blocks alone (the old cap far below them) enter at 20.8 mm/s.
    assert!(old_cap < 2.0, "{old_cap}");
    assert!(e > 22.5, "entry {e:.2} mm/s");
    assert!(
        e <= turn_cap * 1.01,
        "entry {e:.2} mm/s over the turns' cap {turn_cap:.2}"
    );
    assert!(b.iter().all(|b| b.entry <= b.max_entry * 1.0001));
}
