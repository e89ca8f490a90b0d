//! Lines per second over the shared corpus: burin's lexer + interpreter
//! (parse AND interpret, every line) against the `gcode` 0.7 crate only
//! tokenising/parsing the same text with its zero-allocation core and a
//! no-op visitor. Run: `cargo bench -p firmware --bench parse`.
//! Throughput is reported in lines (criterion's "elements"). burin is fed
//! pre-split lines (line splitting is the link layer's job and happens as
//! bytes arrive); the gcode crate parses the whole text.

#[path = "support/parse_work.rs"]
mod work;

use criterion::{criterion_group, Criterion, Throughput};
use std::hint::black_box;
use std::sync::OnceLock;
use std::time::Instant;
use work::{burin_pass, gcode_pass};

/// The corpus text and its line count, read once for criterion and the
/// interleaved run.
fn corpus() -> &'static (String, u64) {
    static CORPUS: OnceLock<(String, u64)> = OnceLock::new();
    CORPUS.get_or_init(|| {
        let mut text = work::corpus_text();
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
    })
}

fn bench(c: &mut Criterion) {
    let (text, lines) = corpus();
    let split: Vec<&str> = text.lines().collect();
    let mut g = c.benchmark_group("corpus");
    g.throughput(Throughput::Elements(*lines));
    g.bench_function("burin_parse_and_interpret", |b| {
        b.iter(|| black_box(burin_pass(&split)))
    });
    g.bench_function("gcode_0_7_tokenise", |b| b.iter(|| gcode_pass(text)));
    g.finish();
}

/// Criterion measures the two one after the other, so a machine whose
/// speed drifts (a shared VM) can skew their ratio. This measures them in
/// alternation, pass for pass, and prints the ratio of each pair's times:
/// drift then hits both sides of a pair alike.
fn interleaved_ratio() {
    let (text, _) = corpus();
    let split: Vec<&str> = text.lines().collect();
    let mut ratios = Vec::new();
    for _ in 0..5 {
        burin_pass(&split);
        gcode_pass(text);
    }
    for _ in 0..101 {
        let t = Instant::now();
        black_box(burin_pass(&split));
        let b = t.elapsed().as_secs_f64();
        let t = Instant::now();
        gcode_pass(text);
        let g = t.elapsed().as_secs_f64();
        ratios.push(g / b);
    }
    ratios.sort_by(f64::total_cmp);
    let q = |f: f64| ratios[((ratios.len() - 1) as f64 * f) as usize];
    println!(
        "corpus/interleaved: gcode_0_7 time / burin time over {} alternating pass pairs: \
         median {:.2}x (quartiles {:.2}x .. {:.2}x)",
        ratios.len(),
        q(0.5),
        q(0.25),
        q(0.75)
    );
}

criterion_group!(benches, bench);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    // Not in `cargo test --benches` / `--test` / `--list` runs.
    if !std::env::args().any(|a| a == "--test" || a == "--list") {
        interleaved_ratio();
    }
}
