//! Machine settings, numbered as GRBL 1.1 numbers them (`$0`–`$132`) so that
//! senders' settings dialogs work, plus burin's own from `$200` up.
//!
//! Values live in one plain struct the planner and stepper read directly;
//! the numbered table is only the text/wire view of it.

use crate::AXES;

pub mod ceiling;
pub mod table;

/// How rapids (G0) move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RapidMode {
    /// All axes start and stop together along a straight line (GRBL's way).
    Coordinated,
    /// Each axis runs at its own maximum rate (dog-leg path), as many
    /// industrial controls do; the move ends when the slowest axis arrives.
    Independent,
}

/// Velocity profile shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Profile {
    /// Constant acceleration ramps (GRBL).
    Trapezoid,
    /// Jerk-limited ramps: acceleration itself ramps at `jerk` mm/s³.
    SCurve,
}

/// Per-axis limits, GRBL `$100`–`$132`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisSettings {
    /// `$100+n`
    pub steps_per_mm: f32,
    /// `$110+n`, mm/min
    pub max_rate: f32,
    /// `$120+n`, mm/s² (GRBL's unit)
    pub max_accel: f32,
    /// `$130+n`, mm: the machine envelope is `[-travel, 0]` after homing to
    /// the positive end, or `[0, travel]` after homing to the negative end.
    pub max_travel: f32,
}

/// Every setting the core reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// `$0` step pulse width, µs.
    pub step_pulse_us: f32,
    /// `$1` idle delay before drivers are disabled, ms (255 = keep enabled).
    pub idle_delay_ms: u16,
    /// `$2` step pin invert mask.
    pub step_invert: u8,
    /// `$3` direction pin invert mask.
    pub dir_invert: u8,
    /// `$4` invert the stepper-enable pin.
    pub enable_invert: bool,
    /// `$5` limit pins invert mask.
    pub limit_invert: u8,
    /// `$6` probe pin invert.
    pub probe_invert: bool,
    /// `$10` status report mask (bit 0: MPos instead of WPos, bit 1: buffer).
    pub status_mask: u8,
    /// `$11` junction deviation, mm.
    pub junction_deviation: f32,
    /// `$12` arc (and spline) chord tolerance, mm.
    pub arc_tolerance: f32,
    /// `$13` report in inches.
    pub report_inches: bool,
    /// `$14` control input invert mask (grblHAL's): bit 0 reset/e-stop,
    /// bit 1 feed hold, bit 2 cycle start. Set bit 0 for a normally-closed
    /// e-stop, the safe wiring: a broken wire then stops the machine.
    pub control_invert: u8,
    /// `$20` soft limits.
    pub soft_limits: bool,
    /// `$21` hard limits.
    pub hard_limits: bool,
    /// `$22` homing cycle enabled.
    pub homing_enable: bool,
    /// `$23` homing direction invert mask (set: home towards negative).
    pub homing_dir_invert: u8,
    /// `$24` homing locate feed, mm/min.
    pub homing_feed: f32,
    /// `$25` homing seek rate, mm/min.
    pub homing_seek: f32,
    /// `$26` homing switch debounce, ms.
    pub homing_debounce_ms: u16,
    /// `$27` homing pull-off, mm.
    pub homing_pulloff: f32,
    /// `$30` maximum spindle speed, rpm.
    pub spindle_max: f32,
    /// `$31` minimum spindle speed, rpm.
    pub spindle_min: f32,
    /// `$32` laser mode.
    pub laser_mode: bool,
    pub axes: [AxisSettings; AXES],
    /// `$200` direction setup time before a step, µs.
    pub dir_setup_us: f32,
    /// `$201` step-rate ceiling per axis, Hz; a move needing more is refused.
    pub max_step_rate_hz: f32,
    /// `$202` profile: 0 trapezoid, 1 S-curve.
    pub profile: Profile,
    /// `$203` jerk for the S-curve profile, mm/s³.
    pub jerk: f32,
    /// `$204` rapid mode: 0 coordinated, 1 independent axes.
    pub rapid_mode: RapidMode,
    /// `$205` G27 verify-home tolerance, mm.
    pub verify_home_tolerance: f32,
    /// `$206` homing order: up to four cycles, a nibble of axes each, first
    /// cycle in the low nibble. Default: Z alone, then X and Y together.
    pub homing_order: u16,
    /// `$207` delay from driver enable to the first step pulse, µs. The
    /// step interrupt asserts the enable pin when it starts from rest and
    /// holds the first edge back this long: opto-isolated drivers such as
    /// the DM542 ignore steps for at least 5 µs after enable. 0 (the
    /// default) suits A4988/DRV8825/TMC drivers. Costs this much once per
    /// start from rest, never while stepping.
    pub enable_delay_us: f32,
    /// `$208` axes in reports (status positions, `$#`, `$I`'s `AXS`, the
    /// framed handshake): 3 for an XYZ machine, up to the [`AXES`] burin
    /// drives. GRBL senders size their position displays from it.
    pub report_axes: u8,
    /// `$210` what G28/G30 mean: 0 (default) RS274NGC's and GRBL's stored
    /// positions through an intermediate point, the meaning CAM posts for
    /// GRBL assume; 1 BeagleG's: G28 homes, G30 probes Z
    /// (`interp/homes.rs`).
    pub g28_homes: bool,
    /// `$211`-`$219`: the manual tool change (M6).
    pub tool_change: ToolChange,
    /// `$220` spindle spin-up delay, s: after a safety door or a spindle
    /// stop (0x9E), cycle start turns the spindle back on and waits this
    /// long before the coolant and the motion resume (GRBL's compiled-in
    /// 4 s; grblHAL's `$392`). 0 resumes at once.
    pub spindle_delay_s: f32,
    /// `$160`-`$163` backlash per axis, mm (grblHAL's numbers): the
    /// mechanical slack a reversing axis takes up before the tool moves.
    /// The motion pipeline moves the motors that much more at each
    /// reversal (`motion::Pipeline`), without it showing in the reported
    /// position. 0: no compensation.
    pub backlash_mm: [f32; AXES],
    /// `$376` rotary axes, bit n = axis n (grblHAL's number): their
    /// positions are degrees, and a feed move that also moves a linear
    /// axis takes F along the linear axes' path alone, the rotary ones
    /// following (RS274NGC's rule, `motion::Pipeline::rotary_feed`).
    /// 0 (the default): every axis counts in the path length, as GRBL.
    pub rotary_axes: u8,
}

