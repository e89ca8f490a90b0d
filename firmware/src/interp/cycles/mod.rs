//! Canned cycles G73, G81-G89 (G80 cancels), with G98/G99 and L repeats,
//! in all three planes, as LinuxCNC 2.9 runs them (its `rs274` was the
//! reference for every end point; see the tests).
//!
//! A cycle block resolves its words here into one [`Cycle`] command in
//! machine mm; `command::cycle` ([`CycleSteps`](crate::command::CycleSteps))
//! expands it into moves (the executor runs the same expansion). The plane
//! decides the axes: G17 drills along Z at X/Y
//! holes, G18 along Y at Z/X holes, G19 along X at Y/Z holes; the depth
//! word is that axis's letter.
//!
//! Rules (LinuxCNC's):
//! - R and the depth are required on the first block of a cycle; they,
//!   P and Q carry over while the same cycle stays the motion mode; a
//!   different cycle needs them again; G80 or any other motion clears them;
//! - G90: R and depth are work coordinates. G91: R is relative to the
//!   level the run of cycles began at and the depth relative to R; the hole
//!   position steps by X/Y (in-plane words) once per repeat;
//! - G98 retracts to the higher of R and the level the run of cycles began
//!   at (reset by any other motion); G99 to R;
//! - errors: depth above R, Q <= 0 (G73/G83), a missing P (G82/G86/G88/
//!   G89), L not a positive integer, inverse-time feed, no feed, an A word,
//!   G86/G88 with the spindle stopped; and burin's own bounds: more than
//!   [`MAX_PECKS`] pecks per hole (Q) or [`MAX_MOVES`] moves per block (L);
//! - G88: LinuxCNC stops the program at the bottom for the operator to
//!   retract by hand, and carries on as if the tool were at the clear
//!   level. burin cannot jog in a hold, so it pauses there (M0's hold,
//!   `~` resumes), then rapids to the clear level itself with the spindle
//!   still stopped, and restarts it: the machine ends where LinuxCNC's
//!   interpreter believes it is.

use super::block::{AXIS_LETTERS, EXTRA_AXIS_BITS};
use super::exec::{push, Ctx, Out};
use super::state::State;
use crate::command::cycle::{MAX_MOVES, MAX_PECKS};
use crate::command::{Command, Cycle, CycleKind, SpindleDir};
use crate::gcode::{ErrorKind, GcodeError};

/// Cycle words that carry over to the next block of the same cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sticky {
    /// The cycle these belong to; `None`: no cycle ran since the last
    /// other motion.
    kind: Option<CycleKind>,
    /// Program values as given (units and G90/G91 apply per block).
    r: f32,
    depth: f32,
    p: Option<f32>,
    q: Option<f32>,
    /// Machine level along the drilling axis when the run of cycles began.
    initial: f32,
}

impl Sticky {
    pub const NONE: Sticky = Sticky {
        kind: None,
        r: 0.0,
        depth: 0.0,
        p: None,
        q: None,
        initial: 0.0,
    };
}

