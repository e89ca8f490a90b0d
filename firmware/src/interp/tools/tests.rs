//! Tool words against hand-computed offsets (LinuxCNC's rules).

use crate::command::Command;
use crate::gcode::ErrorKind;
use crate::interp::Interpreter;

fn run(it: &mut Interpreter, line: &str) -> Vec<Command> {
    let mut v = Vec::new();
    it.execute_line(line.as_bytes(), &mut |c| v.push(c))
        .unwrap_or_else(|e| panic!("{line}: {e}"));
    v
}

fn err(it: &mut Interpreter, line: &str) -> ErrorKind {
    match it.execute_line(line.as_bytes(), &mut |_| {}) {
        Ok(()) => panic!("{line}: accepted"),
        Err(e) => e.kind,
    }
}

fn end_z(cmds: &[Command]) -> f32 {
    cmds.iter().rev().find_map(|c| c.end()).expect("a move")[2]
}

#[test]
fn g43_h_applies_the_table_length_and_g49_cancels() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L1 P3 Z25.5 R3");
    assert_eq!(end_z(&run(&mut it, "G43 H3 G0 Z0")), 25.5);
    assert_eq!(it.wco()[2], 25.5, "WCO includes the tool offset (GRBL)");
    assert_eq!(end_z(&run(&mut it, "G0 Z-5")), 20.5);
    assert_eq!(end_z(&run(&mut it, "G49 G0 Z-5")), -5.0);
    assert_eq!(it.wco()[2], 0.0);
    // Inch program: table values stay mm, the word is inches.
    assert_eq!(end_z(&run(&mut it, "G20 G43 H3 G0 Z1")), 25.5 + 25.4);
    assert_eq!(it.take_tool_warning(), None);
}

/// LinuxCNC refuses a length it does not know ("requested tool not found
/// in the tool table"); the line leaves no trace. M6 still changes to it
/// (a tool setter may measure it) and says so.
#[test]
fn a_tool_without_an_entry_is_refused_where_its_offset_would_apply() {
    let mut it = Interpreter::new();
    run(&mut it, "G43.1 Z7");
    // cds.ngc's first line: refused whole, G20 included.
    assert_eq!(err(&mut it, "G43 H1 g20"), ErrorKind::ToolNotInTable);
    assert!(!it.state().inch);
    assert_eq!(it.wco()[2], 7.0, "the old offset stays");
    assert_eq!(err(&mut it, "G43.2 H1"), ErrorKind::ToolNotInTable);
    run(&mut it, "T5 M6");
    assert_eq!(it.take_tool_warning(), Some(5));
    it.set_machine_position([0.0; crate::AXES]);
    assert_eq!(err(&mut it, "G43"), ErrorKind::ToolNotInTable);
    run(&mut it, "G10 L1 P5 Z2");
    run(&mut it, "G43");
    assert_eq!(it.wco()[2], 2.0);
}

/// LinuxCNC 2.9: H0 is the tool in the spindle, not "no tool".
#[test]
fn g43_h0_uses_the_tool_in_the_spindle() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L1 P3 Z10");
    run(&mut it, "T3 M6");
    it.set_machine_position([0.0; crate::AXES]);
    run(&mut it, "G43 H0");
    assert_eq!(it.wco()[2], 10.0);
    run(&mut it, "M61 Q0 G43 H0");
    assert_eq!(it.wco()[2], 0.0, "no tool in the spindle: no offset");
}

#[test]
fn g43_without_h_uses_the_tool_in_the_spindle() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L1 P102 Z12");
    let c = run(&mut it, "M6 T102");
    assert!(c.contains(&Command::ToolChange { tool: 102 }), "{c:?}");
    assert!(it.needs_sync(), "the machine moved for the change");
    it.set_machine_position([0.0; crate::AXES]);
    run(&mut it, "G43");
    assert_eq!(it.wco()[2], 12.0);
    run(&mut it, "M61 Q0 G43");
    assert_eq!(it.wco()[2], 0.0);
    assert_eq!(it.state().loaded, 0);
}

#[test]
fn dynamic_and_additional_offsets() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L1 P2 Z10");
    run(&mut it, "G43.1 Z1.5");
    assert_eq!(it.wco()[2], 1.5);
    run(&mut it, "G43.2 H2");
    assert_eq!(it.wco()[2], 11.5);
    run(&mut it, "G43.2 Z-0.5");
    assert_eq!(it.wco()[2], 11.0);
    // G43.1 owns its axis words: no move in the G1 mode.
    let c = run(&mut it, "G1 F100 X1");
    assert_eq!(c.len(), 1);
    assert!(run(&mut it, "G43.1 Z2").is_empty());
    // A bare G43.1 changes nothing (LinuxCNC accepts it).
    run(&mut it, "G43.1");
    assert_eq!(it.wco()[2], 2.0);
    assert_eq!(err(&mut it, "G43.1 G0 Z1"), ErrorKind::AxisCommandConflict);
    assert_eq!(err(&mut it, "G43.2"), ErrorKind::ValueWordMissing(b'H'));
    assert_eq!(err(&mut it, "G49 H1"), ErrorKind::UnusedWord(b'H'));
}

