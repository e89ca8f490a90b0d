//! Corners that stop holding once quiet blocks surround them
//! (`planner::quiet`): a zigzag of small blocks swings an axis's velocity
//! within much less than one window's worth of its acceleration, so its
//! corners need no hold; the corners next to a loud block keep theirs.
use burin::planner::{Planner, Speed, Watch};
use burin::settings::Settings;

/// A zigzag along X, swinging Y by `±amp` mm every `pitch` mm, from
/// vertex `from` on.
fn zigzag(p: &mut Planner<64>, from: usize, n: usize, pitch: f32, amp: f32) {
    for k in from..from + n {
        let y = if k % 2 == 1 { amp } else { -amp };
        p.push_line_mm(
            &burin::pad([k as f32 * pitch, y, 0.0, 0.0]),
            Speed::Feed(80.0),
            Watch::default(),
            k as u32,
        )
        .unwrap();
    }
}

#[test]
fn a_quiet_zigzag_stops_holding_its_corners() {
    let mut p: Planner<64> = Planner::new(Settings::default());
    zigzag(&mut p, 1, 40, 0.05, 0.025);
    assert_eq!(p.len(), 40);
    // Y swings within ±(speed·0.707) with corners at 2.5 mm/s and peaks
    // near 4: quiet (limit 0.75·500·0.05/2 = 9.4 mm/s of Y).
    for k in 2..34 {
        let b = p.block(k).unwrap();
        assert_eq!(b.hold_m, 0.0, "corner {k} still holds");
        assert_eq!(b.junction, b.corner, "corner {k}");
        assert!(b.corner > 2.0, "corner {k} at {}", b.corner);
        assert!(b.cap <= 9.375 / std::f32::consts::FRAC_1_SQRT_2 + 1e-3);
    }
    // The newest corners have less than 37.5 ms of quiet blocks after
    // them yet: they hold until more come.
    assert!(p.block(39).unwrap().hold_m > 0.0);
}

#[test]
fn a_zigzag_into_a_long_move_keeps_its_last_holds() {
    let mut p: Planner<64> = Planner::new(Settings::default());
    zigzag(&mut p, 1, 40, 0.05, 0.025);
    let held: Vec<usize> = (2..40)
        .filter(|&k| p.block(k).unwrap().hold_m > 0.0)
        .collect();
    assert!(!held.is_empty());
    p.push_line_mm(
        &burin::pad([20.0, 10.0, 0.0, 0.0]),
        Speed::Feed(80.0),
        Watch::default(),
        99,
    )
    .unwrap();
    // The long move is loud in Y (36 mm/s): the corners near it never had
    // 37.5 ms of quiet blocks after them, and keep holding.
    for k in held {
        assert!(p.block(k).unwrap().hold_m > 0.0, "corner {k} released");
    }
    let into = p.block(40).unwrap();
    assert!(into.hold_m > 0.0, "the corner into the long move holds");
}

#[test]
fn a_loud_zigzag_holds_every_corner() {
    let mut p: Planner<64> = Planner::new(Settings::default());
    // 0.6 mm swings of Y every 0.1 mm: Y near 20 mm/s each way.
    zigzag(&mut p, 1, 40, 0.1, 0.3);
    for k in 1..40 {
        let b = p.block(k).unwrap();
        assert!(b.hold_m > 0.0, "corner {k} holds nothing");
        assert_eq!(b.quiet & 0b10, 0, "block {k} quiet in Y");
    }
}
