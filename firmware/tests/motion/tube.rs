//! Stretches within a step of a line (`planner::tube`): a large circle in
//! inch decimals is judged on its stretches (its corners rise to junction
//! deviation under the stretch's bend, without holds, and the ramps beside
//! them keep the rest of the acceleration), while a dip back along a line
//! and a real curve of short chords keep their own limits.
use burin::planner::{Block, Planner, Speed, Watch};
use burin::settings::Settings;

/// The queued blocks after pushing `moves` (mm), popping the oldest
/// whenever the ring is full, as the segment preparer does.
fn run(settings: Settings, moves: &[[f32; 3]], feed: f32) -> Vec<Block> {
    let mut p: Planner<64> = Planner::new(settings);
    for (k, m) in moves.iter().enumerate() {
        if p.is_full() {
            p.pop();
        }
        p.push_line_mm(
            &burin::pad(*m),
            Speed::Feed(feed),
            Watch::default(),
            k as u32 + 1,
        )
        .unwrap();
    }
    (0..p.len()).filter_map(|k| p.block(k)).copied().collect()
}

/// circle_small.ngc's first `n` chords: a 1 inch radius in 10,000 chords,
/// each end rounded to four decimals.
fn inch_circle(n: u32) -> Vec<[f32; 3]> {
    let round4 = |v: f64| (v * 10_000.0).round() / 10_000.0;
    (0..n)
        .map(|k| {
            let a = core::f64::consts::TAU * k as f64 / 10_000.0;
            [
                (round4(a.sin()) * 25.4) as f32,
                (round4(a.cos()) * 25.4) as f32,
                0.0,
            ]
        })
        .collect()
}

#[test]
fn a_circle_in_inch_decimals_is_judged_on_its_stretches() {
    // The queue after 760 chords, past 27° round: the corners behind the
    // newest few (whose stretches have not closed yet) lie inside
    // stretches within a step of their line. Judged one or two chords at
    // a time, 12 of these 45 were held under 25 mm/s (9-15 mm/s); on their
    // stretches none is, and those the stretch's bend limits hold nothing
    // at `sqrt(0.7·500·r)` = 31.4 mm/s, `r` = 0.75²/(8·2·0.0125) mm.
    let blocks = run(Settings::default(), &inch_circle(760), 4_000.0);
    let inside = &blocks[3..blocks.len() - 16];
    assert_eq!(inside.len(), 45);
    for b in inside {
        assert!(b.corner >= 25.0, "line {}: corner {}", b.line, b.corner);
    }
    let bent: Vec<&Block> = inside.iter().filter(|b| b.corner < 31.5).collect();
    assert!(
        bent.len() >= 10,
        "{} corners at the bend's limit",
        bent.len()
    );
    for b in bent {
        assert!(
            b.hold_m == 0.0 && b.hold_pre_m == 0.0,
            "line {} holds",
            b.line
        );
        // At most 0.3 of the line's acceleration (500 mm/s² along an
        // axis, 707 on the diagonal) for the ramps beside the bend.
        assert!(b.accel <= 0.3 * 708.0, "line {}: accel {}", b.line, b.accel);
    }
}

#[test]
fn a_dip_back_along_a_climb_keeps_its_hold() {
    // Cereal.ngc: a steep straight climb in XYZ of 0.2 mm steps, one
    // vertex followed by a Z move 0.014 mm back down before the climb goes
    // on. Every vertex lies within a step of the climb's line, but the dip
    // turns Z round: its corners keep their holds (with the dip released,
    // Z read 106 % of its limit over 50 ms windows).
    let mut s = Settings::default();
    s.axes[2].steps_per_mm = 400.0;
    s.axes[2].max_accel = 100.0;
    let step = [0.0597f32, -0.0864, 0.1496];
    let mut moves = vec![[0.0f32, 0.0, 0.0]];
    for k in 1..=12 {
        let f = k as f32;
        moves.push([step[0] * f, step[1] * f, step[2] * f]);
        if k == 6 {
            moves.push([step[0] * f, step[1] * f, step[2] * f - 0.014]);
        }
    }
    let blocks = run(s, &moves, 20.0);
    let dip = blocks.iter().find(|b| b.line == 8).expect("dip queued");
    assert!(dip.steps[0] == 0 && dip.steps[2] > 0, "the dip is Z only");
    assert!(dip.hold_m > 0.0, "the dip's corner holds: {}", dip.hold_m);
    let after = blocks.iter().find(|b| b.line == 9).expect("queued");
    assert!(
        after.hold_m > 0.0,
        "the corner out of it holds: {}",
        after.hold_m
    );
}

#[test]
fn a_real_curve_of_short_chords_is_no_straight_stretch() {
    // A 1 mm radius of 0.02 mm chords, 200 of them: 0.75 mm of it bows
    // 0.07 mm (5.6 steps) off its chord, so no stretch passes and every
    // corner keeps the curvature rule, `v² ≤ a·l/φ` (at most 26.6 mm/s).
    let moves: Vec<[f32; 3]> = (0..200)
        .map(|k| {
            let a = 0.02 * k as f32;
            [libm::cosf(a), libm::sinf(a), 0.0]
        })
        .collect();
    let blocks = run(Settings::default(), &moves, 80.0);
    for b in &blocks[2..blocks.len() - 1] {
        assert!(b.corner < 26.7, "line {}: corner {}", b.line, b.corner);
    }
}
