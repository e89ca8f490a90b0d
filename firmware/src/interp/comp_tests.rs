//! Compensated paths through the interpreter, against the canonical moves
//! LinuxCNC 2.9's rs274 prints for the same programs (figures copied from
//! its output; `cargo xtask rs274` compares whole files).

use crate::command::{ArcDir, Command};
use crate::gcode::ErrorKind;
use crate::interp::Interpreter;

/// Tool 1 has a 4 mm diameter; the tool is at X0 Y0 Z-1.
const SETUP: &str = "G21 G90 G17\nG10 L1 P1 R2 Z0\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100";

/// (line, command) for every line of `prog` after the setup.
fn run(prog: &str) -> (Interpreter, Vec<(u32, Command)>) {
    let mut it = Interpreter::new();
    for l in SETUP.lines() {
        it.execute_line(l.as_bytes(), &mut |_| {}).unwrap();
    }
    it.set_machine_position(crate::pad([0.0, 0.0, -1.0, 0.0]));
    let mut out = Vec::new();
    for (i, l) in prog.lines().enumerate() {
        let n = i as u32 + 1;
        it.execute_line_at(l.as_bytes(), n, &mut |ln, c| out.push((ln, c)))
            .unwrap_or_else(|e| panic!("line {n} `{l}`: {e}"));
    }
    (it, out)
}

/// The moves as `('L'|'R'|'A', x, y, centre or NaN)`.
fn moves(cmds: &[(u32, Command)]) -> Vec<(char, f32, f32, [f32; 2])> {
    cmds.iter()
        .filter_map(|(_, c)| match c {
            Command::Line { end, .. } => Some(('L', end[0], end[1], [f32::NAN; 2])),
            Command::Rapid { end } => Some(('R', end[0], end[1], [f32::NAN; 2])),
            Command::Arc(a) => Some((
                if a.dir == ArcDir::Cw { 'W' } else { 'C' },
                a.end[0],
                a.end[1],
                a.center,
            )),
            _ => None,
        })
        .collect()
}

