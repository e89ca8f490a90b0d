use super::*;
use crate::command::Command;
use crate::gcode::OWord;

/// Runs `src` line by line; returns the X of every move's end with the
/// source line it came from, and each failed line with its code.
/// (source line, X) per move; (source line, code) per error.
type Ran = (Vec<(u32, f32)>, Vec<(u32, u16)>);

fn run(src: &str) -> Ran {
    let mut flow = Flow::new();
    let mut interp = Interpreter::new();
    let mut moves = Vec::new();
    let mut errs = Vec::new();
    for (i, line) in src.lines().enumerate() {
        let n = i as u32 + 1;
        let r = flow.feed_line(
            line.as_bytes(),
            n,
            &mut interp,
            100_000,
            &mut |it, t, ln| {
                it.execute_line(t, &mut |c| {
                    if let Some(e) = c.end() {
                        moves.push((ln, e[0]));
                    }
                    let _ = matches!(c, Command::ProgramEnd);
                })
            },
        );
        if let Err((ln, e)) = r {
            errs.push((ln, e.code()));
        }
    }
    (moves, errs)
}

fn xs(m: &[(u32, f32)]) -> Vec<f32> {
    m.iter().map(|p| p.1).collect()
}

#[test]
fn untaken_if_never_runs() {
    let (m, e) = run("O1 if [0]\nG0 X5\nO1 endif\nG0 X1");
    assert_eq!(e, vec![]);
    assert_eq!(xs(&m), vec![1.0]);
}

#[test]
fn if_elseif_else_take_one_branch() {
    let prog = |v: u8| {
        format!(
            "#1={v}\nO<b> if [#1 EQ 1]\nG0 X1\nO<b> elseif [#1 EQ 2]\nG0 X2\nO<b> else\nG0 X3\nO<b> endif"
        )
    };
    for (v, x) in [(1, 1.0), (2, 2.0), (7, 3.0)] {
        let (m, e) = run(&prog(v));
        assert_eq!((xs(&m), e), (vec![x], vec![]), "#1={v}");
    }
}

#[test]
fn while_runs_every_pass_with_source_lines() {
    let (m, e) = run("#1=0\nG91\nO1 while [#1 LT 3]\nG0 X1\n#1=[#1+1]\nO1 endwhile\nG90 G0 X0");
    assert_eq!(e, vec![]);
    assert_eq!(xs(&m), vec![1.0, 2.0, 3.0, 0.0]);
    // Each pass's move reports the line it was written on.
    assert_eq!(m.iter().map(|p| p.0).collect::<Vec<_>>(), vec![4, 4, 4, 7]);
}

#[test]
fn do_repeat_break_continue() {
    let (m, e) = run("G91\n#1=0\nO2 do\nG0 X1\n#1=[#1+1]\nO2 while [#1 LT 2]");
    assert_eq!((xs(&m), e), (vec![1.0, 2.0], vec![]));
    let (m, e) = run("G91\nO3 repeat [4]\nG0 X1\nO3 endrepeat");
    assert_eq!((xs(&m), e), (vec![1.0, 2.0, 3.0, 4.0], vec![]));
    // break leaves at pass 3; continue skips the Y... here: X2 on odd passes.
    let src = "G91\n#1=0\nO4 while [1]\n#1=[#1+1]\nO5 if [#1 GT 3]\nO4 break\nO5 endif\nO6 if [#1 EQ 2]\nO4 continue\nO6 endif\nG0 X1\nO4 endwhile\nG0 X10";
    let (m, e) = run(src);
    assert_eq!((xs(&m), e), (vec![1.0, 2.0, 12.0], vec![]));
}

