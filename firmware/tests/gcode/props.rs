//! Property tests: arbitrary bytes and grammar-shaped random lines never
//! panic, always terminate, emit only finite numbers, and a failing line
//! emits nothing and leaves the state unchanged.
//! Runs 10_000 arbitrary-byte lines and 10_000 grammar-shaped lines
//! (each case feeds one line to an interpreter primed by the previous ones).

use burin::command::Command;
use burin::interp::Interpreter;
use proptest::prelude::*;

fn finite(c: &Command) -> bool {
    let s = format!("{c:?}");
    !(s.contains("NaN") || s.contains("inf"))
}

fn check(it: &mut Interpreter, line: &[u8]) {
    let before = (*it.state(), it.offsets());
    let mut cmds = Vec::new();
    match it.execute_line(line, &mut |c| cmds.push(c)) {
        Ok(()) => {
            assert!(
                cmds.iter().all(finite),
                "non-finite output for {:?}: {cmds:?}",
                String::from_utf8_lossy(line)
            );
            if it.needs_sync() {
                it.set_machine_position(it.state().pos);
            }
        }
        Err(e) => {
            assert!(cmds.is_empty());
            assert_eq!(
                (*it.state(), it.offsets()),
                before,
                "state changed by failing line"
            );
            assert!(
                usize::from(e.col) <= line.len() + 1,
                "column {} beyond line {:?}",
                e.col,
                line
            );
            let _ = e.to_string();
        }
    }
    assert!(it.state().pos.iter().all(|v| v.is_finite()));
}

fn word() -> impl Strategy<Value = String> {
    let letter = prop::sample::select(vec![
        "G", "M", "X", "Y", "Z", "A", "I", "J", "K", "R", "P", "Q", "F", "S", "T", "L", "N", "E",
        "#1=", "#<a>=", "O",
    ]);
    let gnum = prop::sample::select(vec![
        "0", "1", "2", "3", "4", "5", "5.1", "10", "17", "18", "19", "20", "21", "27", "28", "30",
        "38.2", "38.5", "53", "54", "59.3", "80", "90", "91", "90.1", "91.1", "92", "92.1", "92.2",
        "92.3", "93", "94", "41", "3", "5", "7", "8", "9", "17", "42", "62", "106", "117", "220",
    ]);
    let num = prop_oneof![
        (-1000.0f64..1000.0).prop_map(|v| format!("{v:.3}")),
        gnum.prop_map(String::from),
        Just("[1/0]".to_string()),
        Just("[#1*2+SIN[30]]".to_string()),
        Just("#<a>".to_string()),
        Just("[2**200]".to_string()),
        Just("1e5".to_string()),
        Just("".to_string()),
        Just("[[1]".to_string()),
    ];
    (
        letter,
        num,
        prop::sample::select(vec!["", " ", "(c)", "\t"]),
    )
        .prop_map(|(l, n, sep)| format!("{l}{n}{sep}"))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes(lines in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..300), 1..4)) {
        let mut it = Interpreter::new();
        for l in &lines {
            check(&mut it, l);
        }
    }

    #[test]
    fn grammar_shaped(lines in prop::collection::vec(prop::collection::vec(word(), 0..12), 1..6)) {
        let mut it = Interpreter::new();
        it.execute_line(b"G21 F100", &mut |_| {}).unwrap();
        for words in &lines {
            check(&mut it, words.concat().as_bytes());
        }
    }
}
