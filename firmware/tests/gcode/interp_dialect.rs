//! Issue 14 part A: the rules where LinuxCNC and BeagleG agree, `$210`,
//! and BeagleG's M list, one behaviour per test.

use burin::command::{Command, Feed};
use burin::interp::Interpreter;

fn run(it: &mut Interpreter, line: &str) -> Vec<Command> {
    let mut v = Vec::new();
    it.execute_line(line.as_bytes(), &mut |c| v.push(c))
        .unwrap_or_else(|e| panic!("{line}: {e}"));
    v
}

fn code(it: &mut Interpreter, line: &str) -> u16 {
    match it.execute_line(line.as_bytes(), &mut |_| {}) {
        Err(e) => e.code(),
        Ok(()) => panic!("{line}: accepted"),
    }
}

fn ends(cmds: &[Command]) -> Vec<[f32; burin::AXES]> {
    cmds.iter().filter_map(|c| c.end().copied()).collect()
}

fn near(a: [f32; burin::AXES], b: [f32; burin::AXES]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-3)
}

#[test]
fn several_commands_read_left_to_right() {
    let mut it = Interpreter::new();
    let c = run(&mut it, "G1 X10 F100 G20 G91 G1 X1");
    assert_eq!(c.len(), 2, "{c:?}");
    assert!(
        near(ends(&c)[0], burin::pad([10.0, 0.0, 0.0, 0.0])),
        "{c:?}"
    );
    assert!(
        near(ends(&c)[1], burin::pad([35.4, 0.0, 0.0, 0.0])),
        "{c:?}"
    );
    // F100 was read in mm before G20: the inch move keeps 100 mm/min.
    assert!(
        matches!(c[1], Command::Line { feed: Feed::PerMin(f), .. } if (f - 100.0).abs() < 1e-3)
    );

    let mut it = Interpreter::new();
    let c = run(&mut it, "G0 X10 G91 G0 X5");
    assert_eq!(
        ends(&c),
        vec![
            burin::pad([10.0, 0.0, 0.0, 0.0]),
            burin::pad([15.0, 0.0, 0.0, 0.0])
        ]
    );
    assert!(it.state().incremental);
}

#[test]
fn a_mode_word_after_the_last_command_is_ambiguous() {
    let mut it = Interpreter::new();
    assert_eq!(code(&mut it, "G1 X10 F100 G91"), 340);
    assert_eq!(code(&mut it, "G0 X1 G0 X2 G21 F50"), 340);
    // Refused as a whole: nothing moved, no mode changed.
    assert_eq!(it.state().pos, [0.0; burin::AXES]);
    assert!(!it.state().incremental);
    // A mode word before its command is fine, as is F with its command.
    let c = run(&mut it, "G91 G0 X1 G90 G0 X5 F10");
    assert_eq!(
        ends(&c),
        vec![
            burin::pad([1.0, 0.0, 0.0, 0.0]),
            burin::pad([5.0, 0.0, 0.0, 0.0])
        ]
    );
}

#[test]
fn beagleg_g28_then_a_move_on_one_line() {
    let mut it = Interpreter::new();
    it.set_g28_homes(true);
    let c = run(&mut it, "G28 G1 X100 F100");
    assert!(
        matches!(
            c[0],
            Command::Home {
                axes: burin::command::ALL_AXES
            }
        ),
        "{c:?}"
    );
    assert!(
        matches!(c[1], Command::Line { end, .. } if end == burin::pad([100.0, 0.0, 0.0, 0.0])),
        "{c:?}"
    );
}

