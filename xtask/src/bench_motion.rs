//! `cargo xtask bench-motion [--machine M.toml] [JOBS…]`: job time against
//! the time-optimal bound and the axis limits, per job, in simulated time
//! (deterministic: the same figures on every machine and run). Issues 12
//! and 31.
//!
//! Default: the 14 jobs of `../shared/bench-motion/` (outside the repo;
//! "skipped" when absent) on `host-sim/machines/grbl_match.toml`, the
//! settings GRBL 1.1h was timed on, whose times are printed alongside as
//! the outside reference; then bench-motion's own generated jobs
//! (`host_sim::bench::jobs`: pen plotters, a 3-D contour).

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
    /// Leave out the generated jobs (plotters, 3-D contour).
    #[arg(long)]
    pub no_generated: bool,
    /// G-code jobs (default: the 14 jobs in ../shared/bench-motion/, then
    /// the generated ones).
    pub jobs: Vec<PathBuf>,
}

/// Running sums of the table.
#[derive(Default)]
struct Totals {
    time: f64,
    bound: f64,
    curved_ref: f64,
    grbl: f64,
    all_grbl: bool,
    short: u64,
    worst: [[f64; 3]; 6],
    /// S-curve only: the jerk-limited bounds' sum, the worst segment jerk %.
    jbound: f64,
    jrest: f64,
    seg_jerk: f64,
}

