//! The interpreter's contract with the motion and link layers.

use burin::command::Command;
use burin::interp::Interpreter;

fn run(it: &mut Interpreter, line: &str) -> Vec<Command> {
    let mut v = Vec::new();
    it.execute_line(line.as_bytes(), &mut |c| v.push(c))
        .unwrap_or_else(|e| panic!("{line}: {e}"));
    v
}

#[test]
fn size_is_bounded() {
    let n = core::mem::size_of::<Interpreter>();
    println!("size_of::<Interpreter>() = {n} bytes");
    // 4136 B: the 64-tool table (1.3 KB, issue 30) and cutter
    // compensation's queue (376 B, issue 33) since the 4 KiB bound; the
    // image's RAM budget (`cargo xtask build`) is the board's real limit.
    assert!(
        n <= 4608,
        "Interpreter grew to {n} bytes (the F401's statics budget is 44 KiB)"
    );
}

#[test]
fn gc_state_report() {
    let mut it = Interpreter::new();
    let mut s = String::new();
    it.write_gc_state(&mut s).unwrap();
    assert_eq!(s, "G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0");
    // M7 and M8 are one modal group: two lines (LinuxCNC), both stay on.
    run(&mut it, "G20 G91 G18 G59.2 M4 S300 M7 T2 F10 G1");
    run(&mut it, "M8");
    s.clear();
    it.write_gc_state(&mut s).unwrap();
    assert_eq!(s, "G1 G59.2 G18 G20 G91 G94 M4 M7 M8 T2 F10 S300");
}

#[test]
fn offsets_report_and_wco() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L2 P2 X1 Y2 Z3");
    run(&mut it, "G55 G92 X0");
    assert_eq!(it.wco(), burin::pad([0.0, 2.0, 3.0, 0.0]));
    let mut s = String::new();
    it.write_offsets(&mut s, "\n", 4).unwrap();
    assert!(
        s.starts_with("[G54:0.000,0.000,0.000,0.000]\n[G55:1.000,2.000,3.000,0.000]\n"),
        "{s}"
    );
    assert!(s.contains("[G59.3:0.000,0.000,0.000,0.000]\n"));
    assert!(s.contains("[G92:-1.000,0.000,0.000,0.000]\n"));
    assert!(s.ends_with("[TLO:0.000]\n[PRB:0.000,0.000,0.000,0.000:0]\n"));
}

/// The offset tables are backed up lazily (on a line's first write), so a
/// line that writes them and then fails must still leave them untouched.
#[test]
fn failing_line_restores_offsets_it_wrote() {
    let mut it = Interpreter::new();
    run(&mut it, "G21 G90 F100 G10 L2 P1 X1 Y1 Z1");
    assert!(it.take_offsets_changed());
    let before = it.offsets();
    for line in [
        // G10 runs as the first command of the line, the second one fails.
        "G10 L2 P1 X5 G0 X1 Q1",
        "G10 L20 P2 X7 G1 X[1/0]",
        // Parameter writes to the tables, then a bad word.
        "#5221=9 #5161=3 G0 X1 E1",
        // G28.1 stores, the block's motion then fails.
        "G28.1 G0 X1 Q2",
    ] {
        let mut n = 0;
        let r = it.execute_line(line.as_bytes(), &mut |_| n += 1);
        assert!(r.is_err(), "{line} should fail");
        assert_eq!(n, 0, "{line} emitted commands");
        assert_eq!(it.offsets(), before, "{line} changed the offsets");
        assert!(!it.take_offsets_changed(), "{line} flagged a save");
    }
    // The same writes on good lines do land.
    run(&mut it, "G10 L2 P1 X5");
    assert_eq!(it.offsets().wcs[0], burin::pad([5.0, 1.0, 1.0, 0.0]));
    run(&mut it, "#5161=3");
    assert_eq!(it.offsets().g28[0], 3.0);
}

#[test]
fn machine_position_feedback() {
    let mut it = Interpreter::new();
    it.set_g28_homes(true);
    run(&mut it, "G28");
    assert!(it.needs_sync());
    it.set_machine_position(burin::pad([-5.0, -6.0, -1.0, 0.0]));
    assert!(!it.needs_sync());
    let c = run(&mut it, "G91 G0 X1");
    assert_eq!(
        c,
        vec![Command::Rapid {
            end: burin::pad([-4.0, -6.0, -1.0, 0.0])
        }]
    );
}

#[test]
fn parameter_table_full_is_an_error() {
    let mut it = Interpreter::new();
    let mut n = 1;
    let err = loop {
        match it.execute_line(format!("#{n}=1").as_bytes(), &mut |_| {}) {
            Ok(()) => n += 1,
            Err(e) => break e,
        }
        assert!(n < 1000);
    };
    assert_eq!(err.code(), 208);
    assert_eq!(n, burin::gcode::params::NUMBERED_CAP as u32 + 1);
}

#[test]
fn grbl_codes() {
    let mut it = Interpreter::new();
    let grbl = |it: &mut Interpreter, l: &str| {
        it.execute_line(l.as_bytes(), &mut |_| {})
            .unwrap_err()
            .grbl_code()
    };
    assert_eq!(grbl(&mut it, "G1 X1"), 22);
    assert_eq!(grbl(&mut it, "G0 G1 X1"), 21);
    assert_eq!(grbl(&mut it, "G33 X1 K1"), 20);
    assert_eq!(grbl(&mut it, "G0 X1 X2"), 25);
    assert_eq!(grbl(&mut it, "G0 I1 X1"), 36);
    assert_eq!(grbl(&mut it, "G2 X1 F1"), 35);
    assert_eq!(grbl(&mut it, &format!("G0 X1 ({})", "x".repeat(300))), 11);
}
