//! Every input that ever broke a fuzz target (kept minimised in
//! `firmware/fuzz/regressions/<target>/`) replayed through the same checks
//! (`host_sim::fuzz`), on stable, with no fuzzer. Also a smoke run of every
//! target over the project's own jobs, so the checks themselves stay sound.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("repo root")
}

#[test]
fn fuzz_regressions_replay() {
    let mut n = 0;
    for (name, f) in host_sim::fuzz::TARGETS {
        let dir = root().join("firmware/fuzz/regressions").join(name);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<_> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        for p in files {
            if p.file_name()
                .is_some_and(|f| f.to_string_lossy().starts_with('.'))
            {
                continue;
            }
            let data = std::fs::read(&p).expect("read regression input");
            eprintln!("{name}: {}", p.display());
            f(&data);
            n += 1;
        }
    }
    eprintln!("{n} regression inputs replayed");
}

#[test]
fn fuzz_targets_accept_project_jobs() {
    let dir = root().join("host-sim/jobs");
    for e in std::fs::read_dir(dir).expect("jobs").flatten() {
        let data = std::fs::read(e.path()).expect("job");
        let head = &data[..data.len().min(2000)];
        for (name, f) in host_sim::fuzz::TARGETS {
            eprintln!("{name}: {}", e.path().display());
            f(head);
        }
    }
}

/// Each starting state of `gcode_line` is valid G-code on its own.
#[test]
fn fuzz_gcode_line_preludes() {
    for i in 0..=255u8 {
        host_sim::fuzz::gcode_line(&[i]);
    }
}

/// Runs `text` with the device and executor targets' envelope check (no
/// step outside the box of the committed moves, plus one step) on the
/// default machine (80 steps/mm); returns the step events checked.
fn envelope(text: &str, max_s: f64) -> u64 {
    let cfg = host_sim::config::MachineConfig::default();
    host_sim::fuzz::envelope::run_gcode(&cfg, text.as_bytes(), max_s).0
}

/// The envelope check passes in-bounds programs: arcs of both directions,
/// and of more than half a turn, full circles and helices, a G5 spline
/// that swings past its end, rapids, lines and a canned cycle, the
/// project's jobs and the first lines of every file in `../shared/corpus`
/// (when it is there), so a finding of it is a runaway, not the check.
#[test]
fn envelope_passes_in_bounds_programs() {
    let arcs = "G21 G90 G17 G0 X-50 Y-50 Z-5\nG2 X-40 Y-50 R5 F900\n\
                G3 X-50 Y-50 R-5\nG2 X-50 Y-50 I5 J0\nG3 X-50 Y-50 Z-7 I0 J5 P2\n\
                G18 G2 X-45 Z-7 I2.5 K0\nG19 G3 Y-40 Z-7 J5 K0\nG17\n\
                G5 I20 J5 P-10 Q5 X-40 Y-40\nG1 X-60 F1500\n\
                G81 X-70 Y-70 Z-8 R-6 F300\nG80\nG0 X-1 Y-1 Z-1\n";
    let n = envelope(arcs, 60.0);
    assert!(n > 5_000, "only {n} step events checked");
    let mut files = Vec::new();
    files_under(&root().join("host-sim/jobs"), &mut files);
    let shared = root().join("../shared/corpus");
    if shared.is_dir() {
        files_under(&shared, &mut files);
    } else {
        eprintln!("{}: not found, skipped", shared.display());
    }
    for p in files {
        let Ok(text) = std::fs::read_to_string(&p) else {
            continue;
        };
        let head: String = text.lines().take(150).flat_map(|l| [l, "\n"]).collect();
        let n = envelope(&head, 20.0);
        eprintln!("envelope: {}: {n} step events", p.display());
    }
}

