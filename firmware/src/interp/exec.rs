//! Executing one block in RS274NGC order: message, modes, F S T, spindle,
//! coolant, other M codes, dwell, non-modal codes, motion, stops.
//!
//! Choices documented here because dialects differ:
//! - mode words (G20/G21, G90/G91, G17-19, G93/94, G54..) apply to the whole
//!   block, before any number in it is interpreted (as GRBL does);
//! - G4 P is seconds (RS274NGC, GRBL), never milliseconds;
//! - G28 homes the named axes, all when none are named (BeagleG/RepRap);
//!   axis values are ignored and the homed axes are taken to be at machine 0;
//! - G27 seeks the switches of the named (or all) axes to verify home;
//! - G30 probes down along Z by [`G30_PROBE_TRAVEL`]; an optional Z word is the
//!   thickness of the touch plate, which becomes work Z on contact (BeagleG);
//! - G40, G49, G61, G61.1 and G64 (with its P/Q tolerances) are accepted as
//!   no-ops: they select the only modes burin has (no cutter or tool-length
//!   compensation; blending is the planner's junction deviation);
//! - M2/M30 stop spindle and coolant, and reset G1 G17 G90 G94 G54 and
//!   suspend G92 (LinuxCNC), keeping units.

use super::block::{bit, Block, GGroup, MGroup, AXIS_LETTERS};
use super::geom;
use super::state::{Motion, State, WCS_COUNT};
use crate::command::{Arc, ArcDir, Command, Feed, Plane, Pos, ReportKind, SpindleDir, Spline};
use crate::gcode::{ErrorKind, GcodeError, Unsupported};
use crate::AXES;

/// Commands one line may produce.
pub const LINE_COMMANDS: usize = 16;
pub(crate) type Out = heapless::Vec<Command, LINE_COMMANDS>;

/// How far G30 probes down before giving up, mm.
pub const G30_PROBE_TRAVEL: f32 = 100.0;

struct Ctx<'b, 'a> {
    b: &'b Block<'a>,
    used: u32,
}

impl Ctx<'_, '_> {
    fn take(&mut self, l: u8) -> Option<f32> {
        let v = self.b.get(l)?;
        self.used |= bit(l);
        Some(v)
    }
    fn err(&self, k: ErrorKind, l: u8) -> GcodeError {
        let c = self.b.col_of(l);
        GcodeError::new(k, if c == 0 { self.b.first_col } else { c })
    }
    /// A required integer word in `lo..=hi`.
    fn int(&mut self, l: u8, lo: f32, hi: f32) -> Result<u32, GcodeError> {
        let v = self
            .take(l)
            .ok_or_else(|| self.err(ErrorKind::ValueWordMissing(l), l))?;
        if libm::floorf(v) != v {
            return Err(self.err(ErrorKind::NotInteger(l), l));
        }
        if v < lo || v > hi {
            return Err(self.err(ErrorKind::ValueOutOfRange(l), l));
        }
        Ok(v as u32)
    }
}

fn push(out: &mut Out, c: Command, col: u16) -> Result<(), GcodeError> {
    out.push(c)
        .map_err(|_| GcodeError::new(ErrorKind::TooManyCommands, col))
}

fn all_axes() -> u8 {
    (1u8 << AXES) - 1
}

