//! Tools: T (select), M6 (change), M61 (set the current tool), the tool
//! length offset (G43 H, G43.1, G43.2, G49) and the tool table that G10 L1,
//! L10 and L11 write.
//!
//! Choices (LinuxCNC 2.9's semantics, measured with its `rs274`, unless said):
//! - the table is keyed by tool number, not pocket: CAM output numbers
//!   tools freely (Carbide Create's `M6 T102`); it holds [`TOOLS`] entries,
//!   numbers 1..=[`TOOL_MAX`], 2^31 − 1 as in LinuxCNC (words are `f32`,
//!   exact below 2^24: a larger tool number is read again from its digits,
//!   so no tool is ever read as its neighbour, see `Ctx::tool`);
//! - an entry holds offsets along X, Y and Z (G10 L1 X Y Z; a mill's
//!   length is Z, a lathe's tools use X too; LinuxCNC also holds the
//!   rotary and UVW axes, which burin refuses in G10 L1) and the diameter
//!   (G10 L1 R is the radius, as LinuxCNC);
//! - G43 H*n*, G43 with tool *n* in the spindle and G43.2 H*n* refuse a
//!   tool without an entry, as LinuxCNC does: an unknown length must not
//!   become 0. T, M6 and M61 still accept one (LinuxCNC refuses them too):
//!   a tool setter measures tools no table lists, and T alone applies
//!   nothing; M6 says so in a `[MSG:]`;
//! - G43 without H and G43 H0 use the tool in the spindle (M6/M61);
//! - the offset is a work offset along the axes it names, in machine mm:
//!   the status report's `WCO:` includes it, as in GRBL; G43.1 replaces
//!   the named axes only (`G43 H3` then `G43.1 X2` keeps tool 3's Z), a
//!   bare G43.1 changes nothing; G43.2 adds a table entry (H) or axis
//!   words, not both;
//! - G10 L1 P*n* needs a value; L10 computes the length so that the
//!   current Z becomes the given value with the current G5x and G92
//!   offsets, L11 as if in G59.3 without G92; the table persists like the
//!   work offsets (`session::persist`);
//! - M6 changes to the last T word's tool; the executor stops the spindle,
//!   goes to the tool-change position and holds (`executor::script`);
//!   afterwards the interpreter waits for the machine's real position;
//! - the offset and the current tool survive a soft reset and M2 (they
//!   describe the machine, not the program).

use super::block::{GGroup, MGroup, AXIS_LETTERS};
use super::exec::{push, Ctx, Out};
use super::state::{Offsets, State, Tables, WCS_COUNT};
use crate::command::Command;
use crate::gcode::{ErrorKind, GcodeError};
use crate::AXES;

/// Entries in the tool table: 20 bytes each in RAM (and a 4-byte
/// fingerprint in the persist mirror).
pub const TOOLS: usize = 64;
/// Axes a table entry holds offsets for: X, Y and Z (a rotary axis has
/// no tool offset on a mill; each copy of the table the stack holds at
/// boot costs 256 B more per axis, and the F401's stack is tight).
pub const TOOL_AXES: usize = 3;
/// Highest tool number (T, H, D, M61 Q, G10 L1 P): LinuxCNC's, an `int`.
pub const TOOL_MAX: u32 = i32::MAX as u32;

/// One tool: `number` 0 is an empty entry. Offsets along X, Y, Z and the
/// diameter, mm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToolEntry {
    pub number: u32,
    pub offset: [f32; TOOL_AXES],
    pub diameter: f32,
}

impl ToolEntry {
    pub const EMPTY: ToolEntry = ToolEntry {
        number: 0,
        offset: [0.0; TOOL_AXES],
        diameter: 0.0,
    };
    /// The length along Z (a mill's tool length).
    pub fn length(&self) -> f32 {
        self.offset[2]
    }
}

/// The entry of tool `n` (never for tool 0).
pub fn find(tools: &[ToolEntry; TOOLS], n: u32) -> Option<&ToolEntry> {
    tools.iter().find(|e| n != 0 && e.number == n)
}

