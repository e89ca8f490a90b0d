//! Group 1: where a motion block goes (units, G90/G91, work offsets, G53
//! applied) and the arc/spline geometry of G2/G3/G5/G5.1.

use super::block::{bit, AXIS_LETTERS, EXTRA_AXIS_BITS};
use super::exec::{push, Ctx, Out};
use super::geom;
use super::state::{Motion, State};
use crate::command::{Arc, ArcDir, Command, Feed, Plane, Pos, Spline};
use crate::gcode::{ErrorKind, GcodeError};

/// The target of a motion block in machine mm.
pub(super) fn target(cx: &mut Ctx, st: &State, g53: bool) -> Pos {
    let u = st.unit();
    let wco = cx.wco;
    let mut end = st.pos;
    for (i, l) in AXIS_LETTERS.iter().enumerate() {
        let (Some(v), Some(e)) = (cx.take(*l), end.get_mut(i)) else {
            continue;
        };
        let v = if i < 3 { v * u } else { v };
        *e = if g53 {
            v
        } else if st.incremental {
            *e + v
        } else {
            v + wco.get(i).copied().unwrap_or(0.0)
        };
    }
    end
}

pub(super) fn motion(
    cx: &mut Ctx,
    st: &mut State,
    g53: bool,
    inverse_f: Option<f32>,
    explicit: Option<u16>,
    has_axes: bool,
    out: &mut Out,
) -> Result<(), GcodeError> {
    let col = explicit.unwrap_or(cx.b.first_col);
    let e = |k| GcodeError::new(k, col);
    // Cycle words carry over only while cycles follow each other.
    if !matches!(st.motion, Motion::Cycle(_)) {
        st.cycle = super::cycles::Sticky::NONE;
    }
    let arc_mode = matches!(st.motion, Motion::ArcCw | Motion::ArcCcw);
    // LinuxCNC: offsets without axis words are a full circle where the tool is.
    let (p0, p1, _) = st.plane.axes();
    let ijk = |i: usize| [b'I', b'J', b'K'].get(i).is_some_and(|&l| cx.b.has(l));
    let has_axes = has_axes || (arc_mode && (ijk(p0) || ijk(p1)));
    if !has_axes {
        if explicit.is_some()
            && !matches!(st.motion, Motion::Rapid | Motion::Linear | Motion::Cancel)
        {
            return Err(e(ErrorKind::NoAxisWords));
        }
        return Ok(());
    }
    let feed = || -> Result<Feed, GcodeError> {
        match inverse_f {
            Some(f) if f > 0.0 => Ok(Feed::InverseTime(f)),
            _ if st.inverse_time => Err(e(ErrorKind::UndefinedFeed)),
            _ if st.feed > 0.0 => Ok(Feed::PerMin(st.feed)),
            _ => Err(e(ErrorKind::UndefinedFeed)),
        }
    };
    let start = st.pos;
    let cmd = match st.motion {
        Motion::Cancel => return Err(e(ErrorKind::AxisWordsUnused)),
        Motion::Cycle(k) => return super::cycles::cycle(cx, st, k, col, out),
        Motion::Rapid => Command::Rapid {
            end: target(cx, st, g53),
        },
        Motion::Linear => {
            let f = feed()?;
            Command::Line {
                end: target(cx, st, g53),
                feed: f,
            }
        }
        Motion::Probe(kind) => {
            let f = match feed()? {
                Feed::PerMin(f) => Feed::PerMin(f),
                Feed::InverseTime(_) => return Err(e(ErrorKind::UndefinedFeed)),
            };
            let end = target(cx, st, g53);
            if end == start {
                return Err(e(ErrorKind::InvalidTarget));
            }
            st.needs_sync = true;
            Command::Probe { end, feed: f, kind }
        }
        Motion::ArcCw | Motion::ArcCcw => {
            let f = feed()?;
            Command::Arc(arc(cx, st, f, col)?)
        }
        Motion::Cubic | Motion::Quadratic => {
            let f = feed()?;
            let sp = spline(cx, st, f, col)?;
            return finish(st, Command::Spline(sp), col, out, true);
        }
    };
    finish(st, cmd, col, out, false)
}

fn finish(
    st: &mut State,
    cmd: Command,
    col: u16,
    out: &mut Out,
    keep_g5: bool,
) -> Result<(), GcodeError> {
    if !keep_g5 {
        st.last_g5 = None;
    }
    if let Some(end) = cmd.end() {
        st.pos = *end;
    }
    push(out, cmd, col)
}

