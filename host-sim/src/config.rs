//! The simulated machine: the firmware settings plus the world around the
//! steppers (where the limit switches and the probe surface are).
//! Loaded from TOML with `--machine FILE`; see `MachineConfig::default` for
//! the documented default, and `host-sim/machines/default.toml` for the same
//! machine written out as a file with every key explained.

mod file;
mod interrupts;

pub use interrupts::{Interrupts, IrqTicks, MaskPhase, Masks, PulseEnd, BOARD_PULSE_DMA};

use std::fmt;
use std::path::{Path, PathBuf};

use burin::settings::{AxisSettings, Settings};
use burin::stepper::StepConfig;
use burin::{AXES, AXIS_NAMES};

use crate::record::{AxisInfo, RunInfo};

/// A limit switch that closes when the axis reaches `trip_mm` (machine
/// coordinates) going in its homing direction, and opens again `hysteresis_mm`
/// back off it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimitSwitch {
    pub trip_mm: f32,
    pub hysteresis_mm: f32,
}

/// A probe that closes while the tool is at or beyond a plane on one axis,
/// e.g. a workpiece top at Z = -20 mm: `axis: 2, trip_mm: -20.0, towards_negative: true`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeSurface {
    pub axis: usize,
    pub trip_mm: f32,
    pub towards_negative: bool,
}

/// How the machine is wired, where that is a fact of the machine and not
/// of its settings: normally-closed switches read active while open, a
/// reversed motor turns negative while its direction pin is low. The
/// settings (`$3`, `$5`, `$6`) must match for the machine to work; a
/// machine file that leaves the wiring out is wired as its settings say
/// ([`Wiring::matching`]), and tests wire it otherwise to see the firmware
/// adopt a corrected setting (`$5=7` for NC switches) at once.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Wiring {
    /// Axes whose limit switch is normally closed (`$5` needs the bit).
    pub limits_nc: u8,
    /// The probe is normally closed (`$6=1` reads it right).
    pub probe_nc: bool,
    /// Axes whose motor turns towards negative while its direction pin is
    /// low (`$3` needs the bit).
    pub motors_reversed: u8,
}

impl Wiring {
    /// The machine the settings `s` describe correctly.
    pub fn matching(s: &Settings) -> Self {
        Wiring {
            limits_nc: s.limit_invert,
            probe_nc: s.probe_invert,
            motors_reversed: s.dir_invert,
        }
    }
}

/// How fast the host side of the simulation is: the link a streamed job
/// arrives on and the run time of the parse/plan task (RTIC priority 1,
/// which the step timer preempts). Zero means "no cost".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HostModel {
    /// Link rate for jobs streamed from text (`run_job`), bytes per second;
    /// 0: every line is there at once. 11_520 is a 115 200 baud serial line.
    pub link_bytes_per_s: u32,
    /// Bytes the sender may have in flight or unparsed (character counting
    /// against the firmware's receive window, `protocol::RX_WINDOW`).
    pub rx_window_bytes: u32,
    /// Parse task time per G-code line (or pushed command), nanoseconds.
    pub line_ns: u32,
    /// Planning time per planner block (line, chord, homing or probe move), ns.
    pub block_ns: u32,
    /// In S-curve mode (`$202`), besides `block_ns`: planning time per
    /// block the planner's passes visit (`Planner::work`), each reckoning
    /// S ramps, ns.
    pub scurve_visit_ns: u32,
}

impl HostModel {
    /// An infinitely fast host: no link time, no task time.
    pub const INSTANT: HostModel = HostModel {
        link_bytes_per_s: 0,
        rx_window_bytes: 128,
        line_ns: 0,
        block_ns: 0,
        scurve_visit_ns: 0,
    };
}