/// #5400 the tool in the spindle, #5401-#5404 its offset X Y Z A (the
/// active tool length offset), #5410 its diameter.
pub(super) fn param(st: &State, o: &Offsets, n: u16) -> Option<f32> {
    Some(match n {
        5400 => st.loaded as f32,
        5401..=5404 => st.tlo.get(usize::from(n - 5401)).copied()?,
        5410 => find(&o.tools, st.loaded).map_or(0.0, |e| e.diameter),
        _ => 0.0,
    })
}

/// Whether the tool-length word of `b` owns its axis words (G43.1, G43.2).
pub(super) fn owns_axes(b: &super::block::Block) -> bool {
    matches!(b.g_of(GGroup::ToolLength), Some((431 | 432, _)))
}

/// A tool's offsets; tool 0 (none) has none, a tool without an entry is
/// an error (LinuxCNC: "requested tool not found in the tool table").
fn offset_of(tb: &Tables, n: u32) -> Result<crate::command::Pos, ErrorKind> {
    if n == 0 {
        return Ok([0.0; AXES]);
    }
    let e = find(&tb.get().tools, n).ok_or(ErrorKind::ToolNotInTable)?;
    let mut v = [0.0; AXES];
    v[..TOOL_AXES].copy_from_slice(&e.offset);
    Ok(v)
}

fn axis_words(cx: &mut Ctx, st: &State) -> Option<crate::command::Pos> {
    let u = st.unit();
    let mut v = [0.0; AXES];
    let mut any = false;
    for (i, l) in AXIS_LETTERS.iter().enumerate() {
        if let (Some(x), Some(s)) = (cx.take(*l), v.get_mut(i)) {
            *s = if i < 3 { x * u } else { x };
            any = true;
        }
    }
    any.then_some(v)
}

/// T, M6/M61 and G43..G49 of one block, in RS274NGC's order.
pub(super) fn tool_words(
    cx: &mut Ctx,
    st: &mut State,
    tb: &mut Tables,
    out: &mut Out,
) -> Result<(), GcodeError> {
    let b = cx.b;
    if b.has(b'T') {
        let t = cx.tool(b'T', 0)?;
        st.tool = t;
        push(out, Command::Tool { number: t }, b.col_of(b'T'))?;
    }
    if let Some((m, col)) = b.m_of(MGroup::Tool) {
        if m == 6 {
            let t = st.tool;
            push(out, Command::ToolChange { tool: t }, col)?;
            st.loaded = t;
            st.needs_sync = true;
            st.last_g5 = None;
            if t != 0 && find(&tb.get().tools, t).is_none() {
                st.tool_warning = Some(t);
            }
        } else {
            let q = cx.tool(b'Q', 0)?;
            st.loaded = q;
            st.tool = q;
            push(out, Command::Tool { number: q }, col)?;
        }
    }
    let Some((g, col)) = b.g_of(GGroup::ToolLength) else {
        return Ok(());
    };
    let h = if b.has(b'H') {
        Some(cx.tool(b'H', 0)?)
    } else {
        None
    };
    let h_err = |cx: &Ctx, k| cx.err(k, b'H');
    match g {
        430 => {
            // H0 and no H alike: the tool in the spindle (LinuxCNC 2.9).
            let n = h.filter(|&n| n != 0).unwrap_or(st.loaded);
            st.tlo = offset_of(tb, n).map_err(|k| match h {
                Some(_) => h_err(cx, k),
                None => GcodeError::new(k, col),
            })?;
        }
        431 => {
            if h.is_some() {
                return Err(cx.err(ErrorKind::UnusedWord(b'H'), b'H'));
            }
            // Only the named axes change; a bare G43.1 changes nothing.
            let u = st.unit();
            for (i, l) in AXIS_LETTERS.iter().enumerate() {
                if let (Some(v), Some(t)) = (cx.take(*l), st.tlo.get_mut(i)) {
                    *t = if i < 3 { v * u } else { v };
                }
            }
        }
        432 => {
            let words = axis_words(cx, st);
            let add = match (h, words) {
                (Some(_), Some(_)) => return Err(h_err(cx, ErrorKind::MixedToolOffset)),
                (Some(n), None) => offset_of(tb, n).map_err(|k| h_err(cx, k))?,
                (None, Some(w)) => w,
                (None, None) => {
                    return Err(GcodeError::new(ErrorKind::ValueWordMissing(b'H'), col))
                }
            };
            for (t, a) in st.tlo.iter_mut().zip(add) {
                *t += a;
            }
        }
        _ => {
            if h.is_some() {
                return Err(cx.err(ErrorKind::UnusedWord(b'H'), b'H'));
            }
            st.tlo = [0.0; AXES];
        }
    }
    Ok(())
}