fn arc(cx: &mut Ctx, st: &mut State, feed: Feed, col: u16) -> Result<Arc, GcodeError> {
    let (a0, a1, _) = st.plane.axes();
    let letters = [b'I', b'J', b'K'];
    let axis_l = |i: usize| AXIS_LETTERS.get(i).copied().unwrap_or(b'X');
    let in_plane = cx.b.has(axis_l(a0)) || cx.b.has(axis_l(a1));
    let end = target(cx, st, false);
    let s = [
        st.pos.get(a0).copied().unwrap_or(0.0),
        st.pos.get(a1).copied().unwrap_or(0.0),
    ];
    let en = [
        end.get(a0).copied().unwrap_or(0.0),
        end.get(a1).copied().unwrap_or(0.0),
    ];
    let cw = st.motion == Motion::ArcCw;
    let u = st.unit();
    let turns = if cx.b.has(b'P') {
        cx.int(b'P', 1.0, 10_000.0)? - 1
    } else {
        0
    };
    // An offset off the plane (`K` in G17, `J` in G18, `I` in G19) is an
    // error, as in LinuxCNC: it would be ignored, and is usually a
    // forgotten plane select. A zero one changes nothing, so it passes
    // with a warning (BeagleG's spiral-cut.gcode writes `I0` in G19).
    let li = |i: usize| letters.get(i).copied().unwrap_or(b'I');
    let (_, _, off) = st.plane.axes();
    if cx.b.has(li(off)) {
        if cx.b.get(li(off)) != Some(0.0) {
            return Err(cx.err(ErrorKind::ArcWordOffPlane(li(off)), li(off)));
        }
        st.off_plane_zero = Some(li(off));
    }
    if cx.b.has(b'R') && (cx.b.has(li(a0)) || cx.b.has(li(a1))) {
        return Err(cx.err(ErrorKind::MixedArcFormat, b'R'));
    }
    let center = if let Some(r) = cx.take(b'R') {
        for l in letters {
            cx.take(l);
        }
        if !in_plane {
            return Err(cx.err(ErrorKind::InvalidTarget, b'R'));
        }
        geom::centre_r(s, en, r * u, cw).map_err(|k| cx.err(k, b'R'))?
    } else {
        let (o0, o1) = (cx.take(li(a0)), cx.take(li(a1)));
        for l in letters {
            cx.take(l);
        }
        if o0.is_none() && o1.is_none() {
            return Err(GcodeError::new(ErrorKind::NoOffsetsInPlane, col));
        }
        let wco = cx.wco;
        let abs = |o: Option<f32>, a: usize, start: f32| match o {
            Some(v) if st.arc_absolute => v * u + wco.get(a).copied().unwrap_or(0.0),
            Some(v) => start + v * u,
            None if st.arc_absolute => wco.get(a).copied().unwrap_or(0.0),
            None => start,
        };
        let c = [abs(o0, a0, s[0]), abs(o1, a1, s[1])];
        geom::centre_ijk(s, en, c, st.inch).map_err(|k| GcodeError::new(k, col))?
    };
    Ok(Arc {
        end,
        center,
        plane: st.plane,
        dir: if cw { ArcDir::Cw } else { ArcDir::Ccw },
        turns: turns as u16,
        feed,
    })
}

fn spline(cx: &mut Ctx, st: &mut State, feed: Feed, col: u16) -> Result<Spline, GcodeError> {
    if st.plane != Plane::XY {
        return Err(GcodeError::new(ErrorKind::SplinePlane, col));
    }
    if let Some(l) = cx.b.first_axis_of(bit(b'Z') | EXTRA_AXIS_BITS) {
        return Err(cx.err(ErrorKind::SplinePlane, l));
    }
    let u = st.unit();
    let start = st.pos;
    let end = target(cx, st, false);
    let s = [start[0], start[1]];
    let e = [end[0], end[1]];
    let (i, j) = (cx.take(b'I'), cx.take(b'J'));
    let (p1, p2) = if st.motion == Motion::Cubic {
        let (p, q) = (cx.take(b'P'), cx.take(b'Q'));
        let (Some(p), Some(q)) = (p, q) else {
            let l = if p.is_none() { b'P' } else { b'Q' };
            return Err(GcodeError::new(ErrorKind::ValueWordMissing(l), col));
        };
        let first = match (i, j, st.last_g5) {
            (Some(i), Some(j), _) => [i * u, j * u],
            (None, None, Some(prev)) => [-prev[0], -prev[1]],
            (None, None, None) => {
                return Err(GcodeError::new(ErrorKind::ValueWordMissing(b'I'), col))
            }
            (None, Some(_), _) => {
                return Err(GcodeError::new(ErrorKind::ValueWordMissing(b'I'), col))
            }
            (Some(_), None, _) => {
                return Err(GcodeError::new(ErrorKind::ValueWordMissing(b'J'), col))
            }
        };
        let pq = [p * u, q * u];
        st.last_g5 = Some(pq);
        (
            [s[0] + first[0], s[1] + first[1]],
            [e[0] + pq[0], e[1] + pq[1]],
        )
    } else {
        if i.is_none() && j.is_none() {
            return Err(GcodeError::new(ErrorKind::ValueWordMissing(b'I'), col));
        }
        st.last_g5 = None;
        let c = [s[0] + i.unwrap_or(0.0) * u, s[1] + j.unwrap_or(0.0) * u];
        geom::quadratic_to_cubic(s, c, e)
    };
    Ok(Spline { p1, p2, end, feed })
}
