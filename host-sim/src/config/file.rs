//! The TOML layout of a machine file, kept apart from [`MachineConfig`] so the
//! file can use readable names and units while the core keeps GRBL's struct.
//!
//! Every field is optional: a file says only what differs from the default
//! machine, and [`apply`] overlays it. Unknown keys are refused (a typo must
//! not silently leave a default in place).

use serde::Deserialize;

use super::{ConfigError, LimitSwitch, MachineConfig, MaskPhase, ProbeSurface, PulseEnd};
use burin::settings::{Profile, RapidMode};
use burin::{AXES, AXIS_NAMES};

mod letters;
use letters::{driven, ALL_TRIP_KEYS};
pub(super) use letters::{AXIS_KEYS, TRIP_KEYS};

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct File {
    tick_hz: Option<u32>,
    /// X Y Z and up to [`AXES`] values in all, the rest 0: a file written
    /// for four axes runs on a build with more.
    start_position_mm: Option<Vec<f32>>,
    #[serde(default)]
    axes: Axes,
    #[serde(default)]
    motion: Motion,
    #[serde(default)]
    pulses: Pulses,
    #[serde(default)]
    homing: Homing,
    #[serde(default)]
    limits: Limits,
    #[serde(default)]
    probe: Probe,
    #[serde(default)]
    spindle: Spindle,
    #[serde(default)]
    report: Report,
    #[serde(default)]
    host: Host,
    #[serde(default)]
    interrupts: Irq,
    #[serde(default)]
    gcode: Gcode,
    wiring: Option<WiringFile>,
}