/// G10 L1 / L10 / L11 P<tool> [Z] [R]: writes the tool table.
pub(super) fn g10_tool(
    cx: &mut Ctx,
    st: &mut State,
    tb: &mut Tables,
    l: u32,
    col: u16,
) -> Result<(), GcodeError> {
    let n = cx.tool(b'P', 1)?;
    let u = st.unit();
    let mut words = [None; TOOL_AXES];
    for (l, w) in AXIS_LETTERS.iter().zip(words.iter_mut()) {
        *w = cx.take(*l).map(|v| v * u);
    }
    // LinuxCNC stores 2R as the diameter, whatever its sign.
    let r = cx.take(b'R').map(|r| r * u);
    if r.is_none() && words.iter().all(Option::is_none) {
        return Err(GcodeError::new(ErrorKind::NoToolValues, col));
    }
    // L1: the values themselves; L10/L11: what makes the current position
    // read the given value (with the current G5x/G92, or in G59.3).
    let g593 = tb
        .get()
        .wcs
        .get(WCS_COUNT - 1)
        .copied()
        .unwrap_or([0.0; AXES]);
    let base = st.wco_no_tool(tb.get());
    let mut offset = [None; TOOL_AXES];
    for (i, (o, w)) in offset.iter_mut().zip(words).enumerate() {
        let here = st.pos.get(i).copied().unwrap_or(0.0);
        *o = w.map(|v| match l {
            1 => v,
            10 => here - base.get(i).copied().unwrap_or(0.0) - v,
            _ => here - g593.get(i).copied().unwrap_or(0.0) - v,
        });
    }
    let tools = &tb.get().tools;
    let slot = match tools.iter().position(|e| e.number == n) {
        Some(i) => i,
        None => tools
            .iter()
            .position(|e| e.number == 0)
            .ok_or(GcodeError::new(ErrorKind::ValueOutOfRange(b'P'), col))?,
    };
    let e = tb
        .tool(slot)
        .ok_or(GcodeError::new(ErrorKind::TooManyCommands, col))?;
    if e.number != n {
        *e = ToolEntry {
            number: n,
            ..ToolEntry::EMPTY
        };
    }
    for (o, v) in e.offset.iter_mut().zip(offset) {
        if let Some(v) = v {
            *o = v;
        }
    }
    if let Some(r) = r {
        e.diameter = 2.0 * r;
    }
    st.offsets_changed = true;
    Ok(())
}

impl super::Interpreter {
    /// Once after a line that changed to a tool without a table entry
    /// (M6): the device tells the operator that tool has no offset.
    pub fn take_tool_warning(&mut self) -> Option<u32> {
        self.state.tool_warning.take()
    }

    /// Once after an arc with a zero offset off its plane (`I0` in G19):
    /// the letter, which was ignored.
    pub fn take_arc_warning(&mut self) -> Option<u8> {
        self.state.off_plane_zero.take()
    }

    /// A tool setter measured the new tool: its length offset along Z
    /// becomes `z` mm (as `G43.1 Z` would set it, in mm).
    pub fn set_tool_length(&mut self, z: f32) {
        if z.is_finite() {
            self.state.tlo = [0.0; crate::AXES];
            self.state.tlo[2] = z;
        }
    }
}

/// The table for `$#`: one `[T:n|x,y,z|diameter]` line per entry, in
/// grblHAL's bracketed shape (offsets per axis, as grblHAL prints them)
/// so GRBL senders skip what they do not know.
pub(super) fn write_table(
    w: &mut dyn core::fmt::Write,
    tools: &[ToolEntry; TOOLS],
    eol: &str,
) -> core::fmt::Result {
    for e in tools.iter().filter(|e| e.number != 0) {
        write!(w, "[T:{}|", e.number)?;
        for (i, o) in e.offset.iter().enumerate() {
            if i > 0 {
                w.write_char(',')?;
            }
            crate::num::write_fixed(w, *o, 3)?;
        }
        w.write_char('|')?;
        crate::num::write_fixed(w, e.diameter, 3)?;
        write!(w, "]{eol}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