/// Runs one block against `st`, appending its commands to `out`.
pub(crate) fn execute(st: &mut State, b: &Block, out: &mut Out) -> Result<(), GcodeError> {
    let mut cx = Ctx { b, used: 0 };
    let col0 = b.first_col;
    let gcol = |g: GGroup| b.g_of(g).map_or(col0, |x| x.1);

    if let Some((text, col)) = b.msg {
        push(out, Command::Message(message(text)), col)?;
    }
    // Modes first: they govern how every number below is read.
    if let Some((t, _)) = b.g_of(GGroup::Units) {
        st.inch = t == 200 || t == 700;
    }
    if let Some((t, _)) = b.g_of(GGroup::Plane) {
        st.plane = match t {
            170 => Plane::XY,
            180 => Plane::ZX,
            _ => Plane::YZ,
        };
    }
    if let Some((t, _)) = b.g_of(GGroup::Distance) {
        st.incremental = t == 910;
    }
    if let Some((t, _)) = b.g_of(GGroup::ArcDistance) {
        st.arc_absolute = t == 901;
    }
    if let Some((t, _)) = b.g_of(GGroup::FeedMode) {
        st.inverse_time = t == 930;
    }
    if let Some((t, _)) = b.g_of(GGroup::Wcs) {
        st.wcs = match t {
            540..=590 => ((t - 540) / 10) as u8,
            _ => (t - 591 + 6) as u8,
        };
    }
    if let Some((640, _)) = b.g_of(GGroup::Path) {
        cx.take(b'P');
        cx.take(b'Q');
    }
    let misc = b.m_of(MGroup::Misc).map(|m| m.0);
    let s_is_arg = matches!(misc, Some(42 | 106 | 220));

    // F: mm/min in G94; in G93 the F of this line only.
    let mut inverse_f = None;
    if let Some(f) = cx.take(b'F') {
        if f < 0.0 {
            return Err(cx.err(ErrorKind::ValueOutOfRange(b'F'), b'F'));
        }
        if st.inverse_time {
            inverse_f = Some(f);
        } else {
            st.feed = f * st.unit();
        }
    }
    let spindle_m = b.m_of(MGroup::Spindle);
    if !s_is_arg {
        if let Some(s) = cx.take(b'S') {
            if s < 0.0 {
                return Err(cx.err(ErrorKind::ValueOutOfRange(b'S'), b'S'));
            }
            st.speed = s;
            if spindle_m.is_none() && st.spindle != SpindleDir::Off {
                push(
                    out,
                    Command::Spindle {
                        dir: st.spindle,
                        speed: s,
                    },
                    b.col_of(b'S'),
                )?;
            }
        }
    }
    if b.has(b'T') {
        let t = cx.int(b'T', 0.0, 99_999_999.0)?;
        st.tool = t;
        push(out, Command::Tool { number: t }, b.col_of(b'T'))?;
    }
    if let Some((m, col)) = spindle_m {
        st.spindle = match m {
            3 => SpindleDir::Cw,
            4 => SpindleDir::Ccw,
            _ => SpindleDir::Off,
        };
        push(
            out,
            Command::Spindle {
                dir: st.spindle,
                speed: st.speed,
            },
            col,
        )?;
    }
    if let Some((_, col)) = b.m_of(MGroup::Coolant) {
        if b.coolant & 4 != 0 {
            st.mist = false;
            st.flood = false;
        }
        st.mist |= b.coolant & 1 != 0;
        st.flood |= b.coolant & 2 != 0;
        push(
            out,
            Command::Coolant {
                mist: st.mist,
                flood: st.flood,
            },
            col,
        )?;
    }

    // Which command owns the axis words.
    let non_modal = b.g_of(GGroup::NonModal);
    let nm = non_modal.map(|x| x.0);
    let axis_nm = matches!(nm, Some(100 | 270 | 280 | 300 | 920));
    let motion_word = b.g_of(GGroup::Motion);
    if axis_nm && motion_word.is_some() {
        return Err(GcodeError::new(
            ErrorKind::AxisCommandConflict,
            gcol(GGroup::Motion),
        ));
    }
    let axes = b.axis_mask();
    let motors_take_axes = matches!(misc, Some(17 | 18 | 84)) && !axis_nm && motion_word.is_none();

    if let Some((m, col)) = b.m_of(MGroup::Misc) {
        misc_m(&mut cx, st, m, col, motors_take_axes, out)?;
    }
    let mut g53 = false;
    if let Some((t, col)) = non_modal {
        g53 = non_modal_g(&mut cx, st, t, col, out)?;
    }
    if let Some((t, _)) = motion_word {
        st.motion = Motion::from_tenths(t).unwrap_or(Motion::Cancel);
    }
    if g53 && (st.incremental || !matches!(st.motion, Motion::Rapid | Motion::Linear)) {
        return Err(GcodeError::new(
            ErrorKind::G53Invalid,
            non_modal.map_or(col0, |x| x.1),
        ));
    }
    if !axis_nm && !motors_take_axes {
        motion(
            &mut cx,
            st,
            g53,
            inverse_f,
            motion_word.map(|x| x.1),
            axes != 0,
            out,
        )?;
    }
    if let Some((m, col)) = b.m_of(MGroup::Stop) {
        match m {
            0 | 1 => push(out, Command::Pause { optional: m == 1 }, col)?,
            _ => {
                st.spindle = SpindleDir::Off;
                st.mist = false;
                st.flood = false;
                st.motion = Motion::Linear;
                st.plane = Plane::XY;
                st.incremental = false;
                st.inverse_time = false;
                st.wcs = 0;
                st.g92_active = false;
                st.last_g5 = None;
                push(
                    out,
                    Command::Spindle {
                        dir: SpindleDir::Off,
                        speed: st.speed,
                    },
                    col,
                )?;
                push(
                    out,
                    Command::Coolant {
                        mist: false,
                        flood: false,
                    },
                    col,
                )?;
                push(out, Command::ProgramEnd, col)?;
            }
        }
    }
    // Every word must have had a user.
    let unused = b.present & !cx.used;
    if unused != 0 {
        let axes_bits = AXIS_LETTERS.iter().fold(0, |m, &l| m | bit(l));
        let l = (0..26u8)
            .map(|i| b'A' + i)
            .find(|&l| unused & bit(l) != 0)
            .unwrap_or(b'A');
        let kind = if unused & axes_bits != 0 && unused & !axes_bits == 0 {
            ErrorKind::AxisWordsUnused
        } else {
            ErrorKind::UnusedWord(l)
        };
        return Err(cx.err(kind, l));
    }
    Ok(())
}

