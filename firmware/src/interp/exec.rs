//! Executing one block in RS274NGC order: message, modes, F S T, spindle,
//! coolant, other M codes, dwell, non-modal codes, motion, stops.
//!
//! Choices documented here because dialects differ:
//! - mode words (G20/G21, G90/G91, G17-19, G93/94, G54..) apply to the whole
//!   block, before any number in it is interpreted (as GRBL does);
//! - G4 P is seconds (RS274NGC, GRBL), never milliseconds;
//! - G28/G30 follow `$210` (`homes.rs`): by default RS274NGC's stored
//!   positions through an intermediate point; with `$210=1` G28 homes the
//!   named axes, all when none are named (BeagleG/RepRap; axis values are
//!   ignored and the homed axes are taken to be at machine 0), and G30
//!   probes down along Z by [`G30_PROBE_TRAVEL`], an optional Z word being
//!   the touch plate's thickness, which becomes work Z on contact;
//! - G27 seeks the switches of the named (or all) axes to verify home;
//! - G61, G61.1 and G64 (with its P/Q tolerances) are accepted as no-ops:
//!   they select the only mode burin has (blending is the planner's
//!   junction deviation); tools and tool length offsets are `tools`, canned
//!   cycles `cycles`, cutter compensation (G40-G42.1) `cutter`;
//! - M2/M30 also turn cutter compensation off (LinuxCNC);
//! - M2/M30 stop spindle and coolant, and reset G1 G17 G90 G94 G54 and
//!   suspend G92 (LinuxCNC), keeping units;
//! - axis letters without a number (`G28 X Y`, `M18 Z`) are accepted only
//!   where they name axes (G27, G28, M17, M18, M84); elsewhere they are a
//!   bad-number error, never a silent 0;
//! - G10 L2 under G91 adds to the stored offset (BeagleG); LinuxCNC 2.9
//!   treats L2 values as absolute in both modes; G10 L20 makes the current
//!   point the given value in both modes (LinuxCNC);
//! - G2/G3 with in-plane offsets but no axis words is a full circle where
//!   the tool is (LinuxCNC); an explicit G2/G3 with neither is an error;
//! - G80 may share a block with another motion code, which wins (LinuxCNC);
//! - G8 (lathe radius mode) is a no-op: it is the only mode; G7 is refused;
//! - `M42 P<pin> S<0-255>` sets an aux output at once; M62/M63 switch one
//!   with motion, M64/M65 at once; `M106 [P<fan>] [S<0-255>]` / M107 drive
//!   aux output P (default 0) with motion;
//! - the centre-format radius check is LinuxCNC 2.9's as measured (issue
//!   14): error when the radii differ by more than 2.83 mm, or by more than
//!   0.0283 mm and 0.1 % of the radius; the centre is then moved onto the
//!   chord's bisector so the arc is consistent. An R short of half the
//!   chord by up to 0.001 mm cuts the semicircle; more is an error.

use super::block::{bit, Block, GGroup, MGroup, AXIS_BITS, MODE_GROUPS};
use super::state::{Motion, State, Tables};
use super::tools::TOOL_MAX;
use crate::command::{Command, Plane, SpindleDir};
use crate::gcode::{ErrorKind, GcodeError};
use crate::AXES;

/// Commands one line may produce.
pub const LINE_COMMANDS: usize = 16;
pub(crate) type Out = heapless::Vec<Command, LINE_COMMANDS>;

/// How far G30 probes down before giving up, mm.
pub const G30_PROBE_TRAVEL: f32 = 100.0;

pub(super) struct Ctx<'b, 'a> {
    pub(super) b: &'b Block<'a>,
    pub(super) used: u32,
    /// The work offset motion words are relative to (set before motion).
    pub(super) wco: crate::command::Pos,
}

