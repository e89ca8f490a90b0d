//! The envelope's boxes and its window, on hand-made steps.
use super::*;
use burin::command::{Feed, Plane};

const SPM: [f64; AXES] = [100.0; AXES];

fn arc(end: [f32; 2], center: [f32; 2], dir: ArcDir) -> Committed {
    Committed::Arc(Arc {
        end: burin::pad([end[0], end[1], 0.0, 0.0]),
        center,
        plane: Plane::XY,
        dir,
        turns: 0,
        feed: Feed::PerMin(100.0),
    })
}

#[test]
fn arc_boxes_include_the_bulge_they_sweep() {
    let s = burin::pad([1.0, 0.0, 0.0, 0.0]);
    // A quarter CCW from +X to +Y about the origin: no cardinal inside.
    let (b, fin) = move_bounds(&s, &arc([0.0, 1.0], [0.0, 0.0], ArcDir::Ccw), &SPM);
    assert_eq!((b.lo[0], b.hi[0], b.lo[1], b.hi[1]), (0.0, 1.0, 0.0, 1.0));
    assert!(fin);
    // The same end clockwise: three quarters, through -Y and -X.
    let (b, fin) = move_bounds(&s, &arc([0.0, 1.0], [0.0, 0.0], ArcDir::Cw), &SPM);
    assert_eq!((b.lo[0], b.hi[0], b.lo[1], b.hi[1]), (-1.0, 1.0, -1.0, 1.0));
    assert!(!fin);
    // A half circle +X to -X, CCW: over +Y only.
    let (b, _) = move_bounds(&s, &arc([-1.0, 0.0], [0.0, 0.0], ArcDir::Ccw), &SPM);
    assert_eq!((b.lo[1], b.hi[1]), (0.0, 1.0));
}

#[test]
fn a_short_arc_on_a_huge_radius_has_a_short_box() {
    // Issue 35: G2 X0.01 R30000 from (-150, -150); the centre is
    // 30 m away on -Y. Its box is the 0.01 mm chord and its sagitta.
    let s = burin::pad([-150.0, -150.0, 0.0, 0.0]);
    let c = [-149.995, -150.0 - 30_000.0];
    let (b, fin) = move_bounds(&s, &arc([-149.99, -150.0], c, ArcDir::Cw), &SPM);
    assert!(
        b.hi[0] - b.lo[0] < 0.011 && b.hi[1] - b.lo[1] < 1e-3,
        "{b:?}"
    );
    assert!(fin);
    // Start and end on the same steps: a full circle is allowed.
    let (b, _) = move_bounds(&s, &arc([-149.999, -150.0], c, ArcDir::Cw), &SPM);
    assert!(b.hi[1] - b.lo[1] > 59_000.0, "{b:?}");
}

#[test]
fn spline_box_is_the_control_polygon() {
    let s = [0.0; AXES];
    let sp = Committed::Spline(Spline {
        p1: [-2.0, 3.0],
        p2: [5.0, -1.0],
        end: burin::pad([1.0, 1.0, 2.0, 0.0]),
        feed: Feed::PerMin(100.0),
    });
    let (b, fin) = move_bounds(&s, &sp, &SPM);
    assert_eq!(b.lo, burin::pad([-2.0, -1.0, 0.0, 0.0]));
    assert_eq!(b.hi, burin::pad([5.0, 3.0, 2.0, 0.0]));
    assert!(!fin);
}

#[test]
fn steps_outside_the_window_fail_and_finished_moves_retire() {
    let mut e = Envelope::new([100.0; AXES]);
    e.settle([0; AXES]);
    e.motion(
        1,
        [0.0; AXES],
        Committed::Straight(burin::pad([1.0, 0.0, 0.0, 0.0])),
    );
    e.motion(
        2,
        burin::pad([1.0, 0.0, 0.0, 0.0]),
        Committed::Straight(burin::pad([1.0, 1.0, 0.0, 0.0])),
    );
    for x in 0..=100 {
        e.step(&burin::pad([x, 0, 0, 0]));
    }
    for y in 0..=50 {
        e.step(&burin::pad([100, y, 0, 0]));
    }
    // Within line 1's box, but line 1 is finished: outside line 2's
    // box and the two steps around line 1's end.
    let back = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        e.step(&burin::pad([97, 50, 0, 0]))
    }));
    assert!(
        back.is_err(),
        "three steps back along a finished move passed"
    );
}

#[test]
fn a_step_with_nothing_committed_fails() {
    let mut e = Envelope::new([100.0; AXES]);
    e.settle(burin::pad([5, 0, 0, 0]));
    e.step(&burin::pad([6, 0, 0, 0]));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        e.step(&burin::pad([7, 0, 0, 0]))
    }));
    assert!(r.is_err(), "two steps from rest with no move passed");
}
