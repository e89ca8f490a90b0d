//! The programmed feed is a speed along the commanded path (RS274NGC), not
//! along the path its ends round to in steps. On chords a step or two long
//! the two differ by several percent: a chord of 1.3 steps is stepped as 1
//! or 2, and the stepped polyline zigzags around the commanded one. burin
//! times each block by its commanded length (`planner::push`) and caps its
//! own step rate by its step counts (`planner::interval`).

use crate::common;
use host_sim::bench::run_job;

const STEPS_PER_MM: f64 = 80.0;

/// A quarter circle of 25.4 mm from the origin in 2,500 chords, written to 4 decimals of
/// an inch the way the CAM output of `circle_small_segments` is: chords of
/// 0.016 mm, 1.3 steps on the grbl_match machine.
fn quarter_circle() -> Vec<(f64, f64)> {
    let n = 2500;
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64 * std::f64::consts::FRAC_PI_2;
            let q = |v: f64| (v / 25.4 * 1e4).round() / 1e4 * 25.4;
            (q(25.4 * t.sin()), q(25.4 * t.cos() - 25.4))
        })
        .collect()
}

fn length(pts: &[(f64, f64)], round: impl Fn(f64) -> f64) -> f64 {
    pts.windows(2)
        .map(|w| (round(w[1].0) - round(w[0].0)).hypot(round(w[1].1) - round(w[0].1)))
        .sum()
}

#[test]
fn tiny_chords_run_at_the_programmed_feed_along_the_commanded_path() {
    let pts = quarter_circle();
    let mut src = String::from("G21 G90 G94\nG1 F120\n");
    for (x, y) in &pts[1..] {
        src.push_str(&format!("G1 X{x:.4} Y{y:.4}\n"));
    }
    let f = run_job(&common::grbl_match(), &src);
    assert!(f.summary.errors.is_empty(), "{:?}", f.summary.errors);
    let commanded = length(&pts, |v| v);
    let stepped = length(&pts, |v| (v * STEPS_PER_MM).round() / STEPS_PER_MM);
    // The case only tells the two apart if the rounding makes a difference.
    assert!(
        stepped > 1.03 * commanded,
        "{stepped:.3} / {commanded:.3} mm"
    );
    // 2 mm/s along the commanded path (plus a ramp of 4 ms from rest and
    // one back): the stepped length at that speed is 3 % more.
    let t = commanded / 2.0;
    assert!(
        (f.time_s - t).abs() < 0.005 * t,
        "{:.3} s for {commanded:.3} mm at 2 mm/s ({:.3} s), {stepped:.3} mm stepped, bound {:.3}",
        f.time_s,
        t,
        f.bound_s
    );
}

/// Pieces of one line whose ends round to 2 or 3 steps (0.0254 mm is 2.03
/// steps) merge into one block (`planner::merge`) though each piece's own
/// cap differs with its step count, so the line reaches its rate: as fast
/// as the bound within 3 %. Kept apart at each 3-step piece (the line is
/// capped there at 2/3 of its rate), it ran 37 % over the bound.
#[test]
fn collinear_pieces_that_round_to_different_step_counts_merge() {
    let mut src = String::from("G21 G90 G94\nG1 F5000\n");
    for k in 1..=4000 {
        src.push_str(&format!("G1 X{:.4}\n", k as f64 * 0.0254));
    }
    let f = run_job(&common::grbl_match(), &src);
    assert!(f.summary.errors.is_empty(), "{:?}", f.summary.errors);
    assert!(
        f.time_s < 1.03 * f.bound_s,
        "{:.3} s, bound {:.3} s",
        f.time_s,
        f.bound_s
    );
    assert_eq!(f.limits.short_intervals, [0; burin::AXES]);
}
