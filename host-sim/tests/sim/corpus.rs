//! Every corpus job that interprets cleanly simulates to its exact final
//! position in steps, and its trace keeps the rate, acceleration, path and
//! pin-timing properties.
use crate::common;
use std::path::PathBuf;

use burin::command::Command;
use burin::interp::Interpreter;
use common::*;
use host_sim::engine::run_job;

fn corpus_dir() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/corpus");
    d.is_dir().then_some(d)
}

/// Interprets the whole job; `None` if any line fails or the job's end
/// depends on the machine (homing, probing, a tool change's moves).
fn expected_end(src: &str) -> Option<([f32; burin::AXES], usize)> {
    let mut it = Interpreter::new();
    let mut end = [0.0f32; burin::AXES];
    let mut n = 0usize;
    let mut depends = false;
    for line in src.lines() {
        let mut ok = true;
        it.execute_line(line.as_bytes(), &mut |c: Command| {
            if matches!(
                c,
                Command::Home { .. }
                    | Command::VerifyHome { .. }
                    | Command::Probe { .. }
                    | Command::ToolChange { .. }
            ) {
                depends = true;
            }
            if let Some(e) = c.end() {
                end = *e;
                n += 1;
            }
        })
        .map_err(|_| ok = false)
        .ok();
        if !ok {
            return None;
        }
    }
    (!depends).then_some((end, n))
}

/// Jobs whose per-axis acceleration is known to exceed the limit where
/// the path check sees no corner, and by how much the check lets them
/// (issue 12, open: junction deviation bounds the path's velocity jump, not
/// each axis's). `linuxcnc-tp/Cereal.ngc` runs since G43 exists (issue 14):
/// Z reverses between short 3-D moves whose corners the stepped path
/// registers 70-150 ms away (up to 130 mm/s² against 109.5 allowed here);
/// `cargo xtask bench-motion` shows its Z peak at 160 % of the limit over
/// 50 ms windows (163 % before the issue-12 planner changes).
const KNOWN_ACCEL: &[(&str, f64)] = &[("linuxcnc-tp/Cereal.ngc", 1.7)];

/// One job: its summary line, or `None` when it was skipped.
fn check_job(cfg: &host_sim::config::MachineConfig, rel: &str, src: &str) -> Option<String> {
    let (end, moves) = expected_end(src)?;
    if moves == 0 {
        return None;
    }
    let mut rec = Collect::default();
    let s = run_job(cfg, src, &mut rec);
    let info = rec.info.clone().unwrap();
    assert!(
        s.errors.is_empty(),
        "{rel}: {:?}",
        &s.errors[..s.errors.len().min(3)]
    );
    assert_eq!(s.final_position_steps, expected_steps(&info, end), "{rel}");
    assert_eq!(s.planner_underruns, 0, "{rel}");
    let rate = check_max_rate(&info, &rec.events);
    let (dev, corners) = check_path(&info, cfg.start_position_mm, &rec.path, &rec.events, 0.0);
    let slack = KNOWN_ACCEL.iter().find(|k| k.0 == rel).map_or(1.0, |k| k.1);
    let acc = check_max_accel_within(
        &info,
        &rec.events,
        &corners,
        cfg.settings.junction_deviation as f64,
        slack,
    );
    check_pin_timing(&info, &rec.events);
    Some(format!(
        "{rel}: {} moves, {} step events, {:.1} s simulated, rate {rate:.3}, accel {acc:.3}, path dev {dev:.4} mm",
        s.moves,
        rec.events.len(),
        s.job_time_s
    ))
}

/// The jobs are independent: one worker per core takes the next (CI's
/// step runs alone on 2 cores, and this test is most of it).
#[test]
fn corpus_jobs_end_exactly_and_keep_limits() {
    let Some(dir) = corpus_dir() else {
        println!("corpus not found next to the workspace: skipped");
        return;
    };
    let manifest = std::fs::read_to_string(dir.join("MANIFEST.tsv")).unwrap();
    let cfg = config();
    let jobs: Vec<(String, String)> = manifest
        .lines()
        .skip(1)
        .filter_map(|row| {
            let rel = row.split('\t').next()?;
            let src = std::fs::read_to_string(dir.join(rel)).ok()?;
            Some((rel.to_string(), src))
        })
        .collect();
    // Longest first, so the last job to start is a short one.
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(jobs[i].1.len()));
    let results = host_sim::par::each_core(&order, |i| {
        let (rel, src) = &jobs[i];
        check_job(&cfg, rel, src)
    });
    let (mut ran, mut skipped) = (0, 0);
    for line in results {
        match line {
            Some(l) => {
                println!("{l}");
                ran += 1;
            }
            None => skipped += 1,
        }
    }
    println!("corpus: {ran} jobs simulated, {skipped} skipped (interpreter errors or machine-dependent end)");
    assert!(ran > 0);
}
