//! Canned-cycle end points: the expected lists are LinuxCNC 2.9's `rs274`
//! output for the same programs (`rs274 -g`, STRAIGHT_TRAVERSE/FEED
//! coordinates; no work offsets, so its coordinates are machine mm here),
//! and hand-computed values where offsets and units come in.

use crate::command::{Command, Feed};
use crate::gcode::ErrorKind;
use crate::interp::Interpreter;

/// Every move the program makes, cycles expanded, as (R|F, X Y Z).
fn moves(prog: &str) -> Vec<(char, [f32; 3])> {
    let mut it = Interpreter::new();
    let mut out = Vec::new();
    for line in prog.lines() {
        let mut at = it.state().pos;
        let mut cmds = Vec::new();
        it.execute_line(line.as_bytes(), &mut |c| cmds.push(c))
            .unwrap_or_else(|e| panic!("{line}: {e}"));
        for c in cmds {
            let steps: Vec<Command> = match &c {
                Command::Cycle(cy) => {
                    let s: Vec<Command> = cy.steps(&at).collect();
                    let end = s.iter().rev().find_map(|c| c.end()).copied();
                    assert_eq!(end, Some(cy.end(&at)), "{line}: Cycle::end");
                    s
                }
                c => vec![c.clone()],
            };
            for s in steps {
                let (k, e) = match &s {
                    Command::Rapid { end } => ('R', end),
                    Command::Line { end, .. } => ('F', end),
                    _ => continue,
                };
                out.push((k, [e[0], e[1], e[2]]));
                at = *e;
            }
        }
        assert_eq!(at, it.state().pos, "{line}: interpreter position");
    }
    out
}

fn same(prog: &str, want: &[(char, [f32; 3])]) {
    let got = moves(prog);
    for (i, (g, w)) in got.iter().zip(want.iter()).enumerate() {
        let close = g.0 == w.0
            && g.1
                .iter()
                .zip(w.1.iter())
                .all(|(a, b)| (a - b).abs() < 1e-3);
        assert!(close, "move {i}: got {g:?}, rs274 {w:?}\n{got:?}");
    }
    assert_eq!(got.len(), want.len(), "{got:?}");
}

#[test]
fn g83_g73_g81_with_g98_g99_and_l_repeats_in_g17_and_g18() {
    same(
        "G21 G17 G90\nG0 X0 Y0 Z10\nG99 G83 X5 Y5 Z-3 R2 Q1 F100\nX10\n\
         G98 G73 X20 Z-2.5 R1 Q1\nG80\nG91 G81 X5 Y0 Z-2 R-3 L3 F100\nG90 G80\n\
         G18 G0 X0 Y10 Z0\nG98 G81 X1 Z2 Y-3 R5 F100",
        T1,
    );
}

#[test]
fn every_cycle_in_g19_and_g91_pecks() {
    same(
        "G21 G90 M3 S1000 G0 X1 Y10 Z2\nG19 G98 G86 Y1 Z1 X-3 R5 P0.5 F100\n\
         G89 Y3 P2 X-1 R5\nG85 Y4 X-1 R5\nG82 Y5 P1.5 X-1 R5\nG99 G83 Y6 Q1.5 R4 X0\n\
         G91 G73 Y1 Z1 X-2 R-1 Q0.7 L2\nM2",
        T3,
    );
}

#[test]
fn a_run_that_began_below_r_goes_to_r_first_in_all_planes() {
    same(
        "G21 G90 G0 X0 Y0 Z1\nG98 G82 X1 Z-1 R5 P1 F100\nG99 G83 X2 Q1.5 R4 Z0\n\
         G80 G19 G0 X1 Y0 Z0\nG98 G82 Y1 X-1 R5 P1 F100\nG99 G83 Y2 Q1.5 R4 X0\n\
         G80 G18 G0 X0 Y1 Z0\nG98 G82 X1 Y-1 R5 P1 F100\nG99 G83 X2 Q1.5 R4 Y0\nM2",
        T5,
    );
}

