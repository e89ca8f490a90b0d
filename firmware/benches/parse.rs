//! Lines per second over the shared corpus: burin's lexer + interpreter
//! (parse AND interpret, every line) against the `gcode` 0.7 crate only
//! tokenising/parsing the same text with its zero-allocation core and a
//! no-op visitor. Run: `cargo bench -p firmware --bench parse`.
//! Throughput is reported in lines (criterion's "elements"). burin is fed
//! pre-split lines (line splitting is the link layer's job and happens as
//! bytes arrive); the gcode crate parses the whole text.

use burin::interp::Interpreter;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use std::path::{Path, PathBuf};

fn corpus() -> (String, u64) {
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
    if text.trim().is_empty() {
        // No corpus: a synthetic job so the bench still measures something.
        for i in 0..20_000 {
            text.push_str(&format!(
                "G1 X{:.3} Y{:.3} F1200\nG2 X{:.3} Y0 I5 J0\n",
                i as f32 * 0.01,
                i as f32 * 0.02,
                i as f32 * 0.01
            ));
        }
    }
    let lines = text.lines().count() as u64;
    (text, lines)
}

fn bench(c: &mut Criterion) {
    let (text, lines) = corpus();
    // burin gets lines already split, as the link layer hands them over on
    // the device; the gcode crate gets the whole text and finds the line
    // ends itself (its tokenizer treats newlines as tokens).
    let split: Vec<&str> = text.lines().collect();
    let mut g = c.benchmark_group("corpus");
    g.throughput(Throughput::Elements(lines));
    g.bench_function("burin_parse_and_interpret", |b| {
        b.iter(|| {
            let mut it = Interpreter::new();
            let mut n = 0u32;
            for line in &split {
                let _ = it.execute_line(line.as_bytes(), &mut |c| {
                    black_box(&c);
                    n += 1;
                });
                if it.needs_sync() {
                    it.set_machine_position(it.state().pos);
                }
            }
            black_box(n)
        })
    });
    g.bench_function("gcode_0_7_tokenise", |b| {
        b.iter(|| {
            let mut v = gcode::core::Noop;
            gcode::core::parse(black_box(&text), &mut v);
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
