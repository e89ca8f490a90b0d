//! The `bad` set: each line of tests/data/bad/cases.txt is `CODE COL | gcode`.
//! Every case must fail with exactly that stable code and column, emit
//! nothing, and leave the interpreter's state unchanged.

use burin::interp::Interpreter;

#[test]
fn bad_cases() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/bad/cases.txt");
    let text = std::fs::read_to_string(path).expect("cases.txt");
    let mut n = 0;
    let mut failures = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        if raw.trim().is_empty() || raw.starts_with("//") {
            continue;
        }
        let (head, line) = raw.split_once(" | ").expect("CODE COL | line");
        let mut it = head
            .split_whitespace()
            .map(|x| x.parse::<u16>().expect("number"));
        let (code, col) = (it.next().expect("code"), it.next().expect("col"));
        let mut interp = Interpreter::new();
        interp
            .execute_line(b"G21 G90 F100", &mut |_| {})
            .expect("preamble");
        let before = (*interp.state(), interp.offsets());
        let mut emitted = 0;
        let r = interp.execute_line(line.as_bytes(), &mut |_| emitted += 1);
        n += 1;
        match r {
            Err(e)
                if e.code() == code
                    && e.col == col
                    && emitted == 0
                    && (*interp.state(), interp.offsets()) == before => {}
            other => failures.push(format!(
                "line {}: `{line}` want {code}@{col}, got {other:?} (emitted {emitted})",
                i + 1
            )),
        }
    }
    println!("bad set: {n} cases");
    assert!(n >= 60, "only {n} cases");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
