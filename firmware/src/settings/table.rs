//! The numbered view of [`Settings`]: GRBL's `$n` numbers (so senders'
//! settings dialogs work) plus burin's own from `$200`. Every write is
//! validated here, once, so the planner and stepper can trust the struct.

use super::{Profile, RapidMode, Settings};
use crate::AXES;
use protocol::Code;

/// Why `$n=v` was refused. [`SettingError::code`] is the `error:N` number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SettingError {
    /// No setting has this number.
    Unknown,
    /// The value is NaN or infinite.
    NotANumber,
    /// Negative where only positive values make sense.
    Negative,
    /// Outside the setting's range.
    OutOfRange,
    /// A fraction given to a whole-number setting.
    NotInteger,
    /// A mask with bits for axes that do not exist.
    BadMask,
    /// `$201` above the step-rate ceiling that `$0` and the step path's
    /// cost allow ([`super::ceiling::ceiling_hz`]), or a `$0`
    /// that makes the current `$201` impossible.
    StepRateCeiling,
}

impl SettingError {
    /// Stable code: GRBL's where one exists (3, 2, 4), burin's otherwise.
    pub const fn code(self) -> Code {
        match self {
            SettingError::Unknown => Code::InvalidStatement,
            SettingError::NotANumber => Code::BadNumber,
            SettingError::Negative => Code::NegativeValue,
            SettingError::OutOfRange => Code::SettingRange,
            SettingError::NotInteger => Code::SettingNotInteger,
            SettingError::BadMask => Code::SettingBadMask,
            SettingError::StepRateCeiling => Code::StepRateCeiling,
        }
    }
}

/// The shape of a setting's values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// Any real number in `min..=max`.
    Real { min: f32, max: f32 },
    /// A whole number in `min..=max`.
    Int { min: u32, max: u32 },
    /// 0 or 1.
    Bool,
    /// A bit mask using only `bits`.
    Mask { bits: u8 },
}

const AXIS_BITS: u8 = (1 << AXES) - 1;
const BIG: f32 = 1.0e6;

/// `$0`–`$32`, in order.
const GLOBAL: [(u16, Kind); 23] = [
    (
        0,
        Kind::Real {
            min: 0.5,
            max: 100.0,
        },
    ),
    (1, Kind::Int { min: 0, max: 255 }),
    (2, Kind::Mask { bits: AXIS_BITS }),
    (3, Kind::Mask { bits: AXIS_BITS }),
    (4, Kind::Bool),
    (5, Kind::Mask { bits: AXIS_BITS }),
    (6, Kind::Bool),
    (10, Kind::Mask { bits: 0b11 }),
    (
        11,
        Kind::Real {
            min: 0.0,
            max: 10.0,
        },
    ),
    (
        12,
        Kind::Real {
            min: 0.0001,
            max: 10.0,
        },
    ),
    (13, Kind::Bool),
    (14, Kind::Mask { bits: 0b111 }),
    (20, Kind::Bool),
    (21, Kind::Bool),
    (22, Kind::Bool),
    (23, Kind::Mask { bits: AXIS_BITS }),
    (24, Kind::Real { min: 0.1, max: BIG }),
    (25, Kind::Real { min: 0.1, max: BIG }),
    (26, Kind::Int { min: 0, max: 65535 }),
    (
        27,
        Kind::Real {
            min: 0.0,
            max: 1000.0,
        },
    ),
    (30, Kind::Real { min: 0.0, max: BIG }),
    (31, Kind::Real { min: 0.0, max: BIG }),
    (32, Kind::Bool),
];