/// What M6 does (`$211`-`$219`). Positions are machine mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolChange {
    /// `$211` 0: M6 only sets the current tool (GRBL 1.1; the sender
    /// runs its own tool-change macro); 1: spindle off, move to the
    /// tool-change position, hold until cycle start; 2: as 1, then measure
    /// the new tool on the tool setter and apply the difference to the
    /// first tool measured since power-up as its length offset.
    pub mode: u8,
    /// `$212`, `$213`, `$214` the tool-change position X, Y, Z.
    pub position: [f32; 3],
    /// `$215` which axes go there (mask, Z first, then X/Y); 4 = Z only.
    pub axes: u8,
    /// `$216`, `$217` the tool setter's X, Y.
    pub setter: [f32; 2],
    /// `$218` the probing feed on the tool setter, mm/min.
    pub feed: f32,
    /// `$219` how far down the setter probe searches from the change Z, mm.
    pub travel: f32,
}

impl ToolChange {
    pub const DEFAULT: ToolChange = ToolChange {
        mode: 1,
        position: [0.0; 3],
        axes: 0b100,
        setter: [0.0; 2],
        feed: 100.0,
        travel: 50.0,
    };
    /// See [`Settings::ZEROED`].
    pub const ZEROED: ToolChange = ToolChange {
        mode: 0,
        position: [0.0; 3],
        axes: 0,
        setter: [0.0; 2],
        feed: 0.0,
        travel: 0.0,
    };
}

