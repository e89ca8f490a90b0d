//! The interpreter's modal state: small and `Copy`, so a line can be rolled
//! back by restoring a snapshot taken before it ran. The large offset
//! tables ([`Offsets`]) sit beside it and are backed up only when written.
//!
//! Offsets and stored positions are typed values in machine mm and are
//! also visible through their RS274NGC parameter numbers (see
//! [`State::param`]). All of them stay in mm whatever G20/G21 say, like
//! LinuxCNC's parameters in a metric machine's units.

use super::cycles::Sticky;
use super::tools::{ToolEntry, TOOLS};
use crate::command::CycleKind;
use crate::command::{Plane, Pos, ProbeKind, SpindleDir};
use crate::gcode::ErrorKind;
use crate::AXES;

/// Work coordinate systems G54..G59.3.
pub const WCS_COUNT: usize = 9;

/// Group 1 motion modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    Rapid,
    Linear,
    ArcCw,
    ArcCcw,
    /// G5 cubic spline.
    Cubic,
    /// G5.1 quadratic spline.
    Quadratic,
    Probe(ProbeKind),
    /// G80: axis words without a motion word are an error.
    Cancel,
    /// G73, G81-G89: a canned cycle (`interp::cycles`).
    Cycle(CycleKind),
}

impl Motion {
    /// The G number in tenths.
    pub const fn tenths(self) -> u16 {
        match self {
            Motion::Rapid => 0,
            Motion::Linear => 10,
            Motion::ArcCw => 20,
            Motion::ArcCcw => 30,
            Motion::Cubic => 50,
            Motion::Quadratic => 51,
            Motion::Probe(ProbeKind::Toward) => 382,
            Motion::Probe(ProbeKind::TowardNoError) => 383,
            Motion::Probe(ProbeKind::Away) => 384,
            Motion::Probe(ProbeKind::AwayNoError) => 385,
            Motion::Cancel => 800,
            Motion::Cycle(k) => k.tenths(),
        }
    }
    pub(crate) const fn from_tenths(t: u16) -> Option<Motion> {
        Some(match t {
            0 => Motion::Rapid,
            10 => Motion::Linear,
            20 => Motion::ArcCw,
            30 => Motion::ArcCcw,
            50 => Motion::Cubic,
            51 => Motion::Quadratic,
            382 => Motion::Probe(ProbeKind::Toward),
            383 => Motion::Probe(ProbeKind::TowardNoError),
            384 => Motion::Probe(ProbeKind::Away),
            385 => Motion::Probe(ProbeKind::AwayNoError),
            800 => Motion::Cancel,
            t => match CycleKind::from_tenths(t) {
                Some(k) => Motion::Cycle(k),
                None => return None,
            },
        })
    }
}

/// Everything modal, plus positions and offsets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    pub motion: Motion,
    pub plane: Plane,
    /// G20 (true) / G21.
    pub inch: bool,
    /// G91 (true) / G90.
    pub incremental: bool,
    /// G90.1 (true): arc centres absolute. G91.1 (default): relative to the start.
    pub arc_absolute: bool,
    /// G93 (true) / G94.
    pub inverse_time: bool,
    /// Active work coordinate system, 0 = G54 .. 8 = G59.3.
    pub wcs: u8,
    pub g92: Pos,
    pub g92_active: bool,
    /// Where the tool is (or will be after the last emitted command), machine mm.
    pub pos: Pos,
    /// G94 feed rate, mm/min (0: none given yet).
    pub feed: f32,
    pub speed: f32,
    pub spindle: SpindleDir,
    pub mist: bool,
    pub flood: bool,
    /// The last T word (GRBL's `$G` T), or the tool M6/M61 made current.
    pub tool: u32,
    /// The tool in the spindle (M6, M61): G43 without H uses its length.
    pub loaded: u32,
    /// Tool length offset (G43, G43.1, G43.2; 0 after G49), machine mm per
    /// axis; part of the work offset ([`State::wco`]).
    pub tlo: Pos,
    /// An M6 named a tool without a table entry: the device says so.
    pub tool_warning: Option<u32>,
    /// An arc carried a zero offset off its plane (`I0` in G19): ignored,
    /// and the device says so.
    pub off_plane_zero: Option<u8>,
    /// G99 (true): canned cycles retract to R; G98: to where they began.
    pub retract_r: bool,
    /// Canned-cycle words that carry over to the next cycle block.
    pub cycle: Sticky,
    /// Last probe contact (machine mm) and whether it succeeded.
    pub probe: Pos,
    pub probe_ok: bool,
    /// After a G5: the second control point's offset from the end, for the
    /// next G5's implicit first control point.
    pub last_g5: Option<[f32; 2]>,
    /// G30 asked for the probed Z to become this work Z (mm).
    pub pending_probe_z: Option<f32>,
    /// `/` lines are skipped while this is on.
    pub block_delete: bool,
    /// The last command ended where only the machine knows (home, probe).
    pub needs_sync: bool,
    /// G10 L2/L20, G28.1 or G30.1 ran: the device persists the offsets.
    pub offsets_changed: bool,
    /// `$210=1`: G28 homes and G30 probes (BeagleG); else RS274NGC's stored positions.
    pub g28_homes: bool,
    /// `%` lines seen: 1 after the opening one; 2 after the closing one,
    /// when lines are skipped until the next `%` or a reset.
    pub percent: u8,
    /// G41/G42 (G41.1/G42.1) in effect; `None`: G40.
    pub comp: Option<crate::command::CompSide>,
}

