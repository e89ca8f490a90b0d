//! Tools: T (select), M6 (change), M61 (set the current tool), the tool
//! length offset (G43 H, G43.1, G43.2, G49) and the tool table that G10 L1,
//! L10 and L11 write.
//!
//! Choices (LinuxCNC's semantics unless said):
//! - the table is keyed by tool number, not pocket: CAM output numbers
//!   tools freely (Carbide Create's `M6 T102`); it holds [`TOOLS`] entries,
//!   numbers 1..=[`TOOL_MAX`] (a stored number must be exact in `f32`);
//! - a tool without an entry has no offset: G43 H*n* then applies 0 and
//!   the device says so in a `[MSG:]` (LinuxCNC refuses the line);
//! - G43 without H uses the tool in the spindle (M6/M61); H0 is no offset;
//! - the offset is a work offset along the axes it names (Z for table
//!   lengths), in machine mm: the status report's `WCO:` includes it, as
//!   in GRBL; G43.1 sets it from axis words (GRBL 1.1's dynamic offset),
//!   G43.2 adds a table length and/or axis words to it;
//! - G10 L1 P*n* Z R writes length and radius (stored as the diameter);
//!   L10 computes the length so that the current Z becomes the given value
//!   with the current G5x and G92 offsets, L11 as if in G59.3 without G92;
//!   the table persists like the work offsets (`session::persist`);
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

/// Entries in the tool table.
pub const TOOLS: usize = 16;
/// Highest tool number a table entry may have: exact in an `f32` record.
pub const TOOL_MAX: u32 = 9_999_999;
/// Highest T word (GRBL accepts any 8-digit T).
const T_MAX: f32 = 99_999_999.0;

/// One tool: `number` 0 is an empty entry. Lengths and diameters in mm.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToolEntry {
    pub number: u32,
    pub length: f32,
    pub diameter: f32,
}

impl ToolEntry {
    pub const EMPTY: ToolEntry = ToolEntry {
        number: 0,
        length: 0.0,
        diameter: 0.0,
    };
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

/// A tool's length along Z as an offset vector; a missing entry is no
/// offset and a warning.
fn length_of(st: &mut State, tb: &Tables, n: u32) -> crate::command::Pos {
    let mut v = [0.0; AXES];
    if n == 0 {
        return v;
    }
    match find(&tb.get().tools, n) {
        Some(e) => v[2] = e.length,
        None => st.tool_warning = Some(n),
    }
    v
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
        let t = cx.int(b'T', 0.0, T_MAX)?;
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
            let q = cx.int(b'Q', 0.0, T_MAX)?;
            st.loaded = q;
            st.tool = q;
            push(out, Command::Tool { number: q }, col)?;
        }
    }
    let Some((g, col)) = b.g_of(GGroup::ToolLength) else {
        return Ok(());
    };
    let h = if b.has(b'H') {
        Some(cx.int(b'H', 0.0, TOOL_MAX as f32)?)
    } else {
        None
    };
    match g {
        430 => {
            let n = h.unwrap_or(st.loaded);
            st.tlo = length_of(st, tb, n);
        }
        431 => {
            if h.is_some() {
                return Err(cx.err(ErrorKind::UnusedWord(b'H'), b'H'));
            }
            st.tlo = axis_words(cx, st).ok_or(GcodeError::new(ErrorKind::NoAxisWords, col))?;
        }
        432 => {
            let words = axis_words(cx, st);
            if h.is_none() && words.is_none() {
                return Err(GcodeError::new(ErrorKind::ValueWordMissing(b'H'), col));
            }
            let add = length_of(st, tb, h.unwrap_or(0));
            let w = words.unwrap_or([0.0; AXES]);
            for i in 0..AXES {
                st.tlo[i] += add[i] + w[i];
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
    let n = cx.int(b'P', 1.0, TOOL_MAX as f32)?;
    let u = st.unit();
    let z = cx.take(b'Z').map(|z| z * u);
    let r = cx.take(b'R').map(|r| r * u);
    if r.is_some_and(|r| r < 0.0) {
        return Err(cx.err(ErrorKind::ValueOutOfRange(b'R'), b'R'));
    }
    let length = z.map(|z| match l {
        1 => z,
        10 => st.pos[2] - st.wco_no_tool(tb.get())[2] - z,
        _ => {
            let g593 = tb.get().wcs.get(WCS_COUNT - 1).map_or(0.0, |w| w[2]);
            st.pos[2] - g593 - z
        }
    });
    let tools = &mut tb.edit().tools;
    let slot = match tools.iter().position(|e| e.number == n) {
        Some(i) => i,
        None => tools
            .iter()
            .position(|e| e.number == 0)
            .ok_or(GcodeError::new(ErrorKind::ValueOutOfRange(b'P'), col))?,
    };
    let Some(e) = tools.get_mut(slot) else {
        return Ok(());
    };
    if e.number != n {
        *e = ToolEntry {
            number: n,
            ..ToolEntry::EMPTY
        };
    }
    if let Some(len) = length {
        e.length = len;
    }
    if let Some(r) = r {
        e.diameter = 2.0 * r;
    }
    st.offsets_changed = true;
    Ok(())
}

impl super::Interpreter {
    /// Once after a line that named a tool without a table entry (G43 H,
    /// M6): the device tells the operator that tool has no offset.
    pub fn take_tool_warning(&mut self) -> Option<u32> {
        self.state.tool_warning.take()
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

/// The table for `$#`: one `[T:n|length|diameter]` line per entry, in
/// grblHAL's bracketed shape so GRBL senders skip what they do not know.
pub(super) fn write_table(
    w: &mut dyn core::fmt::Write,
    tools: &[ToolEntry; TOOLS],
    eol: &str,
) -> core::fmt::Result {
    for e in tools.iter().filter(|e| e.number != 0) {
        write!(w, "[T:{}|", e.number)?;
        crate::num::write_fixed(w, e.length, 3)?;
        w.write_char('|')?;
        crate::num::write_fixed(w, e.diameter, 3)?;
        write!(w, "]{eol}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