#[test]
fn work_offsets_inches_and_g91_steps() {
    // rs274 reports these in work coordinates and program units (its
    // output for this program, fresh parameter file); here they are
    // machine mm: G54 is (10, 20, -5), inch values x 25.4.
    let m = |x: f32, y: f32, z: f32| [x + 10.0, y + 20.0, z - 5.0];
    let i = |x: f32, y: f32, z: f32| m(x * 25.4, y * 25.4, z * 25.4);
    let want = [
        ('R', m(0.0, 0.0, 3.0)),
        ('R', m(1.0, 1.0, 3.0)),
        ('R', m(1.0, 1.0, 1.0)),
        ('F', m(1.0, 1.0, -2.0)),
        ('R', m(1.0, 1.0, 1.0)),
        ('R', i(0.5, 0.5, 0.1)),
        ('F', i(0.5, 0.5, -0.1)),
        ('R', i(0.5, 0.5, 0.1)),
        ('R', m(14.7, 11.7, 2.54)),
        ('R', m(14.7, 11.7, 1.0)),
        ('F', m(14.7, 11.7, 0.0)),
        ('R', m(14.7, 11.7, 3.0)),
        ('R', m(16.7, 10.7, 3.0)),
        ('R', m(16.7, 10.7, 1.0)),
        ('F', m(16.7, 10.7, 0.0)),
        ('R', m(16.7, 10.7, 3.0)),
    ];
    same(
        "G10 L2 P1 X10 Y20 Z-5\nG21 G90 G54 G0 X0 Y0 Z3\nG99 G81 X1 Y1 Z-2 R1 F200\n\
         G20 X0.5 Y0.5 Z-0.1 R0.1\nG21 G91 G98 G82 X2 Y-1 Z-1 R-2 P0.25 L2",
        &want,
    );
}

#[test]
fn g88_pauses_at_the_bottom_then_retracts_with_the_spindle_stopped() {
    let mut it = Interpreter::new();
    let mut cmds = Vec::new();
    for l in ["G0 Z10", "M3 S800", "G98 G88 X5 Z-4 R1 P0.5 F60"] {
        cmds.clear();
        it.execute_line(l.as_bytes(), &mut |c| cmds.push(c))
            .unwrap_or_else(|e| panic!("{l}: {e}"));
    }
    let Some(Command::Cycle(c)) = cmds.first().cloned() else {
        panic!("{cmds:?}")
    };
    let steps: Vec<Command> = c.steps(&crate::pad([0.0, 0.0, 10.0, 0.0])).collect();
    use crate::command::SpindleDir::*;
    assert_eq!(
        steps,
        [
            Command::Rapid {
                end: crate::pad([5.0, 0.0, 10.0, 0.0])
            },
            Command::Rapid {
                end: crate::pad([5.0, 0.0, 1.0, 0.0])
            },
            Command::Line {
                end: crate::pad([5.0, 0.0, -4.0, 0.0]),
                feed: Feed::PerMin(60.0)
            },
            Command::Dwell { seconds: 0.5 },
            Command::Spindle {
                dir: Off,
                speed: 800.0
            },
            Command::Pause { optional: false },
            Command::Rapid {
                end: crate::pad([5.0, 0.0, 10.0, 0.0])
            },
            Command::Spindle {
                dir: Cw,
                speed: 800.0
            },
        ]
    );
}

