//! `gcode_line` and `gcode_program`: lines through the lexer and the
//! interpreter. Invariants: a line that errors leaves the interpreter as it
//! was (modal state, offsets, parameters) and emits nothing; every number a
//! line emits, and every position, offset and parameter it leaves, is
//! finite.

use burin::command::{Command, Feed};
use burin::interp::Interpreter;

/// States to start a single line from: the first input byte picks one, so
/// a line meets inches, incremental mode, offsets and parameters too.
const PRELUDES: &[&str] = &[
    "",
    "G20\nG91",
    "G10 L2 P2 X1.5 Y-2 Z3\nG55\nG92 X1\n#1=2.5\n#<a>=-3",
    "G18\nG2 X1 Z1 I1 F100\nG93\nG91.1",
    "G17\nG5 X1 Y1 I1 J0 P1 Q1 F50\nM3 S1000",
    "G10 L20 P1 X0\nG0 X1\nG91.1",
    "G28.1\nG30.1\nG94\nG64",
    "#<_g>=7\n#5221=2\nG54\nG1 X-1 F200",
    "G10 L1 P3 Z-2 R1\nT3 M6\nG43\nM3 S100\nG98 G81 X1 Y1 Z-1 R1 F100",
    "G43.1 Z1\nG19 G99 G83 Y1 Z1 X-1 R2 Q0.5 F60\nG91",
];

fn finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn feed_ok(f: &Feed) -> bool {
    match f {
        Feed::PerMin(v) | Feed::InverseTime(v) => v.is_finite(),
    }
}

/// Every number in a command is finite.
fn command_finite(c: &Command) -> bool {
    match c {
        Command::Rapid { end } => finite(end),
        Command::Line { end, feed } | Command::Probe { end, feed, .. } => {
            finite(end) && feed_ok(feed)
        }
        Command::Arc(a) => finite(&a.end) && finite(&a.center) && feed_ok(&a.feed),
        Command::Spline(s) => finite(&s.end) && finite(&s.p1) && finite(&s.p2) && feed_ok(&s.feed),
        Command::Dwell { seconds } => seconds.is_finite(),
        Command::Spindle { speed, .. } => speed.is_finite(),
        Command::Aux { value, .. } => value.is_finite(),
        Command::Cycle(c) => {
            let start = [0.0; burin::AXES];
            finite(&c.hole)
                && finite(&c.step)
                && finite(&[c.r, c.bottom, c.clear, c.q, c.p, c.feed, c.speed])
                && c.steps(&start).take(100_000).all(|s| command_finite(&s))
        }
        _ => true,
    }
}

fn offsets_finite(it: &Interpreter) -> bool {
    let o = it.offsets();
    o.wcs.iter().all(|w| finite(w))
        && finite(&o.g28)
        && finite(&o.g30)
        && o.tools
            .iter()
            .all(|t| finite(&t.offset) && t.diameter.is_finite())
}

/// One line; panics on a broken invariant. `n` is the line's index.
fn check_line(it: &mut Interpreter, line: &[u8], n: usize) {
    let before = it.clone();
    let mut emitted = 0usize;
    let mut bad = None;
    let r = it.execute_line(line, &mut |c| {
        emitted += 1;
        if bad.is_none() && !command_finite(&c) {
            bad = Some(c);
        }
    });
    let text = String::from_utf8_lossy(line);
    if let Some(c) = bad {
        panic!("line {n} {text:?} emitted a non-finite number: {c:?}");
    }
    match r {
        Err(e) => {
            assert_eq!(emitted, 0, "line {n} {text:?} failed ({e}) but emitted");
            assert!(
                it.state() == before.state(),
                "line {n} {text:?} failed ({e}) and changed the modal state"
            );
            assert!(
                it.offsets() == before.offsets(),
                "line {n} {text:?} failed ({e}) and changed the offsets"
            );
            assert!(
                it.params().same_values(before.params()),
                "line {n} {text:?} failed ({e}) and changed parameters"
            );
        }
        Ok(()) => {
            assert!(
                finite(&it.state().pos),
                "line {n} {text:?} left a non-finite position {:?}",
                it.state().pos
            );
            assert!(
                offsets_finite(it),
                "line {n} {text:?} left a non-finite offset"
            );
            assert!(
                it.params().all_finite(),
                "line {n} {text:?} left a non-finite parameter"
            );
        }
    }
    // The executor would report where homing or probing really ended.
    if it.needs_sync() {
        let pos = it.state().pos;
        it.set_machine_position(pos);
    }
}

fn prelude(it: &mut Interpreter, pick: u8) {
    for p in PRELUDES[usize::from(pick) % PRELUDES.len()].split('\n') {
        it.execute_line(p.as_bytes(), &mut |_| {})
            .unwrap_or_else(|e| panic!("prelude {p:?}: {e}"));
        if it.needs_sync() {
            let pos = it.state().pos;
            it.set_machine_position(pos);
        }
    }
}

/// One line from one of a few starting states (first byte).
pub fn gcode_line(data: &[u8]) {
    let Some((&pick, line)) = data.split_first() else {
        return;
    };
    let mut it = Interpreter::new();
    prelude(&mut it, pick);
    check_line(&mut it, line, 0);
}

/// Many lines (split at `\n`) with state carried between them.
pub fn gcode_program(data: &[u8]) {
    let mut it = Interpreter::new();
    for (n, line) in data.split(|&b| b == b'\n').enumerate() {
        check_line(&mut it, line, n);
    }
}
