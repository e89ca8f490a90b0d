//! Runs N passes of the parse benchmark's work, burin or the `gcode` 0.7
//! crate, over ../shared/corpus, for an instruction count that does not
//! drift the way wall time does on a shared machine:
//!
//! ```sh
//! cargo build --release -p firmware --example parse_passes
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null \
//!     target/release/examples/parse_passes burin 3
//! ```
//!
//! Run it with 1 and with 3 passes and halve the difference of the two
//! "Collected" totals: that is one pass, without start-up and file reading.
//! `gcode` instead of `burin` counts the other side.

use burin::interp::Interpreter;
use std::hint::black_box;
use std::path::{Path, PathBuf};

fn corpus_text() -> String {
    let root = std::env::var_os("BURIN_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/corpus"));
    let mut files = Vec::new();
    let mut stack = vec![root];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let p = entry.path();
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

fn main() {
    let mut args = std::env::args().skip(1);
    let side = args.next().unwrap_or_else(|| "burin".into());
    let passes: usize = args.next().and_then(|n| n.parse().ok()).unwrap_or(1);
    let text = corpus_text();
    if text.trim().is_empty() {
        eprintln!("no corpus (set BURIN_CORPUS or check out ../shared/corpus)");
        std::process::exit(2);
    }
    let lines: Vec<&str> = text.lines().collect();
    for _ in 0..passes {
        match side.as_str() {
            "burin" => {
                let mut it = Interpreter::new();
                let mut n = 0u32;
                for line in &lines {
                    let _ = it.execute_line(line.as_bytes(), &mut |c| {
                        black_box(&c);
                        n += 1;
                    });
                    if it.needs_sync() {
                        it.set_machine_position(it.state().pos);
                    }
                }
                black_box(n);
            }
            "gcode" => {
                let mut v = gcode::core::Noop;
                gcode::core::parse(black_box(&text), &mut v);
            }
            other => {
                eprintln!("unknown side {other:?}: burin or gcode");
                std::process::exit(2);
            }
        }
    }
    println!("{passes} pass(es) of {side} over {} lines", lines.len());
}