/// `[wiring]`: the machine's own wiring where it differs from its settings
/// (see `config::Wiring`); keys left out follow the settings.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct WiringFile {
    limits_nc: Option<String>,
    probe_nc: Option<bool>,
    motors_reversed: Option<String>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Gcode {
    /// `$210`: "rs274" (stored positions, the default) or "beagleg" (G28 homes).
    g28_meaning: Option<G28Name>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum G28Name {
    Rs274,
    Beagleg,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Irq {
    step_entry_ns: Option<u32>,
    step_handler_ns: Option<u32>,
    step_fall_ns: Option<u32>,
    /// "hardware" or "interrupt".
    pulse_end: Option<String>,
    pulse_end_latency_ns: Option<u32>,
    mask_window_us: Option<f32>,
    mask_period_us: Option<f32>,
    /// "random", or an offset in µs.
    mask_phase: Option<PhaseValue>,
    mask_seed: Option<u64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum PhaseValue {
    Word(String),
    Us(f32),
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Host {
    link_bytes_per_s: Option<u32>,
    rx_window_bytes: Option<u32>,
    line_ns: Option<u32>,
    block_ns: Option<u32>,
    scurve_visit_ns: Option<u32>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Axes {
    x: Option<Axis>,
    y: Option<Axis>,
    z: Option<Axis>,
    a: Option<Axis>,
    b: Option<Axis>,
    c: Option<Axis>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Axis {
    steps_per_mm: Option<f32>,
    max_rate_mm_min: Option<f32>,
    max_accel_mm_s2: Option<f32>,
    travel_mm: Option<f32>,
    backlash_mm: Option<f32>,
    slack_mm: Option<f32>,
    /// `$376`'s bit: degrees, and RS274NGC's rotary feed rule.
    rotary: Option<bool>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Motion {
    junction_deviation_mm: Option<f32>,
    arc_tolerance_mm: Option<f32>,
    profile: Option<ProfileName>,
    jerk_mm_s3: Option<f32>,
    rapid_mode: Option<RapidName>,
    max_step_rate_hz: Option<f32>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum ProfileName {
    Trapezoid,
    Scurve,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum RapidName {
    Coordinated,
    Independent,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Pulses {
    step_pulse_us: Option<f32>,
    dir_setup_us: Option<f32>,
    step_invert: Option<String>,
    dir_invert: Option<String>,
    enable_invert: Option<bool>,
    idle_delay_ms: Option<u16>,
    enable_delay_us: Option<f32>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Homing {
    enable: Option<bool>,
    towards_negative: Option<String>,
    feed_mm_min: Option<f32>,
    seek_mm_min: Option<f32>,
    debounce_ms: Option<u16>,
    pulloff_mm: Option<f32>,
    order: Option<Vec<String>>,
    verify_tolerance_mm: Option<f32>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Limits {
    soft: Option<bool>,
    hard: Option<bool>,
    invert: Option<String>,
    switches: Option<String>,
    x_trip_mm: Option<f32>,
    y_trip_mm: Option<f32>,
    z_trip_mm: Option<f32>,
    a_trip_mm: Option<f32>,
    b_trip_mm: Option<f32>,
    c_trip_mm: Option<f32>,
    hysteresis_mm: Option<f32>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Probe {
    axis: Option<String>,
    trip_mm: Option<f32>,
    direction: Option<Direction>,
    invert: Option<bool>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum Direction {
    Negative,
    Positive,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Spindle {
    max_rpm: Option<f32>,
    min_rpm: Option<f32>,
    laser_mode: Option<bool>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Report {
    machine_position: Option<bool>,
    buffer_state: Option<bool>,
    inches: Option<bool>,
    axes: Option<u8>,
}

fn set<T>(slot: &mut T, v: Option<T>) {
    if let Some(v) = v {
        *slot = v;
    }
}

/// `"XZ"` → bits 0 and 2. Case-insensitive; anything but axis letters is refused.
fn axis_mask(key: &str, letters: &str) -> Result<u8, ConfigError> {
    let mut mask = 0u8;
    for c in letters.chars().filter(|c| !c.is_whitespace() && *c != ',') {
        let i = AXIS_NAMES
            .iter()
            .position(|n| n.eq_ignore_ascii_case(&c))
            .ok_or_else(|| {
                ConfigError::invalid(
                    key,
                    format!(
                        "`{c}` is not an axis (use letters of {})",
                        String::from_iter(AXIS_NAMES)
                    ),
                )
            })?;
        mask |= 1 << i;
    }
    Ok(mask)
}

fn set_mask(slot: &mut u8, key: &str, v: Option<String>) -> Result<(), ConfigError> {
    if let Some(v) = v {
        *slot = axis_mask(key, &v)?;
    }
    Ok(())
}

/// Overlays the TOML document `text` on `cfg`.
pub(super) fn apply(text: &str, cfg: &mut MachineConfig) -> Result<(), ConfigError> {
    let f: File = toml::from_str(text).map_err(|e| ConfigError::Parse(e.to_string()))?;
    set(&mut cfg.tick_hz, f.tick_hz);
    if let Some(p) = f.start_position_mm {
        if !(3..=AXES).contains(&p.len()) {
            return Err(ConfigError::invalid(
                "start_position_mm",
                format!("{} values; give X Y Z and at most {AXES} in all", p.len()),
            ));
        }
        cfg.start_position_mm = [0.0; AXES];
        cfg.start_position_mm[..p.len()].copy_from_slice(&p);
    }
    let h = f.host;
    set(&mut cfg.host.link_bytes_per_s, h.link_bytes_per_s);
    set(&mut cfg.host.rx_window_bytes, h.rx_window_bytes);
    set(&mut cfg.host.line_ns, h.line_ns);
    set(&mut cfg.host.block_ns, h.block_ns);
    set(&mut cfg.host.scurve_visit_ns, h.scurve_visit_ns);
    apply_interrupts(cfg, f.interrupts)?;
    let s = &mut cfg.settings;

    // `$208` follows the axes the file describes (issue 29): X/Y/Z tables
    // and no A are an XYZ machine, which GRBL senders must not show an A
    // for. `report.axes` still says otherwise when given.
    let ax = f.axes;
    let axes = driven(
        [ax.x, ax.y, ax.z, ax.a, ax.b, ax.c],
        ["axes.x", "axes.y", "axes.z", "axes.a", "axes.b", "axes.c"],
    )?;
    if let Some(last) = axes.iter().rposition(Option::is_some) {
        if last < AXES - 1 {
            s.report_axes = (last.max(2) + 1) as u8;
        }
    }
    for (i, src) in axes.into_iter().enumerate() {
        let src = src.unwrap_or_default();
        let dst = &mut s.axes[i];
        set(&mut dst.steps_per_mm, src.steps_per_mm);
        set(&mut dst.max_rate, src.max_rate_mm_min);
        set(&mut dst.max_accel, src.max_accel_mm_s2);
        set(&mut dst.max_travel, src.travel_mm);
        set(&mut s.backlash_mm[i], src.backlash_mm);
        set(&mut cfg.slack_mm[i], src.slack_mm);
        if let Some(r) = src.rotary {
            s.rotary_axes = (s.rotary_axes & !(1 << i)) | (u8::from(r) << i);
        }
    }

    if let Some(g) = f.gcode.g28_meaning {
        s.g28_homes = matches!(g, G28Name::Beagleg);
    }
    let m = f.motion;
    set(&mut s.junction_deviation, m.junction_deviation_mm);
    set(&mut s.arc_tolerance, m.arc_tolerance_mm);
    set(&mut s.jerk, m.jerk_mm_s3);
    set(&mut s.max_step_rate_hz, m.max_step_rate_hz);
    if let Some(p) = m.profile {
        s.profile = match p {
            ProfileName::Trapezoid => Profile::Trapezoid,
            ProfileName::Scurve => Profile::SCurve,
        };
    }
    if let Some(r) = m.rapid_mode {
        s.rapid_mode = match r {
            RapidName::Coordinated => RapidMode::Coordinated,
            RapidName::Independent => RapidMode::Independent,
        };
    }

    let p = f.pulses;
    set(&mut s.step_pulse_us, p.step_pulse_us);
    set(&mut s.dir_setup_us, p.dir_setup_us);
    set_mask(&mut s.step_invert, "pulses.step_invert", p.step_invert)?;
    set_mask(&mut s.dir_invert, "pulses.dir_invert", p.dir_invert)?;
    set(&mut s.enable_invert, p.enable_invert);
    set(&mut s.idle_delay_ms, p.idle_delay_ms);
    set(&mut s.enable_delay_us, p.enable_delay_us);

    let h = f.homing;
    set(&mut s.homing_enable, h.enable);
    set_mask(
        &mut s.homing_dir_invert,
        "homing.towards_negative",
        h.towards_negative,
    )?;
    set(&mut s.homing_feed, h.feed_mm_min);
    set(&mut s.homing_seek, h.seek_mm_min);
    set(&mut s.homing_debounce_ms, h.debounce_ms);
    set(&mut s.homing_pulloff, h.pulloff_mm);
    set(&mut s.verify_home_tolerance, h.verify_tolerance_mm);
    if let Some(order) = h.order {
        s.homing_order = homing_order(&order)?;
    }

    let mut l = f.limits;
    set(&mut s.soft_limits, l.soft);
    set(&mut s.hard_limits, l.hard);
    set_mask(&mut s.limit_invert, "limits.invert", l.invert.take())?;
    apply_switches(cfg, l)?;
    apply_probe(cfg, f.probe)?;

    let s = &mut cfg.settings;
    set(&mut s.spindle_max, f.spindle.max_rpm);
    set(&mut s.spindle_min, f.spindle.min_rpm);
    set(&mut s.laser_mode, f.spindle.laser_mode);

    let r = f.report;
    let bit = |mask: &mut u8, b: u8, v: Option<bool>| match v {
        Some(true) => *mask |= b,
        Some(false) => *mask &= !b,
        None => {}
    };
    bit(&mut s.status_mask, 1, r.machine_position);
    bit(&mut s.status_mask, 2, r.buffer_state);
    set(&mut s.report_inches, r.inches);
    set(&mut s.report_axes, r.axes);
    if let Some(w) = f.wiring {
        let mut wiring = super::Wiring::matching(s);
        set_mask(&mut wiring.limits_nc, "wiring.limits_nc", w.limits_nc)?;
        set(&mut wiring.probe_nc, w.probe_nc);
        set_mask(
            &mut wiring.motors_reversed,
            "wiring.motors_reversed",
            w.motors_reversed,
        )?;
        cfg.wiring = Some(wiring);
    }
    Ok(())
}

fn apply_interrupts(cfg: &mut MachineConfig, i: Irq) -> Result<(), ConfigError> {
    let m = &mut cfg.interrupts;
    set(&mut m.step_entry_ns, i.step_entry_ns);
    set(&mut m.step_handler_ns, i.step_handler_ns);
    set(&mut m.step_fall_ns, i.step_fall_ns);
    let kept = match m.pulse_end {
        PulseEnd::Hardware { latency_ns } => latency_ns,
        PulseEnd::Interrupt => 0,
    };
    let hardware = PulseEnd::Hardware {
        latency_ns: i.pulse_end_latency_ns.unwrap_or(kept),
    };
    m.pulse_end = match i.pulse_end.as_deref() {
        Some("hardware") => hardware,
        Some("interrupt") => PulseEnd::Interrupt,
        Some(w) => {
            return Err(ConfigError::invalid(
                "interrupts.pulse_end",
                format!("`{w}`: use \"hardware\" or \"interrupt\""),
            ))
        }
        None if m.pulse_end == PulseEnd::Interrupt => PulseEnd::Interrupt,
        None => hardware,
    };
    set(&mut m.mask_window_us, i.mask_window_us);
    set(&mut m.mask_period_us, i.mask_period_us);
    let seed = match (i.mask_seed, m.mask_phase) {
        (Some(s), _) | (None, MaskPhase::Random(s)) => s,
        (None, MaskPhase::Fixed(_)) => 1,
    };
    m.mask_phase = match i.mask_phase {
        Some(PhaseValue::Us(at)) => MaskPhase::Fixed(at),
        Some(PhaseValue::Word(w)) if w == "random" => MaskPhase::Random(seed),
        Some(PhaseValue::Word(w)) => {
            return Err(ConfigError::invalid(
                "interrupts.mask_phase",
                format!("`{w}`: use \"random\" or an offset in µs"),
            ))
        }
        None => match m.mask_phase {
            MaskPhase::Random(_) => MaskPhase::Random(seed),
            fixed => fixed,
        },
    };
    Ok(())
}

/// `["Z", "XY"]` → `0x34`: one nibble of axes per cycle, first cycle lowest.
fn homing_order(cycles: &[String]) -> Result<u16, ConfigError> {
    const KEY: &str = "homing.order";
    if cycles.len() > 4 {
        return Err(ConfigError::invalid(KEY, "at most 4 homing cycles"));
    }
    let mut order = 0u16;
    for (i, c) in cycles.iter().enumerate() {
        let m = axis_mask(KEY, c)?;
        if m == 0 {
            return Err(ConfigError::invalid(KEY, "a homing cycle names no axis"));
        }
        order |= u16::from(m) << (4 * i);
    }
    Ok(order)
}

fn apply_switches(cfg: &mut MachineConfig, l: Limits) -> Result<(), ConfigError> {
    let fitted = match l.switches {
        Some(letters) => axis_mask("limits.switches", &letters)?,
        None => (0..AXES).fold(0u8, |m, i| m | (u8::from(cfg.limits[i].is_some()) << i)),
    };
    let trips = driven(
        [
            l.x_trip_mm,
            l.y_trip_mm,
            l.z_trip_mm,
            l.a_trip_mm,
            l.b_trip_mm,
            l.c_trip_mm,
        ],
        ALL_TRIP_KEYS,
    )?;
    for (i, (slot, trip)) in cfg.limits.iter_mut().zip(trips).enumerate() {
        if fitted & (1 << i) == 0 {
            *slot = None;
            continue;
        }
        let mut sw = slot.unwrap_or(LimitSwitch {
            trip_mm: 0.0,
            hysteresis_mm: 0.05,
        });
        set(&mut sw.trip_mm, trip);
        set(&mut sw.hysteresis_mm, l.hysteresis_mm);
        *slot = Some(sw);
    }
    Ok(())
}

fn apply_probe(cfg: &mut MachineConfig, p: Probe) -> Result<(), ConfigError> {
    set(&mut cfg.settings.probe_invert, p.invert);
    let axis = match p.axis.as_deref() {
        Some(a) if a.eq_ignore_ascii_case("none") => {
            cfg.probe = None;
            return Ok(());
        }
        Some(a) => {
            let m = axis_mask("probe.axis", a)?;
            if m.count_ones() != 1 {
                return Err(ConfigError::invalid(
                    "probe.axis",
                    "name one axis, or \"none\"",
                ));
            }
            Some(m.trailing_zeros() as usize)
        }
        None => None,
    };
    let base = match (cfg.probe, axis) {
        (Some(b), _) => b,
        (None, Some(axis)) => ProbeSurface {
            axis,
            trip_mm: 0.0,
            towards_negative: true,
        },
        (None, None) if p.trip_mm.is_none() && p.direction.is_none() => return Ok(()),
        (None, None) => return Err(ConfigError::invalid("probe.axis", "is needed")),
    };
    let mut surf = base;
    set(&mut surf.axis, axis);
    set(&mut surf.trip_mm, p.trip_mm);
    if let Some(d) = p.direction {
        surf.towards_negative = matches!(d, Direction::Negative);
    }
    cfg.probe = Some(surf);
    Ok(())
}
