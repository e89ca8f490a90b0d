//! Issue 33 item 3 through the virtual board: a compensated move is held
//! until the next line shows its corner, so its `ok` comes first; nothing
//! acknowledged is lost or run twice, `Ln:` shows the held move's own line
//! when it runs, G40 hands the last move on, a reset drops what is held
//! without moving, and a refused line runs nothing.

use host_sim::record::Discard;

use crate::rig;

use rig::{origin, Rig};

fn pos(r: &mut Rig) -> (f32, f32) {
    let p = r.status().mpos.unwrap_or_default();
    (p[0], p[1])
}

fn near(a: (f32, f32), b: (f32, f32)) -> bool {
    (a.0 - b.0).abs() < 0.02 && (a.1 - b.1).abs() < 0.02
}

/// Entry from the origin to (-10,-10) on the left with a 4 mm cutter, then
/// a line to (-30,-10): the corner at (-10,-10) is outside, so the entry
/// and the corner arc run and the line waits (the tool at (-10,-12)).
fn held_line(r: &mut Rig) {
    r.lines();
    for l in ["G21 G90 G17 F3000", "G41.1 D4 G1 X-10 Y-10", "G1 X-30 Y-10"] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    r.until_idle();
    let at = pos(r);
    assert!(
        near(at, (-10.0, -12.0)),
        "at {at:?}: the line of line 3 waits"
    );
}

#[test]
fn a_held_move_runs_as_its_own_line_when_g40_hands_it_on() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    held_line(&mut r);
    assert_eq!(r.cmd("G40 G1 X-40 Y-20"), ["ok"]);
    let mut lines_seen = Vec::new();
    for _ in 0..2000 {
        r.run(5);
        let st = r.status();
        let x = st.mpos.as_ref().map_or(0.0, |p| p[0]);
        if st.state == "Run" && x < -12.0 && x > -28.0 {
            lines_seen.push(st.line);
        }
        if st.state == "Idle" {
            break;
        }
    }
    assert!(!lines_seen.is_empty());
    assert!(
        lines_seen.iter().all(|l| *l == Some(3)),
        "the held move runs as line 3: {lines_seen:?}"
    );
    let end = pos(&mut r);
    assert!(
        near(end, (-40.0, -20.0)),
        "exit ends on the program: {end:?}"
    );
}

#[test]
fn a_reset_drops_the_held_move_without_moving() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    held_line(&mut r);
    let before = pos(&mut r);
    r.send(&[0x18]);
    r.run(50);
    let lines = r.lines();
    assert!(
        !lines.iter().any(|l| l.starts_with("ALARM")),
        "nothing moved: no alarm {lines:?}"
    );
    assert!(near(pos(&mut r), before));
    // Compensation is off after the reset: a move ends where it says.
    assert_eq!(r.cmd("G1 X-20 Y-20 F3000"), ["ok"]);
    r.until_idle();
    assert!(near(pos(&mut r), (-20.0, -20.0)));
}

#[test]
fn a_refused_corner_runs_nothing_and_the_held_move_stays() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    held_line(&mut r);
    // Down and back up a notch 1 mm wide with a 4 mm cutter: the corner
    // that closes it is error 382 (GRBL 33), where rs274 refuses it too.
    assert_eq!(r.cmd("G1 X-30 Y-15"), ["ok"]);
    assert_eq!(r.cmd("G1 X-29 Y-15"), ["ok"]);
    assert_eq!(r.cmd("G1 X-29 Y-5"), ["error:33"]);
    r.until_idle();
    // Line 3 ran cut short at the notch, line 4 down to (-28,-13); line 5
    // waits; nothing of line 6 ran (the tool never went up).
    let at = pos(&mut r);
    assert!(near(at, (-28.0, -13.0)), "at {at:?}");
    // The held move itself runs backwards: G40 cannot end it cleanly.
    assert_eq!(r.cmd("G40 G1 X-40 Y-30"), ["error:33"]);
    // M2 runs what was acknowledged, as it stands, once.
    assert_eq!(r.cmd("M2"), ["ok"]);
    r.until_idle();
    assert!(near(pos(&mut r), (-29.0, -13.0)));
}