#[test]
fn g28_default_is_rs274_stored_position() {
    let mut it = Interpreter::new();
    run(&mut it, "G0 X10 Y20 Z-5");
    run(&mut it, "G28.1");
    run(&mut it, "G0 X50 Y60 Z-30");
    // Fusion 360's GRBL post: Z up to the stored Z, X/Y untouched.
    let c = run(&mut it, "G28 G91 Z0");
    assert_eq!(
        ends(&c),
        vec![
            burin::pad([50.0, 60.0, -30.0, 0.0]),
            burin::pad([50.0, 60.0, -5.0, 0.0])
        ]
    );
    let c = run(&mut it, "G28 G91 X0 Y0");
    assert_eq!(ends(&c)[1], burin::pad([10.0, 20.0, -5.0, 0.0]));
    assert!(!it.needs_sync(), "no homing, nothing to wait for");
    // Through an absolute intermediate point; without axes, all axes.
    run(&mut it, "G90 G0 X0 Y0 Z0");
    let c = run(&mut it, "G28 Z-2");
    assert_eq!(
        ends(&c),
        vec![
            burin::pad([0.0, 0.0, -2.0, 0.0]),
            burin::pad([0.0, 0.0, -5.0, 0.0])
        ]
    );
    let c = run(&mut it, "G28");
    assert_eq!(ends(&c)[1], burin::pad([10.0, 20.0, -5.0, 0.0]));
    // G30 likewise, with its own position.
    run(&mut it, "G0 X1 Y2 Z3");
    run(&mut it, "G30.1");
    run(&mut it, "G0 X0 Y0 Z0");
    let c = run(&mut it, "G30 X5");
    assert_eq!(
        ends(&c),
        vec![
            burin::pad([5.0, 0.0, 0.0, 0.0]),
            burin::pad([1.0, 0.0, 0.0, 0.0])
        ]
    );
    // A bare axis letter would be a silent 0 here: refused.
    assert_eq!(code(&mut it, "G28 X"), 102);
}

#[test]
fn g28_beagleg_homes_and_g30_probes() {
    let mut it = Interpreter::new();
    it.set_g28_homes(true);
    let c = run(&mut it, "G28 X Y");
    assert!(matches!(c[0], Command::Home { axes: 0b11 }), "{c:?}");
    it.set_machine_position([0.0; burin::AXES]);
    run(&mut it, "F100");
    let c = run(&mut it, "G30 Z1.5");
    assert!(matches!(c[0], Command::Probe { .. }), "{c:?}");
}

#[test]
fn g10_l20_ignores_g91_but_l2_adds() {
    let mut it = Interpreter::new();
    run(&mut it, "G0 X1 Y1 Z1");
    run(&mut it, "G91 G10 L20 P1 X5");
    assert_eq!(it.offsets().wcs[0][0], -4.0);
    run(&mut it, "G91 G10 L2 P1 X1");
    assert_eq!(it.offsets().wcs[0][0], -3.0);
}

#[test]
fn linuxcnc_refusals() {
    let mut it = Interpreter::new();
    assert_eq!(code(&mut it, "M7 M8"), 310);
    assert_eq!(code(&mut it, "G19 G2 Y1 Z1 I1 J1 F10"), 342);
    assert_eq!(code(&mut it, "G18 G2 X1 Z1 J1 I1 F10"), 342);
    assert_eq!(code(&mut it, "G2 X1 Y1 K1 I1 F10"), 342);
    assert_eq!(code(&mut it, "G53"), 318);
    run(&mut it, "G53 G0 X1");
    run(&mut it, "G53 X2");
}

#[test]
fn nothing_after_the_closing_percent_runs() {
    let mut it = Interpreter::new();
    run(&mut it, "%");
    assert_eq!(run(&mut it, "G0 X1").len(), 1);
    run(&mut it, "%");
    assert!(run(&mut it, "G0 X100").is_empty());
    assert!(run(&mut it, "M3 S100").is_empty());
    // The next job's opening % starts reading again.
    run(&mut it, "%");
    assert_eq!(run(&mut it, "G0 X2").len(), 1);
    // A program ended by M2 before its closing % does not swallow the next job.
    run(&mut it, "M2");
    run(&mut it, "%");
    assert_eq!(run(&mut it, "G0 X3").len(), 1);
    // A reset clears it too.
    run(&mut it, "%");
    run(&mut it, "%");
    it.reset();
    assert_eq!(run(&mut it, "G0 X4").len(), 1);
}