#[test]
fn g10_l10_and_l11_compute_the_length_from_the_current_point() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L2 P1 Z-40");
    run(&mut it, "G10 L2 P9 Z-30");
    run(&mut it, "G0 G53 Z-10");
    // L10: with G54 (Z-40) active, work Z would be 30; make it 5 => 25.
    run(&mut it, "G10 L10 P4 Z5");
    run(&mut it, "G43 H4");
    let mut s = String::new();
    it.write_offsets(&mut s, "\n", 3).unwrap();
    assert!(
        s.contains("[TLO:25.000]\n[T:4|0.000,0.000,25.000|0.000]\n"),
        "{s}"
    );
    // L11: as if in G59.3 (Z-30) without G92: 20 - 5 = 15.
    run(&mut it, "G10 L11 P4 Z5 R1");
    let t = crate::interp::tools::find(&it.offsets().tools, 4).copied();
    assert_eq!(t.map(|e| (e.length(), e.diameter)), Some((15.0, 2.0)));
    assert!(it.take_offsets_changed(), "the table persists like G10 L2");
}

#[test]
fn the_table_has_sixty_four_entries_keyed_by_number() {
    let mut it = Interpreter::new();
    for n in 0..64 {
        run(&mut it, &format!("G10 L1 P{} Z{}", 100 + n, n));
    }
    assert_eq!(
        err(&mut it, "G10 L1 P999 Z1"),
        ErrorKind::ValueOutOfRange(b'P')
    );
    // Rewriting an existing number takes no new entry.
    run(&mut it, "G10 L1 P105 Z50");
    let e = crate::interp::tools::find(&it.offsets().tools, 105).copied();
    assert_eq!(e.map(|e| e.length()), Some(50.0));
    assert_eq!(
        err(&mut it, "G10 L1 P0 Z1"),
        ErrorKind::ValueOutOfRange(b'P')
    );
}

/// Tool numbers up to 2^31 - 1, LinuxCNC's limit, each exact: a word's
/// f32 holds integers below 2^24 only, so 16777217 and 16777216 (the same
/// f32) are told apart from their digits; from an expression such a number
/// is refused rather than rounded onto a neighbour, as is 2^31.
#[test]
fn large_tool_numbers() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L1 P10000000 Z1");
    run(&mut it, "G10 L1 P16777215 Z2");
    run(&mut it, "G43 H16777215");
    assert_eq!(it.wco()[2], 2.0);
    run(&mut it, "G43 H10000000");
    assert_eq!(it.wco()[2], 1.0);
    run(&mut it, "G10 L1 P16777217 Z3");
    run(&mut it, "G10 L1 P 1677 7216.000 Z4");
    run(&mut it, "G10 L1 P2147483647 Z5");
    run(&mut it, "G43 H16777217");
    assert_eq!(it.wco()[2], 3.0);
    run(&mut it, "G43 H16777216");
    assert_eq!(it.wco()[2], 4.0);
    run(&mut it, "G43 H+2147483647");
    assert_eq!(it.wco()[2], 5.0);
    run(&mut it, "T2147483647 M6");
    assert_eq!(it.state().tool, 2147483647);
    run(&mut it, "M61 Q16777217");
    assert_eq!(it.state().tool, 16777217);
    assert_eq!(
        err(&mut it, "G10 L1 P2147483648 Z1"),
        ErrorKind::ValueOutOfRange(b'P')
    );
    assert_eq!(
        err(&mut it, "G43 H[16777216 + 1]"),
        ErrorKind::ValueOutOfRange(b'H')
    );
    assert_eq!(err(&mut it, "T16777217.5"), ErrorKind::NotInteger(b'T'));
}

/// G10 L1 writes every axis the table holds, R as the radius (stored as
/// the diameter, negative too, as LinuxCNC), and needs a value.
#[test]
fn g10_l1_every_axis_and_radius() {
    let mut it = Interpreter::new();
    assert_eq!(err(&mut it, "G10 L1 P3"), ErrorKind::NoToolValues);
    run(&mut it, "G10 L1 P3 Z1 R-1");
    let e = crate::interp::tools::find(&it.offsets().tools, 3).copied();
    assert_eq!(e.map(|e| (e.length(), e.diameter)), Some((1.0, -2.0)));
    run(&mut it, "G20 G10 L1 P5 X1 Y2 Z3 R0.5");
    let e = crate::interp::tools::find(&it.offsets().tools, 5).copied();
    assert_eq!(
        e.map(|e| (e.offset, e.diameter)),
        Some(([25.4, 50.8, 76.2], 25.4))
    );
    run(&mut it, "G21 G43 H5");
    assert_eq!(it.wco(), crate::pad([25.4, 50.8, 76.2, 0.0]));
    // The table holds no rotary offset.
    assert_eq!(err(&mut it, "G10 L1 P5 Z1 A1"), ErrorKind::AxisWordsUnused);
}

#[test]
fn tool_parameters_and_g92_with_an_offset() {
    let mut it = Interpreter::new();
    run(&mut it, "G10 L1 P7 Z3 R2");
    run(&mut it, "M61 Q7 G43");
    run(&mut it, "#1=#5400 #2=#5403 #3=#5410");
    let p = |it: &Interpreter, n| it.params().get_num(n);
    assert_eq!((p(&it, 1), p(&it, 2), p(&it, 3)), (7.0, 3.0, 4.0));
    assert_eq!(err(&mut it, "#5400=1"), ErrorKind::ParamReadOnly);
    // G92 Z0 with the offset on: work Z is 0 here, and stays so after G49 G43.
    run(&mut it, "G0 Z10");
    run(&mut it, "G92 Z0");
    assert_eq!(it.state().pos[2] - it.wco()[2], 0.0);
    // The offset and tool survive a soft reset (they describe the machine).
    it.reset();
    assert_eq!(it.wco()[2], it.state().g92[2] + 3.0);
    assert_eq!(it.state().loaded, 7);
}