/// Per-axis groups: `$100+i` steps/mm, `$110+i` rate, `$120+i` accel,
/// `$130+i` travel, `$160+i` backlash.
const AXIS_GROUPS: [(u16, Kind); 5] = [
    (
        100,
        Kind::Real {
            min: 0.001,
            max: BIG,
        },
    ),
    (
        110,
        Kind::Real {
            min: 0.001,
            max: BIG,
        },
    ),
    (
        120,
        Kind::Real {
            min: 0.001,
            max: BIG,
        },
    ),
    (130, Kind::Real { min: 0.0, max: BIG }),
    // Backlash: more than a few mm of slack is a broken machine, and a
    // take-up is a move nobody programmed.
    (
        160,
        Kind::Real {
            min: 0.0,
            max: 10.0,
        },
    ),
];

/// `$201`'s maximum, Hz: what the CPU sustains whatever `$0` is
/// ([`super::ceiling::CPU_RATE_HZ`]); `$0` may lower it further
/// ([`Settings::set`] refuses a pair beyond it).
pub const MAX_STEP_RATE_HZ: f32 = super::ceiling::CPU_RATE_HZ;

/// burin's own, `$200`–`$208` and `$210` (documented on the [`Settings`]
/// fields).
const BURIN: [(u16, Kind); 10] = [
    (
        200,
        Kind::Real {
            min: 0.0,
            max: 100.0,
        },
    ),
    // Range only: the ceiling (`$0` and the step path's cost) is checked
    // in `set`, with its own error.
    (
        201,
        Kind::Real {
            min: 1.0,
            max: 1.0e7,
        },
    ),
    (202, Kind::Int { min: 0, max: 1 }),
    (
        203,
        Kind::Real {
            min: 1.0,
            max: 1.0e9,
        },
    ),
    (204, Kind::Int { min: 0, max: 1 }),
    (
        205,
        Kind::Real {
            min: 0.0,
            max: 100.0,
        },
    ),
    (
        206,
        Kind::Int {
            min: 0,
            max: 0xFFFF,
        },
    ),
    // Up to 10 ms: longer than any driver's wake-up, and short enough that
    // a start from rest never looks like a stall.
    (
        207,
        Kind::Real {
            min: 0.0,
            max: 10_000.0,
        },
    ),
    (
        208,
        Kind::Int {
            min: 3,
            max: AXES as u32,
        },
    ),
    (210, Kind::Bool),
];

/// `$211`-`$219`: the tool change (`$210` belongs to the G28 meaning).
const TOOL: [(u16, Kind); 9] = [
    (211, Kind::Int { min: 0, max: 2 }),
    (212, POSITION),
    (213, POSITION),
    (214, POSITION),
    (215, Kind::Mask { bits: 0b111 }),
    (216, POSITION),
    (217, POSITION),
    (218, Kind::Real { min: 1.0, max: BIG }),
    (219, Kind::Real { min: 0.1, max: BIG }),
];
/// `$220`: the spindle's spin-up delay after a door or spindle stop.
const SPINDLE: [(u16, Kind); 1] = [(
    220,
    Kind::Real {
        min: 0.0,
        max: 20.0,
    },
)];
/// `$376`: the rotary axes (grblHAL's number), whose feed rule
/// `motion::Pipeline` applies.
const ROTARY: [(u16, Kind); 1] = [(376, Kind::Mask { bits: AXIS_BITS })];
const POSITION: Kind = Kind::Real {
    min: -BIG,
    max: BIG,
};

/// The kind of setting `n`, or `None` if there is no such setting.
pub fn kind(n: u16) -> Option<Kind> {
    let mut own = GLOBAL
        .iter()
        .chain(BURIN.iter())
        .chain(TOOL.iter())
        .chain(SPINDLE.iter())
        .chain(ROTARY.iter());
    if let Some(&(_, k)) = own.find(|(m, _)| *m == n) {
        return Some(k);
    }
    AXIS_GROUPS
        .iter()
        .find(|(base, _)| (*base..*base + AXES as u16).contains(&n))
        .map(|(_, k)| *k)
}

/// Whether `$n` prints without decimals.
pub fn is_integer(n: u16) -> bool {
    !matches!(kind(n), Some(Kind::Real { .. }) | None)
}

