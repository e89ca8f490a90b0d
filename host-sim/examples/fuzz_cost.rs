//! Where a device/executor fuzz input's time goes (`cargo run --release
//! -p host-sim --example fuzz_cost`).
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let [_, name, dir] = &args[..] {
        return corpus(name, dir);
    }
    let cfg = host_sim::fuzz::small_machine(false, false);
    let n = 2000;
    let t = Instant::now();
    for _ in 0..n {
        let mut rec = host_sim::record::Discard;
        let d = host_sim::device_sim::VirtualDevice::new(&cfg, &mut rec);
        std::hint::black_box(&d);
    }
    println!(
        "VirtualDevice::new: {:.1} us",
        t.elapsed().as_secs_f64() * 1e6 / n as f64
    );
    let t = Instant::now();
    for _ in 0..n {
        let mut rec = host_sim::record::Discard;
        let d = host_sim::engine::Sim::new(&cfg, &mut rec);
        std::hint::black_box(&d);
    }
    println!(
        "Sim::new: {:.1} us",
        t.elapsed().as_secs_f64() * 1e6 / n as f64
    );
    for (name, data) in [
        ("device empty", &[][..]),
        (
            "device 11,20 x10",
            &[11u8, 20, 11, 20, 11, 20, 11, 20, 11, 20, 11, 20][..],
        ),
        ("executor empty", &[][..]),
        ("executor G1", &b"\x00G1 X-5 F1000\n"[..]),
    ] {
        let f = if name.starts_with("device") {
            host_sim::fuzz::device
        } else {
            host_sim::fuzz::executor
        };
        let t = Instant::now();
        for _ in 0..n {
            f(data);
        }
        println!(
            "{name}: {:.1} us",
            t.elapsed().as_secs_f64() * 1e6 / n as f64
        );
    }
}

/// Mean and worst time per input of a corpus directory (args: target dir).
#[allow(dead_code)]
fn corpus(name: &str, dir: &str) {
    let f = host_sim::fuzz::target(name).expect("target");
    let mut times = Vec::new();
    for e in std::fs::read_dir(dir).expect("dir").flatten() {
        let d = std::fs::read(e.path()).expect("read");
        let t = Instant::now();
        f(&d);
        times.push((t.elapsed().as_secs_f64() * 1e6, e.path()));
    }
    times.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mean = times.iter().map(|t| t.0).sum::<f64>() / times.len().max(1) as f64;
    println!(
        "{name}: {} inputs, mean {mean:.0} us, median {:.0} us",
        times.len(),
        times[times.len() / 2].0
    );
    for t in times.iter().rev().take(3) {
        println!("  {:.0} us {}", t.0, t.1.display());
    }
}
