//! `cargo xtask bench-motion [--machine M.toml] [JOBS…]`: job time against
//! the time-optimal bound and the axis limits, per job, in simulated time
//! (deterministic: the same figures on every machine and run). Issue 12.
//!
//! Default: the 14 jobs of `../shared/bench-motion/` (outside the repo;
//! "skipped" when absent) on `host-sim/machines/grbl_match.toml`, the
//! settings GRBL 1.1h was timed on, whose times are printed alongside as
//! the outside reference.

use anyhow::Result;
use host_sim::bench::limits::jerk_quantum;
use host_sim::bench::{axis_limits, run_job, JobFigures};
use host_sim::config::MachineConfig;
use std::path::PathBuf;

use crate::util::root;

/// GRBL 1.1h's times on the default jobs (issue 12; first step to last,
/// its own firmware in a cycle-exact simulator, same settings).
const GRBL_S: [(&str, f64); 14] = [
    ("linuxcnc-tp__short_segments_0.001.ngc", 5.81),
    ("linuxcnc-tp__circle_small_segments_ncd.ngc", 18.64),
    ("linuxcnc-tp__zigzag_0.002_0.001.ngc", 26.37),
    ("linuxcnc-tp__spiral_tight_circular.ngc", 5.80),
    ("linuxcnc-tp__stellabee-violation-spirals.ngc", 30.57),
    ("pcb2gcode__milldrilldiatest-milldrill.ngc", 18.68),
    ("pcb2gcode__multivibrator-milldrill.ngc", 43.84),
    ("grbl-sim__HelloWorld.nc", 55.77),
    ("linuxcnc__plasmatest.ngc", 92.97),
    ("linuxcnc-tp__Cereal.ngc", 287.53),
    ("linuxcnc__tort.ngc", 572.90),
    ("linuxcnc__arcspiral.ngc", 257.21),
    ("gcode-rs__circle_a.gcode", 219.68),
    ("linuxcnc-tp__blur_torus.ngc", 299.60),
];

#[derive(clap::Args)]
pub struct BenchMotionArgs {
    /// Machine description (default: host-sim/machines/grbl_match.toml).
    #[arg(long, value_name = "FILE")]
    pub machine: Option<PathBuf>,
    /// After each job, the N source lines that lose the most time against
    /// the bound (where the step trace reaches each path vertex).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub losses: usize,
    /// G-code jobs (default: the 14 jobs in ../shared/bench-motion/).
    pub jobs: Vec<PathBuf>,
}