pub fn run(a: BenchMotionArgs) -> Result<i32> {
    let machine = a
        .machine
        .unwrap_or_else(|| root().join("host-sim/machines/grbl_match.toml"));
    let cfg = MachineConfig::load(&machine).map_err(|e| anyhow::anyhow!("{e}"))?;
    // (name, source or the error reading it)
    let mut jobs: Vec<(String, Result<String, String>)> = Vec::new();
    let read = |p: &PathBuf| {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        (name, std::fs::read_to_string(p).map_err(|e| e.to_string()))
    };
    if a.jobs.is_empty() {
        let dir = root().join("../shared/bench-motion");
        if dir.is_dir() {
            jobs.extend(GRBL_S.iter().map(|(n, _)| read(&dir.join(n))));
        } else {
            println!("bench-motion: corpus skipped ({} not found)", dir.display());
        }
        if !a.no_generated {
            jobs.extend(
                host_sim::bench::jobs::all()
                    .into_iter()
                    .map(|(n, s)| (n.to_string(), Ok(s))),
            );
        }
    } else {
        jobs.extend(a.jobs.iter().map(read));
    }
    let (vmax, amax) = axis_limits(&cfg);
    let jmax = f64::from(cfg.settings.jerk);
    println!("bench-motion on {}", machine.display());
    println!(
        "limits: rate X/Y/Z {:.1}/{:.1}/{:.1} mm/s, accel {:.0}/{:.0}/{:.0} mm/s^2; \
         jerk {:.0} mm/s^3 ($203, reached only in S-curve mode); v, a and j over {} ms windows of \
         the step trace (j within {:.0}/{:.0}/{:.0} mm/s^3 of step quantisation); curv = each axis's \
         centripetal acceleration v^2*|n_i|/r at curve vertices (turns <= {:.0} deg; circle through \
         a vertex and its neighbours, a few chords apart where nearer ones lie within half a step of a line); short = step intervals below the rate limit (1 tick slack); \
         bound = junction deviation and the axis limits only (no curvature rule); +curv = a reference, \
         not a bound: the same with burin's curvature rule v^2 <= a*l/phi (issue 12's bound); bound a / curv = \
         the same meters on the bound's own profile",
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
        host_sim::bench::curvature::MAX_TURN.to_degrees(),
    );
    let scurve = cfg.settings.profile == burin::settings::Profile::SCurve;
    if scurve {
        println!(
            "S-curve: jbound = the jerk-limited lower bound (the same limits plus $203 as the path's \
             jerk; host_sim::bench::jerk); seg j = the segments' peak path jerk, third differences of \
             the path position at their speed changes, points >= {:.1} ms apart (a trapezoid reads >= ~125 %); \
             jrest = a reference, not a bound: jbound with the path acceleration zero at every valley \
             (what carrying acceleration through corners can gain at most is jrest - jbound)",
            1000.0 * (host_sim::bench::axis_limits(&cfg).1.iter().fold(0.0f64, |m, &a| m.max(a))
                / (4.0 * jmax.max(1.0)))
            .clamp(0.002, 0.05)
        );
    }
    print!(
        "{:<44} {:>8} {:>8} {:>6} {:>8} {:>8} {:>6} | {:>14} | {:>14} | {:>14} | {:>14} | {:>11} | {:>14} | {:>14}",
        "job",
        "burin s",
        "bound s",
        "ratio",
        "+curv s",
        "GRBL s",
        "/GRBL",
        "peak v % X/Y/Z",
        "peak a % X/Y/Z",
        "curv % X/Y/Z",
        "peak j % X/Y/Z",
        "short X/Y/Z",
        "bound a %",
        "bound curv %"
    );
    if scurve {
        print!(
            " | {:>9} {:>7} {:>7} {:>8}",
            "jbound s", "/jbound", "seg j %", "jrest s"
        );
    }
    println!();
    let mut corpus = Totals {
        all_grbl: true,
        ..Default::default()
    };
    let mut own = Totals::default();
    let mut failed = 0;
    for (name, source) in &jobs {
        let source = match source {
            Ok(s) => s,
            Err(e) => {
                println!("{name:<44} skipped ({e})");
                continue;
            }
        };
        let f: JobFigures = run_job(&cfg, source);
        let grbl = GRBL_S.iter().find(|(n, _)| n == name).map(|g| g.1);
        let tot = if name.starts_with("gen:") {
            &mut own
        } else {
            &mut corpus
        };
        let l = &f.limits;
        let pct = |v: f64, lim: f64| 100.0 * v / lim;
        let cols: [[f64; 3]; 6] = [
            std::array::from_fn(|i| pct(l.peak_vel[i], vmax[i])),
            std::array::from_fn(|i| pct(l.peak_acc[i], amax[i])),
            std::array::from_fn(|i| pct(f.curv.peak[i], amax[i])),
            std::array::from_fn(|i| pct(l.peak_jerk[i], jmax)),
            std::array::from_fn(|i| pct(f.bound_limits.peak_acc[i], amax[i])),
            std::array::from_fn(|i| pct(f.bound_curv.peak[i], amax[i])),
        ];
        for (w, c) in tot.worst.iter_mut().zip(&cols) {
            for i in 0..3 {
                w[i] = w[i].max(c[i]);
            }
        }
        let short = l.short_intervals;
        print!(
            "{:<44} {:>8.2} {:>8.2} {:>6.3} {:>8.2} {:>8} {:>6} | {} | {} | {} | {} | {:>3} {:>3} {:>3} | {} | {}",
            name,
            f.time_s,
            f.bound_s,
            f.time_s / f.bound_s.max(1e-9),
            f.curved_ref_s,
            grbl.map_or("-".into(), |g| format!("{g:.2}")),
            grbl.map_or("-".into(), |g| format!("{:.3}", f.time_s / g)),
            three(cols[0]),
            three(cols[1]),
            three(cols[2]),
            three(cols[3]),
            short[0],
            short[1],
            short[2],
            three(cols[4]),
            three(cols[5]),
        );
        if let Some(j) = f.jerk {
            print!(
                " | {:>9.2} {:>7.3} {:>7.0} {:>8.2}",
                j.bound_s,
                f.time_s / j.bound_s.max(1e-9),
                100.0 * j.peak / jmax.max(1e-9),
                j.rest_ref_s
            );
            tot.jbound += j.bound_s;
            tot.jrest += j.rest_ref_s;
            tot.seg_jerk = tot.seg_jerk.max(100.0 * j.peak / jmax.max(1e-9));
        }
        println!();
        if a.losses > 0 {
            print_losses(&f, a.losses);
            for (i, ax) in ["X", "Y", "Z"].iter().enumerate() {
                if f.curv.peak[i] > 0.0 {
                    let line = f.piece_lines.get(f.curv.at[i]).copied().unwrap_or(0);
                    println!("    curv {ax}: peak {:.0} % at line {line}", cols[2][i]);
                }
            }
        }
        if !f.summary.errors.is_empty() {
            failed += 1;
            for e in f.summary.errors.iter().take(3) {
                println!("    {name}:{}: error[{}]: {}", e.line, e.code, e.message);
            }
        }
        tot.time += f.time_s;
        tot.bound += f.bound_s;
        tot.curved_ref += f.curved_ref_s;
        tot.short += short.iter().sum::<u64>();
        match grbl {
            Some(g) => tot.grbl += g,
            None => tot.all_grbl = false,
        }
    }
    for (label, tot) in [
        ("total, corpus (peaks: worst job)", &corpus),
        ("total, generated", &own),
    ] {
        if tot.time == 0.0 {
            continue;
        }
        let grbl = tot.all_grbl && tot.grbl > 0.0;
        print!(
            "{:<44} {:>8.2} {:>8.2} {:>6.3} {:>8.2} {:>8} {:>6} | {} | {} | {} | {} | {:>11} | {} | {}",
            label,
            tot.time,
            tot.bound,
            tot.time / tot.bound.max(1e-9),
            tot.curved_ref,
            if grbl {
                format!("{:.2}", tot.grbl)
            } else {
                "-".into()
            },
            if grbl {
                format!("{:.3}", tot.time / tot.grbl)
            } else {
                "-".into()
            },
            three(tot.worst[0]),
            three(tot.worst[1]),
            three(tot.worst[2]),
            three(tot.worst[3]),
            tot.short,
            three(tot.worst[4]),
            three(tot.worst[5]),
        );
        if scurve {
            print!(
                " | {:>9.2} {:>7.3} {:>7.0} {:>8.2}",
                tot.jbound,
                tot.time / tot.jbound.max(1e-9),
                tot.seg_jerk,
                tot.jrest
            );
        }
        println!();
    }
    if failed > 0 {
        println!("{failed} job(s) reported errors");
        return Ok(1);
    }
    Ok(0)
}

fn three(v: [f64; 3]) -> String {
    format!("{:>4.0} {:>4.0} {:>4.0}", v[0], v[1], v[2])
}

fn print_losses(f: &JobFigures, n: usize) {
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
    for l in f.losses.iter().take(n) {
        println!(
            "    line {:>6} {:>7?} {:>5} pieces: lost {:>8.4} s over the bound's {:>8.4} s",
            l.line, l.kind, l.pieces, l.lost_s, l.bound_s
        );
    }
}
