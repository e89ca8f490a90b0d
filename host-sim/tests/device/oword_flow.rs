//! O-word flow control through the device session (issue 30): lines in a
//! branch not taken never run, loops and calls replay from the capture
//! buffer with their source lines in `Ln:`, a block too large for the
//! buffer is refused before any of it runs, a reset clears it all.

use host_sim::record::Discard;
use protocol::client::grbl::{classify, TextEvent};

use crate::rig;

use rig::{origin, Rig};

fn x(r: &mut Rig) -> f32 {
    let st = r.until_idle();
    st.mpos.map_or(f32::NAN, |p| p[0])
}

fn is_err(reply: &[String]) -> bool {
    reply
        .last()
        .is_some_and(|l| matches!(classify(l), TextEvent::Error(_)))
}

#[test]
fn lines_in_an_untaken_branch_never_run() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    // The position first: before issue 30 the O-lines were refused
    // (error 302) and the line between them moved to X5.
    let replies: Vec<_> = ["O1 if [0]", "G0 X5", "O1 endif"]
        .iter()
        .map(|l| r.cmd(l))
        .collect();
    assert_eq!(
        x(&mut r),
        0.0,
        "the line inside `if [0]` moved: {replies:?}"
    );
    assert!(replies.iter().all(|x| x == &["ok"]), "{replies:?}");
    for l in [
        "#2=3",
        "O2 if [#2 EQ 1]",
        "G0 X1",
        "O2 elseif [#2 EQ 3]",
        "G0 X3",
        "O2 else",
        "G0 X9",
        "O2 endif",
    ] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    assert_eq!(x(&mut r), 3.0);
}

#[test]
fn a_dollar_command_in_an_untaken_branch_or_a_loop_never_runs() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    for l in ["O1 if [0]", "$J=G91 X5 F1000", "O1 endif"] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    assert_eq!(x(&mut r), 0.0, "a jog in `if [0]` moved");
    assert_eq!(r.cmd("O2 repeat [2]"), ["ok"]);
    assert!(
        is_err(&r.cmd("$J=G91 X5 F1000")),
        "a jog is refused in a loop body"
    );
    assert!(is_err(&r.cmd("O2 endrepeat")));
    assert_eq!(x(&mut r), 0.0);
    assert_eq!(r.cmd("$J=G91 X1 F1000"), ["ok"], "outside blocks `$` runs");
    assert_eq!(x(&mut r), 1.0);
}

#[test]
fn untaken_branch_never_runs_in_check_mode_either() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("$C"), ["[MSG:Enabled]", "ok"]);
    // An arc that is an error where it stands: never interpreted.
    for l in ["O1 if [0]", "G2 X-5 R0", "O1 endif"] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    assert!(
        is_err(&r.cmd("G2 X-5 R0")),
        "the same line outside the if fails"
    );
}

#[test]
fn while_runs_every_pass_and_status_shows_the_source_line() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    // Text lines are numbered as received: the move is line 4.
    for l in [
        "G91",
        "#1=0",
        "O1 while [#1 LT 3]",
        "G1 X10 F600",
        "#1=[#1+1]",
    ] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    assert_eq!(
        r.status().state,
        "Idle",
        "nothing runs before the block ends"
    );
    assert_eq!(r.cmd("O1 endwhile"), ["ok"]);
    r.run(20);
    let st = r.status();
    assert_eq!((st.state.as_str(), st.line), ("Run", Some(4)), "{st:?}");
    assert_eq!(r.cmd("G90"), ["ok"]);
    assert_eq!(x(&mut r), 30.0, "three passes");
}

