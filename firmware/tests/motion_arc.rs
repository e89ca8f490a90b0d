//! Segmenter: chord error within tolerance in every plane, helix, full
//! circles, multi-turn, exact end points; splines flattened to tolerance.
use burin::arc::{ArcChords, ArcError, SplineChords};
use burin::command::{Arc, ArcDir, Feed, Plane, Pos, Spline};

const TOL: f32 = 0.002;

/// Largest distance from the true circle over chord midpoints (the sagitta
/// is largest there), in f64.
fn worst_chord_error(start: Pos, arc: &Arc, chords: &[Pos]) -> f64 {
    let (a, b, _) = arc.plane.axes();
    let c = [arc.center[0] as f64, arc.center[1] as f64];
    let r0 = (start[a] as f64 - c[0]).hypot(start[b] as f64 - c[1]);
    let mut prev = start;
    let mut worst = 0.0f64;
    for p in chords {
        let r_end = (p[a] as f64 - c[0]).hypot(p[b] as f64 - c[1]);
        let mid = [
            (prev[a] as f64 + p[a] as f64) / 2.0,
            (prev[b] as f64 + p[b] as f64) / 2.0,
        ];
        let r_mid = (mid[0] - c[0]).hypot(mid[1] - c[1]);
        worst = worst.max((r0 - r_mid).abs()).max((r0 - r_end).abs());
        prev = *p;
    }
    worst
}

fn arc(end: Pos, center: [f32; 2], plane: Plane, dir: ArcDir, turns: u16) -> Arc {
    Arc {
        end,
        center,
        plane,
        dir,
        turns,
        feed: Feed::PerMin(1000.0),
    }
}

#[test]
fn chords_within_tolerance_all_planes() {
    for plane in [Plane::XY, Plane::ZX, Plane::YZ] {
        let (a, b, h) = plane.axes();
        for dir in [ArcDir::Cw, ArcDir::Ccw] {
            for r in [0.5f32, 5.0, 50.0, 250.0] {
                let mut s = [0.0f32; 4];
                s[a] = r;
                let mut e = [0.0f32; 4];
                e[b] = r;
                e[h] = 3.0; // helical
                e[3] = 7.0;
                let arc = arc(e, [0.0, 0.0], plane, dir, 0);
                let ch: Vec<Pos> = ArcChords::new(&s, &arc, TOL).unwrap().collect();
                assert_eq!(*ch.last().unwrap(), e, "end point exact");
                let err = worst_chord_error(s, &arc, &ch);
                assert!(
                    err <= TOL as f64 * 1.01 + 1e-5,
                    "{plane:?} {dir:?} r={r}: {err}"
                );
                // helix axis and A advance linearly
                let mid = ch[ch.len() / 2];
                assert!(mid[h] > 0.0 && mid[h] < 3.0);
            }
        }
    }
}

#[test]
fn full_circle_and_multi_turn() {
    let s = [10.0, 0.0, 0.0, 0.0];
    let one = arc(s, [0.0, 0.0], Plane::XY, ArcDir::Ccw, 0);
    let three = arc(
        [10.0, 0.0, -6.0, 0.0],
        [0.0, 0.0],
        Plane::XY,
        ArcDir::Ccw,
        2,
    );
    let c1 = ArcChords::new(&s, &one, TOL).unwrap();
    let c3 = ArcChords::new(&s, &three, TOL).unwrap();
    let n1 = c1.chords();
    assert!(
        n1 > 50,
        "a full circle of r=10 at 2 µm needs many chords, got {n1}"
    );
    assert!(
        c3.chords() + 2 >= 3 * n1 && c3.chords() <= 3 * n1,
        "{} vs {n1}",
        c3.chords()
    );
    let pts: Vec<Pos> = c3.collect();
    assert_eq!(*pts.last().unwrap(), [10.0, 0.0, -6.0, 0.0]);
    // after one turn Z is at -2
    let p = pts[n1 as usize - 1];
    assert!(
        (p[2] + 2.0).abs() < 0.1 && (p[0] - 10.0).abs() < 0.1,
        "{p:?}"
    );
    assert!(worst_chord_error(s, &three, &pts) <= TOL as f64 * 1.01);
}

#[test]
fn cw_vs_ccw_go_opposite_ways() {
    let s = [10.0, 0.0, 0.0, 0.0];
    let e = [0.0, 10.0, 0.0, 0.0];
    let ccw: Vec<Pos> = ArcChords::new(&s, &arc(e, [0.0, 0.0], Plane::XY, ArcDir::Ccw, 0), TOL)
        .unwrap()
        .collect();
    let cw: Vec<Pos> = ArcChords::new(&s, &arc(e, [0.0, 0.0], Plane::XY, ArcDir::Cw, 0), TOL)
        .unwrap()
        .collect();
    assert!(
        ccw[ccw.len() / 2][0] > 0.0 && ccw[ccw.len() / 2][1] > 0.0,
        "quarter through +X+Y"
    );
    assert!(
        cw[cw.len() / 2][0] < 0.0 && cw[cw.len() / 2][1] < 0.0,
        "three quarters through -X-Y"
    );
    assert!(cw.len() > 2 * ccw.len());
}

#[test]
fn bad_arcs_are_errors_not_panics() {
    let s = [0.0, 0.0, 0.0, 0.0];
    assert_eq!(
        ArcChords::new(
            &s,
            &arc([1.0, 0.0, 0.0, 0.0], [0.0, 0.0], Plane::XY, ArcDir::Cw, 0),
            TOL
        )
        .err(),
        Some(ArcError::InvalidArc),
        "zero start radius"
    );
    assert_eq!(
        ArcChords::new(
            &[f32::NAN; 4],
            &arc(s, [1.0, 0.0], Plane::XY, ArcDir::Cw, 0),
            TOL
        )
        .err(),
        Some(ArcError::InvalidNumber)
    );
    let huge = arc(
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0],
        Plane::XY,
        ArcDir::Cw,
        u16::MAX,
    );
    assert_eq!(
        ArcChords::new(&[1.0, 0.0, 0.0, 0.0], &huge, 1e-6).err(),
        Some(ArcError::TooManySegments),
        "too many chords is refused"
    );
}

#[test]
fn spline_flattened_within_tolerance() {
    let s = [0.0, 0.0, 0.0, 0.0];
    let sp = Spline {
        p1: [30.0, 60.0],
        p2: [70.0, -40.0],
        end: [100.0, 10.0, -5.0, 0.0],
        feed: Feed::PerMin(1000.0),
    };
    let c = SplineChords::new(&s, &sp, TOL).unwrap();
    let exact = c.clone();
    let pts: Vec<Pos> = c.collect();
    assert_eq!(*pts.last().unwrap(), sp.end);
    // Dense sampling: every curve point lies within TOL of its chord.
    let n = pts.len();
    let mut prev = s;
    for (k, p) in pts.iter().enumerate() {
        for j in 1..10 {
            let t = (k as f32 + j as f32 / 10.0) / n as f32;
            let q = exact.point(t);
            let (ax, ay) = ((p[0] - prev[0]) as f64, (p[1] - prev[1]) as f64);
            let (qx, qy) = ((q[0] - prev[0]) as f64, (q[1] - prev[1]) as f64);
            let l = ax.hypot(ay);
            let d = (ax * qy - ay * qx).abs() / l;
            assert!(d <= TOL as f64 * 1.01 + 1e-5, "chord {k}: {d}");
        }
        prev = *p;
    }
}
