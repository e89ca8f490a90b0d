//! The manual tool change (M6) and canned cycles on the virtual board,
//! driven as a GRBL text sender drives it: the job streams on, the board
//! holds at the tool-change position and says which tool to load, cycle
//! start resumes, and nothing acknowledged meanwhile is lost.

use crate::rig;

use host_sim::record::Discard;
use protocol::client::grbl::{parse_status, TextStatus};
use rig::{origin, Rig};

/// Runs until the board reports `Hold:0`; returns that status and every
/// other line received meanwhile (the status queries' own lines dropped).
fn held(r: &mut Rig) -> (TextStatus, Vec<String>) {
    let mut seen = Vec::new();
    for _ in 0..20_000 {
        r.run(5);
        r.send(b"?");
        r.run(1);
        let mut st = None;
        for l in r.lines() {
            match parse_status(&l) {
                Some(s) => st = Some(s),
                None => seen.push(l),
            }
        }
        if let Some(st) = st.filter(|s| s.state == "Hold:0") {
            return (st, seen);
        }
    }
    panic!("never held: {seen:?}");
}

/// Runs until idle; returns the last status and the other lines.
fn idle(r: &mut Rig) -> (TextStatus, Vec<String>) {
    let mut seen = Vec::new();
    for _ in 0..100_000 {
        r.run(10);
        r.send(b"?");
        r.run(1);
        let mut st = None;
        for l in r.lines() {
            match parse_status(&l) {
                Some(s) => st = Some(s),
                None => seen.push(l),
            }
        }
        if let Some(st) = st.filter(|s| s.state == "Idle") {
            return (st, seen);
        }
    }
    panic!("never idle: {seen:?}");
}

fn ok_all(r: &mut Rig, lines: &[&str]) {
    for l in lines {
        assert_eq!(r.cmd(l), ["ok"], "{l}");
    }
}

#[test]
fn m6_stops_the_spindle_moves_holds_announces_and_resumes_on_cycle_start() {
    let mut rec = Discard;
    let mut r = Rig::new(&origin(), &mut rec);
    r.lines();
    ok_all(
        &mut r,
        &[
            "$10=0",
            "$212=50",
            "$213=40",
            "$214=-1",
            "$215=7",
            "G10 L1 P2 Z-3.5",
            "M3 S1000",
            "G0 X10 Y10 Z-5",
        ],
    );
    // The change and the lines after it arrive at once, as a sender streams.
    r.send(b"T2 M6\nG43 H2\nG0 X20 Z-10\nM5\n");
    let (st, out) = held(&mut r);
    assert!(
        out.iter()
            .any(|l| l == "[MSG:Tool change: load T2, then cycle start]"),
        "{out:?}"
    );
    // Spindle off, at the tool-change position (machine mm).
    assert_eq!(st.spindle, Some(0.0), "{st:?}");
    // The lines after it are already planned (held): the machine, not the
    // plan, is at the tool-change position (default 80/80/400 steps/mm).
    assert_eq!(
        r.dev.position_steps(),
        burin::pad([50 * 80, 40 * 80, -400, 0])
    );
    // Held: more time changes nothing.
    r.run(200);
    assert_eq!(r.status().wpos, st.wpos);
    // Every line was acknowledged while held (none waits unacknowledged).
    let oks = out.iter().filter(|l| *l == "ok").count();
    assert_eq!(oks, 4, "{out:?}");
    r.send(b"~");
    let end = r.until_idle();
    // G43 H2 (-3.5) applies to the move after the change: work Z -10 is
    // machine Z -13.5; the status reports WPos, which the offset is part of.
    assert_eq!(end.wpos, rig::shown([20.0, 40.0, -10.0, 0.0]), "{end:?}");
    let mut params = r.cmd("$#");
    params.retain(|l| l.starts_with("[TLO") || l.starts_with("[T:"));
    assert_eq!(params, ["[TLO:-3.500]", "[T:2|0.000,0.000,-3.500|0.000]"]);
    assert_eq!(
        r.dev.sim.machine.commanded_position(),
        burin::pad([20.0, 40.0, -13.5, 0.0])
    );
}

#[test]
fn a_tool_setter_measures_each_new_tool_against_the_first() {
    let mut rec = Discard;
    let mut r = Rig::new(&origin(), &mut rec);
    r.lines();
    ok_all(
        &mut r,
        &[
            "$211=2",
            "$214=-1",
            "$215=4",
            "$216=5",
            "$217=6",
            "$218=1000",
            "$219=100",
        ],
    );
    r.send(b"M6 T1\n");
    held(&mut r);
    r.send(b"~");
    let (_, out) = idle(&mut r);
    assert!(
        out.iter().any(|l| l == "[MSG:T1 length offset 0.000]"),
        "{out:?}"
    );
    // A tool 3.5 mm longer: the setter (the default machine's probe plane
    // at Z -50) trips 3.5 mm higher.
    let spm = f64::from(r.dev.sim.machine.settings().axes[2].steps_per_mm);
    r.dev.sim.world.shift_probe((3.5 * spm).round() as i64);
    r.send(b"M6 T2\nG0 Z-10\n");
    let (st, _) = held(&mut r);
    assert_eq!(
        st.mpos.as_deref().map(|p| p[2]),
        Some(-1.0),
        "at the change Z"
    );
    r.send(b"~");
    let (end, out) = idle(&mut r);
    assert!(
        out.iter().any(|l| l == "[MSG:T2 length offset 3.500]"),
        "{out:?}"
    );
    // The measured offset applies to the job's next move.
    assert_eq!(end.mpos, rig::shown([5.0, 6.0, -6.5, 0.0]), "{end:?}");
}

#[test]
fn a_peck_cycle_runs_to_its_end_point_on_the_board() {
    let mut rec = Discard;
    let mut r = Rig::new(&origin(), &mut rec);
    r.lines();
    ok_all(&mut r, &["G0 Z5", "G91 G99 G83 X3 Y4 Z-6 R1 Q0.5 F600 L2"]);
    let end = r.until_idle();
    // G91: holes at +3/+4 twice, R 1 above the start level, Z 6 below R.
    assert_eq!(end.mpos, rig::shown([6.0, 8.0, 6.0, 0.0]), "{end:?}");
    assert_eq!(r.cmd("G90 G80 G0 X0 Y0"), ["ok"]);
    assert_eq!(r.until_idle().mpos, rig::shown([0.0, 0.0, 6.0, 0.0]));
}
