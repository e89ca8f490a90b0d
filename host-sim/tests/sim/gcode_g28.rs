//! `$210` (issue 14): what G28/G30 mean, through the virtual board and in
//! check mode. A file shaped like Fusion 360's GRBL post output used to
//! stop at `G28 G91 Z0` with `error 409 homing is disabled`.
use crate::common;
use crate::rig;

use common::*;
use host_sim::engine::run_job;

const FUSION: &str = include_str!("../data/rs274/fusion_g28.ngc");

#[test]
fn fusion_post_runs_to_the_end_by_default() {
    let cfg = config();
    assert!(!cfg.settings.g28_homes, "$210 defaults to 0");
    let mut rec = Collect::default();
    let s = run_job(&cfg, FUSION, &mut rec);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    let info = rec.info.clone().unwrap();
    // The last line's G28 returns every axis to the G28.1 point (10, 10, 5).
    assert_eq!(
        s.final_position_steps,
        expected_steps(&info, burin::pad([10.0, 10.0, 5.0, 0.0]))
    );
}

#[test]
fn beagleg_meaning_homes_and_so_needs_homing() {
    let mut cfg = config();
    cfg.settings.g28_homes = true;
    let s = run_job(&cfg, "G28 G91 Z0\nG90 G0 X1\n", &mut Collect::default());
    // Refused after the line was acknowledged: the job stops there as an
    // alarm (issue 35), and `G0 X1` never runs.
    assert_eq!(
        s.errors.iter().map(|e| e.code).collect::<Vec<_>>(),
        [protocol::codes::alarm::LATE_ERROR, 409],
        "{:?}",
        s.errors
    );
    assert_eq!(s.final_position_steps, [0; burin::AXES]);
}

#[test]
fn check_mode_interprets_with_the_machine_settings() {
    let mut out = Vec::new();
    let mut s = burin::settings::Settings::default();
    host_sim::check::check_file("t", "G28 Z0\n", true, &s, &mut out).unwrap();
    let rs274 = String::from_utf8(out).unwrap();
    assert_eq!(rs274.matches("\"kind\":\"rapid\"").count(), 2, "{rs274}");
    s.g28_homes = true;
    let mut out = Vec::new();
    host_sim::check::check_file("t", "G28 Z0\n", true, &s, &mut out).unwrap();
    let beagleg = String::from_utf8(out).unwrap();
    assert!(beagleg.contains("\"kind\":\"home\""), "{beagleg}");
}

#[test]
fn machine_file_key_sets_210() {
    let dir = std::env::temp_dir().join(format!("burin-g28-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("m.toml");
    std::fs::write(&p, "[gcode]\ng28_meaning = \"beagleg\"\n").unwrap();
    let cfg = host_sim::config::MachineConfig::load(&p).unwrap();
    assert!(cfg.settings.g28_homes);
    std::fs::write(&p, "[gcode]\ng28_meaning = \"grbl\"\n").unwrap();
    assert!(host_sim::config::MachineConfig::load(&p).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Through the device session: operator text reaches the sender as
/// `[MSG:]` before the line's `ok`; heaters are a GRBL error (20).
#[test]
fn device_prints_messages_and_refuses_heaters() {
    let cfg = rig::origin();
    let mut rec = host_sim::record::Discard;
    let mut r = rig::Rig::new(&cfg, &mut rec);
    r.lines();
    assert_eq!(r.cmd("#1=12.5"), ["ok"]);
    assert_eq!(r.cmd("#1"), ["[MSG:#1=12.5]", "ok"]);
    assert_eq!(r.cmd("M10"), ["[MSG:M10: vacuum not fitted]", "ok"]);
    assert_eq!(r.cmd("(MSG, hello)"), ["[MSG:hello]", "ok"]);
    assert_eq!(r.cmd("M109 S200"), ["error:20"]);
}