impl Default for Settings {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// `$208`'s default: the default machine is an XYZA mill (a rotary A), so
/// GRBL senders show the four positions they showed before burin drove six
/// axes; a machine that wires B and C sets `$208=6`.
pub const DEFAULT_REPORT_AXES: u8 = if AXES < 4 { AXES as u8 } else { 4 };

const fn axis(steps: f32, rate: f32, accel: f32, travel: f32) -> AxisSettings {
    AxisSettings {
        steps_per_mm: steps,
        max_rate: rate,
        max_accel: accel,
        max_travel: travel,
    }
}

impl Settings {
    /// The defaults, as a constant.
    pub const DEFAULT: Settings = Settings {
        step_pulse_us: 2.0,
        idle_delay_ms: 25,
        step_invert: 0,
        dir_invert: 0,
        enable_invert: false,
        limit_invert: 0,
        probe_invert: false,
        status_mask: 1,
        junction_deviation: 0.01,
        arc_tolerance: 0.002,
        report_inches: false,
        control_invert: 0,
        soft_limits: false,
        hard_limits: false,
        homing_enable: false,
        homing_dir_invert: 0,
        homing_feed: 25.0,
        homing_seek: 500.0,
        homing_debounce_ms: 250,
        homing_pulloff: 1.0,
        spindle_max: 1000.0,
        spindle_min: 0.0,
        laser_mode: false,
        // Per letter, X Y Z A B C; the first AXES are this build's.
        // The rotary letters: 10 steps per degree, no travel limit.
        axes: protocol::first_axes([
            axis(80.0, 5000.0, 500.0, 300.0),
            axis(80.0, 5000.0, 500.0, 300.0),
            axis(400.0, 1000.0, 100.0, 100.0),
            axis(10.0, 3600.0, 300.0, 0.0),
            axis(10.0, 3600.0, 300.0, 0.0),
            axis(10.0, 3600.0, 300.0, 0.0),
        ]),
        dir_setup_us: 1.0,
        max_step_rate_hz: 200_000.0,
        profile: Profile::Trapezoid,
        jerk: 5000.0,
        rapid_mode: RapidMode::Coordinated,
        verify_home_tolerance: 0.05,
        homing_order: 0x34,
        enable_delay_us: 0.0,
        report_axes: DEFAULT_REPORT_AXES,
        g28_homes: false,
        tool_change: ToolChange::DEFAULT,
        spindle_delay_s: 4.0,
        backlash_mm: [0.0; AXES],
        rotary_axes: 0,
    };

    /// Every field zero (enums their first variant): only the board's
    /// machine slot is built from it (`Machine::placeholder`), so that the
    /// slot's value is all zero bits and the static sits in `.bss`, not in
    /// `.data` with an 11 KB load image in flash. `Machine::rebuild`
    /// replaces it before anything reads it (a zero `steps_per_mm` divides).
    pub const ZEROED: Settings = Settings {
        step_pulse_us: 0.0,
        idle_delay_ms: 0,
        step_invert: 0,
        dir_invert: 0,
        enable_invert: false,
        limit_invert: 0,
        probe_invert: false,
        status_mask: 0,
        junction_deviation: 0.0,
        arc_tolerance: 0.0,
        report_inches: false,
        control_invert: 0,
        soft_limits: false,
        hard_limits: false,
        homing_enable: false,
        homing_dir_invert: 0,
        homing_feed: 0.0,
        homing_seek: 0.0,
        homing_debounce_ms: 0,
        homing_pulloff: 0.0,
        spindle_max: 0.0,
        spindle_min: 0.0,
        laser_mode: false,
        axes: [axis(0.0, 0.0, 0.0, 0.0); AXES],
        dir_setup_us: 0.0,
        max_step_rate_hz: 0.0,
        profile: Profile::Trapezoid,
        jerk: 0.0,
        rapid_mode: RapidMode::Coordinated,
        verify_home_tolerance: 0.0,
        homing_order: 0,
        enable_delay_us: 0.0,
        report_axes: 0,
        g28_homes: false,
        tool_change: ToolChange::ZEROED,
        spindle_delay_s: 0.0,
        backlash_mm: [0.0; AXES],
        rotary_axes: 0,
    };
}
