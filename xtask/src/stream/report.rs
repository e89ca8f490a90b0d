//! `cargo xtask stream --eta-report DIR [--speed N]`: how good the ETA is.
//! Each job in DIR is streamed, without a terminal, to a fresh virtual
//! board (`sim --pty --speed N`); the ETA shown when 10, 50 and 90 % of
//! the running time had passed is compared with the time that was really
//! left then. Slow on purpose: it runs every job in (scaled) real time.
//! Status is asked again as soon as it is answered: a 0.14 s job (2.8 s at
//! `--speed 20`) leaves 14 ms at 90 %, and 2 % of that is less than the
//! 5 ms a fixed poll would add to seeing its end; at real speed the
//! streamer's 50 ms poll is the same share of the job as 2.5 ms here.

use super::{job::Job, stream_file, Options, Outcome};
use anyhow::{bail, Context, Result};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

pub fn run(dir: &Path, speed: f64) -> Result<i32> {
    let mut jobs: Vec<_> = std::fs::read_dir(dir)
        .with_context(|| format!("listing {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("ngc" | "nc" | "gcode")
            )
        })
        .collect();
    jobs.sort();
    let exe = std::env::current_exe()?;
    println!("ETA against the real time left, sim --pty --speed {speed}, status queried continuously (one query in flight)");
    println!("| job | sim s | wall s | at 10 %: ETA / real s (err) | at 50 % | at 90 % |");
    println!("|---|---:|---:|---|---|---|");
    let mut worst: f64 = 0.0;
    let (mut within, mut points) = (0, 0);
    for path in &jobs {
        let mut sim = Command::new(&exe)
            .args(["sim", "--pty", "--speed", &speed.to_string()])
            .stdout(Stdio::piped())
            .spawn()
            .context("starting sim --pty")?;
        let mut first = String::new();
        if let Some(out) = sim.stdout.take() {
            BufReader::new(out).read_line(&mut first)?;
        }
        let port = first.trim().to_string();
        let source = std::fs::read_to_string(path)?;
        let name = path
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into());
        let opts = Options {
            check: false,
            resume_pauses: true,
            eta: true,
            interactive: false,
            status_every: Duration::ZERO,
        };
        let result = stream_file(&port, Job::new(name.clone(), &source), &source, &opts);
        let _ = sim.kill();
        let _ = sim.wait();
        let (outcome, sum) = result?;
        if outcome != Outcome::Done {
            bail!("{name}: ended {outcome:?}");
        }
        let run_s = sum.wall_s - sum.paused_s;
        let mut cells = Vec::new();
        for frac in [0.1, 0.5, 0.9] {
            let at = frac * run_s;
            match sum.samples.iter().find(|(a, _)| *a >= at) {
                Some(&(a, eta)) => {
                    let real = run_s - a;
                    let err = (eta - real) / real * 100.0;
                    worst = worst.max(err.abs());
                    points += 1;
                    if err.abs() <= 2.0 {
                        within += 1;
                    }
                    cells.push(format!("{eta:.2} / {real:.2} ({err:+.1} %)"));
                }
                None => cells.push("-".into()),
            }
        }
        println!(
            "| {name} | {:.1} | {run_s:.2} | {} |",
            sum.simulated_s.unwrap_or(0.0),
            cells.join(" | ")
        );
    }
    println!("within 2 %: {within} of {points} points; worst |error|: {worst:.1} %");
    Ok(0)
}