impl Default for State {
    fn default() -> Self {
        Self::new()
    }
}

impl State {
    pub const fn new() -> Self {
        State {
            motion: Motion::Rapid,
            plane: Plane::XY,
            inch: false,
            incremental: false,
            arc_absolute: false,
            inverse_time: false,
            wcs: 0,
            g92: [0.0; AXES],
            g92_active: false,
            pos: [0.0; AXES],
            feed: 0.0,
            speed: 0.0,
            spindle: SpindleDir::Off,
            mist: false,
            flood: false,
            tool: 0,
            loaded: 0,
            tlo: [0.0; AXES],
            tool_warning: None,
            off_plane_zero: None,
            retract_r: false,
            cycle: Sticky::NONE,
            probe: [0.0; AXES],
            probe_ok: false,
            last_g5: None,
            pending_probe_z: None,
            block_delete: true,
            needs_sync: false,
            offsets_changed: false,
            g28_homes: false,
            percent: 0,
            comp: None,
        }
    }

    /// Work coordinate offset: active G54.., G92 when active, and the tool
    /// length offset (GRBL's WCO includes it too).
    pub fn wco(&self, o: &Offsets) -> Pos {
        let mut w = self.wco_no_tool(o);
        for (a, t) in w.iter_mut().zip(self.tlo.iter()) {
            *a += t;
        }
        w
    }

    /// The work offset without the tool length offset (G10 L10, G92).
    pub fn wco_no_tool(&self, o: &Offsets) -> Pos {
        let base = o
            .wcs
            .get(usize::from(self.wcs))
            .copied()
            .unwrap_or([0.0; AXES]);
        let mut o = base;
        if self.g92_active {
            for (a, g) in o.iter_mut().zip(self.g92.iter()) {
                *a += g;
            }
        }
        o
    }

    /// Length factor from program units to mm.
    pub fn unit(&self) -> f32 {
        if self.inch {
            25.4
        } else {
            1.0
        }
    }

    /// The typed value behind parameter `n`, if `n` is one of ours.
    /// #5061-5064 probe (machine mm), #5070 probe ok, #5161 G28, #5181 G30,
    /// #5210 G92 on, #5211 G92, #5220 active system 1-9, #5221+20k G54+k.
    pub fn param(&self, o: &Offsets, n: u16) -> Option<f32> {
        match n {
            5061..=5064 => self.probe.get(usize::from(n - 5061)).copied(),
            5070 => Some(f32::from(u8::from(self.probe_ok))),
            5210 => Some(f32::from(u8::from(self.g92_active))),
            5220 => Some(f32::from(self.wcs + 1)),
            5400..=5410 => super::tools::param(self, o, n),
            _ => match slot_of(n)? {
                Slot::G28(a) => o.g28.get(a).copied(),
                Slot::G30(a) => o.g30.get(a).copied(),
                Slot::G92(a) => self.g92.get(a).copied(),
                Slot::Wcs(k, a) => o.wcs.get(k).and_then(|w| w.get(a)).copied(),
            },
        }
    }

    /// Writes a typed parameter. `Ok(false)`: not one of ours (use the table).
    pub(crate) fn set_param(&mut self, t: &mut Tables, n: u16, v: f32) -> Result<bool, ErrorKind> {
        let slot = match n {
            5061..=5064 | 5070 | 5220 | 5400..=5410 => return Err(ErrorKind::ParamReadOnly),
            5210 => {
                self.g92_active = v != 0.0;
                return Ok(true);
            }
            _ => match slot_of(n) {
                None => return Ok(false),
                Some(Slot::G92(a)) => self.g92.get_mut(a),
                Some(Slot::G28(a)) => t.edit().g28.get_mut(a),
                Some(Slot::G30(a)) => t.edit().g30.get_mut(a),
                Some(Slot::Wcs(k, a)) => t.edit().wcs.get_mut(k).and_then(|w| w.get_mut(a)),
            },
        };
        if let Some(s) = slot {
            *s = v;
        }
        Ok(true)
    }
}