fn assert_path(got: &[(char, f32, f32, [f32; 2])], want: &[(char, f32, f32, [f32; 2])]) {
    assert_eq!(got.len(), want.len(), "moves: {got:?}");
    for (g, w) in got.iter().zip(want) {
        let close = |a: f32, b: f32| (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-3;
        assert!(
            g.0 == w.0
                && close(g.1, w.1)
                && close(g.2, w.2)
                && close(g.3[0], w.3[0])
                && close(g.3[1], w.3[1]),
            "got {g:?}, want {w:?} in {got:?}"
        );
    }
}

const N: [f32; 2] = [f32::NAN; 2];

#[test]
fn outside_corners_roll_around_the_programmed_corner() {
    // G42 round a 20 x 20 square: every corner is convex for the right side.
    let (_, out) = run("G42 G1 X10 Y0\nG1 X30 Y0\nG1 X30 Y20\nG1 X10 Y20\nG1 X10 Y5\nG40 G0 X0 Y0");
    assert_path(
        &moves(&out),
        &[
            ('L', 10.0, -2.0, N),
            ('L', 30.0, -2.0, N),
            ('C', 32.0, 0.0, [30.0, 0.0]),
            ('L', 32.0, 20.0, N),
            ('C', 30.0, 22.0, [30.0, 20.0]),
            ('L', 10.0, 22.0, N),
            ('C', 8.0, 20.0, [10.0, 20.0]),
            ('L', 8.0, 5.0, N),
            ('R', 0.0, 0.0, N),
        ],
    );
}

#[test]
fn inside_corners_meet_at_the_offsets_intersection() {
    // G41 inside a pocket, entered on a diagonal: the entry's end rolls
    // onto the first side, the inside corners are cut short.
    let (_, out) =
        run("G41 G1 X10 Y10\nG1 X40 Y10\nG1 X40 Y40\nG1 X10 Y40\nG1 X10 Y10\nG40 G1 X0 Y0");
    assert_path(
        &moves(&out),
        &[
            ('L', 8.5858, 11.4142, N),
            ('W', 10.0, 12.0, [10.0, 10.0]),
            ('L', 38.0, 12.0, N),
            ('L', 38.0, 38.0, N),
            ('L', 12.0, 38.0, N),
            ('L', 12.0, 10.0, N),
            ('L', 0.0, 0.0, N),
        ],
    );
}

#[test]
fn lines_and_arcs_meet_as_in_linuxcnc() {
    // Tangent arcs outside and inside, corners between arcs and lines.
    let (_, out) = run(
        "G41 G1 X10 Y0\nG1 X30 Y0\nG3 X40 Y10 I0 J10\nG1 X40 Y30\nG2 X30 Y40 I-10 J0\n\
         G1 X10 Y40\nG1 X0 Y30\nG1 X0 Y10\nG40 G1 X-10 Y0",
    );
    assert_path(
        &moves(&out),
        &[
            ('L', 10.0, 2.0, N),
            ('L', 30.0, 2.0, N),
            ('C', 38.0, 10.0, [30.0, 10.0]),
            ('L', 38.0, 21.0557, N),
            ('W', 21.0557, 38.0, [30.0, 30.0]),
            ('L', 10.8284, 38.0, N),
            ('L', 2.0, 29.1716, N),
            ('L', 2.0, 10.0, N),
            ('L', -10.0, 0.0, N),
        ],
    );
    // Arc to arc, both ways round, right side.
    let (_, out) = run(
        "G42 G1 X10 Y0\nG1 X20 Y0\nG2 X40 Y0 I10 J0\nG1 X40 Y-20\nG3 X60 Y-20 I10 J0\n\
         G1 X60 Y10\nG40 G1 X70 Y10",
    );
    assert_path(
        &moves(&out),
        &[
            ('L', 10.0, -2.0, N),
            ('L', 20.0, -2.0, N),
            ('C', 22.0, 0.0, [20.0, 0.0]),
            ('W', 38.0, 0.0, [30.0, 0.0]),
            ('L', 38.0, -20.0, N),
            ('C', 62.0, -20.0, [50.0, -20.0]),
            ('L', 62.0, 10.0, N),
            ('L', 70.0, 10.0, N),
        ],
    );
}

#[test]
fn a_u_turn_off_an_inside_arc_leaves_nothing_of_the_arc() {
    // The return line's offset is tangent to the compensated arc at the
    // arc's start: the arc is cut back to nothing. rs274 prints it as an
    // ARC_FEED from (20,2) to (20,2), which as an arc is a full circle
    // (burin's too); burin hands on a move of no length there instead.
    // In f32 through angles the point came out 0.0012 mm off; as vectors
    // it is exact.
    let (_, out) = run("G41 G1 X10\nG1 X20\nG3 X24 Y4 I0 J4\nG1 X0 Y4\nG40 G1 X0 Y0");
    assert_path(
        &moves(&out),
        &[
            ('L', 10.0, 2.0, N),
            ('L', 20.0, 2.0, N),
            ('L', 20.0, 2.0, N),
            ('L', 0.0, 2.0, N),
            ('L', 0.0, 0.0, N),
        ],
    );
}

#[test]
fn an_entry_arc_keeps_the_tool_tangent() {
    let (_, out) = run("G41 G2 X20 Y0 I10 J0\nG1 X30 Y0\nG40 G1 X40 Y0");
    assert_path(
        &moves(&out),
        &[
            ('W', 21.8167, 2.0, [11.0, 0.0]),
            ('L', 30.0, 2.0, N),
            ('L', 40.0, 0.0, N),
        ],
    );
}

#[test]
fn what_waits_behind_a_held_move_keeps_its_place() {
    // The move of line 2 is held until line 6 turns the corner; the
    // coolant, the dwell and the plunge of lines 3-5 wait behind it, and
    // the plunge follows the corner's new end.
    let (_, out) = run("G41 G1 X10 Y0\nG1 X20 Y0\nM8\nG4 P0.5\nG1 Z-2\nG1 X20 Y10\nG40 G1 X0 Y10");
    let kinds: Vec<(u32, &str)> = out
        .iter()
        .map(|(l, c)| {
            (
                *l,
                match c {
                    Command::Line { .. } => "line",
                    Command::Coolant { .. } => "coolant",
                    Command::Dwell { .. } => "dwell",
                    _ => "other",
                },
            )
        })
        .collect();
    assert_eq!(
        kinds,
        [
            (1, "line"),
            (2, "line"),
            (3, "coolant"),
            (4, "dwell"),
            (5, "line"),
            (6, "line"),
            (7, "line")
        ]
    );
    assert_path(
        &moves(&out)[1..3],
        &[('L', 18.0, 2.0, N), ('L', 18.0, 2.0, N)],
    );
    // The pause of an M0 cannot wait: the held move goes first, as it is.
    let (_, out) = run("G41 G1 X10 Y0\nG1 X20 Y0\nM0\nG1 X20 Y10");
    assert!(
        matches!(out[1], (2, Command::Line { end, .. }) if end[0] == 20.0),
        "{out:?}"
    );
    assert!(matches!(out[2], (3, Command::Pause { .. })));
}

#[test]
fn program_end_and_g40_hand_on_the_last_move() {
    let (it, out) = run("G41 G1 X10 Y0\nG1 X20 Y0");
    assert_eq!(moves(&out).len(), 1, "the last move waits for the next");
    assert_eq!(it.max_line_output(), crate::interp::LINE_COMMANDS + 2);
    let (mut it, _) = run("G41 G1 X10 Y0\nG1 X20 Y0");
    let mut out = Vec::new();
    it.execute_line_at(b"M2", 9, &mut |l, c| out.push((l, c)))
        .unwrap();
    assert!(
        matches!(out[0], (2, Command::Line { end, .. }) if end == crate::pad([20.0, 2.0, -1.0, 0.0]))
    );
    assert!(matches!(out.last(), Some((9, Command::ProgramEnd))));
    // After M2 compensation is off: the next move is not offset.
    out.clear();
    it.execute_line_at(b"G1 X30 Y0", 10, &mut |l, c| out.push((l, c)))
        .unwrap();
    assert!(matches!(out[..], [(10, Command::Line { end, .. })] if end[1] == 0.0));
}

#[test]
fn a_refused_line_leaves_the_held_moves_as_they_were() {
    let (mut it, _) = run("G41 G1 X10");
    let mut out = Vec::new();
    // A 1.5 mm arc cut from the inside by a 2 mm tool (rs274: "Tool
    // radius not less than arc radius with comp").
    let e = it
        .execute_line_at(b"G3 X13 Y0 I1.5 J0", 2, &mut |l, c| out.push((l, c)))
        .unwrap_err();
    assert_eq!(e.kind, ErrorKind::CompToolTooBig);
    assert!(out.is_empty(), "nothing of a refused line runs: {out:?}");
    // The same held state takes the next line: the entry of line 1 comes
    // out with its own number, and the interpreter's position did not
    // move to the refused arc's end (the new move starts at X10).
    it.execute_line_at(b"G1 X20 Y0", 3, &mut |l, c| out.push((l, c)))
        .unwrap();
    assert!(
        matches!(out[..], [(1, Command::Line { end, .. })] if end[..2] == [10.0, 2.0]),
        "{out:?}"
    );
    out.clear();
    it.execute_line_at(b"G40 G1 X30 Y0", 4, &mut |l, c| out.push((l, c)))
        .unwrap();
    assert!(
        matches!(out[0], (3, Command::Line { end, .. }) if end[..2] == [20.0, 2.0]),
        "{out:?}"
    );
}

#[test]
fn linuxcnc_errors_on_the_same_line() {
    let err = |prog: &str| {
        let mut it = Interpreter::new();
        for l in SETUP.lines() {
            it.execute_line(l.as_bytes(), &mut |_| {}).unwrap();
        }
        let mut last = None;
        for l in prog.lines() {
            if let Err(e) = it.execute_line(l.as_bytes(), &mut |_| {}) {
                last = Some(e.kind);
                break;
            }
        }
        last
    };
    use ErrorKind::*;
    let forbidden = |letter: u8, tenths: u16| Some(CompForbidden { letter, tenths });
    assert_eq!(err("G41 G1 X1 Y0"), Some(CompEntryTooShort));
    assert_eq!(err("G41 G1 Z-2"), Some(CompEntryTooShort));
    assert_eq!(err("G41 G1 X10\nG41 G1 X20"), Some(CompAlreadyOn));
    assert_eq!(err("G41 G1 X10\nG18"), forbidden(b'G', 180));
    assert_eq!(err("G41 G1 X10\nT2 M6"), forbidden(b'M', 60));
    assert_eq!(err("G41 G1 X10\nG92 X0"), forbidden(b'G', 920));
    assert_eq!(err("G41 G1 X10\nG81 X5 Y5 Z-1 R1"), forbidden(b'G', 810));
    assert_eq!(err("G41 G1 X10\nG28"), forbidden(b'G', 280));
    assert_eq!(err("G41 G1 X10\nG38.2 Z-5"), forbidden(b'G', 382));
    assert_eq!(err("G41 G1 X10\nG53 G1 X5"), forbidden(b'G', 530));
    assert_eq!(err("G41 G1 X10\nG55"), forbidden(b'G', 550));
    assert_eq!(err("G41 G1 X10\nG43 H1"), forbidden(b'G', 430));
    assert_eq!(err("G41 G1 X10\nG10 L2 P1 X1"), forbidden(b'G', 100));
    assert_eq!(err("G41 G1 X10\nG10 L2 P2 X1\nG1 X20"), None);
    assert_eq!(err("G41 G1 X10\nG40 G2 X0 Y0 I-5"), Some(CompArcAfterG40));
    assert_eq!(err("G41 G1 X10\nG3 X13 Y0 I1.5 J0"), Some(CompToolTooBig));
    assert_eq!(err("G19\nG41 G1 Y10"), Some(CompPlane));
    assert_eq!(err("G41.1 D4 L3 G1 X10"), Some(CompPlane));
    assert_eq!(
        err("G41 G1 X10\nG1 X20\nG1 X20 Y5\nG1 X19 Y5\nG1 X19 Y-5"),
        Some(CompGouge)
    );
    // G40 first lifts the ban for what runs after it on the line.
    assert_eq!(err("G41 G1 X10\nG40 G28"), None);
    assert_eq!(err("G41 G1 X10\nG40 G55 G1 X0"), None);
    assert_eq!(err("G41 G1 X10\nG40 G18"), forbidden(b'G', 180));
}

#[test]
fn diameters_come_from_the_table_or_the_line() {
    // D names a table tool; G41.1's D is a diameter, negative on the
    // other side (LinuxCNC: -1 on G41.1 is 0.5 mm on the right).
    let (_, out) = run("G10 L1 P2 R3\nG41 D2 G1 X10 Y0\nG40 G1 X20 Y0");
    assert_path(&moves(&out), &[('L', 10.0, 3.0, N), ('L', 20.0, 0.0, N)]);
    let (_, out) = run("G41.1 D-1 G1 X10\nG40 G1 X0 Y0");
    assert_path(&moves(&out), &[('L', 10.0, -0.5, N), ('L', 0.0, 0.0, N)]);
    // G20: the diameter is in inches.
    let (_, out) = run("G20\nG41.1 D0.2 G1 X1\nG40 G1 X0 Y0");
    assert_path(&moves(&out), &[('L', 25.4, 2.54, N), ('L', 0.0, 0.0, N)]);
}

#[test]
fn a_lathe_tool_orientation_moves_the_controlled_point() {
    // G18, G42.1 with L3: LinuxCNC adds the radius to X and Z at output.
    let mut it = Interpreter::new();
    for l in ["G21 G90 G18", "G0 X0 Z0"] {
        it.execute_line(l.as_bytes(), &mut |_| {}).unwrap();
    }
    it.set_machine_position([0.0; crate::AXES]);
    let mut out = Vec::new();
    for l in [
        "G42.1 D2 L3 G1 X10 Z0 F100",
        "G1 X10 Z-20",
        "G40 G1 X20 Z-20",
    ] {
        it.execute_line(l.as_bytes(), &mut |c| out.push((0, c)))
            .unwrap();
    }
    let ends: Vec<[f32; 2]> = out
        .iter()
        .filter_map(|(_, c)| c.end().map(|e| [e[0], e[2]]))
        .collect();
    // rs274: the entry's radius centre X10 Z1 is reported as X11 Z0; the
    // corner arc ends at X12 Z-1, the side at X12 Z-21; the exit is plain.
    let want = [[11.0, 0.0], [12.0, -1.0], [12.0, -21.0], [20.0, -20.0]];
    assert_eq!(ends.len(), want.len(), "{ends:?}");
    for (g, w) in ends.iter().zip(want) {
        assert!(
            (g[0] - w[0]).abs() < 1e-4 && (g[1] - w[1]).abs() < 1e-4,
            "{ends:?}"
        );
    }
}

#[test]
fn a_compensated_full_circle_stays_a_full_circle() {
    // G42 round a circle from its bottom: the entry rolls onto the
    // circle, which is cut inside (right side of a clockwise arc).
    let (_, out) = run("G42 G1 X20 Y0\nG2 X20 Y0 I0 J10\nG40 G1 X30 Y0");
    assert_path(
        &moves(&out),
        &[
            ('L', 20.0, -2.0, N),
            ('C', 20.0, 2.0, [20.0, 0.0]),
            ('W', 20.0, 2.0, [20.0, 10.0]),
            ('L', 30.0, 0.0, N),
        ],
    );
}
