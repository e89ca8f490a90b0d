//! The parse benchmark's work, shared by `benches/parse.rs` (wall time) and
//! `examples/parse_passes.rs` (instruction counts), so both measure the
//! same thing.

use burin::interp::Interpreter;
use std::hint::black_box;
use std::path::{Path, PathBuf};

/// Every .ngc/.gcode/.nc file under `$BURIN_CORPUS` (default
/// ../shared/corpus), in path order, one newline after each. Empty when
/// there is no corpus.
pub fn corpus_text() -> String {
    let dir = std::env::var_os("BURIN_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/corpus"));
    let mut files = Vec::new();
    let mut stack = vec![dir];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p
                .extension()
                .is_some_and(|x| x == "ngc" || x == "gcode" || x == "nc")
            {
                files.push(p);
            }
        }
    }
    files.sort();
    let mut text = String::new();
    for f in files {
        text.push_str(&String::from_utf8_lossy(
            &std::fs::read(f).unwrap_or_default(),
        ));
        text.push('\n');
    }
    text
}

/// One pass of burin over the pre-split lines: parse and interpret all.
/// burin gets lines already split, as the link layer hands them over on
/// the device.
pub fn burin_pass(lines: &[&str]) -> u32 {
    let mut it = Interpreter::new();
    let mut n = 0u32;
    for line in lines {
        let _ = it.execute_line(line.as_bytes(), &mut |c| {
            black_box(&c);
            n += 1;
        });
        if it.needs_sync() {
            it.set_machine_position(it.state().pos);
        }
    }
    n
}

/// One pass of the gcode 0.7 crate's zero-allocation tokeniser with a
/// no-op visitor over the whole text (it finds the line ends itself).
pub fn gcode_pass(text: &str) {
    let mut v = gcode::core::Noop;
    gcode::core::parse(black_box(text), &mut v);
}