#[test]
fn m2_resets_what_rs274ngc_lists() {
    let mut it = Interpreter::new();
    run(
        &mut it,
        "G20 G91 G18 G55 G93 M3 S100 M8 G92 X1 G2 X1 Z1 I1 F1",
    );
    run(&mut it, "M2");
    let mut s = String::new();
    it.write_gc_state(&mut s).unwrap();
    // Units stay (G20); motion G1, G54, G17, G90, G94, M5, M9.
    assert_eq!(s, "G1 G54 G17 G20 G90 G94 M5 M9 T0 F0 S100");
    assert_eq!(it.wco(), [0.0; burin::AXES], "G92 suspended");
}

#[test]
fn beagleg_m_list() {
    let mut it = Interpreter::new();
    let msg = |c: &[Command]| match c {
        [Command::Message(m)] => m.to_string(),
        other => panic!("{other:?}"),
    };
    assert_eq!(msg(&run(&mut it, "M10")), "M10: vacuum not fitted");
    assert_eq!(
        msg(&run(&mut it, "M81")),
        "M81: power supply control not fitted"
    );
    assert_eq!(msg(&run(&mut it, "M245")), "M245: cooler not fitted");
    assert_eq!(msg(&run(&mut it, "M355 S1")), "M355: case light not fitted");
    assert_eq!(
        msg(&run(&mut it, "M42 P3")),
        "M42 P3: aux output not fitted"
    );
    assert_eq!(
        run(&mut it, "M24"),
        vec![Command::Pause { optional: false }]
    );
    for quiet in ["M82", "M83", "M111 S3", "M120"] {
        assert!(run(&mut it, quiet).is_empty(), "{quiet}");
    }
    assert!(msg(&run(&mut it, "M121")).contains("stays enabled"));
    // S of M111/M355 is theirs, not the spindle's.
    assert_eq!(it.state().speed, 0.0);
    for heater in ["M104 S200", "M105", "M109 S200", "M116"] {
        assert_eq!(code(&mut it, heater), 341, "{heater}");
    }
}

#[test]
fn a_bare_parameter_prints_its_value() {
    let mut it = Interpreter::new();
    run(&mut it, "#1=12.5");
    let c = run(&mut it, "#1");
    assert!(
        matches!(&c[..], [Command::Message(m)] if m == "#1=12.5"),
        "{c:?}"
    );
    run(&mut it, "#<depth>=-3");
    let c = run(&mut it, "#<depth>");
    assert!(
        matches!(&c[..], [Command::Message(m)] if m == "#<depth>=-3"),
        "{c:?}"
    );
}

#[test]
fn arc_tolerance_is_linuxcnc_29() {
    let mut it = Interpreter::new();
    run(&mut it, "G21 F100");
    // 0.02 mm on r=10 and 0.9 mm on r=1000 pass.
    run(&mut it, "G0 X0 Y0");
    run(&mut it, "G2 X20 Y0 I10.01");
    run(&mut it, "G0 X0 Y0");
    run(&mut it, "G2 X2000 Y0 I1000.45");
    run(&mut it, "G0 X0 Y0");
    assert_eq!(code(&mut it, "G2 X20 Y0 I10.02"), 321); // 0.04 mm, 0.2 %
                                                        // R short of half the chord by 0.0005 mm: the semicircle; 0.002 mm: an error.
    let c = run(&mut it, "G2 X10 Y0 R4.9995");
    assert!(matches!(&c[..], [Command::Arc(a)] if (a.center[0] - 5.0).abs() < 1e-4));
    assert_eq!(code(&mut it, "G2 X0 Y0 R4.998"), 321);
}