/// Every setting number in ascending order (the `$$` listing).
/// How many settings [`numbers`] lists: the per-axis groups grow with
/// [`AXES`].
pub const COUNT: usize = GLOBAL.len()
    + AXIS_GROUPS.len() * AXES
    + BURIN.len()
    + TOOL.len()
    + SPINDLE.len()
    + ROTARY.len();

pub fn numbers() -> impl Iterator<Item = u16> {
    let axes = AXIS_GROUPS
        .iter()
        .flat_map(|(base, _)| (0..AXES as u16).map(move |i| base + i));
    GLOBAL
        .iter()
        .map(|(n, _)| *n)
        .chain(axes)
        .chain(BURIN.iter().map(|(n, _)| *n))
        .chain(TOOL.iter().map(|(n, _)| *n))
        .chain(SPINDLE.iter().map(|(n, _)| *n))
        .chain(ROTARY.iter().map(|(n, _)| *n))
}

fn check(k: Kind, v: f32) -> Result<(), SettingError> {
    if !v.is_finite() {
        return Err(SettingError::NotANumber);
    }
    let whole = v == libm::truncf(v);
    match k {
        Kind::Real { min, max } => range(v, min, max),
        Kind::Int { min, max } => {
            if !whole {
                return Err(SettingError::NotInteger);
            }
            range(v, min as f32, max as f32)
        }
        Kind::Bool => {
            if !whole {
                return Err(SettingError::NotInteger);
            }
            range(v, 0.0, 1.0)
        }
        Kind::Mask { bits } => {
            if !whole {
                return Err(SettingError::NotInteger);
            }
            range(v, 0.0, 255.0)?;
            if (v as u32) & !u32::from(bits) != 0 {
                return Err(SettingError::BadMask);
            }
            Ok(())
        }
    }
}

fn range(v: f32, min: f32, max: f32) -> Result<(), SettingError> {
    if v < 0.0 && min >= 0.0 {
        Err(SettingError::Negative)
    } else if v < min || v > max {
        Err(SettingError::OutOfRange)
    } else {
        Ok(())
    }
}

impl Settings {
    /// The value of `$n`, or `None` if there is no such setting.
    pub fn get(&self, n: u16) -> Option<f32> {
        let b = |x: bool| if x { 1.0 } else { 0.0 };
        Some(match n {
            0 => self.step_pulse_us,
            1 => f32::from(self.idle_delay_ms),
            2 => f32::from(self.step_invert),
            3 => f32::from(self.dir_invert),
            4 => b(self.enable_invert),
            5 => f32::from(self.limit_invert),
            6 => b(self.probe_invert),
            10 => f32::from(self.status_mask),
            11 => self.junction_deviation,
            12 => self.arc_tolerance,
            13 => b(self.report_inches),
            14 => f32::from(self.control_invert),
            20 => b(self.soft_limits),
            21 => b(self.hard_limits),
            22 => b(self.homing_enable),
            23 => f32::from(self.homing_dir_invert),
            24 => self.homing_feed,
            25 => self.homing_seek,
            26 => f32::from(self.homing_debounce_ms),
            27 => self.homing_pulloff,
            30 => self.spindle_max,
            31 => self.spindle_min,
            32 => b(self.laser_mode),
            100..=139 => {
                let a = self.axes.get(usize::from(n % 10))?;
                match n / 10 {
                    10 => a.steps_per_mm,
                    11 => a.max_rate,
                    12 => a.max_accel,
                    _ => a.max_travel,
                }
            }
            160..=169 => *self.backlash_mm.get(usize::from(n - 160))?,
            200 => self.dir_setup_us,
            201 => self.max_step_rate_hz,
            202 => b(self.profile == Profile::SCurve),
            203 => self.jerk,
            204 => b(self.rapid_mode == RapidMode::Independent),
            205 => self.verify_home_tolerance,
            206 => f32::from(self.homing_order),
            207 => self.enable_delay_us,
            208 => f32::from(self.report_axes),
            210 => b(self.g28_homes),
            211 => f32::from(self.tool_change.mode),
            212..=214 => *self.tool_change.position.get(usize::from(n - 212))?,
            215 => f32::from(self.tool_change.axes),
            216 | 217 => *self.tool_change.setter.get(usize::from(n - 216))?,
            218 => self.tool_change.feed,
            219 => self.tool_change.travel,
            220 => self.spindle_delay_s,
            376 => f32::from(self.rotary_axes),
            _ => return None,
        })
    }