/// What survives a power cycle (GRBL's EEPROM coordinate data): the nine
/// work offsets G54..G59.3 and the G28/G30 positions, machine mm, and the
/// tool table. G92 and the modal state do not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Offsets {
    pub wcs: [Pos; WCS_COUNT],
    pub g28: Pos,
    pub g30: Pos,
    /// The tool table (G10 L1/L10/L11), keyed by tool number.
    pub tools: [ToolEntry; TOOLS],
}

impl Default for Offsets {
    fn default() -> Self {
        Offsets {
            wcs: [[0.0; AXES]; WCS_COUNT],
            g28: [0.0; AXES],
            g30: [0.0; AXES],
            tools: [ToolEntry::EMPTY; TOOLS],
        }
    }
}

/// What a line backs up of the offset tables before it first writes them,
/// so a refused line leaves no trace: the work offsets and G28/G30 whole,
/// and of the tool table (most of the tables by size: a whole copy on the
/// stack cost 1.5 KB) only the slots written, each once. A line writes one
/// slot per G10; a split line (`G10 … G10 …`) a few.
#[derive(Default)]
pub(crate) struct Saved {
    axes: Option<([Pos; WCS_COUNT], Pos, Pos)>,
    tools: heapless::Vec<(u8, ToolEntry), SAVED_TOOLS>,
}

/// Tool slots one line may write.
pub(crate) const SAVED_TOOLS: usize = 4;

impl Saved {
    /// The line wrote the tables.
    pub(crate) fn any(&self) -> bool {
        self.axes.is_some() || !self.tools.is_empty()
    }
    /// Puts back what the line changed.
    pub(crate) fn restore(self, o: &mut Offsets) {
        if let Some((wcs, g28, g30)) = self.axes {
            o.wcs = wcs;
            o.g28 = g28;
            o.g30 = g30;
        }
        for (k, e) in self.tools {
            if let Some(t) = o.tools.get_mut(usize::from(k)) {
                *t = e;
            }
        }
    }
}

/// The offset tables as one line sees them. They are most of the
/// interpreter's state by size but rarely written, so instead of copying
/// them before every line (as [`State`] is), a line backs up what it
/// writes the first time it writes it, and only then ([`Saved`]).
pub(crate) struct Tables<'t> {
    cur: &'t mut Offsets,
    saved: &'t mut Saved,
}

impl<'t> Tables<'t> {
    pub(crate) fn new(cur: &'t mut Offsets, saved: &'t mut Saved) -> Self {
        Tables { cur, saved }
    }
    pub(crate) fn get(&self) -> &Offsets {
        self.cur
    }
    /// The work offsets and G28/G30 for writing (tools: [`Tables::tool`]).
    pub(crate) fn edit(&mut self) -> &mut Offsets {
        if self.saved.axes.is_none() {
            self.saved.axes = Some((self.cur.wcs, self.cur.g28, self.cur.g30));
        }
        self.cur
    }
    /// Tool slot `k` for writing; `None` when the line has written more
    /// slots than it can back up.
    pub(crate) fn tool(&mut self, k: usize) -> Option<&mut ToolEntry> {
        let old = *self.cur.tools.get(k)?;
        let slot = u8::try_from(k).ok()?;
        if !self.saved.tools.iter().any(|(s, _)| *s == slot) {
            self.saved.tools.push((slot, old)).ok()?;
        }
        self.cur.tools.get_mut(k)
    }
}

enum Slot {
    G28(usize),
    G30(usize),
    G92(usize),
    Wcs(usize, usize),
}

fn slot_of(n: u16) -> Option<Slot> {
    let axis = |base: u16| usize::from(n - base);
    Some(match n {
        5161..=5164 => Slot::G28(axis(5161)),
        5181..=5184 => Slot::G30(axis(5181)),
        5211..=5214 => Slot::G92(axis(5211)),
        5221..=5400 if usize::from((n - 5221) % 20) < AXES => {
            Slot::Wcs(usize::from((n - 5221) / 20), usize::from((n - 5221) % 20))
        }
        _ => return None,
    })
}
