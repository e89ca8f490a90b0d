//! Backlash compensation through the motion gateway (issue 32, item 3) on
//! `machines/backlash.toml`: 0.1 mm of modelled slack on X and Y, and
//! `$160=$161=0.1`. The job (`jobs/backlash.gcode`) reverses X or Y at
//! every move, lines and arcs.

use burin::AXES;
use host_sim::bench::limits::LimitMeter;
use host_sim::config::MachineConfig;
use host_sim::offline::{run_file, run_file_watched};
use host_sim::record::{PathKind, Recorder, Tee};

fn file(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn machine() -> MachineConfig {
    MachineConfig::load(file("machines/backlash.toml")).unwrap()
}

fn job() -> String {
    std::fs::read_to_string(file("jobs/backlash.gcode")).unwrap()
}

#[test]
fn compensated_slack_keeps_the_tool_within_0_02_mm_of_the_path() {
    let cfg = machine();
    assert_eq!(cfg.slack_mm[..2], [0.1, 0.1]);
    assert_eq!(cfg.settings.backlash_mm[..2], [0.1, 0.1]);
    let s = run_file(&cfg, &job(), &mut host_sim::record::Discard);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert!(
        s.max_tool_deviation_mm <= 0.02,
        "{} mm",
        s.max_tool_deviation_mm
    );
    // The reported position is the commanded end: no take-up in it.
    assert_eq!(s.final_work_position_mm, [0.0; AXES]);
    assert_eq!(s.final_position_steps, [0; AXES]);
}

#[test]
fn without_compensation_the_tool_strays_by_the_slack() {
    let src = format!("$160=0\n$161=0\n{}", job());
    let s = run_file(&machine(), &src, &mut host_sim::record::Discard);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert!(
        (0.08..=0.12).contains(&s.max_tool_deviation_mm),
        "{} mm",
        s.max_tool_deviation_mm
    );
    assert_eq!(s.final_work_position_mm, [0.0; AXES]);
}

/// Commanded path vertices as the executor planned them (arcs as chords).
#[derive(Default)]
struct Path(Vec<[f32; AXES]>);
impl Recorder for Path {
    fn commanded(&mut self, _line: u32, _kind: PathKind, to_mm: [f32; AXES]) {
        self.0.push(to_mm);
    }
}

fn seg_dist(p: [f64; 2], a: [f32; AXES], b: [f32; AXES]) -> f64 {
    let (a, b) = ([a[0] as f64, a[1] as f64], [b[0] as f64, b[1] as f64]);
    let ab = [b[0] - a[0], b[1] - a[1]];
    let l2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = [a[0] + t * ab[0], a[1] + t * ab[1]];
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
}

/// The status report's position (`MPos`, every round of the virtual
/// board) stays on the commanded path while the motors take up the slack
/// at each reversal, and the motors end the job a take-up away from it.
/// The take-up moves keep each axis's rate and acceleration limits and
/// step no faster than `$201`.
#[test]
fn take_ups_show_in_no_report_and_keep_the_axis_limits() {
    let cfg = machine();
    let mut path = Path::default();
    let mut meter = LimitMeter::new(cfg.settings.max_step_rate_hz);
    let mut reported: Vec<[i32; AXES]> = Vec::new();
    let s = {
        let mut tee = Tee(vec![&mut path, &mut meter]);
        run_file_watched(&cfg, &job(), &mut tee, &mut |p| reported.push(p.steps))
    };
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    let spm = cfg.settings.axes.map(|a| f64::from(a.steps_per_mm));
    let mut pts = vec![[0.0f32; AXES]];
    pts.extend(path.0);
    let mut worst = 0.0f64;
    for r in &reported {
        let p = [f64::from(r[0]) / spm[0], f64::from(r[1]) / spm[1]];
        let d = pts
            .windows(2)
            .map(|w| seg_dist(p, w[0], w[1]))
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(d);
    }
    assert!(reported.len() > 100, "{} reports", reported.len());
    // A step's rounding on each axis, nothing of the 0.1 mm take-ups.
    assert!(worst <= 0.01, "a report {worst} mm off the path");
    // The last moves go towards -X and -Y: the motors stand 0.1 mm (16
    // steps) beyond the reported end on both.
    let l = &meter.out;
    assert_eq!(l.end_steps[..2], [-16, -16]);
    assert_eq!(s.final_position_steps, [0; AXES]);
    assert_eq!(l.short_intervals, [0; AXES]);
    for i in 0..2 {
        let ax = &cfg.settings.axes[i];
        let (v, a) = (f64::from(ax.max_rate) / 60.0, f64::from(ax.max_accel));
        assert!(
            l.peak_vel[i] <= v * 1.02,
            "axis {i}: {} mm/s",
            l.peak_vel[i]
        );
        assert!(
            l.peak_acc[i] <= a * 1.05,
            "axis {i}: {} mm/s²",
            l.peak_acc[i]
        );
    }
}

#[test]
fn json_reports_the_deviation_and_machine_files_check_the_keys() {
    let s = run_file(&machine(), &job(), &mut host_sim::record::Discard);
    let mut out = Vec::new();
    let info = machine().run_info();
    host_sim::report::write_json(&mut out, &info, &s).unwrap();
    let j: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let d = j["max_tool_deviation_mm"].as_f64().unwrap();
    assert_eq!(d, s.max_tool_deviation_mm);
    assert!(d > 0.0 && d <= 0.02, "{d}");
    for (text, key) in [
        ("[axes.x]\nslack_mm = -0.1", "axes.x.slack_mm"),
        ("[axes.y]\nbacklash_mm = 11", "axes.y.backlash_mm"),
    ] {
        let e = MachineConfig::from_toml_str(text).unwrap_err().to_string();
        assert!(e.contains(key), "{e}");
    }
}

/// Homing (its pull-off reverses each axis), a probe and reversals on the
/// default machine with switches: with the slack compensated the tool
/// keeps to the path as well as on a machine without slack, and the job
/// ends where it was commanded.
#[test]
fn homing_and_probing_with_backlash_end_where_commanded() {
    let src = "$H\nG21 G90 G17 G94\nG1 X-10 Y-10 F1200\nG1 X-2 Y-4\nG1 X-10 Y-8\n\
               G2 X-10 Y-16 I0 J-4\nG1 X-5 Y-5\nG38.2 Z-60 F100\nG0 Z-1\nG1 X-1 Y-1\n";
    let mut plain = MachineConfig::default();
    plain.settings.homing_enable = true;
    let mut slack = plain.clone();
    slack.slack_mm = burin::pad([0.1, 0.1, 0.0, 0.0]);
    slack.settings.backlash_mm = burin::pad([0.1, 0.1, 0.0, 0.0]);
    let p = run_file(&plain, src, &mut host_sim::record::Discard);
    let s = run_file(&slack, src, &mut host_sim::record::Discard);
    for r in [&p, &s] {
        assert!(r.errors.is_empty(), "{:?}", r.errors);
        assert_eq!(r.final_position_mm, burin::pad([-1.0, -1.0, -1.0, 0.0]));
    }
    assert!(
        s.max_tool_deviation_mm <= p.max_tool_deviation_mm + 0.002,
        "{} mm with slack, {} mm without",
        s.max_tool_deviation_mm,
        p.max_tool_deviation_mm
    );
    // Compensated: the motors took the slack up (more steps on X and Y).
    assert!(s.steps[0] > p.steps[0] && s.steps[1] > p.steps[1]);
}
