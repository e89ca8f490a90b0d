//! run_job: G-code in, trace and summary out, through the real interpreter.
use crate::common;
use common::*;
use host_sim::engine::run_job;

const JOB: &str = "G21 G90 G17
G0 X5 Y5
G1 Z-1 F300
G1 X20 F1500
G2 X30 Y15 I0 J10
G3 X30 Y15 Z-3 I-5 J0 P2
G4 P0.2
M3 S1000
G18 G2 X40 Z-3 I5 K0
G17 G91 G1 X-10 Y-10
G90 G0 X0 Y0 Z0
M5
M30
";

#[test]
fn gcode_job_exact_and_within_limits() {
    let cfg = config();
    let mut rec = Collect::default();
    let s = run_job(&cfg, JOB, &mut rec);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert_eq!(s.lines, 13);
    assert_eq!(s.moves, 8);
    assert_eq!(s.final_position_steps, burin::pad([0, 0, 0, 0]));
    let info = rec.info.clone().unwrap();
    check_max_rate(&info, &rec.events);
    let (_, corners) = check_path(&info, [0.0; burin::AXES], &rec.path, &rec.events, 0.0);
    check_max_accel(&info, &rec.events, &corners, 0.01);
    check_pin_timing(&info, &rec.events);
    assert!(s.job_time_s > 0.2, "includes the dwell");
    assert!(s.distance_mm > 100.0, "{}", s.distance_mm);
    assert!(rec.summary.is_some(), "recorder got finish()");
}

#[test]
fn gcode_job_is_deterministic() {
    let cfg = config();
    let (mut a, mut b) = (Collect::default(), Collect::default());
    let sa = run_job(&cfg, JOB, &mut a);
    let sb = run_job(&cfg, JOB, &mut b);
    assert_eq!(sa, sb);
    assert_eq!(trace_hash(&a.events), trace_hash(&b.events));
    assert_eq!(a.velocity, b.velocity);
    assert_eq!(a.path, b.path);
}

#[test]
fn gcode_errors_carry_line_numbers_and_job_continues() {
    let cfg = config();
    let src = "G1 X10 F1000\nG1 X20 Q\nG2 X0 Y0 I0 J0\nG1 X0\n";
    let s = run_job(&cfg, src, &mut Collect::default());
    let lines: Vec<u32> = s.errors.iter().map(|e| e.line).collect();
    assert!(lines.contains(&2), "{:?}", s.errors);
    assert_eq!(s.final_position_steps, burin::pad([0, 0, 0, 0]));
}

#[test]
fn gcode_homing_and_probing_sync_the_interpreter() {
    let mut cfg = config_with_switches();
    cfg.settings.g28_homes = true; // $210=1: G28 homes (BeagleG)
    cfg.start_position_mm = burin::pad([-40.0, -40.0, -10.0, 0.0]);
    // Home, probe down to the plate at Z=-20, then a relative move from
    // wherever the probe stopped.
    let probe = "G28\nG90 G0 X-10 Y-10\nG38.2 Z-40 F600\n";
    let run = |src: &str| {
        let mut rec = Collect::default();
        let s = run_job(&cfg, src, &mut rec);
        assert!(s.errors.is_empty(), "{:?}", s.errors);
        assert_eq!(&s.final_position_steps[..2], &[-800, -800]);
        s.final_position_steps[2]
    };
    // The probe ramps down past the contact (-20 mm = -8000 steps)...
    let stop = run(probe);
    assert!(stop < -8000 && stop > -8000 - 500, "stopped at {stop}");
    // ...a relative move starts where it really stopped...
    assert_eq!(run(&format!("{probe}G91 G1 Z5 F500\nG90\n")), stop + 2000);
    // ...and #5063 holds the contact point itself.
    assert_eq!(run(&format!("{probe}G1 Z[#5063] F500\n")), -8000);
}

/// Issue 35 item 1, on the whole device: after `G53 G0 X-150 Y-150`, a
/// 0.01 mm arc on a radius of 30 m (R and I/J form, G2 and G3) ran as the
/// full 30 m circle, 188 km at F600 and still going after 1.5 s. It moves
/// its 0.01 mm and nothing else: X ends on the step of -149.99, Y never
/// leaves -150, and the job is done long before the circle would be.
#[test]
fn short_arc_on_huge_radius_moves_only_its_chord() {
    let cfg = config();
    let spm = [0, 1].map(|k| f64::from(cfg.settings.axes[k].steps_per_mm));
    let at = |mm: f64, k: usize| (mm * spm[k]).round() as i32;
    // The rapid takes under 3 s; the circle would take five hours.
    let budget = 10 * u64::from(TICK_HZ);
    for arc in [
        "G2 X0.01 Y0 R30000",
        "G2 X0.01 Y0 I0.005 J-30000",
        "G3 X0.01 Y0 R30000",
        "G3 X0.01 Y0 I0.005 J30000",
    ] {
        let src = format!("G21 G90 G53 G0 X-150 Y-150\nG17 G91 {arc} F600\n");
        let mut rec = Collect::default();
        let s = host_sim::offline::run_file_watched(&cfg, &src, &mut rec, &mut |p| {
            assert!(p.tick < budget, "{arc}: still moving at {:?}", p.steps);
            // While the arc runs, X stays on its chord and Y does not move.
            if p.line == 2 {
                assert!(
                    p.steps[0] >= at(-150.0, 0) && p.steps[0] <= at(-149.99, 0),
                    "{arc}: X at step {}",
                    p.steps[0]
                );
                assert_eq!(p.steps[1], at(-150.0, 1), "{arc}: Y moved");
            }
        });
        assert!(s.errors.is_empty(), "{arc}: {:?}", s.errors);
        assert_eq!(
            &s.final_position_steps[..2],
            &[i64::from(at(-149.99, 0)), i64::from(at(-150.0, 1))],
            "{arc}"
        );
        assert!(
            (s.final_work_position_mm[0] + 149.99).abs() < 0.5 / spm[0],
            "{arc}: {:?}",
            s.final_work_position_mm
        );
        let rapid = 150.0 * std::f64::consts::SQRT_2;
        assert!(
            (s.distance_mm - rapid - 0.01).abs() < 1e-3,
            "{arc}: {} mm",
            s.distance_mm
        );
        assert!(s.job_time_s < 5.0, "{arc}: {} s", s.job_time_s);
    }
}
