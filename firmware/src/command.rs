//! The interpreter's output: what the machine should do, in machine-absolute
//! millimetres, with units, work offsets and G92 already applied.
//!
//! This is the contract between the language half of the core (`gcode`,
//! `interp`) and the motion half (`arc`, `planner`, `stepper`). Nothing after
//! this point knows about inches, G54 or G91.

pub mod cycle;

pub use cycle::{Cycle, CycleKind, CycleSteps};

use crate::AXES;

/// A position or displacement in machine millimetres (A in degrees), X Y Z A.
pub type Pos = [f32; AXES];

/// Bit mask over axes: bit 0 is X, bit 1 Y, bit 2 Z, bit 3 A.
pub type AxisMask = u8;

/// Every axis's bit in an [`AxisMask`].
pub const ALL_AXES: AxisMask = ((1u16 << crate::AXES) - 1) as AxisMask;

/// How fast a feed move goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Feed {
    /// G94: millimetres per minute along the path.
    PerMin(f32),
    /// G93: the move takes `1 / value` minutes, whatever its length.
    InverseTime(f32),
}

/// Arc plane (G17/G18/G19). The first two axes of the plane carry the arc,
/// the third is the helix axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plane {
    /// G17: arc in X/Y, helix along Z.
    XY,
    /// G18: arc in Z/X, helix along Y.
    ZX,
    /// G19: arc in Y/Z, helix along X.
    YZ,
}

impl Plane {
    /// Axis indices `(first, second, helix)` so that first x second points
    /// along +helix (right-handed), as RS274NGC defines CW/CCW per plane.
    pub const fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::XY => (0, 1, 2),
            Plane::ZX => (2, 0, 1),
            Plane::YZ => (1, 2, 0),
        }
    }
}

/// Arc direction seen from the positive end of the helix axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArcDir {
    /// G2
    Cw,
    /// G3
    Ccw,
}

/// A circular or helical arc. The start is the previous command's end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    pub end: Pos,
    /// Centre in the plane's two axes (machine mm), ordered as [`Plane::axes`].
    pub center: [f32; 2],
    pub plane: Plane,
    pub dir: ArcDir,
    /// Extra full turns beyond the first (G2 P2 is `turns = 1`).
    pub turns: u16,
    pub feed: Feed,
}

/// A cubic Bezier in X/Y (G5, and G5.1 raised to cubic). Other axes move
/// linearly with the curve parameter. The start is the previous end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spline {
    /// First and second control points in X/Y (machine mm).
    pub p1: [f32; 2],
    pub p2: [f32; 2],
    pub end: Pos,
    pub feed: Feed,
}

/// G38.2–G38.5 and G30-style probing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProbeKind {
    /// G38.2: towards the workpiece, error if no contact.
    Toward,
    /// G38.3: towards the workpiece, no error if no contact.
    TowardNoError,
    /// G38.4: away from the workpiece until contact breaks, error if it does not.
    Away,
    /// G38.5: away, no error.
    AwayNoError,
}

/// Spindle state for M3/M4/M5.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpindleDir {
    Off,
    Cw,
    Ccw,
}

/// Which side of the programmed path a compensated tool runs on, looking
/// along the direction of travel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompSide {
    /// G41, G41.1.
    Left,
    /// G42, G42.1.
    Right,
}

/// Cutter compensation turned on: what the interpreter knows then.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompOn {
    pub side: CompSide,
    /// Tool radius, machine mm. Zero compensates nothing (LinuxCNC).
    pub radius: f32,
    /// G17 or G18.
    pub plane: Plane,
    /// Lathe tool orientation (G41.1/G42.1 `L`, G18 only): for 1-8 the
    /// tool's origin is off the radius centre.
    pub orientation: u8,
    /// Where the tool is, machine mm.
    pub start: Pos,
}

/// Operator text from `(MSG, …)` or M117.
pub type Message = heapless::String<64>;

/// One thing for the machine to do. Motion variants carry machine-absolute
/// millimetres; the non-motion variants are executed in program order, synced
/// with motion by the planner (they wait until the moves before them are done).
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// G0: at the rapid rate.
    Rapid {
        end: Pos,
    },
    /// G1.
    Line {
        end: Pos,
        feed: Feed,
    },
    /// G2/G3.
    Arc(Arc),
    /// G5/G5.1.
    Spline(Spline),
    /// G4: seconds.
    Dwell {
        seconds: f32,
    },
    /// G28 (home the axes in the mask; all when none were named).
    Home {
        axes: AxisMask,
    },
    /// G27: seek the switches of these axes and compare against the expected position.
    VerifyHome {
        axes: AxisMask,
    },
    /// G38.x / G30.
    Probe {
        end: Pos,
        feed: Feed,
        kind: ProbeKind,
    },
    /// M3/M4/M5 with S (rpm or laser power units).
    Spindle {
        dir: SpindleDir,
        speed: f32,
    },
    /// M7/M8/M9 (M9 is both false).
    Coolant {
        mist: bool,
        flood: bool,
    },
    /// M42 / M62–M65 / M106 / M107: aux output `pin` to `value` (0.0–1.0 for PWM).
    /// `synced` outputs change with motion; the others change at once.
    Aux {
        pin: u8,
        value: f32,
        synced: bool,
    },
    /// M17 / M18 / M84: stepper drivers on or off.
    Motors {
        enable: bool,
        axes: AxisMask,
    },
    /// M0 (and M1 when optional stop is on): pause until cycle start.
    Pause {
        optional: bool,
    },
    /// M2 / M30.
    ProgramEnd,
    /// M400: wait until all motion is done.
    WaitIdle,
    /// Operator message.
    Message(Message),
    /// M114 / M115 / M119 requests for a report.
    Report(ReportKind),
    /// M220: feed override percent.
    FeedOverride {
        percent: u16,
    },
    /// T word or M61 (reported and remembered; nothing moves).
    Tool {
        number: u32,
    },
    /// M6: a manual tool change to `tool` (the executor stops the spindle,
    /// goes to the tool-change position and holds; `$211`-`$219`).
    ToolChange {
        tool: u32,
    },
    /// G73, G81-G89: one canned-cycle block, expanded by the executor.
    Cycle(Cycle),
    /// M500 / M501.
    SaveSettings,
    LoadSettings,
    /// M999: clear an alarm / restart after an error.
    ClearAlarm,
    /// G41/G42/G41.1/G42.1 (`Some`) and G40 (`None`): consumed by the
    /// compensation stage (`crate::comp`); the executor never sees it.
    CutterComp(Option<CompOn>),
}

/// What M114/M115/M119 ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReportKind {
    Position,
    Firmware,
    Endstops,
}

impl Command {
    /// The machine position this command ends at, for commands that move.
    pub fn end(&self) -> Option<&Pos> {
        match self {
            Command::Rapid { end }
            | Command::Line { end, .. }
            | Command::Probe { end, .. }
            | Command::Arc(Arc { end, .. })
            | Command::Spline(Spline { end, .. }) => Some(end),
            _ => None,
        }
    }
}
