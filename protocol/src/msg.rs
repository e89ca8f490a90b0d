//! Messages in both directions. All owned and fixed-size (heapless), so the
//! firmware can hold them without a heap and the host client can queue them.
//!
//! Adding a variant at the end is compatible within a protocol version only
//! if old peers never receive it; anything else bumps
//! [`crate::PROTOCOL_VERSION`] (postcard encodes variants by index).

use crate::rt::Rt;
use crate::{MAX_LINE, WIRE_AXES};
use serde::{Deserialize, Serialize};

/// A job line's bytes (G-code is ASCII, but the link does not insist).
pub type LineText = heapless::Vec<u8, MAX_LINE>;
/// Short names: firmware version, board.
pub type ShortText = heapless::String<32>;
/// Operator messages (`[MSG:…]`).
pub type MsgText = heapless::String<64>;

/// Host to device.
// Lines are stored inline on purpose: no heap on the device, and one
// message is never copied often enough for the size to matter.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum HostMsg {
    /// Start of a framed session; the device answers [`DeviceMsg::Welcome`].
    Hello { version: u16 },
    /// A job line (G-code or `$` command) with its sequence number.
    Line { seq: u32, text: LineText },
    /// A realtime command; bypasses the job queue.
    Realtime(Rt),
    /// Read one numbered setting; answered by [`DeviceMsg::Setting`].
    GetSetting { n: u16 },
    /// Write one numbered setting; answered by `Setting` or `Error`.
    SetSetting { n: u16, value: f32 },
    /// All settings: one `Setting` each, then [`DeviceMsg::SettingsEnd`].
    ListSettings,
    /// End of the framed session: the port goes back to text mode.
    Bye,
}

/// Device to host.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DeviceMsg {
    /// Handshake answer.
    Welcome(DeviceInfo),
    /// Line `seq` is queued (or was already: a duplicate). The host may send
    /// lines up to `next + credits - 1`.
    Ack { seq: u32, next: u32, credits: u16 },
    /// A line or frame was refused; resend from `expected`. `code` says why
    /// ([`crate::Code`]: FrameCrc, SeqGap, FlowOverrun, …).
    Nak { expected: u32, code: u16 },
    /// Status report (answer to [`Rt::StatusQuery`]).
    Status(Status),
    /// A queued line failed when parsed or executed. `seq` is its sequence
    /// number (None for requests outside the job stream), `line` its N word.
    Error {
        seq: Option<u32>,
        line: Option<u32>,
        code: u16,
    },
    /// Alarm: the machine stopped; [`crate::codes::alarm`] numbers.
    Alarm { code: u16 },
    /// One setting's value.
    Setting { n: u16, value: f32 },
    /// End of a [`HostMsg::ListSettings`] answer.
    SettingsEnd,
    /// Operator message.
    Msg(MsgText),
}

/// What the device says about itself in the handshake.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceInfo {
    /// The device's [`crate::PROTOCOL_VERSION`].
    pub protocol: u16,
    /// Firmware version (`burin` crate version).
    pub firmware: ShortText,
    /// Board name, e.g. `blackpill-f411`.
    pub board: ShortText,
    /// Axes the device drives (the first `axes` of X, Y, Z, A, B, C).
    pub axes: u8,
    /// Job lines the device can queue (total line slots).
    pub line_slots: u16,
    /// Planner look-ahead blocks.
    pub planner_blocks: u16,
    /// Receive buffer size in bytes.
    pub rx_bytes: u16,
    /// Capability bits, [`caps`].
    pub caps: u32,
    /// Sequence number the device expects next.
    pub next_seq: u32,
    /// Free line slots right now.
    pub credits: u16,
}

/// Capability bits in [`DeviceInfo::caps`].
pub mod caps {
    /// Jerk-limited S-curve profile available.
    pub const SCURVE: u32 = 1 << 0;
    /// Homing switches configured.
    pub const HOMING: u32 = 1 << 1;
    /// Probe input.
    pub const PROBE: u32 = 1 << 2;
    /// Spindle PWM output.
    pub const SPINDLE_PWM: u32 = 1 << 3;
    /// Check mode (`$C`).
    pub const CHECK_MODE: u32 = 1 << 4;
    /// Safety door input.
    pub const DOOR: u32 = 1 << 5;
}

/// Machine state as GRBL names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MachineState {
    Idle,
    Run,
    Hold,
    Jog,
    Alarm,
    Home,
    Check,
    Door,
    Sleep,
}

