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

#[path = "../benches/support/parse_work.rs"]
mod work;

fn main() {
    let mut args = std::env::args().skip(1);
    let side = args.next().unwrap_or_else(|| "burin".into());
    let passes: usize = args.next().and_then(|n| n.parse().ok()).unwrap_or(1);
    let text = work::corpus_text();
    if text.trim().is_empty() {
        eprintln!("no corpus (set BURIN_CORPUS or check out ../shared/corpus)");
        std::process::exit(2);
    }
    let lines: Vec<&str> = text.lines().collect();
    for _ in 0..passes {
        match side.as_str() {
            "burin" => {
                std::hint::black_box(work::burin_pass(&lines));
            }
            "gcode" => work::gcode_pass(&text),
            other => {
                eprintln!("unknown side {other:?}: burin or gcode");
                std::process::exit(2);
            }
        }
    }
    println!("{passes} pass(es) of {side} over {} lines", lines.len());
}