#[test]
fn sub_call_locals_and_return_value() {
    let src = "O<sq> sub\n#<t>=[#1*#1]\nG0 X#<t>\nO<sq> return [#<t>+1]\nG0 X99\nO<sq> endsub\n#1=7\n#<t>=5\nO<sq> call [3]\nG0 X[#<_value>] Y#1 Z#<t>";
    let mut flow = Flow::new();
    let mut interp = Interpreter::new();
    let mut ends = Vec::new();
    for (i, line) in src.lines().enumerate() {
        flow.feed_line(
            line.as_bytes(),
            i as u32 + 1,
            &mut interp,
            1000,
            &mut |it, t, _| it.execute_line(t, &mut |c| ends.extend(c.end().copied())),
        )
        .expect("line runs");
    }
    // The body did not run where it was defined; the call squared 3,
    // returned 10; the caller's #1 and #<t> are back.
    assert_eq!(ends.len(), 2);
    assert_eq!(ends[0][0], 9.0);
    assert_eq!(&ends[1][..3], &[10.0, 7.0, 5.0]);
    assert!(flow.idle());
}

#[test]
fn recursion_keeps_each_levels_locals() {
    // Counts down; each level moves after its inner call returns, so the
    // moves come innermost first: X0, X1, X2, X3.
    let src = "O9 sub\n#<l>=#1\nO8 if [#<l> GT 0]\nO9 call [#<l>-1]\nO8 endif\nG0 X#<l>\nO9 endsub\nO9 call [3]";
    let (m, e) = run(src);
    assert_eq!((xs(&m), e), (vec![0.0, 1.0, 2.0, 3.0], vec![]));
}

#[test]
fn block_too_large_is_refused_before_any_line_runs() {
    let mut src = String::from("G91\nO1 repeat [2]\n");
    let body = 80;
    for _ in 0..body {
        src.push_str("G0 X1 (a move that fills the buffer)  Y0.000000 Z0.000000\n");
    }
    src.push_str("O1 endrepeat\nG0 X100");
    let (m, e) = run(&src);
    assert_eq!(xs(&m), vec![100.0], "only the line after the block ran");
    let code = |k| crate::gcode::ErrorKind::OWord(k).code();
    assert_eq!(e.first().map(|x| x.1), Some(code(OWord::TooLarge)));
    assert!(e.iter().skip(1).all(|x| x.1 == code(OWord::InRefusedBlock)));
    assert_eq!(
        e.last().map(|x| x.0),
        Some(body as u32 + 3),
        "its closer is refused too"
    );
}

#[test]
fn errors_are_typed_and_name_the_source_line() {
    let code = |k| crate::gcode::ErrorKind::OWord(k).code();
    let (_, e) = run("O1 endif");
    assert_eq!(e, vec![(1, code(OWord::Unmatched))]);
    let (_, e) = run("O7 call");
    assert_eq!(e, vec![(1, code(OWord::UndefinedSub))]);
    let (_, e) = run("O1 break");
    assert_eq!(e, vec![(1, code(OWord::Outside))]);
    let (_, e) = run("O1 iff [1]");
    assert_eq!(e, vec![(1, code(OWord::Syntax))]);
    // A bad condition refuses the whole if: its lines never run.
    let (m, e) = run("O1 if [#<nope>]\nG0 X5\nO1 endif\nG0 X1");
    assert_eq!(xs(&m), vec![1.0]);
    assert_eq!(e.len(), 3);
    // An error inside a replay names the stored line.
    let (m, e) = run("G91\nO2 repeat [3]\nG0 X1\nG0 X[1/0]\nO2 endrepeat");
    assert_eq!(xs(&m), vec![1.0]);
    assert_eq!(e, vec![(4, 201)]);
    // Endless recursion stops at the call depth.
    let (_, e) = run("O3 sub\nO3 call\nO3 endsub\nO3 call");
    assert_eq!(e, vec![(2, code(OWord::TooDeep))]);
}

#[test]
fn subs_make_room_for_new_ones_and_redefine() {
    let mut src = String::new();
    for k in 0..40 {
        src.push_str(&format!("O{k} sub\nG0 X{k} Y1.000000 Z2.000000 (pad pad pad)\nG0 X{k} Y3.000000 Z4.000000\nO{k} endsub\nO{k} call\n"));
    }
    src.push_str("O1 sub\nG0 X-1\nO1 endsub\nO1 call\n");
    let (m, e) = run(&src);
    assert_eq!(e, vec![]);
    assert_eq!(m.len(), 81);
    assert_eq!(m.last().map(|p| p.1), Some(-1.0));
}