/// The measured on-target costs (`cargo xtask bench-target`: 2,769
/// instructions per parsed line, 7,532 per planned block with the corner
/// holds, their passes, the quiet axes, the per-chord arc budget and the
/// straight stretches of `planner::tube`, 11,052 before the FPU's square
/// root, session 23) at 96 MHz and the step path's assumed 1.3 cycles per
/// instruction: 37.5 µs and 102.0 µs. In S-curve mode a block costs
/// 96,317 (`plan_chord_scurve_insns`) on the same full ring, whose passes
/// visit 120.0 blocks a push there (counted with `Planner::work` on the
/// same pushes): the 88,785 more, 740 a visit, 10.0 µs. Charged by visit,
/// since the walk varies a hundredfold: a merged step of
/// short_segments.ngc visits one or two blocks, a chord on a full ring all
/// of them twice. The link is instant: a job file can be sent at any rate,
/// so its time is not the controller's.
impl Default for HostModel {
    fn default() -> Self {
        HostModel {
            line_ns: 37_497,
            block_ns: 101_996,
            scurve_visit_ns: 10_018,
            ..HostModel::INSTANT
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct MachineConfig {
    /// Step timer rate in Hz (TIM5 runs at the 96 MHz timer clock on the F411).
    pub tick_hz: u32,
    pub settings: Settings,
    pub limits: [Option<LimitSwitch>; AXES],
    pub probe: Option<ProbeSurface>,
    /// Machine position at power-up, mm.
    pub start_position_mm: [f32; AXES],
    /// Link and parse/plan task timing.
    pub host: HostModel,
    /// Step interrupt latency, handler times and masked windows.
    pub interrupts: Interrupts,
    /// The switches' and motors' wiring; `None`: as the settings the
    /// machine starts with say ([`Wiring::matching`]).
    pub wiring: Option<Wiring>,
    /// Mechanical slack per axis, mm (a fact of the machine, not a
    /// setting; `$160`-`$163` compensate it): the modelled tool follows the
    /// motor with this dead band (`engine::World`), taken up towards the
    /// homing direction at power-up, as the firmware assumes.
    pub slack_mm: [f32; AXES],
}

/// The default machine: a small 300 × 300 × 100 mm gantry mill on the
/// default board (WeAct Black Pill, STM32F411).
///
/// * `tick_hz` = 96 MHz: TIM5 clocked straight from the F411's 96 MHz timer
///   clock with no prescaler, as the firmware runs it. One tick is 10.4 ns, so
///   a 200 kHz step period is 480 ticks and the 2 µs pulse 192 ticks: timing
///   quantisation is well below what a driver can see. (An F401 runs the same
///   timer at 84 MHz; give such a machine its own file.)
/// * `settings` = [`Settings::default`] (GRBL-like values: 80 steps/mm X/Y,
///   400 steps/mm Z, 2 µs pulses, junction deviation 0.01 mm, arc tolerance
///   0.002 mm, homing towards the positive ends, soft/hard limits off).
/// * Limit switches on X, Y and Z at machine 0, the positive end, because the
///   axes home towards positive: after homing the envelope is
///   X ∈ [-300, 0], Y ∈ [-300, 0], Z ∈ [-100, 0] mm, and the firmware's
///   coordinates agree with the simulated world. A (rotary) has no switch.
/// * A probe plate/workpiece top at Z = -50 mm, probed downwards.
/// * Power-up position (-1, -1, -1, 0): parked where a homing cycle leaves
///   the machine, pulled off each switch by `$27` = 1 mm, so no switch is
///   closed at power-up.
/// * `host` = [`HostModel::default`]: the parse/plan task costs its measured
///   on-target time per line and per block; the link is instant.
/// * `interrupts` = [`Interrupts::IDEAL`]: step handlers take no time and
///   nothing masks them (set them to study latency, see `machines/default.toml`).
impl Default for MachineConfig {
    fn default() -> Self {
        let settings = Settings::default();
        let switch = Some(LimitSwitch {
            trip_mm: 0.0,
            hysteresis_mm: 0.05,
        });
        MachineConfig {
            tick_hz: 96_000_000,
            settings,
            limits: burin::pad([switch, switch, switch, None]),
            probe: Some(ProbeSurface {
                axis: 2,
                trip_mm: -50.0,
                towards_negative: true,
            }),
            start_position_mm: burin::pad([-1.0, -1.0, -1.0, 0.0]),
            host: HostModel::default(),
            interrupts: Interrupts::default(),
            wiring: None,
            slack_mm: [0.0; AXES],
        }
    }
}

/// Why a machine file was refused. Every message names the file key at fault.
#[derive(Debug)]
pub enum ConfigError {
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// TOML syntax, a wrong type or an unknown key; `toml`'s message names
    /// the key and shows the line.
    Parse(String),
    /// A value the machine cannot run with.
    Invalid { key: String, message: String },
}

impl ConfigError {
    fn invalid(key: impl Into<String>, message: impl Into<String>) -> Self {
        ConfigError::Invalid {
            key: key.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::Io { path, source } => write!(f, "{}: {source}", path.display()),
            ConfigError::Parse(m) => write!(f, "{m}"),
            ConfigError::Invalid { key, message } => write!(f, "`{key}`: {message}"),
        }
    }
}

impl std::error::Error for ConfigError {}

impl MachineConfig {
    /// Reads a machine file. Keys left out keep the default machine's values.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        let mut cfg = MachineConfig::default();
        file::apply(text, &mut cfg)?;
        cfg.validate()?;
        Ok(cfg)
    }

    pub fn load(path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_toml_str(&text).map_err(|e| match e {
            ConfigError::Parse(m) => ConfigError::Parse(format!("{}: {m}", path.display())),
            other => other,
        })
    }

    /// Step pulse width and direction setup time in timer ticks, exactly as
    /// the core's step generator rounds them.
    pub fn pulse_ticks(&self) -> (u32, u32) {
        let sc = StepConfig::new(&self.settings, self.tick_hz);
        (sc.pulse_ticks, sc.dir_setup_ticks)
    }

    /// The static facts recorders are started with (and the terminal
    /// summary prints axis names from).
    pub fn run_info(&self) -> RunInfo {
        let (pulse_ticks, dir_setup_ticks) = self.pulse_ticks();
        let s = &self.settings;
        RunInfo {
            tick_hz: self.tick_hz,
            axes: std::array::from_fn(|i| AxisInfo {
                name: AXIS_NAMES[i],
                steps_per_mm: s.axes[i].steps_per_mm,
                max_rate_mm_min: s.axes[i].max_rate,
                max_accel_mm_s2: s.axes[i].max_accel,
                travel_mm: s.axes[i].max_travel,
            }),
            pulse_ticks,
            dir_setup_ticks,
        }
    }

    /// Refuses values the core cannot run with; the error names the TOML key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let s = &self.settings;
        if self.tick_hz < 1_000 {
            return Err(ConfigError::invalid("tick_hz", "must be at least 1000 Hz"));
        }
        for (i, ax) in s.axes.iter().enumerate() {
            let keys = file::AXIS_KEYS[i];
            validate_axis(keys, ax)?;
            at_least_zero(keys[4], s.backlash_mm[i])?;
            if s.backlash_mm[i] > 10.0 {
                return Err(ConfigError::invalid(
                    keys[4],
                    "must be at most 10 ($160-$163)",
                ));
            }
            at_least_zero(keys[5], self.slack_mm[i])?;
        }
        positive("motion.arc_tolerance_mm", s.arc_tolerance)?;
        at_least_zero("motion.junction_deviation_mm", s.junction_deviation)?;
        positive("motion.jerk_mm_s3", s.jerk)?;
        positive("motion.max_step_rate_hz", s.max_step_rate_hz)?;
        positive("pulses.step_pulse_us", s.step_pulse_us)?;
        at_least_zero("pulses.dir_setup_us", s.dir_setup_us)?;
        at_least_zero("pulses.enable_delay_us", s.enable_delay_us)?;
        let irq = &self.interrupts;
        at_least_zero("interrupts.mask_window_us", irq.mask_window_us)?;
        positive("interrupts.mask_period_us", irq.mask_period_us)?;
        if irq.mask_window_us >= irq.mask_period_us {
            return Err(ConfigError::invalid(
                "interrupts.mask_window_us",
                "must be shorter than interrupts.mask_period_us",
            ));
        }
        if let MaskPhase::Fixed(at) = irq.mask_phase {
            at_least_zero("interrupts.mask_phase", at)?;
        }
        // The firmware's own rule (`$0`/`$201` refused beyond the one
        // step-rate ceiling, `error:114`).
        if !burin::settings::ceiling::settings_fit(s) {
            return Err(ConfigError::invalid(
                "pulses.step_pulse_us",
                format!(
                    "a {} µs pulse allows at most {:.0} Hz, motion.max_step_rate_hz is {} Hz",
                    s.step_pulse_us,
                    burin::settings::ceiling::ceiling_hz(s.step_pulse_us),
                    s.max_step_rate_hz
                ),
            ));
        }
        positive("homing.feed_mm_min", s.homing_feed)?;
        positive("homing.seek_mm_min", s.homing_seek)?;
        at_least_zero("homing.pulloff_mm", s.homing_pulloff)?;
        at_least_zero("homing.verify_tolerance_mm", s.verify_home_tolerance)?;
        at_least_zero("spindle.min_rpm", s.spindle_min)?;
        at_least_zero("spindle.max_rpm", s.spindle_max)?;
        if s.spindle_min > s.spindle_max {
            return Err(ConfigError::invalid(
                "spindle.min_rpm",
                "must not exceed spindle.max_rpm",
            ));
        }
        for (i, sw) in self.limits.iter().enumerate() {
            if let Some(sw) = sw {
                finite(file::TRIP_KEYS[i], sw.trip_mm)?;
                at_least_zero("limits.hysteresis_mm", sw.hysteresis_mm)?;
            }
        }
        if let Some(p) = &self.probe {
            if p.axis >= AXES {
                return Err(ConfigError::invalid("probe.axis", "no such axis"));
            }
            finite("probe.trip_mm", p.trip_mm)?;
        }
        for &v in &self.start_position_mm {
            finite("start_position_mm", v)?;
        }
        if !(3..=AXES as u8).contains(&s.report_axes) {
            return Err(ConfigError::invalid(
                "report.axes",
                "must be from 3 to the axes this build drives",
            ));
        }
        Ok(())
    }
}

fn validate_axis(keys: [&str; 6], ax: &AxisSettings) -> Result<(), ConfigError> {
    positive(keys[0], ax.steps_per_mm)?;
    positive(keys[1], ax.max_rate)?;
    positive(keys[2], ax.max_accel)?;
    at_least_zero(keys[3], ax.max_travel)
}

fn finite(key: &str, v: f32) -> Result<(), ConfigError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            key,
            format!("must be a finite number (got {v})"),
        ))
    }
}

fn positive(key: &str, v: f32) -> Result<(), ConfigError> {
    finite(key, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            key,
            format!("must be greater than 0 (got {v})"),
        ))
    }
}

fn at_least_zero(key: &str, v: f32) -> Result<(), ConfigError> {
    finite(key, v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(ConfigError::invalid(
            key,
            format!("must not be negative (got {v})"),
        ))
    }
}