/// One block in a cycle motion mode with axis words.
pub(super) fn cycle(
    cx: &mut Ctx,
    st: &mut State,
    kind: CycleKind,
    col: u16,
    out: &mut Out,
) -> Result<(), GcodeError> {
    let e = |k| GcodeError::new(k, col);
    if let Some(l) = cx.b.first_axis_of(EXTRA_AXIS_BITS) {
        return Err(cx.err(ErrorKind::AxisWordsUnused, l));
    }
    if st.inverse_time || st.feed <= 0.0 {
        return Err(e(ErrorKind::UndefinedFeed));
    }
    let (a0, a1, n) = st.plane.axes();
    let letter = |i: usize| AXIS_LETTERS.get(i).copied().unwrap_or(b'Z');
    let u = st.unit();
    let prev = st.cycle;
    let same = prev.kind == Some(kind);
    let level = st.pos[n];
    let initial = if prev.kind.is_some() {
        prev.initial
    } else {
        level
    };
    let r = match cx.take(b'R') {
        Some(r) => r,
        None if same => prev.r,
        None => return Err(e(ErrorKind::ValueWordMissing(b'R'))),
    };
    let depth = match cx.take(letter(n)) {
        Some(z) => z,
        None if same => prev.depth,
        None => return Err(e(ErrorKind::ValueWordMissing(letter(n)))),
    };
    let sticky = |l: u8, old: Option<f32>, cx: &mut Ctx| match cx.take(l) {
        Some(v) => Some(v),
        None if same => old,
        None => None,
    };
    let needs_p = matches!(
        kind,
        CycleKind::G82 | CycleKind::G86 | CycleKind::G88 | CycleKind::G89
    );
    let needs_q = matches!(kind, CycleKind::G73 | CycleKind::G83);
    // A P or Q the cycle has no use for is an error, as in LinuxCNC (which
    // lets P pass only with a dwelling cycle, Q only with a pecking one);
    // one carried over from the previous cycle is simply not used.
    for (l, used) in [(b'P', needs_p), (b'Q', needs_q)] {
        if !used && cx.b.has(l) {
            return Err(cx.err(ErrorKind::UnusedWord(l), l));
        }
    }
    let p = sticky(b'P', prev.p, cx);
    let q = sticky(b'Q', prev.q, cx);
    let p = match p {
        Some(p) if p < 0.0 => return Err(cx.err(ErrorKind::ValueOutOfRange(b'P'), b'P')),
        None if needs_p => return Err(e(ErrorKind::ValueWordMissing(b'P'))),
        p => p,
    };
    let q = match q {
        Some(q) if needs_q && q <= 0.0 => {
            return Err(cx.err(ErrorKind::ValueOutOfRange(b'Q'), b'Q'))
        }
        None if needs_q => return Err(e(ErrorKind::ValueWordMissing(b'Q'))),
        q => q,
    };
    let repeats = if cx.b.has(b'L') {
        cx.int(b'L', 1.0, 65_535.0)? as u16
    } else {
        1
    };
    if matches!(kind, CycleKind::G86 | CycleKind::G88) && st.spindle == SpindleDir::Off {
        return Err(e(ErrorKind::SpindleStopped));
    }
    let wco = cx.wco;
    let (r_m, bottom) = if st.incremental {
        let r_m = initial + r * u;
        (r_m, r_m + depth * u)
    } else {
        (r * u + wco[n], depth * u + wco[n])
    };
    if bottom > r_m {
        return Err(cx.err(ErrorKind::ValueOutOfRange(b'R'), b'R'));
    }
    // Bounded walks: a peck count `f32` can step through, and a block
    // that check mode can list (LinuxCNC has no limit; real jobs are far
    // below these).
    let q_mm = q.unwrap_or(0.0) * u;
    let pecks = if needs_q { (r_m - bottom) / q_mm } else { 0.0 };
    let tiny = needs_q && r_m - q_mm >= r_m;
    if tiny || pecks > MAX_PECKS as f32 {
        return Err(cx.err(ErrorKind::ValueOutOfRange(b'Q'), b'Q'));
    }
    if f32::from(repeats) * (3.0 * pecks + 8.0) > MAX_MOVES as f32 {
        return Err(cx.err(ErrorKind::ValueOutOfRange(b'L'), b'L'));
    }
    let mut hole = [st.pos[a0], st.pos[a1]];
    let mut step = [0.0; 2];
    for (k, a) in [a0, a1].into_iter().enumerate() {
        if let Some(v) = cx.take(letter(a)) {
            if st.incremental {
                step[k] = v * u;
                hole[k] += v * u;
            } else {
                hole[k] = v * u + wco[a];
            }
        }
    }
    let clear = if st.retract_r { r_m } else { initial.max(r_m) };
    let c = Cycle {
        kind,
        plane: st.plane,
        hole,
        step,
        repeats,
        rise: initial < r_m,
        r: r_m,
        bottom,
        clear,
        q: q_mm,
        p: p.unwrap_or(0.0),
        feed: st.feed,
        spindle: st.spindle,
        speed: st.speed,
    };
    st.cycle = Sticky {
        kind: Some(kind),
        r,
        depth,
        p,
        q,
        initial,
    };
    let end = c.end(&st.pos);
    push(out, Command::Cycle(c), col)?;
    st.pos = end;
    st.last_g5 = None;
    Ok(())
}

#[cfg(test)]
mod tests;