fn files_under(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("a directory")
        .flatten()
        .map(|e| e.path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files_under(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// Homing (G28 with `$210=1`, switches at 0: seek, pull-off, the position
/// redefined), probing that trips and ramps down past the plate, and
/// moves after both stay in the envelope.
#[test]
fn envelope_passes_homing_and_probing() {
    use host_sim::config::{LimitSwitch, ProbeSurface};
    let mut cfg = host_sim::config::MachineConfig::default();
    let sw = Some(LimitSwitch {
        trip_mm: 0.0,
        hysteresis_mm: 0.05,
    });
    cfg.limits = burin::pad([sw, sw, sw, None]);
    cfg.probe = Some(ProbeSurface {
        axis: 2,
        trip_mm: -20.0,
        towards_negative: true,
    });
    cfg.settings.homing_enable = true;
    cfg.settings.g28_homes = true;
    cfg.start_position_mm = burin::pad([-40.0, -30.0, -10.0, 0.0]);
    let prog = "G21 G90\nG28\nG0 X-20 Y-20 Z-5\nG38.2 Z-30 F300\nG0 Z-5\n\
                G38.3 Z-25 F600\nG0 Z-2\nG1 X-30 Y-10 F2000\nG28 X\nG0 X-5 Y-5\n";
    let (n, errors) = host_sim::fuzz::envelope::run_gcode(&cfg, prog.as_bytes(), 30.0);
    assert!(errors.is_empty(), "{errors:?}");
    assert!(n > 10_000, "only {n} step events checked");
}

/// On the virtual board: jogs, a jog cancel and a soft reset mid-move (the
/// moves they cut short stay in the window), `$X` and a move after, with
/// the device target's envelope recorder; every step is checked.
#[test]
fn envelope_passes_jogs_and_resets_on_the_board() {
    use host_sim::fuzz::envelope::{Envelope, EnvelopeRec};
    use std::cell::RefCell;
    let cfg = host_sim::config::MachineConfig::default();
    let env = RefCell::new(Envelope::new(cfg.settings.axes.map(|a| a.steps_per_mm)));
    let mut rec = EnvelopeRec(&env);
    let mut dev = host_sim::device_sim::VirtualDevice::new(&cfg, &mut rec);
    env.borrow_mut().settle(dev.position_steps());
    let ms = u64::from(cfg.tick_hz) / 1000;
    let wait = |dev: &mut host_sim::device_sim::VirtualDevice, t: u64| {
        let end = dev.sim.now() + t * ms;
        dev.advance_to(end);
    };
    for (bytes, t) in [
        (&b"$J=G91 X-20 F1200\n"[..], 300),
        (&[0x85][..], 500),
        (&b"$J=G91 Y-10 Z-5 F900\n"[..], 200),
        (&[0x18][..], 300),
        (&b"$X\n"[..], 50),
        (&b"G90 G0 X-30 Y-30\nG2 X-20 Y-30 R5 F1500\n"[..], 4000),
    ] {
        dev.receive(bytes);
        wait(&mut dev, t);
    }
    let out = String::from_utf8_lossy(&dev.take_output()).to_string();
    assert!(out.contains("ALARM:3"), "the reset met no motion: {out}");
    assert_eq!(dev.position_steps()[..2], [-1600, -2400], "{out}");
    let n = env.borrow().checked;
    assert!(n > 3_000, "only {n} step events checked");
}

/// Issue 35's runaway as reported (on 80 steps/mm the 0.01 mm chord does
/// not round to the start's steps): the arc leaves its box (the chord and
/// its sagitta) at once when run as a 30 m circle.
#[test]
fn issue_35_short_arc_on_a_huge_radius_stays_in_its_box() {
    for arc in [
        "G2 X0.01 Y0 R30000",
        "G2 X0.01 Y0 I0.005 J-30000",
        "G3 X0.01 Y0 I0.005 J30000",
    ] {
        envelope(
            &format!("G21 G90 G53 G0 X-150 Y-150\nG17 G91 {arc} F600\n"),
            5.0,
        );
    }
}

/// The runaway seeds of the fuzz targets (`xtask/src/fuzz_seeds.rs`
/// `RUNAWAY`, kept as inputs in `firmware/fuzz/known/<target>/`) pass the
/// targets' checks (they are in `firmware/fuzz/regressions/<target>/`
/// since the arc fix; `known/` is read too).
#[test]
fn fuzz_arc_runaway_seeds_stay_in_their_box() {
    let mut n = 0;
    for name in ["device", "executor"] {
        let f = host_sim::fuzz::target(name).expect("target");
        for kind in ["known", "regressions"] {
            let dir = root().join("firmware/fuzz").join(kind).join(name);
            // Git keeps no empty directory: `known/<target>` exists only
            // while a finding there is open.
            let Ok(entries) = std::fs::read_dir(&dir) else {
                assert_eq!(kind, "known", "{} missing", dir.display());
                continue;
            };
            for e in entries.flatten() {
                if e.file_name().to_string_lossy().starts_with("arc-runaway") {
                    eprintln!("{name}: {}", e.path().display());
                    f(&std::fs::read(e.path()).expect("input"));
                    n += 1;
                }
            }
        }
    }
    assert_eq!(n, 6, "runaway inputs replayed");
}
