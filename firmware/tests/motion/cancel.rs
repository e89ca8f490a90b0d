//! Corners settled by the chord after them (`planner::cancel`): a step of
//! rounding in a line (inch decimals on a large circle) neither holds nor
//! slows its two corners once the next chord shows it taken back; a short
//! dip of a slow axis, which the step trace does show, keeps its hold; and
//! a real curve of short chords keeps its curvature limit.
use burin::planner::{Planner, Speed, Watch};
use burin::settings::Settings;

fn push(p: &mut Planner<64>, k: u32, x: f32, y: f32, z: f32) {
    p.push_line_mm(
        &burin::pad([x, y, z]),
        Speed::Feed(80.0),
        Watch::default(),
        k,
    )
    .unwrap();
}

/// The queued block of source line `line`.
fn block(p: &Planner<64>, line: u32) -> burin::planner::Block {
    (0..p.len())
        .filter_map(|k| p.block(k))
        .find(|b| b.line == line)
        .copied()
        .expect("block queued")
}

/// Chords of 0.0155 mm along X whose Y steps down by 0.00254 mm (0.0001
/// inch, a fifth of a step at 80 steps/mm) at chord 20, as a 25 mm circle
/// in inch decimals does every few chords.
fn staircase(p: &mut Planner<64>) {
    push(p, 1, 0.0, 0.0, 0.0);
    push(p, 2, 5.0, 0.0, 0.0);
    let (mut x, mut y) = (5.0f32, 0.0f32);
    for k in 3..40 {
        x += 0.0155;
        if k == 20 {
            y -= 0.00254;
        }
        push(p, k, x, y, 0.0);
    }
}

#[test]
fn a_step_of_rounding_neither_holds_nor_slows_its_corners() {
    let mut p: Planner<64> = Planner::new(Settings::default());
    staircase(&mut p);
    // Chord 20 goes down by 9.3°, chord 21 back along X: junction
    // deviation alone allows about 38 mm/s at each corner; a chord's own
    // turn over `l/φ` (0.1 mm) would allow 6.8, and a full hold less.
    // (Chord 21 on merges with the X chords after it: one block.)
    let down = block(&p, 20);
    let back = (0..p.len())
        .filter_map(|k| p.block(k))
        .find(|b| b.line > 20)
        .copied()
        .expect("block queued");
    for (line, b) in [(20, down), (21, back)] {
        assert!(b.corner > 30.0, "line {line}: corner {}", b.corner);
        assert!(
            b.junction > 30.0,
            "line {line}: junction {} (hold {})",
            b.junction,
            b.hold_m
        );
        assert!(b.hold_m < 1e-5, "line {line}: hold {}", b.hold_m);
    }
}

#[test]
fn a_short_dip_of_the_slow_axis_keeps_its_hold() {
    // A 3-D contour climbing in Z, with a 0.013 mm Z-only step down
    // between two of its chords (Cereal.ngc line 2203): Z turns from +0.81
    // to −1 and back, a pulse of 0.024 mm, about 10 % of Z's 100 mm/s²
    // over the meter's window. Its first corner keeps its hold.
    let mut p: Planner<64> = Planner::new(Settings::default());
    let d = [0.2f32, -0.271, 0.469];
    let mut at = [0.0f32; 3];
    push(&mut p, 1, 0.0, 0.0, 0.0);
    let mut k = 2;
    for _ in 0..4 {
        at = [at[0] + d[0], at[1] + d[1], at[2] + d[2]];
        push(&mut p, k, at[0], at[1], at[2]);
        k += 1;
    }
    at[2] -= 0.013;
    push(&mut p, k, at[0], at[1], at[2]);
    let dip = k;
    let before = block(&p, dip).hold_m;
    for _ in 0..3 {
        k += 1;
        at = [at[0] + d[0], at[1] + d[1], at[2] + d[2]];
        push(&mut p, k, at[0], at[1], at[2]);
    }
    let after = block(&p, dip).hold_m;
    assert!(before > 0.0, "the dip's corner holds");
    assert!(after >= before, "hold {before} became {after}");
}

#[test]
fn a_real_curve_of_short_chords_keeps_its_curvature_limit() {
    // A 1 mm radius of 0.02 mm chords: each turns 0.02 rad, within a
    // quarter step over its chord (so each corner waits for the next
    // chord), and the curve is real: the settled limit is `v² ≤ a·l/φ`
    // (22.4 mm/s where the turn is along an axis, `a` = 500 mm/s², 26.6
    // where it is diagonal, 707), not junction deviation's 141.
    let mut p: Planner<64> = Planner::new(Settings::default());
    push(&mut p, 1, 1.0, 0.0, 0.0);
    for k in 2..40u32 {
        let a = 0.02 * (k - 1) as f32;
        push(&mut p, k, libm::cosf(a), libm::sinf(a), 0.0);
    }
    for line in 4..36 {
        let c = block(&p, line).corner;
        assert!(c < 26.7, "line {line}: corner {c}");
        assert!(c > 22.3, "line {line}: corner {c}");
    }
}

#[test]
fn a_circle_in_inch_decimals_never_stops_between_its_chords() {
    // circle_small's start: a 1 inch radius in 10,000 chords, each end
    // rounded to four decimals. A corner's hold that filled the block
    // before it to the end left that block's own hold no room, and the
    // backward pass no entry but a stop (ten of them in the first 2,700
    // chords).
    let mut p: Planner<64> = Planner::new(Settings::default());
    let round4 = |v: f64| (v * 10_000.0).round() / 10_000.0;
    for k in 0..1_500u32 {
        let a = core::f64::consts::TAU * k as f64 / 10_000.0;
        let (x, y) = (round4(a.sin()) * 25.4, round4(a.cos()) * 25.4);
        if p.is_full() {
            p.pop();
        }
        p.push_line_mm(
            &burin::pad([x as f32, y as f32, 0.0]),
            Speed::Feed(4_000.0),
            Watch::default(),
            k + 1,
        )
        .unwrap();
        for i in 1..p.len() {
            let b = p.block(i).unwrap();
            assert!(
                b.entry > 0.0 || b.max_entry <= 0.0 || b.line == 1,
                "after line {}: line {} planned to stop (limit {})",
                k + 1,
                b.line,
                b.max_entry
            );
        }
    }
}