#[test]
fn cycle_words_are_sticky_only_within_one_cycle() {
    let mut it = Interpreter::new();
    let ok = |it: &mut Interpreter, l: &str| {
        it.execute_line(l.as_bytes(), &mut |_| {})
            .unwrap_or_else(|e| panic!("{l}: {e}"))
    };
    let err = |it: &mut Interpreter, l: &str| match it.execute_line(l.as_bytes(), &mut |_| {}) {
        Ok(()) => panic!("{l}: accepted"),
        Err(e) => e.kind,
    };
    ok(&mut it, "G0 Z5 F100");
    assert_eq!(
        err(&mut it, "G81 X1 Z-1"),
        ErrorKind::ValueWordMissing(b'R')
    );
    assert_eq!(err(&mut it, "G81 X1 R1"), ErrorKind::ValueWordMissing(b'Z'));
    ok(&mut it, "G81 X1 Z-1 R1");
    ok(&mut it, "X2");
    assert_eq!(err(&mut it, "G82 X3"), ErrorKind::ValueWordMissing(b'R'));
    assert_eq!(
        err(&mut it, "G82 X3 Z-1 R1"),
        ErrorKind::ValueWordMissing(b'P')
    );
    assert_eq!(
        err(&mut it, "G83 X3 Z-1 R1"),
        ErrorKind::ValueWordMissing(b'Q')
    );
    assert_eq!(
        err(&mut it, "G83 X3 Z-1 R1 Q0"),
        ErrorKind::ValueOutOfRange(b'Q')
    );
    assert_eq!(
        err(&mut it, "G81 X3 Z2 R1"),
        ErrorKind::ValueOutOfRange(b'R')
    );
    assert_eq!(err(&mut it, "G81 X3 L0"), ErrorKind::ValueOutOfRange(b'L'));
    assert_eq!(err(&mut it, "G81 X3 L1.5"), ErrorKind::NotInteger(b'L'));
    assert_eq!(err(&mut it, "G81 X3 A1"), ErrorKind::AxisWordsUnused);
    assert_eq!(err(&mut it, "G86 X3 Z-1 R1 P1"), ErrorKind::SpindleStopped);
    assert_eq!(err(&mut it, "G93 G81 X3 F1"), ErrorKind::UndefinedFeed);
    // G80, or any other motion, ends the cycle: axis words then need a motion.
    ok(&mut it, "G80");
    assert_eq!(err(&mut it, "X4"), ErrorKind::AxisWordsUnused);
    ok(&mut it, "G81 X1 Z-1 R1");
    ok(&mut it, "G0 X0");
    assert_eq!(err(&mut it, "G81 X1"), ErrorKind::ValueWordMissing(b'R'));
    // The motion mode stays the cycle and `$G` says so.
    ok(&mut it, "G82 X1 Z-1 R1 P0.1");
    let mut s = String::new();
    it.write_gc_state(&mut s).unwrap();
    assert!(s.starts_with("G82 "), "{s}");
}

#[test]
fn a_deep_peck_cycle_is_one_command_however_many_moves() {
    let mut it = Interpreter::new();
    let mut cmds = Vec::new();
    it.execute_line(b"G0 Z5", &mut |_| {}).unwrap();
    it.execute_line(b"G83 X0 Z-40 R1 Q0.5 F100", &mut |c| cmds.push(c))
        .unwrap();
    let [Command::Cycle(c)] = cmds.as_slice() else {
        panic!("{cmds:?}")
    };
    let n = c.steps(&crate::pad([0.0, 0.0, 5.0, 0.0])).count();
    // 82 pecks of three moves (the last peck feeds to the bottom), the
    // hole move, the move down to R and the retract.
    assert_eq!(n, 3 * 81 + 1 + 1 + 1 + 1, "{n}");
}