#[test]
fn reset_restores_the_callers_locals_and_forgets() {
    let mut flow = Flow::new();
    let mut interp = Interpreter::new();
    let mut out = [0u8; crate::gcode::MAX_LINE];
    let go =
        |flow: &mut Flow, interp: &mut Interpreter, l: &str| flow.intake(l.as_bytes(), 1, interp);
    interp.execute_line(b"#1=4", &mut |_| {}).expect("set");
    assert_eq!(go(&mut flow, &mut interp, "O1 sub"), Intake::Reply(Ok(())));
    assert_eq!(go(&mut flow, &mut interp, "G0 X#1"), Intake::Reply(Ok(())));
    assert_eq!(
        go(&mut flow, &mut interp, "O1 endsub"),
        Intake::Reply(Ok(()))
    );
    assert_eq!(go(&mut flow, &mut interp, "O1 call [9]"), Intake::Replay);
    assert!(matches!(flow.step(&mut interp, &mut out), Step::Run { .. }));
    assert_eq!(interp.params().get_num(1), 9.0);
    flow.reset(&mut interp);
    assert_eq!(interp.params().get_num(1), 4.0);
    assert!(flow.idle() && flow.used() == 0);
    assert_eq!(
        go(&mut flow, &mut interp, "O1 call"),
        Intake::Reply(Err(err(OWord::UndefinedSub)))
    );
}

#[test]
fn compact_keeps_meaning() {
    let mut d = [0u8; 256];
    let n = oline::compact(b"  G1  X1 (cut)  Y2 ; tail", &mut d);
    assert_eq!(&d[..n], b"G1 X1 Y2");
    let n = oline::compact(b"G4 P1 (MSG, hello  world)", &mut d);
    assert_eq!(&d[..n], b"G4 P1 (MSG, hello  world)");
    let n = oline::compact(b"M117 two  spaces ", &mut d);
    assert_eq!(&d[..n], b"M117 two  spaces");
}

/// Random mixes of O-word and motion lines: never a panic, every replay
/// ends (the step cap), and the stage is idle after a reset.
#[test]
fn random_programs_never_panic() {
    const POOL: [&str; 24] = [
        "O1 if [#1 GT 1]",
        "O1 elseif [#1 LT 0]",
        "O1 else",
        "O1 endif",
        "O2 while [#1 LT 3]",
        "O2 endwhile",
        "O3 do",
        "O3 while [#1 LT 2]",
        "O4 repeat [2]",
        "O4 endrepeat",
        "O2 break",
        "O3 continue",
        "O5 sub",
        "O5 endsub [#1]",
        "O5 return",
        "O5 call [#1+1] [2]",
        "O6 call",
        "#1=[#1+1]",
        "G0 X#1",
        "G1 X[1/0]",
        "O<n> sub",
        "O<n> endsub",
        "O<n> call",
        "O7 bogus",
    ];
    let mut seed = 0x2545_f491_u32;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed
    };
    for _ in 0..3000 {
        let len = 5 + next() % 30;
        let src: Vec<&str> = (0..len).map(|_| POOL[(next() % 24) as usize]).collect();
        let mut flow = Flow::new();
        let mut interp = Interpreter::new();
        for (i, l) in src.iter().enumerate() {
            let _ = flow.feed_line(
                l.as_bytes(),
                i as u32,
                &mut interp,
                10_000,
                &mut |it, t, _| it.execute_line(t, &mut |_| {}),
            );
            assert!(!flow.replaying(), "{src:?}");
        }
        flow.reset(&mut interp);
        assert!(flow.idle() && flow.used() == 0, "{src:?}");
    }
}

#[test]
fn nothing_after_a_closing_percent_runs() {
    // Not even an O-word line's error: the stage leaves them all to the
    // interpreter, which skips them.
    let (m, e) = run("%\nG0 X1\n%\nO9 endif\nO1 sub\nG0 X5\nO1 endsub\nO1 call\nO2 if [1]\nG0 X6");
    assert_eq!((xs(&m), e), (vec![1.0], vec![]));
}
