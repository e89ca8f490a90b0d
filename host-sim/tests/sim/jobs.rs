//! The bundled sample jobs run cleanly on the machines they were written for
//! and stay inside those machines' envelopes.

use std::path::Path;

use burin::AXES;
use host_sim::config::MachineConfig;
use host_sim::record::{PinEvent, Recorder};

/// Tracks the extent of the stepped path, in steps.
struct Extent {
    lo: [i64; AXES],
    hi: [i64; AXES],
}

impl Recorder for Extent {
    fn step_event(&mut self, ev: &PinEvent) {
        for i in 0..AXES {
            self.lo[i] = self.lo[i].min(ev.pos[i]);
            self.hi[i] = self.hi[i].max(ev.pos[i]);
        }
    }
}

fn run(job: &str, machine: Option<&str>) -> (MachineConfig, host_sim::record::Summary, Extent) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cfg = match machine {
        Some(m) => MachineConfig::load(dir.join("machines").join(m)).unwrap(),
        None => MachineConfig::default(),
    };
    let src = std::fs::read_to_string(dir.join("jobs").join(job)).unwrap();
    let mut ext = Extent {
        lo: [i64::MAX; AXES],
        hi: [i64::MIN; AXES],
    };
    let s = host_sim::engine::run_job(&cfg, &src, &mut ext);
    assert!(s.errors.is_empty(), "{job}: {:?}", s.errors);
    (cfg, s, ext)
}

/// Every axis that moved stayed within `[lo_mm, hi_mm]`.
fn assert_within(cfg: &MachineConfig, ext: &Extent, lo_mm: [f32; 3], hi_mm: [f32; 3]) {
    for i in 0..3 {
        let spm = cfg.settings.axes[i].steps_per_mm;
        let (lo, hi) = (ext.lo[i] as f32 / spm, ext.hi[i] as f32 / spm);
        assert!(lo >= lo_mm[i] && hi <= hi_mm[i], "axis {i}: [{lo}, {hi}]");
    }
}

#[test]
fn demo_runs_inside_the_default_machine() {
    let (cfg, s, ext) = run("demo.gcode", None);
    assert_eq!(s.final_work_position_mm[..3], [0.0, 200.0, 5.0]);
    assert!(s.moves > 40 && s.distance_mm > 1000.0);
    // Envelope after homing to + : [-travel, 0].
    assert_within(&cfg, &ext, [-300.0, -300.0, -100.0], [0.0, 0.0, 0.0]);
}

#[test]
fn plotter_job_runs_on_the_plotter() {
    let (cfg, s, ext) = run("plotter.gcode", Some("plotter.toml"));
    assert_eq!(s.final_position_mm[..3], [5.0, 5.0, 3.0]);
    assert_within(&cfg, &ext, [0.0, 0.0, 0.0], [420.0, 297.0, 10.0]);
}

#[test]
fn laser_job_runs_on_the_laser() {
    let (cfg, s, ext) = run("laser.gcode", Some("laser.toml"));
    assert_eq!(s.final_work_position_mm[..2], [5.0, 5.0]);
    assert_within(&cfg, &ext, [0.0, -400.0, -40.0], [400.0, 0.0, 0.0]);
}

#[test]
fn simulate_writes_every_requested_file() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("simulate-demo");
    std::fs::create_dir_all(&dir).unwrap();
    let src =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs/demo.gcode"))
            .unwrap();
    let out = host_sim::outputs::Outputs {
        json: Some(dir.join("demo.json")),
        trace: Some(dir.join("demo.csv")),
        vcd: Some(dir.join("demo.vcd")),
        plot: Some(dir.join("demo.svg")),
    };
    let s =
        host_sim::outputs::simulate(&MachineConfig::default(), &src, "demo.gcode", &out).unwrap();
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("demo.json")).unwrap()).unwrap();
    assert_eq!(json["steps"][0].as_u64(), Some(s.steps[0]));
    let csv = std::fs::read_to_string(dir.join("demo.csv")).unwrap();
    let names: String = burin::AXIS_NAMES.iter().map(|c| format!(",{c}")).collect();
    assert!(csv.starts_with(&format!("tick{names}\n")));
    let last: Vec<i64> = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .skip(1)
        .map(|f| f.parse().unwrap())
        .collect();
    assert_eq!(last, s.final_position_steps);
    let vcd = std::fs::read_to_string(dir.join("demo.vcd")).unwrap();
    assert!(vcd.contains("$enddefinitions $end"));
    let svg = std::fs::read_to_string(dir.join("demo.svg")).unwrap();
    assert!(svg.trim_end().ends_with("</svg>"));
}