const T1: &[(char, [f32; 3])] = &[
    ('R', [0.0, 0.0, 10.0]),
    ('R', [5.0, 5.0, 10.0]),
    ('R', [5.0, 5.0, 2.0]),
    ('F', [5.0, 5.0, 1.0]),
    ('R', [5.0, 5.0, 2.0]),
    ('R', [5.0, 5.0, 1.254]),
    ('F', [5.0, 5.0, 0.0]),
    ('R', [5.0, 5.0, 2.0]),
    ('R', [5.0, 5.0, 0.254]),
    ('F', [5.0, 5.0, -1.0]),
    ('R', [5.0, 5.0, 2.0]),
    ('R', [5.0, 5.0, -0.746]),
    ('F', [5.0, 5.0, -2.0]),
    ('R', [5.0, 5.0, 2.0]),
    ('R', [5.0, 5.0, -1.746]),
    ('F', [5.0, 5.0, -3.0]),
    ('R', [5.0, 5.0, 2.0]),
    ('R', [10.0, 5.0, 2.0]),
    ('F', [10.0, 5.0, 1.0]),
    ('R', [10.0, 5.0, 2.0]),
    ('R', [10.0, 5.0, 1.254]),
    ('F', [10.0, 5.0, 0.0]),
    ('R', [10.0, 5.0, 2.0]),
    ('R', [10.0, 5.0, 0.254]),
    ('F', [10.0, 5.0, -1.0]),
    ('R', [10.0, 5.0, 2.0]),
    ('R', [10.0, 5.0, -0.746]),
    ('F', [10.0, 5.0, -2.0]),
    ('R', [10.0, 5.0, 2.0]),
    ('R', [10.0, 5.0, -1.746]),
    ('F', [10.0, 5.0, -3.0]),
    ('R', [10.0, 5.0, 2.0]),
    ('R', [20.0, 5.0, 2.0]),
    ('R', [20.0, 5.0, 1.0]),
    ('F', [20.0, 5.0, 0.0]),
    ('R', [20.0, 5.0, 0.254]),
    ('F', [20.0, 5.0, -1.0]),
    ('R', [20.0, 5.0, -0.746]),
    ('F', [20.0, 5.0, -2.0]),
    ('R', [20.0, 5.0, -1.746]),
    ('F', [20.0, 5.0, -2.5]),
    ('R', [20.0, 5.0, 10.0]),
    ('R', [25.0, 5.0, 10.0]),
    ('R', [25.0, 5.0, 7.0]),
    ('F', [25.0, 5.0, 5.0]),
    ('R', [25.0, 5.0, 10.0]),
    ('R', [30.0, 5.0, 10.0]),
    ('R', [30.0, 5.0, 7.0]),
    ('F', [30.0, 5.0, 5.0]),
    ('R', [30.0, 5.0, 10.0]),
    ('R', [35.0, 5.0, 10.0]),
    ('R', [35.0, 5.0, 7.0]),
    ('F', [35.0, 5.0, 5.0]),
    ('R', [35.0, 5.0, 10.0]),
    ('R', [0.0, 10.0, 0.0]),
    ('R', [1.0, 10.0, 2.0]),
    ('R', [1.0, 5.0, 2.0]),
    ('F', [1.0, -3.0, 2.0]),
    ('R', [1.0, 10.0, 2.0]),
];
const T3: &[(char, [f32; 3])] = &[
    ('R', [1.0, 10.0, 2.0]),
    ('R', [5.0, 10.0, 2.0]),
    ('R', [5.0, 1.0, 1.0]),
    ('F', [-3.0, 1.0, 1.0]),
    ('R', [5.0, 1.0, 1.0]),
    ('R', [5.0, 1.0, 1.0]),
    ('R', [5.0, 3.0, 1.0]),
    ('F', [-1.0, 3.0, 1.0]),
    ('F', [5.0, 3.0, 1.0]),
    ('R', [5.0, 3.0, 1.0]),
    ('R', [5.0, 4.0, 1.0]),
    ('F', [-1.0, 4.0, 1.0]),
    ('F', [5.0, 4.0, 1.0]),
    ('R', [5.0, 4.0, 1.0]),
    ('R', [5.0, 4.0, 1.0]),
    ('R', [5.0, 5.0, 1.0]),
    ('F', [-1.0, 5.0, 1.0]),
    ('R', [5.0, 5.0, 1.0]),
    ('R', [4.0, 5.0, 1.0]),
    ('R', [4.0, 6.0, 1.0]),
    ('F', [2.5, 6.0, 1.0]),
    ('R', [4.0, 6.0, 1.0]),
    ('R', [2.754, 6.0, 1.0]),
    ('F', [1.0, 6.0, 1.0]),
    ('R', [4.0, 6.0, 1.0]),
    ('R', [1.254, 6.0, 1.0]),
    ('F', [0.0, 6.0, 1.0]),
    ('R', [4.0, 6.0, 1.0]),
    ('R', [4.0, 7.0, 2.0]),
    ('R', [0.0, 7.0, 2.0]),
    ('F', [-0.7, 7.0, 2.0]),
    ('R', [-0.446, 7.0, 2.0]),
    ('F', [-1.4, 7.0, 2.0]),
    ('R', [-1.146, 7.0, 2.0]),
    ('F', [-2.0, 7.0, 2.0]),
    ('R', [0.0, 7.0, 2.0]),
    ('R', [0.0, 8.0, 3.0]),
    ('F', [-0.7, 8.0, 3.0]),
    ('R', [-0.446, 8.0, 3.0]),
    ('F', [-1.4, 8.0, 3.0]),
    ('R', [-1.146, 8.0, 3.0]),
    ('F', [-2.0, 8.0, 3.0]),
    ('R', [0.0, 8.0, 3.0]),
];
const T5: &[(char, [f32; 3])] = &[
    ('R', [0.0, 0.0, 1.0]),
    ('R', [0.0, 0.0, 5.0]),
    ('R', [1.0, 0.0, 5.0]),
    ('F', [1.0, 0.0, -1.0]),
    ('R', [1.0, 0.0, 5.0]),
    ('R', [1.0, 0.0, 4.0]),
    ('R', [2.0, 0.0, 4.0]),
    ('F', [2.0, 0.0, 2.5]),
    ('R', [2.0, 0.0, 4.0]),
    ('R', [2.0, 0.0, 2.754]),
    ('F', [2.0, 0.0, 1.0]),
    ('R', [2.0, 0.0, 4.0]),
    ('R', [2.0, 0.0, 1.254]),
    ('F', [2.0, 0.0, 0.0]),
    ('R', [2.0, 0.0, 4.0]),
    ('R', [1.0, 0.0, 0.0]),
    ('R', [5.0, 0.0, 0.0]),
    ('R', [5.0, 1.0, 0.0]),
    ('F', [-1.0, 1.0, 0.0]),
    ('R', [5.0, 1.0, 0.0]),
    ('R', [4.0, 1.0, 0.0]),
    ('R', [4.0, 2.0, 0.0]),
    ('F', [2.5, 2.0, 0.0]),
    ('R', [4.0, 2.0, 0.0]),
    ('R', [2.754, 2.0, 0.0]),
    ('F', [1.0, 2.0, 0.0]),
    ('R', [4.0, 2.0, 0.0]),
    ('R', [1.254, 2.0, 0.0]),
    ('F', [0.0, 2.0, 0.0]),
    ('R', [4.0, 2.0, 0.0]),
    ('R', [0.0, 1.0, 0.0]),
    ('R', [0.0, 5.0, 0.0]),
    ('R', [1.0, 5.0, 0.0]),
    ('F', [1.0, -1.0, 0.0]),
    ('R', [1.0, 5.0, 0.0]),
    ('R', [1.0, 4.0, 0.0]),
    ('R', [2.0, 4.0, 0.0]),
    ('F', [2.0, 2.5, 0.0]),
    ('R', [2.0, 4.0, 0.0]),
    ('R', [2.0, 2.754, 0.0]),
    ('F', [2.0, 1.0, 0.0]),
    ('R', [2.0, 4.0, 0.0]),
    ('R', [2.0, 1.254, 0.0]),
    ('F', [2.0, 0.0, 0.0]),
    ('R', [2.0, 4.0, 0.0]),
];

/// Issue 30: G99 G82 left the tool at R 1; a G98 G83 with R 2 starts below
/// its R, and rs274 goes to the hole at the level the run began at (10),
/// in one rapid, not at R.
#[test]
fn a_g98_block_below_its_r_goes_to_the_clear_level() {
    same(
        "G21 G17 G90\nG0 X0 Y0 Z10\nG99 G82 X15 Y5 Z-3 R1 P0.5 F300\n\
         G98 G83 X20 Y5 Z-1 R2 Q1.5",
        &[
            ('R', [0.0, 0.0, 10.0]),
            ('R', [15.0, 5.0, 10.0]),
            ('R', [15.0, 5.0, 1.0]),
            ('F', [15.0, 5.0, -3.0]),
            ('R', [15.0, 5.0, 1.0]),
            ('R', [20.0, 5.0, 10.0]),
            ('R', [20.0, 5.0, 2.0]),
            ('F', [20.0, 5.0, 0.5]),
            ('R', [20.0, 5.0, 2.0]),
            ('R', [20.0, 5.0, 0.754]),
            ('F', [20.0, 5.0, -1.0]),
            ('R', [20.0, 5.0, 10.0]),
        ],
    );
}