pub fn run(a: BenchMotionArgs) -> Result<i32> {
    let machine = a
        .machine
        .unwrap_or_else(|| root().join("host-sim/machines/grbl_match.toml"));
    let cfg = MachineConfig::load(&machine).map_err(|e| anyhow::anyhow!("{e}"))?;
    let jobs = if a.jobs.is_empty() {
        let dir = root().join("../shared/bench-motion");
        if !dir.is_dir() {
            println!("bench-motion: skipped ({} not found)", dir.display());
            return Ok(0);
        }
        GRBL_S.iter().map(|(n, _)| dir.join(n)).collect()
    } else {
        a.jobs.clone()
    };
    let (vmax, amax) = axis_limits(&cfg);
    let jmax = f64::from(cfg.settings.jerk);
    println!("bench-motion on {}", machine.display());
    println!(
        "limits: rate X/Y/Z {:.1}/{:.1}/{:.1} mm/s, accel {:.0}/{:.0}/{:.0} mm/s^2; \
         jerk {:.0} mm/s^3 ($203, reached only in S-curve mode); v, a and j over {} ms windows of \
         the step trace (j within {:.0}/{:.0}/{:.0} mm/s^3 of step quantisation); short = step \
         intervals below the rate limit (1 tick slack); bound a = the same meter on the bound's own profile",
        vmax[0],
        vmax[1],
        vmax[2],
        amax[0],
        amax[1],
        amax[2],
        jmax,
        host_sim::bench::limits::WINDOW_S * 1000.0,
        jerk_quantum(f64::from(cfg.settings.axes[0].steps_per_mm)),
        jerk_quantum(f64::from(cfg.settings.axes[1].steps_per_mm)),
        jerk_quantum(f64::from(cfg.settings.axes[2].steps_per_mm)),
    );
    println!(
        "{:<44} {:>8} {:>8} {:>6} {:>8} {:>6} | {:>14} | {:>14} | {:>14} | {:>11} | {:>14}",
        "job",
        "burin s",
        "bound s",
        "ratio",
        "GRBL s",
        "/GRBL",
        "peak v % X/Y/Z",
        "peak a % X/Y/Z",
        "peak j % X/Y/Z",
        "short X/Y/Z",
        "bound a % X/Y/Z"
    );
    let mut tot = (0.0, 0.0, 0.0, 0u64);
    let mut all_grbl = true;
    let mut worst_v = [0.0f64; 3];
    let mut worst_a = [0.0f64; 3];
    let mut worst_j = [0.0f64; 3];
    let mut worst_ba = [0.0f64; 3];
    let mut failed = 0;
    for job in &jobs {
        let name = job
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let source = match std::fs::read_to_string(job) {
            Ok(s) => s,
            Err(e) => {
                println!("{name:<44} skipped ({e})");
                continue;
            }
        };
        let f: JobFigures = run_job(&cfg, &source);
        let grbl = GRBL_S.iter().find(|(n, _)| *n == name).map(|g| g.1);
        let l = &f.limits;
        let pct = |v: f64, lim: f64| 100.0 * v / lim;
        let v: [f64; 3] = std::array::from_fn(|i| pct(l.peak_vel[i], vmax[i]));
        let acc: [f64; 3] = std::array::from_fn(|i| pct(l.peak_acc[i], amax[i]));
        let jerk: [f64; 3] = std::array::from_fn(|i| pct(l.peak_jerk[i], jmax));
        let ba: [f64; 3] = std::array::from_fn(|i| pct(f.bound_limits.peak_acc[i], amax[i]));
        for i in 0..3 {
            worst_v[i] = worst_v[i].max(v[i]);
            worst_a[i] = worst_a[i].max(acc[i]);
            worst_j[i] = worst_j[i].max(jerk[i]);
            worst_ba[i] = worst_ba[i].max(ba[i]);
        }
        let short = l.short_intervals;
        println!(
            "{:<44} {:>8.2} {:>8.2} {:>6.3} {:>8} {:>6} | {:>4.0} {:>4.0} {:>4.0} | {:>4.0} {:>4.0} {:>4.0} | {:>4.0} {:>4.0} {:>4.0} | {:>3} {:>3} {:>3} | {:>4.0} {:>4.0} {:>4.0}",
            name,
            f.time_s,
            f.bound_s,
            f.time_s / f.bound_s.max(1e-9),
            grbl.map_or("-".into(), |g| format!("{g:.2}")),
            grbl.map_or("-".into(), |g| format!("{:.3}", f.time_s / g)),
            v[0],
            v[1],
            v[2],
            acc[0],
            acc[1],
            acc[2],
            jerk[0],
            jerk[1],
            jerk[2],
            short[0],
            short[1],
            short[2],
            ba[0],
            ba[1],
            ba[2],
        );
        if a.losses > 0 {
            let mut by_kind: Vec<(String, f64, f64)> = Vec::new();
            for l in &f.losses {
                let k = format!("{:?}", l.kind);
                match by_kind.iter_mut().find(|e| e.0 == k) {
                    Some(e) => (e.1, e.2) = (e.1 + l.lost_s, e.2 + l.bound_s),
                    None => by_kind.push((k, l.lost_s, l.bound_s)),
                }
            }
            let parts: Vec<String> = by_kind
                .iter()
                .map(|(k, lost, b)| format!("{k} {lost:.3} s of {b:.2}"))
                .collect();
            println!("    lost by kind: {}", parts.join(", "));
        }
        for l in f.losses.iter().take(a.losses) {
            println!(
                "    line {:>6} {:>7?} {:>5} pieces: lost {:>8.4} s over the bound's {:>8.4} s",
                l.line, l.kind, l.pieces, l.lost_s, l.bound_s
            );
        }
        if !f.summary.errors.is_empty() {
            failed += 1;
            for e in f.summary.errors.iter().take(3) {
                println!("    {name}:{}: error[{}]: {}", e.line, e.code, e.message);
            }
        }
        tot.0 += f.time_s;
        tot.1 += f.bound_s;
        tot.3 += short.iter().sum::<u64>();
        match grbl {
            Some(g) => tot.2 += g,
            None => all_grbl = false,
        }
    }
    println!(
        "{:<44} {:>8.2} {:>8.2} {:>6.3} {:>8} {:>6} | {:>4.0} {:>4.0} {:>4.0} | {:>4.0} {:>4.0} {:>4.0} | {:>4.0} {:>4.0} {:>4.0} | {:>11} | {:>4.0} {:>4.0} {:>4.0}",
        "total (peaks: worst job)",
        tot.0,
        tot.1,
        tot.0 / tot.1.max(1e-9),
        if all_grbl { format!("{:.2}", tot.2) } else { "-".into() },
        if all_grbl { format!("{:.3}", tot.0 / tot.2) } else { "-".into() },
        worst_v[0],
        worst_v[1],
        worst_v[2],
        worst_a[0],
        worst_a[1],
        worst_a[2],
        worst_j[0],
        worst_j[1],
        worst_j[2],
        tot.3,
        worst_ba[0],
        worst_ba[1],
        worst_ba[2],
    );
    if failed > 0 {
        println!("{failed} job(s) reported errors");
        return Ok(1);
    }
    Ok(0)
}