#[test]
fn simulate_names_a_file_it_cannot_create() {
    let out = host_sim::outputs::Outputs {
        plot: Some("/nonexistent-dir/plot.svg".into()),
        ..Default::default()
    };
    let e = host_sim::outputs::simulate(&MachineConfig::default(), "G0 X1", "x", &out).unwrap_err();
    assert!(e.to_string().contains("/nonexistent-dir/plot.svg"), "{e}");
}

#[cfg(target_os = "linux")]
#[test]
fn simulate_reports_a_write_error_with_its_file() {
    let src =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("jobs/demo.gcode"))
            .unwrap();
    let out = host_sim::outputs::Outputs {
        trace: Some("/dev/full".into()),
        ..Default::default()
    };
    let e = host_sim::outputs::simulate(&MachineConfig::default(), &src, "demo", &out).unwrap_err();
    assert!(e.to_string().starts_with("/dev/full: "), "{e}");
}

/// `machines/six-axis.toml` with `jobs/six-axis.gcode` (issue 32): on a
/// six-axis build `--json`'s `final_work_position_mm` holds all six
/// commanded positions; a build with fewer axes refuses the machine file
/// by its first letter past them instead of running it on fewer.
#[test]
fn six_axis_job_ends_on_all_six_commanded_positions() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let loaded = MachineConfig::load(dir.join("machines").join("six-axis.toml"));
    if AXES < 6 {
        let e = loaded.map(|_| ()).unwrap_err().to_string();
        let first = protocol::ALL_AXIS_NAMES
            .get(AXES)
            .map_or('?', char::to_ascii_lowercase);
        assert!(e.contains(&format!("`axes.{first}`")), "{e}");
        return;
    }
    let (cfg, s, _) = run("six-axis.gcode", Some("six-axis.toml"));
    let mut json = Vec::new();
    host_sim::report::write_json(&mut json, &cfg.run_info(), &s).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&json).unwrap();
    let end: Vec<f64> = v["final_work_position_mm"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let want = [12.5, -7.25, -3.0, 270.0, -90.0, 120.0];
    assert_eq!(end.len(), want.len(), "{end:?}");
    for (got, want) in end.iter().zip(want) {
        assert!((got - want).abs() < 1e-3, "{end:?}");
    }
}

/// `$376` on the six-axis machine (A, B, C rotary): `G1 X10 A30 F600`
/// takes X's 10 mm at 600 mm/min, about 1 s plus A's ramps, with A
/// following at 30 deg/s (within its 60); counted along the whole 31.6
/// mm-or-degree path, as GRBL does, it took 3.2 s.
#[test]
fn a_rotary_axis_follows_the_linear_move_s_feed() {
    if AXES < 6 {
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cfg = MachineConfig::load(dir.join("machines").join("six-axis.toml")).unwrap();
    let job = "G21 G90 G1 X10 A30 F600\n";
    let mut ext = Extent {
        lo: [i64::MAX; AXES],
        hi: [i64::MIN; AXES],
    };
    let rotary = host_sim::engine::run_job(&cfg, job, &mut ext);
    assert!(rotary.errors.is_empty(), "{:?}", rotary.errors);
    assert!(
        (1.0..1.3).contains(&rotary.job_time_s),
        "{}",
        rotary.job_time_s
    );
    cfg.settings.rotary_axes = 0;
    let linear = host_sim::engine::run_job(&cfg, job, &mut ext);
    assert!(linear.job_time_s > 3.1, "{}", linear.job_time_s);
    assert_eq!(rotary.final_position_steps, linear.final_position_steps);
}
