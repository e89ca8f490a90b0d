//! Machine files: the shipped samples parse, the default file is the default
//! machine, and every refusal names the key at fault.

use burin::settings::{Profile, RapidMode};
use host_sim::config::{ConfigError, MachineConfig};

fn machine(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines")
        .join(name)
}

#[test]
fn default_file_is_exactly_the_default_machine() {
    let cfg = MachineConfig::load(machine("default.toml")).unwrap();
    assert_eq!(cfg, MachineConfig::default());
}

#[test]
fn empty_file_is_the_default_machine() {
    assert_eq!(
        MachineConfig::from_toml_str("").unwrap(),
        MachineConfig::default()
    );
}

#[test]
fn default_machine_is_consistent() {
    let d = MachineConfig::default();
    d.validate().unwrap();
    assert_eq!(d.tick_hz, 96_000_000);
    assert_eq!(d.pulse_ticks(), (192, 96));
    // Homing towards +, switches at 0: power-up position is off every switch.
    for (i, sw) in d.limits.iter().enumerate() {
        if let Some(sw) = sw {
            assert!(d.start_position_mm[i] < sw.trip_mm - sw.hysteresis_mm);
        }
    }
}

#[test]
fn sample_machines_parse_and_differ() {
    let p = MachineConfig::load(machine("plotter.toml")).unwrap();
    assert_eq!(p.settings.profile, Profile::SCurve);
    assert_eq!(p.settings.homing_dir_invert, 0b0111);
    assert_eq!(p.settings.axes[0].max_rate, 12000.0);
    assert_eq!(p.probe, None);
    assert!(p.settings.soft_limits);
    let l = MachineConfig::load(machine("laser.toml")).unwrap();
    assert!(l.settings.laser_mode);
    assert_eq!(l.limits[2], None);
    assert_eq!(l.settings.homing_order, 0x3);
    // Keys a sample leaves out keep the default machine's values.
    assert_eq!(l.tick_hz, 96_000_000);
    assert_eq!(l.settings.rapid_mode, RapidMode::Coordinated);
}

#[test]
fn every_section_maps_onto_settings() {
    let cfg = MachineConfig::from_toml_str(
        r#"
        tick_hz = 84_000_000
        start_position_mm = [1, 2, 3, 4]
        [axes.z]
        steps_per_mm = 1600
        [motion]
        profile = "scurve"
        rapid_mode = "independent"
        jerk_mm_s3 = 1e4
        [pulses]
        step_invert = "xa"
        dir_invert = "Y, Z"
        [homing]
        towards_negative = "XY"
        order = ["XY", "Z", "A"]
        [limits]
        switches = "XYZA"
        a_trip_mm = 5.5
        hysteresis_mm = 0.2
        [probe]
        axis = "x"
        trip_mm = 12
        direction = "positive"
        [report]
        machine_position = false
        buffer_state = true
        "#,
    )
    .unwrap();
    let s = &cfg.settings;
    assert_eq!(cfg.tick_hz, 84_000_000);
    assert_eq!(cfg.start_position_mm, burin::pad([1.0, 2.0, 3.0, 4.0]));
    assert_eq!(s.axes[2].steps_per_mm, 1600.0);
    assert_eq!(s.axes[2].max_rate, 1000.0, "unset keys keep the default");
    assert_eq!(
        (s.profile, s.rapid_mode),
        (Profile::SCurve, RapidMode::Independent)
    );
    assert_eq!(s.jerk, 10_000.0);
    assert_eq!((s.step_invert, s.dir_invert), (0b1001, 0b0110));
    assert_eq!((s.homing_dir_invert, s.homing_order), (0b0011, 0x843));
    let a = cfg.limits[3].unwrap();
    assert_eq!((a.trip_mm, a.hysteresis_mm), (5.5, 0.2));
    assert_eq!(cfg.limits[0].unwrap().hysteresis_mm, 0.2);
    let p = cfg.probe.unwrap();
    assert_eq!((p.axis, p.trip_mm, p.towards_negative), (0, 12.0, false));
    assert_eq!(s.status_mask, 0b10);
}

