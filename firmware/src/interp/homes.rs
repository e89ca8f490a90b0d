//! G28 and G30: what they mean is the setting `$210` (issue 14).
//!
//! - `$210=0` (default): RS274NGC's and GRBL's meaning, the one CAM posts
//!   for GRBL assume (Fusion 360 writes `G28 G91 Z0` at the start and
//!   before tool changes). A rapid to the intermediate point given by the
//!   axis words (read in the current units, G90/G91 and offsets), then a
//!   rapid to the stored G28.1/G30.1 position: of the named axes only when
//!   axes are named, of every axis when none are. Both moves are emitted
//!   even when one has no length, as LinuxCNC's canonical output does. The
//!   stored positions are machine mm and persist (`session/persist.rs`).
//! - `$210=1`: BeagleG's meaning. G28 runs the homing cycle on the named
//!   axes (all when none are named) and G30 probes down along Z; see
//!   `codes.rs`.

use super::exec::{push, Ctx, Out};
use super::state::{State, Tables};
use crate::command::Command;
use crate::gcode::GcodeError;
use crate::AXES;

/// `t` is 280 (G28) or 300 (G30), under `$210=0`.
pub(super) fn go_stored(
    cx: &mut Ctx,
    st: &mut State,
    tb: &Tables,
    t: u16,
    col: u16,
    out: &mut Out,
) -> Result<(), GcodeError> {
    let mask = cx.b.axis_mask();
    cx.wco = st.wco(tb.get());
    let via = super::motion::target(cx, st, false);
    let stored = if t == 280 { tb.get().g28 } else { tb.get().g30 };
    let mut end = via;
    for i in 0..AXES {
        if mask == 0 || mask & (1 << i) != 0 {
            if let (Some(e), Some(s)) = (end.get_mut(i), stored.get(i)) {
                *e = *s;
            }
        }
    }
    push(out, Command::Rapid { end: via }, col)?;
    push(out, Command::Rapid { end }, col)?;
    st.pos = end;
    st.last_g5 = None;
    Ok(())
}

/// The next `%` state after a `%` line. RS274NGC: the first `%` opens the
/// program, the second closes it and nothing after it runs. States: 0 none,
/// 1 open, 2 closed (lines are skipped until the next `%` or a reset),
/// 3 ended by M2/M30 while open (its closing `%` then skips nothing, so the
/// next job's opening `%` opens again).
pub(super) fn percent_line(state: u8) -> u8 {
    match state {
        1 => 2,
        3 => 0,
        _ => 1,
    }
}
