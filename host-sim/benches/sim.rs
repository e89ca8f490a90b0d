//! Simulator throughput: simulated steps per second, planned blocks per
//! second, and simulated time over wall time on a long job (the corpus when
//! it is present next to the workspace).
use std::hint::black_box;
use std::time::Instant;

use burin::command::{Command, Feed};
use burin::planner::{Planner, Speed, Watch};
use burin::settings::Settings;
use burin::AXES;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use host_sim::config::MachineConfig;
use host_sim::engine::{run_job, Sim};
use host_sim::record::Discard;

fn config() -> MachineConfig {
    MachineConfig {
        tick_hz: 96_000_000,
        settings: Settings::default(),
        limits: [None; AXES],
        probe: None,
        start_position_mm: [0.0; AXES],
        host: host_sim::config::HostModel::default(),
        interrupts: host_sim::config::Interrupts::default(),
        wiring: None,
        slack_mm: Default::default(),
    }
}

/// Long zig-zag at high feed: mostly cruise, many steps.
fn zigzag() -> Vec<Command> {
    let mut v = Vec::new();
    for i in 0..40 {
        let y = i as f32 * 2.0;
        v.push(Command::Line {
            end: burin::pad([200.0, y + 1.0, 0.0, 0.0]),
            feed: Feed::PerMin(4000.0),
        });
        v.push(Command::Line {
            end: burin::pad([0.0, y + 2.0, -1.0, 0.0]),
            feed: Feed::PerMin(4000.0),
        });
    }
    v
}

fn bench_steps(c: &mut Criterion) {
    let cfg = config();
    let job = zigzag();
    let mut rec = Discard;
    let mut sim = Sim::new(&cfg, &mut rec);
    for (i, cmd) in job.iter().enumerate() {
        sim.push_command(i as u32, cmd.clone());
    }
    sim.run();
    let s = sim.summary(0, [0.0; AXES]);
    let steps: u64 = s.steps.iter().sum();
    let mut g = c.benchmark_group("sim");
    g.sample_size(10);
    g.throughput(Throughput::Elements(steps));
    g.bench_function("steps_zigzag", |b| {
        b.iter(|| {
            let mut rec = Discard;
            let mut sim = Sim::new(&cfg, &mut rec);
            for (i, cmd) in job.iter().enumerate() {
                sim.push_command(i as u32, cmd.clone());
            }
            sim.run();
            black_box(sim.now())
        })
    });
    g.finish();
}

fn bench_planner(c: &mut Criterion) {
    let s = Settings::default();
    const N: u64 = 10_000;
    let mut g = c.benchmark_group("planner");
    g.throughput(Throughput::Elements(N));
    g.bench_function("plan_short_segments", |b| {
        b.iter(|| {
            let mut p: Planner<64> = Planner::new(s);
            for i in 0..N {
                let a = i as f32 * 0.05;
                let t = p
                    .to_steps(&burin::pad([
                        10.0 * libm::cosf(a),
                        10.0 * libm::sinf(a),
                        0.0,
                        0.0,
                    ]))
                    .unwrap_or([0; AXES]);
                if p.is_full() {
                    p.pop();
                }
                let _ = p.push_line(t, Speed::Feed(50.0), Watch::default(), 0);
            }
            black_box(p.len())
        })
    });
    g.finish();
}

fn corpus_jobs() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/corpus");
    let Ok(m) = std::fs::read_to_string(dir.join("MANIFEST.tsv")) else {
        return Vec::new();
    };
    m.lines()
        .skip(1)
        .filter_map(|r| r.split('\t').next())
        .filter_map(|rel| std::fs::read_to_string(dir.join(rel)).ok())
        .collect()
}

fn bench_ratio(c: &mut Criterion) {
    let cfg = config();
    let mut jobs = corpus_jobs();
    if jobs.is_empty() {
        println!("corpus not found: using the built-in zig-zag as the long job");
        let z: String = (0..40)
            .map(|i| format!("G1 X200 Y{} F4000\nG1 X0 Y{} Z-1\n", i * 2 + 1, i * 2 + 2))
            .collect();
        jobs.push(z);
    }
    let t0 = Instant::now();
    let sim_s: f64 = jobs
        .iter()
        .map(|j| run_job(&cfg, j, &mut Discard).job_time_s)
        .sum();
    let wall = t0.elapsed().as_secs_f64();
    println!(
        "corpus: {:.1} s simulated in {:.3} s wall: ratio {:.0}x",
        sim_s,
        wall,
        sim_s / wall
    );
    let mut g = c.benchmark_group("corpus");
    g.sample_size(10);
    g.bench_function("all_jobs", |b| {
        b.iter(|| {
            jobs.iter()
                .map(|j| run_job(&cfg, j, &mut Discard).job_time_s)
                .sum::<f64>()
        })
    });
    g.finish();
}

criterion_group!(benches, bench_steps, bench_planner, bench_ratio);
criterion_main!(benches);