/// Operator text, cut to fit [`crate::command::Message`] on a char boundary.
pub(crate) fn message(text: &[u8]) -> crate::command::Message {
    let s = match core::str::from_utf8(text) {
        Ok(s) => s,
        Err(e) => core::str::from_utf8(text.get(..e.valid_up_to()).unwrap_or(&[])).unwrap_or(""),
    };
    let mut m = crate::command::Message::new();
    for ch in s.chars() {
        if m.push(ch).is_err() {
            break;
        }
    }
    m
}

fn misc_m(
    cx: &mut Ctx,
    st: &mut State,
    m: u16,
    col: u16,
    motors_take_axes: bool,
    out: &mut Out,
) -> Result<(), GcodeError> {
    let cmd = match m {
        17 | 18 | 84 => {
            let mut axes = all_axes();
            if motors_take_axes && cx.b.axis_mask() != 0 {
                axes = cx.b.axis_mask();
                for l in AXIS_LETTERS {
                    cx.take(l);
                }
            }
            Command::Motors {
                enable: m == 17,
                axes,
            }
        }
        42 => {
            let pin = cx.int(b'P', 0.0, 255.0)? as u8;
            let s = cx
                .take(b'S')
                .ok_or_else(|| cx.err(ErrorKind::ValueWordMissing(b'S'), b'P'))?;
            if !(0.0..=255.0).contains(&s) {
                return Err(cx.err(ErrorKind::ValueOutOfRange(b'S'), b'S'));
            }
            Command::Aux {
                pin,
                value: s / 255.0,
                synced: false,
            }
        }
        62..=65 => {
            let pin = cx.int(b'P', 0.0, 255.0)? as u8;
            let value = if m == 62 || m == 64 { 1.0 } else { 0.0 };
            Command::Aux {
                pin,
                value,
                synced: m <= 63,
            }
        }
        106 | 107 => {
            let pin = if cx.b.has(b'P') {
                cx.int(b'P', 0.0, 255.0)? as u8
            } else {
                0
            };
            let s = if m == 106 {
                cx.take(b'S').unwrap_or(255.0)
            } else {
                0.0
            };
            if !(0.0..=255.0).contains(&s) {
                return Err(cx.err(ErrorKind::ValueOutOfRange(b'S'), b'S'));
            }
            Command::Aux {
                pin,
                value: s / 255.0,
                synced: true,
            }
        }
        114 => Command::Report(ReportKind::Position),
        115 => Command::Report(ReportKind::Firmware),
        119 => Command::Report(ReportKind::Endstops),
        117 => Command::Message(message(cx.b.text.unwrap_or(&[]))),
        220 => {
            let p = cx.int(b'S', 1.0, 1000.0)?;
            Command::FeedOverride { percent: p as u16 }
        }
        400 => Command::WaitIdle,
        500 => Command::SaveSettings,
        501 => Command::LoadSettings,
        _ => {
            st.needs_sync = false;
            Command::ClearAlarm
        }
    };
    push(out, cmd, col)
}

