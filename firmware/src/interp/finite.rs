//! The check every line's output passes: no infinite or NaN value may
//! reach the machine or the offset tables (`G10 L20 X4e38` overflowed).

use crate::command::Command;

/// Non-zero when some value in `s` is infinite or NaN (exponent all ones).
/// Branch-free: this runs on every value of every command.
pub(super) fn non_finite(s: &[f32]) -> u32 {
    s.iter().fold(0, |a, v| {
        a | u32::from(v.to_bits() & 0x7f80_0000 == 0x7f80_0000)
    })
}

pub(super) fn cmd_finite(c: &Command) -> bool {
    let feed = |f: &crate::command::Feed| match f {
        crate::command::Feed::PerMin(v) | crate::command::Feed::InverseTime(v) => non_finite(&[*v]),
    };
    0 == match c {
        Command::Rapid { end } => non_finite(end),
        Command::Line { end, feed: f } | Command::Probe { end, feed: f, .. } => {
            non_finite(end) | feed(f)
        }
        Command::Arc(a) => non_finite(&a.end) | non_finite(&a.center) | feed(&a.feed),
        Command::Spline(s) => {
            non_finite(&s.end) | non_finite(&s.p1) | non_finite(&s.p2) | feed(&s.feed)
        }
        Command::Dwell { seconds } => non_finite(&[*seconds]),
        Command::Cycle(c) => {
            non_finite(&c.hole)
                | non_finite(&c.step)
                | non_finite(&[c.r, c.bottom, c.clear, c.q, c.p, c.feed, c.speed])
        }
        Command::Spindle { speed, .. } => non_finite(&[*speed]),
        Command::Aux { value, .. } => non_finite(&[*value]),
        _ => 0,
    }
}