impl Ctx<'_, '_> {
    pub(super) fn take(&mut self, l: u8) -> Option<f32> {
        let v = self.b.get(l)?;
        self.used |= bit(l);
        Some(v)
    }
    pub(super) fn err(&self, k: ErrorKind, l: u8) -> GcodeError {
        let c = self.b.col_of(l);
        GcodeError::new(k, if c == 0 { self.b.first_col } else { c })
    }
    /// A required integer word in `lo..=hi`.
    pub(super) fn int(&mut self, l: u8, lo: f32, hi: f32) -> Result<u32, GcodeError> {
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
    /// A tool number (T, H, D, M61 Q, G10 L1 P) in `lo..=`[`TOOL_MAX`],
    /// exactly. An `f32` holds every integer below 2^24; a larger word is
    /// read again from its digits in the line, as LinuxCNC's tool numbers
    /// go to 2^31 − 1. One that came from a parameter or an expression is
    /// refused as out of range: its `f32` cannot tell neighbours apart,
    /// and a neighbouring tool's offsets are worse than an error.
    pub(super) fn tool(&mut self, l: u8, lo: u32) -> Result<u32, GcodeError> {
        let v = self.int(l, lo as f32, TOOL_MAX as f32)?;
        if v < 1 << 24 {
            return Ok(v);
        }
        let col = usize::from(self.b.col_of(l));
        match literal_int(self.b.line.get(col..).unwrap_or(&[])) {
            Ok(n) if n <= u64::from(TOOL_MAX) => Ok(n as u32),
            Err(Literal::Fraction) => Err(self.err(ErrorKind::NotInteger(l), l)),
            _ => Err(self.err(ErrorKind::ValueOutOfRange(l), l)),
        }
    }
}

/// Why a word's text is not a tool number's digits.
enum Literal {
    /// Digits after the point that are not all zeros (`f32` rounded them).
    Fraction,
    /// A parameter or an expression, or more than `u32` holds.
    Other,
}

/// The integer a word's digits spell (blanks inside, leading zeros, a `+`
/// and a fraction of zeros allowed).
fn literal_int(text: &[u8]) -> Result<u64, Literal> {
    let mut n: u64 = 0;
    let (mut digits, mut dot, mut sign) = (0u32, false, false);
    for &c in text {
        match c {
            b' ' | b'\t' => {}
            b'+' if digits == 0 && !sign && !dot => sign = true,
            b'.' if !dot => dot = true,
            b'0' if dot => {}
            b'1'..=b'9' if dot => return Err(Literal::Fraction),
            b'0'..=b'9' => {
                n = n * 10 + u64::from(c - b'0');
                digits += 1;
                if n > u64::from(u32::MAX) {
                    return Err(Literal::Other);
                }
            }
            _ => break,
        }
    }
    if digits == 0 {
        return Err(Literal::Other);
    }
    Ok(n)
}

pub(super) fn push(out: &mut Out, c: Command, col: u16) -> Result<(), GcodeError> {
    out.push(c)
        .map_err(|_| GcodeError::new(ErrorKind::TooManyCommands, col))
}

pub(super) fn all_axes() -> u8 {
    (1u8 << AXES) - 1
}

/// F: mm/min in G94; in G93 the F of this line only (returned).
fn feed_word(cx: &mut Ctx, st: &mut State) -> Result<Option<f32>, GcodeError> {
    let Some(f) = cx.take(b'F') else {
        return Ok(None);
    };
    if f < 0.0 {
        return Err(cx.err(ErrorKind::ValueOutOfRange(b'F'), b'F'));
    }
    if st.inverse_time {
        return Ok(Some(f));
    }
    st.feed = f * st.unit();
    Ok(None)
}

/// Letters a plain move may carry (see [`plain_move`]).
const MOVE_LETTERS: u32 = AXIS_BITS | bit(b'F');

/// The shape of most lines in a job: a straight move (G0/G1, given or
/// modal) with axis words and maybe F, and nothing else. For such a block
/// every other step of [`execute`] finds nothing to do, so this goes
/// straight to the F word and the motion; `None` for any other block.
fn plain_move(
    cx: &mut Ctx,
    st: &mut State,
    tb: &Tables,
    out: &mut Out,
) -> Option<Result<(), GcodeError>> {
    let b = cx.b;
    let plain = b.gmask & !(1 << GGroup::Motion as u16) == 0
        && b.mmask == 0
        && b.msg.is_none()
        && b.bare_col == 0
        && b.present & !MOVE_LETTERS == 0
        && b.axis_mask() != 0;
    if !plain {
        return None;
    }
    let word = b.g_of(GGroup::Motion);
    let motion = match word {
        Some((t, _)) => Motion::from_tenths(t)?,
        None => st.motion,
    };
    if !matches!(motion, Motion::Rapid | Motion::Linear) {
        return None;
    }
    Some((|| {
        let inverse_f = feed_word(cx, st)?;
        st.motion = motion;
        cx.wco = st.wco(tb.get());
        super::motion::motion(cx, st, false, inverse_f, word.map(|x| x.1), true, out)
    })())
}

/// Runs one block against `st`, appending its commands to `out`.
pub(crate) fn execute(
    st: &mut State,
    tb: &mut Tables,
    b: &Block,
    out: &mut Out,
) -> Result<(), GcodeError> {
    let mut cx = Ctx {
        b,
        used: 0,
        wco: [0.0; AXES],
    };
    if let Some(r) = plain_move(&mut cx, st, tb, out) {
        return r;
    }
    super::cutter::check_block(b, st)?;
    let col0 = b.first_col;
    let gcol = |g: GGroup| b.g_of(g).map_or(col0, |x| x.1);

    if let Some((text, col)) = b.msg {
        push(out, Command::Message(message(text)), col)?;
    }
    // Modes first: they govern how every number below is read.
    if b.gmask & MODE_GROUPS != 0 {
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
        if let Some((t, _)) = b.g_of(GGroup::Retract) {
            st.retract_r = t == 990;
        }
        if let Some((640, _)) = b.g_of(GGroup::Path) {
            cx.take(b'P');
            cx.take(b'Q');
        }
    }
    let misc = b.m_of(MGroup::Misc).map(|m| m.0);
    let s_is_arg = matches!(misc, Some(42 | 106 | 220)) || misc.is_some_and(super::mcodes::takes_s);

    let inverse_f = feed_word(&mut cx, st)?;
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
    super::tools::tool_words(&mut cx, st, tb, out)?;
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

    super::cutter::cutter(&mut cx, st, tb, out)?;

    // Which command owns the axis words.
    let non_modal = b.g_of(GGroup::NonModal);
    let nm = non_modal.map(|x| x.0);
    let axis_nm = matches!(nm, Some(100 | 270 | 280 | 300 | 920)) || super::tools::owns_axes(b);
    let motion_word = b.g_of(GGroup::Motion);
    if axis_nm && motion_word.is_some() {
        return Err(GcodeError::new(
            ErrorKind::AxisCommandConflict,
            gcol(GGroup::Motion),
        ));
    }
    let axes = b.axis_mask();
    let motors_take_axes = matches!(misc, Some(17 | 18 | 84)) && !axis_nm && motion_word.is_none();

    // `G28 X Y` / `M18 Z`: bare axis letters only name axes; anywhere else
    // a missing number is an error, never a silent 0.
    let names_axes = nm == Some(270) || nm == Some(280) && st.g28_homes || motors_take_axes;
    if b.bare_col != 0 && !names_axes {
        return Err(GcodeError::new(ErrorKind::BadNumber, b.bare_col));
    }
    if let Some((m, col)) = b.m_of(MGroup::Misc) {
        super::codes::misc_m(&mut cx, st, m, col, motors_take_axes, out)?;
    }
    let mut g53 = false;
    if let Some((t, col)) = non_modal {
        g53 = super::codes::non_modal_g(&mut cx, st, tb, t, col, out)?;
    }
    if let Some((t, _)) = motion_word {
        st.motion = Motion::from_tenths(t).unwrap_or(Motion::Cancel);
    }
    // G53 alone is refused (LinuxCNC): it must move, or name G0/G1.
    let g53_alone = axes == 0 && motion_word.is_none();
    if g53 && (st.incremental || g53_alone || !matches!(st.motion, Motion::Rapid | Motion::Linear))
    {
        return Err(GcodeError::new(
            ErrorKind::G53Invalid,
            non_modal.map_or(col0, |x| x.1),
        ));
    }
    if !axis_nm && !motors_take_axes {
        cx.wco = st.wco(tb.get());
        super::motion::motion(
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
                st.comp = None;
                if st.percent == 1 {
                    st.percent = 3;
                }
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
        let axes_bits = AXIS_BITS;
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