    /// Set `$n` to `v` after validating it; on error nothing changes.
    pub fn set(&mut self, n: u16, v: f32) -> Result<(), SettingError> {
        check(kind(n).ok_or(SettingError::Unknown)?, v)?;
        if n == 0 || n == 201 {
            let mut next = *self;
            next.set_checked(n, v)?;
            if !super::ceiling::settings_fit(&next) {
                return Err(SettingError::StepRateCeiling);
            }
        }
        self.set_checked(n, v)
    }

    /// [`Settings::set`] after the checks.
    fn set_checked(&mut self, n: u16, v: f32) -> Result<(), SettingError> {
        // Validated above: whole numbers in range, so these casts are exact.
        let (u8v, u16v, on) = (v as u8, v as u16, v != 0.0);
        match n {
            0 => self.step_pulse_us = v,
            1 => self.idle_delay_ms = u16v,
            2 => self.step_invert = u8v,
            3 => self.dir_invert = u8v,
            4 => self.enable_invert = on,
            5 => self.limit_invert = u8v,
            6 => self.probe_invert = on,
            10 => self.status_mask = u8v,
            11 => self.junction_deviation = v,
            12 => self.arc_tolerance = v,
            13 => self.report_inches = on,
            14 => self.control_invert = u8v,
            20 => self.soft_limits = on,
            21 => self.hard_limits = on,
            22 => self.homing_enable = on,
            23 => self.homing_dir_invert = u8v,
            24 => self.homing_feed = v,
            25 => self.homing_seek = v,
            26 => self.homing_debounce_ms = u16v,
            27 => self.homing_pulloff = v,
            30 => self.spindle_max = v,
            31 => self.spindle_min = v,
            32 => self.laser_mode = on,
            100..=139 => {
                let a = self
                    .axes
                    .get_mut(usize::from(n % 10))
                    .ok_or(SettingError::Unknown)?;
                match n / 10 {
                    10 => a.steps_per_mm = v,
                    11 => a.max_rate = v,
                    12 => a.max_accel = v,
                    _ => a.max_travel = v,
                }
            }
            160..=169 => {
                *self
                    .backlash_mm
                    .get_mut(usize::from(n - 160))
                    .ok_or(SettingError::Unknown)? = v;
            }
            200 => self.dir_setup_us = v,
            201 => self.max_step_rate_hz = v,
            202 => {
                self.profile = if on {
                    Profile::SCurve
                } else {
                    Profile::Trapezoid
                }
            }
            203 => self.jerk = v,
            204 => {
                self.rapid_mode = if on {
                    RapidMode::Independent
                } else {
                    RapidMode::Coordinated
                }
            }
            205 => self.verify_home_tolerance = v,
            206 => self.homing_order = u16v,
            207 => self.enable_delay_us = v,
            208 => self.report_axes = u8v,
            210 => self.g28_homes = on,
            211 => self.tool_change.mode = u8v,
            212..=214 => {
                if let Some(p) = self.tool_change.position.get_mut(usize::from(n - 212)) {
                    *p = v;
                }
            }
            215 => self.tool_change.axes = u8v,
            216 | 217 => {
                if let Some(p) = self.tool_change.setter.get_mut(usize::from(n - 216)) {
                    *p = v;
                }
            }
            218 => self.tool_change.feed = v,
            219 => self.tool_change.travel = v,
            220 => self.spindle_delay_s = v,
            376 => self.rotary_axes = u8v,
            _ => return Err(SettingError::Unknown),
        }
        Ok(())
    }
}