fn refusal(text: &str) -> String {
    match MachineConfig::from_toml_str(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn unknown_keys_are_refused_by_name() {
    for (text, key) in [
        ("stepz_per_mm = 3", "stepz_per_mm"),
        ("[axes.x]\nsteps_per_nm = 80", "steps_per_nm"),
        ("[axes.d]\nsteps_per_mm = 80", "d"),
        ("[motion]\njunction_deviation = 0.01", "junction_deviation"),
        ("[limits]\nsoft_limits = true", "soft_limits"),
        ("[probe]\nplane = 1", "plane"),
    ] {
        let m = refusal(text);
        assert!(m.contains(&format!("`{key}`")), "{m}");
    }
}

/// A letter of grblHAL's six that this build does not drive is refused
/// by its key, not run as if the machine had fewer axes.
#[test]
fn axes_past_the_build_are_refused_by_key() {
    for c in protocol::ALL_AXIS_NAMES[burin::AXES..].iter() {
        let l = c.to_ascii_lowercase();
        let m = refusal(&format!("[axes.{l}]\nsteps_per_mm = 80"));
        assert!(m.contains(&format!("`axes.{l}`")), "{m}");
        let m = refusal(&format!("[limits]\n{l}_trip_mm = 1"));
        assert!(m.contains(&format!("`limits.{l}_trip_mm`")), "{m}");
    }
}

#[test]
fn bad_values_are_refused_by_key() {
    for (text, key) in [
        ("[axes.x]\nsteps_per_mm = -80", "axes.x.steps_per_mm"),
        ("[axes.y]\nmax_accel_mm_s2 = 0", "axes.y.max_accel_mm_s2"),
        ("[axes.z]\nmax_rate_mm_min = nan", "axes.z.max_rate_mm_min"),
        ("[axes.a]\ntravel_mm = -inf", "axes.a.travel_mm"),
        ("tick_hz = 0", "tick_hz"),
        ("[motion]\narc_tolerance_mm = 0", "motion.arc_tolerance_mm"),
        ("[pulses]\nstep_pulse_us = 10", "pulses.step_pulse_us"),
        ("[pulses]\nstep_invert = \"XQ\"", "pulses.step_invert"),
        ("[homing]\norder = [\"Z\", \"\"]", "homing.order"),
        ("[homing]\npulloff_mm = -1", "homing.pulloff_mm"),
        ("[spindle]\nmin_rpm = 2000", "spindle.min_rpm"),
        ("[limits]\nx_trip_mm = nan", "limits.x_trip_mm"),
        ("[probe]\naxis = \"xy\"", "probe.axis"),
        ("start_position_mm = [0, 0, nan, 0]", "start_position_mm"),
    ] {
        let e = MachineConfig::from_toml_str(text).unwrap_err();
        assert!(matches!(e, ConfigError::Invalid { .. }), "{text}: {e}");
        assert!(e.to_string().contains(&format!("`{key}`")), "{text}: {e}");
    }
}

#[test]
fn wrong_types_and_enum_names_are_refused_with_the_key() {
    for (text, key) in [
        ("[motion]\nprofile = \"jerky\"", "profile"),
        ("[motion]\nrapid_mode = 1", "rapid_mode"),
        ("[axes.x]\nsteps_per_mm = \"80\"", "steps_per_mm"),
        ("tick_hz = -5", "tick_hz"),
        ("start_position_mm = [0, 0]", "start_position_mm"),
        (
            "start_position_mm = [0, 0, 0, 0, 0, 0, 0]",
            "start_position_mm",
        ),
    ] {
        let m = refusal(text);
        assert!(m.contains(key), "{text}: {m}");
    }
}

/// A machine file written for X Y Z A runs on a build of any axis count:
/// the axes it leaves out start at 0.
#[test]
fn a_start_position_of_fewer_axes_is_padded() {
    let cfg = MachineConfig::from_toml_str("start_position_mm = [1, 2, 3]").unwrap();
    assert_eq!(cfg.start_position_mm, burin::pad([1.0, 2.0, 3.0]));
}

#[test]
fn missing_file_names_the_path() {
    let e = MachineConfig::load("/nonexistent/burin.toml").unwrap_err();
    assert!(e.to_string().contains("/nonexistent/burin.toml"));
}

#[test]
fn run_info_matches_the_settings() {
    let cfg = MachineConfig::load(machine("plotter.toml")).unwrap();
    let info = cfg.run_info();
    assert_eq!(
        (info.tick_hz, info.pulse_ticks, info.dir_setup_ticks),
        (96_000_000, 192, 96)
    );
    assert_eq!(info.axes[1].name, 'Y');
    assert_eq!(info.axes[1].max_accel_mm_s2, 2500.0);
    assert_eq!(info.axes[2].travel_mm, 10.0);
}

#[test]
fn interrupt_model_keys() {
    use host_sim::config::{Interrupts, MaskPhase};
    let cfg = MachineConfig::from_toml_str(
        "[interrupts]\nstep_entry_ns = 250\nstep_handler_ns = 1600\nmask_window_us = 4.0\nmask_phase = 2.5\n[pulses]\nenable_delay_us = 5.0\n",
    )
    .unwrap();
    assert_eq!(
        cfg.interrupts,
        Interrupts {
            step_entry_ns: 250,
            step_handler_ns: 1600,
            mask_window_us: 4.0,
            mask_phase: MaskPhase::Fixed(2.5),
            ..Interrupts::default()
        }
    );
    assert_eq!(cfg.settings.enable_delay_us, 5.0);
    assert_eq!(
        cfg.interrupts.pulse_end,
        host_sim::config::PulseEnd::Hardware { latency_ns: 0 }
    );
    let qemu = MachineConfig::from_toml_str("[interrupts]\npulse_end = \"interrupt\"\n").unwrap();
    assert_eq!(
        qemu.interrupts.pulse_end,
        host_sim::config::PulseEnd::Interrupt
    );
    let dma = MachineConfig::from_toml_str("[interrupts]\npulse_end_latency_ns = 333\n").unwrap();
    assert_eq!(
        dma.interrupts.pulse_end,
        host_sim::config::PulseEnd::Hardware { latency_ns: 333 }
    );
    let seeded = MachineConfig::from_toml_str("[interrupts]\nmask_seed = 9\n").unwrap();
    assert_eq!(seeded.interrupts.mask_phase, MaskPhase::Random(9));
    for bad in [
        "[interrupts]\nmask_phase = \"sometimes\"\n",
        "[interrupts]\npulse_end = \"dma\"\n",
        "[interrupts]\nmask_window_us = 2000.0\n",
        "[interrupts]\nmask_period_us = 0.0\n",
        "[pulses]\nenable_delay_us = -1.0\n",
    ] {
        assert!(MachineConfig::from_toml_str(bad).is_err(), "{bad}");
    }
    // A fixed window masks exactly its span, every period.
    let m = cfg.interrupts.ticks(96_000_000).masks;
    let (start, end) = (240, 240 + 384);
    assert_eq!(m.unmasked_at(start - 1), start - 1);
    assert_eq!(m.unmasked_at(start), end);
    assert_eq!(m.unmasked_at(96_000 + start + 10), 96_000 + end);
    assert_eq!(m.unmasked_at(end), end);
}

#[test]
fn wiring_defaults_to_the_settings_and_can_differ_from_them() {
    use host_sim::config::Wiring;
    let cfg = MachineConfig::from_toml_str("[limits]\ninvert = \"X\"\n").unwrap();
    assert_eq!(cfg.wiring, None, "wired as the settings say");
    let cfg = MachineConfig::from_toml_str(
        "[pulses]\ndir_invert = \"Z\"\n[wiring]\nlimits_nc = \"XYZ\"\n",
    )
    .unwrap();
    assert_eq!(cfg.settings.limit_invert, 0, "$5 stays as the file sets it");
    assert_eq!(
        cfg.wiring,
        Some(Wiring {
            limits_nc: 0b111,
            probe_nc: false,
            motors_reversed: 0b100,
        })
    );
    let bad = MachineConfig::from_toml_str("[wiring]\nmotors_reversed = \"Q\"\n");
    assert!(
        bad.is_err_and(|e| e.to_string().contains("wiring.motors_reversed")),
        "the key at fault is named"
    );
}
