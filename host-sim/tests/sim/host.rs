//! The host model: a streamed job over a finite-rate link and a parse/plan
//! task that takes time. A planner that runs empty because the next line is
//! not there yet is an underrun, counted and reported; the step timer stops
//! safely (every stop is still a planned, acceleration-limited one) and
//! starts again when the next line is in.
use crate::common;
use common::*;
use host_sim::config::{HostModel, MachineConfig};
use host_sim::engine::run_job;

/// 600 collinear one-step moves (0.0125 mm) at 5000 mm/min.
fn tiny_segments() -> String {
    let mut s = String::from("G21 G90 G94\n");
    for i in 1..=600 {
        s.push_str(&format!("G1 X{:.4} F5000\n", i as f32 * 0.0125));
    }
    s
}

/// A 9600 baud serial line: a 17-byte line takes 17.7 ms, longer than a
/// one-step move takes from rest to rest (2·sqrt(0.0125/500) = 10 ms), so
/// the planner runs empty and the machine stops before the next line is
/// in. (At 115 200 baud the look-ahead instead settles at a lower speed
/// and the stepper never runs dry: a slow host shows as lost speed first.)
fn serial(mut cfg: MachineConfig) -> MachineConfig {
    cfg.host.link_bytes_per_s = 960;
    cfg
}

fn run(cfg: &MachineConfig, src: &str) -> (Collect, host_sim::record::Summary) {
    let mut rec = Collect::default();
    let s = run_job(cfg, src, &mut rec);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    (rec, s)
}

#[test]
fn slow_link_starves_the_planner_and_is_counted() {
    let cfg = serial(config());
    let src = tiny_segments();
    let (rec, s) = run(&cfg, &src);
    println!(
        "tiny segments over 9600 baud: {} underruns, {:.3} s",
        s.planner_underruns, s.job_time_s
    );
    assert!(s.planner_underruns > 0);
    // The link bounds the job: 601 lines of ~17 bytes at 960 B/s.
    assert!(s.job_time_s > 10.0, "{}", s.job_time_s);
    // Every step is still there and every stop stayed within the limits.
    assert_eq!(s.final_position_steps[0], 600);
    let info = rec.info.as_ref().unwrap();
    check_max_rate(info, &rec.events);
    check_max_accel(info, &rec.events, &[], 0.01);
    check_pin_timing(info, &rec.events);
    // Deterministic, link and task time included.
    let (rec2, s2) = run(&cfg, &src);
    assert_eq!(s, s2);
    assert_eq!(trace_hash(&rec.events), trace_hash(&rec2.events));
}

#[test]
fn fast_host_keeps_up_with_the_same_job() {
    // Instant link, measured task cost (the default): 55 µs of task time
    // per one-step move keeps the planner full.
    let (_, s) = run(&config(), &tiny_segments());
    assert_eq!(s.planner_underruns, 0);
    let mut cfg = config();
    cfg.host = HostModel::INSTANT;
    let (_, fast) = run(&cfg, &tiny_segments());
    assert_eq!(fast.planner_underruns, 0);
    assert_eq!(fast.final_position_steps, s.final_position_steps);
}

#[test]
fn demo_job_has_no_underruns() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(dir.join("jobs/demo.gcode")).unwrap();
    let cfg = MachineConfig::default();
    let (_, s) = run(&cfg, &src);
    assert_eq!(s.planner_underruns, 0);
    let (_, slow) = run(&serial(cfg), &src);
    println!(
        "demo: {:.3} s, over 9600 baud {:.3} s with {} underruns",
        s.job_time_s, slow.job_time_s, slow.planner_underruns
    );
}