impl MachineState {
    /// The word GRBL prints in the status report.
    pub const fn name(self) -> &'static str {
        match self {
            MachineState::Idle => "Idle",
            MachineState::Run => "Run",
            MachineState::Hold => "Hold",
            MachineState::Jog => "Jog",
            MachineState::Alarm => "Alarm",
            MachineState::Home => "Home",
            MachineState::Check => "Check",
            MachineState::Door => "Door",
            MachineState::Sleep => "Sleep",
        }
    }

    /// Whether GRBL prints a sub-state (`Hold:0`, `Door:1`).
    pub const fn has_substate(self) -> bool {
        matches!(self, MachineState::Hold | MachineState::Door)
    }
}

/// Override percentages.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Overrides {
    pub feed: u8,
    pub rapid: u8,
    pub spindle: u8,
}

impl Default for Overrides {
    fn default() -> Self {
        Overrides {
            feed: 100,
            rapid: 100,
            spindle: 100,
        }
    }
}

/// Input pin bits in [`Status::pins`] (GRBL's `Pn:` letters).
pub mod pins {
    use crate::{AXES, AXIS_NAMES};

    /// Axis `i`'s limit bit: the limits take the first [`AXES`] bits, the
    /// other inputs follow them.
    pub const fn limit(i: usize) -> u16 {
        1 << i
    }
    pub const LIMIT_X: u16 = limit(0);
    pub const LIMIT_Y: u16 = limit(1);
    pub const LIMIT_Z: u16 = limit(2);
    pub const PROBE: u16 = 1 << AXES;
    pub const DOOR: u16 = 1 << (AXES + 1);
    pub const HOLD: u16 = 1 << (AXES + 2);
    pub const RESET: u16 = 1 << (AXES + 3);
    pub const START: u16 = 1 << (AXES + 4);
    const _: () = assert!(AXES + 5 <= 16);
    /// `(bit, letter)` in the order GRBL prints them: the axes' limits,
    /// then P D H R S.
    pub const LETTERS: [(u16, char); AXES + 5] = {
        let mut l = [(0, 'P'); AXES + 5];
        let mut i = 0;
        while i < AXES {
            l[i] = (limit(i), AXIS_NAMES[i]);
            i += 1;
        }
        l[AXES] = (PROBE, 'P');
        l[AXES + 1] = (DOOR, 'D');
        l[AXES + 2] = (HOLD, 'H');
        l[AXES + 3] = (RESET, 'R');
        l[AXES + 4] = (START, 'S');
        l
    };
}

/// One status snapshot. The device fills this once; text mode formats it as
/// `<…>` and framed mode sends it as is, so both report the same thing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Status {
    pub state: MachineState,
    /// `Hold:0` (stopped, ready to resume) / `Hold:1` (still stopping), `Door:n`.
    pub substate: u8,
    /// Machine position, mm (A in degrees).
    pub mpos: [f32; WIRE_AXES],
    /// Work coordinate offset: `WPos = MPos - WCO`.
    pub wco: [f32; WIRE_AXES],
    /// Current feed, mm/min.
    pub feed: f32,
    /// Current spindle speed, rpm.
    pub spindle: f32,
    /// Free planner blocks (`Bf:` first number).
    pub planner_free: u16,
    /// Free receive bytes (`Bf:` second number).
    pub rx_free: u16,
    /// N word of the line executing (`Ln:`).
    pub line: Option<u32>,
    pub overrides: Overrides,
    /// [`pins`] bits that are active.
    pub pins: u16,
    /// [`accessory`] bits: spindle and coolant as the pins are (`A:`).
    pub accessories: u8,
}

/// GRBL 1.1's `A:` field letters as [`Status::accessories`] bits, in the
/// order GRBL prints them.
pub mod accessory {
    pub const SPINDLE_CW: u8 = 1;
    pub const SPINDLE_CCW: u8 = 2;
    pub const FLOOD: u8 = 4;
    pub const MIST: u8 = 8;
    pub const LETTERS: [(u8, char); 4] = [
        (SPINDLE_CW, 'S'),
        (SPINDLE_CCW, 'C'),
        (FLOOD, 'F'),
        (MIST, 'M'),
    ];
}

impl Default for Status {
    fn default() -> Self {
        Status {
            state: MachineState::Idle,
            substate: 0,
            mpos: [0.0; WIRE_AXES],
            wco: [0.0; WIRE_AXES],
            feed: 0.0,
            spindle: 0.0,
            planner_free: 0,
            rx_free: 0,
            line: None,
            overrides: Overrides::default(),
            pins: 0,
            accessories: 0,
        }
    }
}

impl Status {
    /// Work position: machine position minus the work offset.
    pub fn wpos(&self) -> [f32; WIRE_AXES] {
        let mut w = self.mpos;
        for (w, o) in w.iter_mut().zip(self.wco) {
            *w -= o;
        }
        w
    }
}
