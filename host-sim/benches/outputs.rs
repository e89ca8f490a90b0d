//! Writer throughput, per step event: a long job is tens of millions of
//! events, and `--trace`/`--vcd`/`--plot` must not dominate its run time.
//!
//! `cargo bench -p host-sim --bench outputs`; criterion prints events/s.

use std::hint::black_box;
use std::io::sink;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use host_sim::config::MachineConfig;
use host_sim::plot::SvgPlot;
use host_sim::record::{PinEvent, Recorder};
use host_sim::trace::TraceCsv;
use host_sim::vcd::Vcd;

const N: usize = 100_000;

/// A spiral of X/Y steps with Z stepping now and then, 20 µs apart.
fn events() -> Vec<PinEvent> {
    let mut pos = [0i64; burin::AXES];
    (0..N as u64)
        .map(|i| {
            let a = i as f64 * 1e-3;
            let target = [(8000.0 * a.cos()) as i64, (8000.0 * a.sin()) as i64];
            let mut step = 0u8;
            let mut dir = 0u8;
            for k in 0..2 {
                let d = (target[k] - pos[k]).signum();
                if d != 0 {
                    pos[k] += d;
                    step |= 1 << k;
                    dir |= u8::from(d < 0) << k;
                }
            }
            if i % 97 == 0 {
                pos[2] -= 1;
                step |= 4;
                dir |= 4;
            }
            PinEvent {
                tick: 1920 * i,
                dir_mask: dir,
                step_mask: step | 1,
                dir_changed_tick: 1920 * i.saturating_sub(1),
                pos,
            }
        })
        .collect()
}

fn feed(r: &mut dyn Recorder, evs: &[PinEvent], round: u64) {
    let shift = round * 1920 * N as u64;
    for e in evs {
        let mut e = *e;
        e.tick += shift;
        e.dir_changed_tick += shift;
        r.step_event(black_box(&e));
    }
}

fn writers(c: &mut Criterion) {
    let evs = events();
    let info = MachineConfig::default().run_info();
    let mut g = c.benchmark_group("writers");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("trace_csv", |b| {
        let mut t = TraceCsv::new(sink());
        let mut round = 0;
        b.iter(|| {
            feed(&mut t, &evs, round);
            round += 1;
        });
    });
    g.bench_function("vcd", |b| {
        let mut v = Vcd::new(sink());
        v.start(&info);
        let mut round = 0;
        b.iter(|| {
            feed(&mut v, &evs, round);
            round += 1;
        });
    });
    g.bench_function("svg_plot_collect", |b| {
        let mut p = SvgPlot::new(sink(), "bench");
        p.start(&info);
        let mut round = 0;
        b.iter(|| {
            feed(&mut p, &evs, round);
            round += 1;
        });
    });
    g.finish();
}

criterion_group!(benches, writers);
criterion_main!(benches);
