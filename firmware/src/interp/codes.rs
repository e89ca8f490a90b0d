//! The non-motion codes: the "misc" M group (motors, aux outputs, fan,
//! reports, messages, overrides, settings) and G group 0 (dwell, G10,
//! homing, stored positions, G30 probing, G53, G92 and friends).

use super::block::{bit, AXIS_BITS, AXIS_LETTERS};
use super::exec::{all_axes, message, push, Ctx, Out, G30_PROBE_TRAVEL};
use super::state::{State, Tables, WCS_COUNT};
use crate::command::{Command, Feed, ReportKind};
use crate::gcode::{ErrorKind, GcodeError, Unsupported};
use crate::AXES;

pub(super) fn misc_m(
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
        42 if !cx.b.has(b'S') => {
            let pin = cx.int(b'P', 0.0, 255.0)? as u8;
            return super::mcodes::report_pin(pin, col, out);
        }
        m if super::mcodes::handles(m) => return super::mcodes::beagleg(cx, m, col, out),
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
pub(super) fn non_modal_g(
    cx: &mut Ctx,
    st: &mut State,
    tb: &mut Tables,
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
            if matches!(l, 1 | 10 | 11) {
                super::tools::g10_tool(cx, st, tb, l, col)?;
                return Ok(false);
            }
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
            st.offsets_changed = true;
            let vals = axis_vals(cx);
            let pos = st.pos;
            let mut g92 = if st.g92_active { st.g92 } else { [0.0; AXES] };
            // L20 sets the offset so the current point, tool offset
            // included, becomes the value: the tool offset counts like G92.
            for (g, t) in g92.iter_mut().zip(st.tlo.iter()) {
                *g += t;
            }
            let inc = st.incremental;
            let Some(off) = tb.edit().wcs.get_mut(k) else {
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
                // L20: the current point becomes `v`, whatever G90/G91 say
                // (LinuxCNC); L2 under G91 adds to the offset (BeagleG).
                *o = match (l, inc) {
                    (2, false) => *v,
                    (2, true) => *o + v,
                    _ => p_i - g_i - v,
                };
            }
        }
        280 | 300 if !st.g28_homes => super::homes::go_stored(cx, st, tb, t, col, out)?,
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
        281 | 301 => {
            if t == 281 {
                tb.edit().g28 = st.pos;
            } else {
                tb.edit().g30 = st.pos;
            }
            st.offsets_changed = true;
        }
        300 => {
            if st.feed <= 0.0 || st.inverse_time {
                return Err(GcodeError::new(ErrorKind::UndefinedFeed, col));
            }
            if let Some(l) = b.first_axis_of(AXIS_BITS & !bit(b'Z')) {
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
            let base = tb
                .get()
                .wcs
                .get(usize::from(st.wcs))
                .copied()
                .unwrap_or([0.0; AXES]);
            for i in 0..AXES {
                let (Some(Some(v)), Some(g)) = (vals.get(i), st.g92.get_mut(i)) else {
                    continue;
                };
                let t = st.tlo.get(i).copied().unwrap_or(0.0);
                *g = st.pos.get(i).copied().unwrap_or(0.0)
                    - base.get(i).copied().unwrap_or(0.0)
                    - t
                    - v;
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