#[test]
fn sub_defined_in_the_stream_runs_only_when_called() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    for l in [
        "O<go> sub",
        "G0 X[#1*2] Y#<_y>",
        "O<go> return [#1+1]",
        "O<go> endsub",
    ] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    assert_eq!(x(&mut r), 0.0, "the body ran where it was defined");
    assert_eq!(r.cmd("#<_y>=1"), ["ok"]);
    assert_eq!(r.cmd("O<go> call [4]"), ["ok"]);
    assert_eq!(x(&mut r), 8.0);
    assert_eq!(r.cmd("G0 X#<_value>"), ["ok"]);
    assert_eq!(x(&mut r), 5.0);
}

#[test]
fn a_block_too_large_is_refused_before_any_of_it_runs() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("G91"), ["ok"]);
    assert_eq!(r.cmd("O1 repeat [2]"), ["ok"]);
    let mut replies = Vec::new();
    for _ in 0..100 {
        replies.push(r.cmd("G0 X1 Y0.0000000 Z0.0000000"));
    }
    let first = replies.iter().position(|x| is_err(x)).expect("refused");
    assert!(replies[first..].iter().all(|x| is_err(x)), "{replies:?}");
    assert!(is_err(&r.cmd("O1 endrepeat")), "the closer is refused too");
    assert_eq!(x(&mut r), 0.0, "a line of the refused block moved");
    assert_eq!(r.cmd("G0 X1"), ["ok"], "after its closer lines run again");
    assert_eq!(x(&mut r), 1.0);
}

#[test]
fn an_error_inside_a_replay_answers_its_closing_line() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    for l in ["G91", "O1 repeat [3]", "G0 X1", "G0 X[1/0]"] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    let end = r.cmd("O1 endrepeat");
    assert!(is_err(&end), "{end:?}");
    assert!(
        end[0].starts_with("[MSG:line 4: division by zero"),
        "{end:?}"
    );
    assert_eq!(x(&mut r), 1.0, "the pass stopped at the error");
}

#[test]
fn reset_stops_an_endless_loop_and_clears_the_flow_state() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    for l in [
        "G91",
        "O1 sub",
        "G1 X1 F3000",
        "O1 endsub",
        "O2 while [1]",
        "O1 call",
    ] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    // The loop's closer is answered only when the replay ends: never.
    assert_eq!(r.cmd("O2 endwhile"), Vec::<String>::new());
    r.send(b"G90\n");
    r.run(200);
    assert_eq!(r.status().state, "Run");
    r.send(&[0x18]);
    r.run(20);
    r.lines();
    assert_eq!(r.status().state, "Alarm");
    assert_eq!(r.cmd("$X"), ["[MSG:Caution: Unlocked]", "ok"]);
    // Subroutines are forgotten, and lines are read again (the reset put
    // the modal state back to G90).
    assert!(is_err(&r.cmd("O1 call")));
    assert_eq!(r.cmd("G0 X1"), ["ok"]);
    assert_eq!(x(&mut r), 1.0);
}

/// Framed lines: each stored line is acknowledged into its slot as usual;
/// a replay's commands carry the stored line's sequence number, and an
/// error inside it comes as the closing line's `Error`, with a message
/// naming the stored line.
#[test]
fn framed_replay_carries_the_stored_lines_and_its_error() {
    use protocol::DeviceMsg;
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.dev.log = Some(Vec::new());
    let s = r.go_framed();
    let lines = [
        "G91",
        "O1 repeat [3]",
        "G0 X1",
        "O1 endrepeat",
        "O2 repeat [2]",
        "G0 X[1/0]",
        "O2 endrepeat",
        "G90",
    ];
    let mut burst = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        burst.extend(rig::line_frame(s + i as u32, l));
    }
    r.send(&burst);
    let mut msgs = Vec::new();
    for _ in 0..100 {
        msgs.extend(r.run_framed(10));
    }
    let errs: Vec<_> = msgs
        .iter()
        .filter_map(|m| match m {
            DeviceMsg::Error { seq, code, .. } => Some((*seq, *code)),
            _ => None,
        })
        .collect();
    assert_eq!(errs, vec![(Some(s + 6), 201)], "{msgs:?}");
    let named = format!("line {}: division by zero", s + 5);
    assert!(
        msgs.iter()
            .any(|m| matches!(m, DeviceMsg::Msg(t) if t.as_str() == named)),
        "{msgs:?}"
    );
    assert_eq!(r.dev.log.as_deref(), Some(&[s + 2, s + 2, s + 2][..]));
}