/// Group 0. Returns whether G53 is in effect.
fn non_modal_g(
    cx: &mut Ctx,
    st: &mut State,
    t: u16,
    col: u16,
    out: &mut Out,
) -> Result<bool, GcodeError> {
    let b = cx.b;
    let u = st.unit();
    let axis_vals = |cx: &mut Ctx| {
        let mut v: [Option<f32>; AXES] = [None; AXES];
        for (i, l) in AXIS_LETTERS.iter().enumerate() {
            if let (Some(x), Some(s)) = (cx.take(*l), v.get_mut(i)) {
                *s = Some(if i < 3 { x * u } else { x });
            }
        }
        v
    };
    match t {
        40 => {
            let p = cx
                .take(b'P')
                .ok_or_else(|| GcodeError::new(ErrorKind::ValueWordMissing(b'P'), col))?;
            if p < 0.0 {
                return Err(cx.err(ErrorKind::ValueOutOfRange(b'P'), b'P'));
            }
            push(out, Command::Dwell { seconds: p }, col)?;
        }
        100 => {
            let l = cx.int(b'L', 0.0, 100.0)?;
            if l != 2 && l != 20 {
                return Err(GcodeError::new(
                    ErrorKind::Unsupported(Unsupported::Code {
                        letter: b'G',
                        tenths: 100,
                    }),
                    col,
                ));
            }
            let p = cx.int(b'P', 0.0, WCS_COUNT as f32)? as usize;
            if cx.take(b'R').is_some_and(|r| r != 0.0) {
                return Err(cx.err(ErrorKind::Unsupported(Unsupported::Letter(b'R')), b'R'));
            }
            let k = if p == 0 { usize::from(st.wcs) } else { p - 1 };
            let vals = axis_vals(cx);
            let pos = st.pos;
            let g92 = if st.g92_active { st.g92 } else { [0.0; AXES] };
            let inc = st.incremental;
            let Some(off) = st.wcs_offsets.get_mut(k) else {
                return Ok(false);
            };
            for i in 0..AXES {
                let (Some(Some(v)), Some(o)) = (vals.get(i), off.get_mut(i)) else {
                    continue;
                };
                let (p_i, g_i) = (
                    pos.get(i).copied().unwrap_or(0.0),
                    g92.get(i).copied().unwrap_or(0.0),
                );
                *o = match (l, inc) {
                    (2, false) => *v,
                    (2, true) => *o + v,
                    (_, false) => p_i - g_i - v,
                    (_, true) => *o - v,
                };
            }
        }
        270 | 280 => {
            let mask = b.axis_mask();
            for l in AXIS_LETTERS {
                cx.take(l);
            }
            let axes = if mask == 0 { all_axes() } else { mask };
            for (i, p) in st.pos.iter_mut().enumerate() {
                if axes & (1 << i) != 0 {
                    *p = 0.0;
                }
            }
            st.needs_sync = true;
            st.last_g5 = None;
            let c = if t == 280 {
                Command::Home { axes }
            } else {
                Command::VerifyHome { axes }
            };
            push(out, c, col)?;
        }
        281 => st.g28 = st.pos,
        301 => st.g30 = st.pos,
        300 => {
            if st.feed <= 0.0 || st.inverse_time {
                return Err(GcodeError::new(ErrorKind::UndefinedFeed, col));
            }
            if b.axis_mask() & !0b100 != 0 {
                let l = if b.has(b'X') {
                    b'X'
                } else if b.has(b'Y') {
                    b'Y'
                } else {
                    b'A'
                };
                return Err(cx.err(ErrorKind::AxisWordsUnused, l));
            }
            st.pending_probe_z = cx.take(b'Z').map(|z| z * u);
            let mut end = st.pos;
            if let Some(z) = end.get_mut(2) {
                *z -= G30_PROBE_TRAVEL;
            }
            push(
                out,
                Command::Probe {
                    end,
                    feed: Feed::PerMin(st.feed),
                    kind: crate::command::ProbeKind::Toward,
                },
                col,
            )?;
            st.pos = end;
            st.needs_sync = true;
            st.last_g5 = None;
        }
        530 => return Ok(true),
        80 => {} // G8: lathe radius mode, the only mode burin has.
        920 => {
            let vals = axis_vals(cx);
            if vals.iter().all(Option::is_none) {
                return Err(GcodeError::new(ErrorKind::NoAxisWords, col));
            }
            let base = st
                .wcs_offsets
                .get(usize::from(st.wcs))
                .copied()
                .unwrap_or([0.0; AXES]);
            for i in 0..AXES {
                let (Some(Some(v)), Some(g)) = (vals.get(i), st.g92.get_mut(i)) else {
                    continue;
                };
                *g =
                    st.pos.get(i).copied().unwrap_or(0.0) - base.get(i).copied().unwrap_or(0.0) - v;
            }
            st.g92_active = true;
        }
        921 => {
            st.g92 = [0.0; AXES];
            st.g92_active = false;
        }
        922 => st.g92_active = false,
        _ => st.g92_active = true,
    }
    Ok(false)
}

/// The target of a motion block in machine mm.
fn target(cx: &mut Ctx, st: &State, g53: bool) -> Pos {
    let u = st.unit();
    let wco = st.wco();
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

fn motion(
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

fn arc(cx: &mut Ctx, st: &State, feed: Feed, col: u16) -> Result<Arc, GcodeError> {
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
    // Off-plane offsets are legal words but meaningless: consume them (LinuxCNC warns).
    let li = |i: usize| letters.get(i).copied().unwrap_or(b'I');
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
        let wco = st.wco();
        let abs = |o: Option<f32>, a: usize, start: f32| match o {
            Some(v) if st.arc_absolute => v * u + wco.get(a).copied().unwrap_or(0.0),
            Some(v) => start + v * u,
            None if st.arc_absolute => wco.get(a).copied().unwrap_or(0.0),
            None => start,
        };
        let c = [abs(o0, a0, s[0]), abs(o1, a1, s[1])];
        geom::centre_ijk(s, en, c).map_err(|k| GcodeError::new(k, col))?
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
    if cx.b.has(b'Z') || cx.b.has(b'A') {
        let l = if cx.b.has(b'Z') { b'Z' } else { b'A' };
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
