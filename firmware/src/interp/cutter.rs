//! G40, G41/G42 (`D`: a tool of the table, the tool in the spindle when
//! omitted) and G41.1/G42.1 (`D`: a diameter, `L`: a lathe tool's
//! orientation): the modal state, the command that turns the compensation
//! stage ([`crate::comp`]) on or off, and what compensation forbids.
//!
//! LinuxCNC's rules, by its order of execution within a block (a G40 on
//! the line lifts the ban for what runs after it: coordinate systems, tool
//! offsets, G28/G30, G53, G92, probes, cycles, splines; a plane change and
//! M6 run before it and are refused): compensation works in G17 and G18
//! only, G41/G42 while it is on is an error, and a radius of 0 (an empty
//! diameter) compensates nothing.

use super::block::{Block, GGroup, MGroup};
use super::exec::{push, Ctx, Out};
use super::state::{State, Tables};
use crate::command::{Command, CompOn, CompSide, Plane};
use crate::gcode::{ErrorKind, GcodeError};

/// Refuses what cannot run with compensation on, before the block changes
/// anything.
pub(super) fn check_block(b: &Block, st: &State) -> Result<(), GcodeError> {
    if st.comp.is_none() {
        return Ok(());
    }
    let forbid = |letter: u8, tenths: u16, col: u16| {
        Err(GcodeError::new(
            ErrorKind::CompForbidden { letter, tenths },
            col,
        ))
    };
    if let Some((t, col)) = b.g_of(GGroup::Plane) {
        let plane = match t {
            170 => Plane::XY,
            180 => Plane::ZX,
            _ => Plane::YZ,
        };
        if plane != st.plane {
            return forbid(b'G', t, col);
        }
    }
    if let Some((6, col)) = b.m_of(MGroup::Tool) {
        return forbid(b'M', 60, col);
    }
    if matches!(b.g_of(GGroup::Cutter), Some((400, _))) {
        return Ok(());
    }
    if let Some((t, col)) = b.g_of(GGroup::Wcs) {
        let wcs = match t {
            540..=590 => ((t - 540) / 10) as u8,
            _ => (t - 591 + 6) as u8,
        };
        if wcs != st.wcs {
            return forbid(b'G', t, col);
        }
    }
    if let Some((t, col)) = b.g_of(GGroup::ToolLength) {
        return forbid(b'G', t, col);
    }
    if let Some((t, col)) = b.g_of(GGroup::NonModal) {
        let active_offsets = t == 100
            && matches!(b.get(b'L'), Some(l) if l == 2.0 || l == 20.0)
            && b.get(b'P')
                .is_some_and(|p| p == 0.0 || p == f32::from(st.wcs) + 1.0);
        if matches!(t, 280 | 300 | 530 | 920..=923) || active_offsets {
            return forbid(b'G', t, col);
        }
    }
    if let Some((t, col)) = b.g_of(GGroup::Motion) {
        if matches!(t, 50 | 51 | 382..=385 | 730 | 810..=890) {
            return forbid(b'G', t, col);
        }
    }
    Ok(())
}

/// The cutter compensation word of a block, if any.
pub(super) fn cutter(
    cx: &mut Ctx,
    st: &mut State,
    tb: &Tables,
    out: &mut Out,
) -> Result<(), GcodeError> {
    let Some((t, col)) = cx.b.g_of(GGroup::Cutter) else {
        return Ok(());
    };
    if t == 400 {
        if st.comp.take().is_some() {
            push(out, Command::CutterComp(None), col)?;
        }
        return Ok(());
    }
    if st.comp.is_some() {
        return Err(GcodeError::new(ErrorKind::CompAlreadyOn, col));
    }
    if st.plane == Plane::YZ {
        return Err(GcodeError::new(ErrorKind::CompPlane, col));
    }
    let side = if t == 410 || t == 411 {
        CompSide::Left
    } else {
        CompSide::Right
    };
    let (radius, orientation) = if t == 411 || t == 421 {
        let d = cx
            .take(b'D')
            .ok_or_else(|| cx.err(ErrorKind::ValueWordMissing(b'D'), b'D'))?;
        let l = if cx.b.has(b'L') {
            cx.int(b'L', 0.0, 9.0)? as u8
        } else {
            0
        };
        if l != 0 && st.plane != Plane::ZX {
            return Err(cx.err(ErrorKind::CompPlane, b'L'));
        }
        (d * st.unit() / 2.0, l)
    } else {
        let n = if cx.b.has(b'D') {
            cx.tool(b'D', 0)?
        } else {
            st.loaded
        };
        let diameter = if n == 0 {
            0.0
        } else {
            super::tools::find(&tb.get().tools, n)
                .map(|e| e.diameter)
                .ok_or_else(|| cx.err(ErrorKind::ToolNotInTable, b'D'))?
        };
        (diameter / 2.0, 0)
    };
    // A negative diameter puts the tool on the other side (LinuxCNC).
    let (side, radius) = if radius < 0.0 {
        let other = match side {
            CompSide::Left => CompSide::Right,
            CompSide::Right => CompSide::Left,
        };
        (other, -radius)
    } else {
        (side, radius)
    };
    st.comp = Some(side);
    push(
        out,
        Command::CutterComp(Some(CompOn {
            side,
            radius,
            plane: st.plane,
            orientation,
            start: st.pos,
        })),
        col,
    )
}