/// The sample program (every construct; it agrees with LinuxCNC's rs274
/// in `cargo xtask rs274`) streamed line by line into the device, as a
/// send-response sender does, runs the commands check mode finds (every pass of
/// every loop and call), from the same source lines, in the same order.
#[test]
fn streamed_sample_runs_the_moves_check_mode_finds() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/rs274/oword_flow.ngc"
    );
    let src = std::fs::read_to_string(path).expect("sample");
    let mut dump = Vec::new();
    let settings = burin::settings::Settings::default();
    let errors = host_sim::check::check_file("s", &src, true, &settings, &mut dump).expect("check");
    assert_eq!(errors, 0);
    let want: Vec<u32> = String::from_utf8_lossy(&dump)
        .lines()
        .filter_map(|l| {
            l.strip_prefix("{\"line\":")?
                .split(',')
                .next()?
                .parse()
                .ok()
        })
        .collect();
    assert!(want.len() > 15, "{want:?}");

    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    r.dev.log = Some(Vec::new());
    for line in src.lines() {
        r.send(line.as_bytes());
        r.send(b"\n");
        let mut got = Vec::new();
        for _ in 0..10_000 {
            r.run(2);
            got.extend(r.lines());
            if got.iter().any(|l| l == "ok" || l.starts_with("error:")) {
                break;
            }
        }
        assert_eq!(
            got.last().map(String::as_str),
            Some("ok"),
            "{line}: {got:?}"
        );
    }
    r.until_idle();
    assert_eq!(r.dev.log.as_deref(), Some(&want[..]));
}

/// A text sender that goes away while an O-word replay runs: the machine
/// holds (the replay would otherwise run on with no one to stop it);
/// `~` from the next client resumes it.
#[test]
fn port_close_during_a_replay_holds() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.lines();
    for l in ["G91", "O2 while [1]", "G1 X1 F3000"] {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
    r.send(b"O2 endwhile\n");
    r.run(100);
    assert_eq!(r.status().state, "Run");
    r.dev.port_closed();
    r.run(200);
    // The replay keeps the parse task busy (a block of planning is 102 µs
    // on the board, `HostModel`): its reply comes in the second round.
    let st = r.status_within(2);
    assert!(st.state.starts_with("Hold"), "{st:?}");
    let x = st.mpos.map_or(0.0, |p| p[0]);
    r.run(200);
    assert_eq!(
        r.status().mpos.map_or(1.0, |p| p[0]),
        x,
        "moved in the hold"
    );
    r.send(b"~");
    r.run(100);
    assert_eq!(r.status().state, "Run");
}

/// Framed mode takes the same path: a line in a branch not taken is
/// acknowledged into its slot and never reaches the executor.
#[test]
fn framed_untaken_branch_never_runs() {
    let cfg = origin();
    let mut rec = Discard;
    let mut r = Rig::new(&cfg, &mut rec);
    r.dev.log = Some(Vec::new());
    let s = r.go_framed();
    let mut burst = Vec::new();
    for (i, l) in ["O1 if [0]", "G0 X5", "O1 endif", "G0 X1"]
        .iter()
        .enumerate()
    {
        burst.extend(rig::line_frame(s + i as u32, l));
    }
    r.send(&burst);
    let mut msgs = Vec::new();
    for _ in 0..50 {
        msgs.extend(r.run_framed(10));
    }
    assert!(
        !msgs
            .iter()
            .any(|m| matches!(m, protocol::DeviceMsg::Error { .. })),
        "{msgs:?}"
    );
    assert_eq!(r.dev.log.as_deref(), Some(&[s + 3][..]));
}
