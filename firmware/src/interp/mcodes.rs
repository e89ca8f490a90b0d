//! The rest of BeagleG's M list (issue 14), so BeagleG jobs run or stop
//! with a reason instead of an unknown-code error.
//!
//! The board has no output pins for vacuum, power, cooler or case light,
//! so those codes run as named "not fitted" messages (`[MSG:]`), never
//! silently; M42 P without S reports that aux pins are not fitted. M24 is
//! a pause until cycle start (like M0), M82/M83 (extruder modes), M111
//! (debug level) and M120 (pause switch on: it always is) are accepted
//! with nothing to do, and M121 says the pause switch cannot be turned
//! off. Heater commands are a typed error: a wrong temperature wait must
//! never be mistaken for done.

use super::exec::{push, Ctx, Out};
use crate::command::Command;
use crate::gcode::{ErrorKind, GcodeError};
use core::fmt::Write;

/// The M numbers this module handles (all in the "misc" group).
pub(super) const fn handles(m: u16) -> bool {
    matches!(
        m,
        10 | 11
            | 24
            | 80
            | 81
            | 82
            | 83
            | 104
            | 105
            | 109
            | 111
            | 116
            | 120
            | 121
            | 245
            | 246
            | 355
    )
}

/// M codes that take S as their argument (not a spindle speed).
pub(super) const fn takes_s(m: u16) -> bool {
    matches!(m, 104 | 109 | 111 | 355)
}

fn text(args: core::fmt::Arguments) -> crate::command::Message {
    let mut m = crate::command::Message::new();
    // A message that does not fit is cut; the line still runs.
    let _ = m.write_fmt(args);
    m
}

pub(super) fn beagleg(cx: &mut Ctx, m: u16, col: u16, out: &mut Out) -> Result<(), GcodeError> {
    let not_fitted = |what: &str| Command::Message(text(format_args!("M{m}: {what} not fitted")));
    let cmd = match m {
        104 | 105 | 109 | 116 => return Err(GcodeError::new(ErrorKind::NoHeaters, col)),
        10 | 11 => not_fitted("vacuum"),
        80 | 81 => not_fitted("power supply control"),
        245 | 246 => not_fitted("cooler"),
        355 => {
            cx.take(b'S');
            not_fitted("case light")
        }
        24 => Command::Pause { optional: false },
        121 => Command::Message(text(format_args!("M121: the pause switch stays enabled"))),
        _ => {
            // M82, M83, M111 [S], M120: nothing to do.
            cx.take(b'S');
            return Ok(());
        }
    };
    push(out, cmd, col)
}

/// M42 P<pin> without S: BeagleG reports the pin's level; burin's board
/// has no aux pins fitted, and says so.
pub(super) fn report_pin(pin: u8, col: u16, out: &mut Out) -> Result<(), GcodeError> {
    push(
        out,
        Command::Message(text(format_args!("M42 P{pin}: aux output not fitted"))),
        col,
    )
}

/// The message for a bare parameter line (`#1` prints `#1=12.5`).
pub(super) fn value_text(reference: &[u8], v: f32) -> crate::command::Message {
    let mut m = super::exec::message(reference);
    let _ = m.push('=');
    let _ = crate::num::write_short(&mut m, v, 4);
    m
}
