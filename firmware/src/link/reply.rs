//! GRBL 1.1 text replies, written into any `core::fmt::Write` sink (a
//! `heapless::String`, a USB writer) so nothing allocates.
//!
//! Senders parse these by eye of the GRBL 1.1 interface document: every
//! line ends in `\r\n`, numbers use `.` and fixed decimals (3 in mm, 4 in
//! inches), and the status report's fields come in GRBL's order.

use crate::num::write_fixed;
use crate::settings::{table, Settings};
use core::fmt::{self, Write};
use protocol::msg::pins;
use protocol::{Status, RX_WINDOW};

/// The version string senders look for; `Grbl 1.1h` makes UGS, CNCjs, bCNC
/// and Candle pick their GRBL 1.1 drivers.
pub const GRBL_VERSION: &str = "1.1h";

/// A reply buffer big enough for any single reply this module writes.
pub type ReplyBuf = heapless::String<320>;

pub fn ok(w: &mut impl Write) -> fmt::Result {
    w.write_str("ok\r\n")
}

pub fn error(w: &mut impl Write, code: u16) -> fmt::Result {
    write!(w, "error:{code}\r\n")
}

pub fn alarm(w: &mut impl Write, code: u16) -> fmt::Result {
    write!(w, "ALARM:{code}\r\n")
}

/// Printed after every reset; senders wait for a line starting `Grbl `.
pub fn banner(w: &mut impl Write) -> fmt::Result {
    write!(w, "\r\nGrbl {GRBL_VERSION} ['$' for help]\r\n")
}

pub fn msg(w: &mut impl Write, text: &str) -> fmt::Result {
    write!(w, "[MSG:{text}]\r\n")
}

/// `$G` reply; the interpreter writes the modal words (`G0 G54 G17 …`).
pub fn gc(w: &mut impl Write, body: &str) -> fmt::Result {
    write!(w, "[GC:{body}]\r\n")
}

/// `$` reply.
pub fn help(w: &mut impl Write) -> fmt::Result {
    w.write_str("[HLP:$$ $# $G $I $N $x=val $J=line $SLP $C $X $H $RST ~ ! ? ctrl-x]\r\n")
}

/// What `$I` reports.
#[derive(Clone, Copy, Debug)]
pub struct BuildInfo<'a> {
    /// burin's version, e.g. `0.1.0`.
    pub firmware: &'a str,
    /// Board name.
    pub board: &'a str,
    /// GRBL option letters (`V` variable spindle, `N` line numbers, `M`
    /// mist, `H` single-axis homing, …).
    pub options: &'a str,
    pub planner_blocks: u16,
    /// Axes reported (`$208`), named from X.
    pub axes: usize,
}

/// `$I`: `[VER:1.1h.burin-<version>:<board>]` and
/// `[OPT:<letters>,<planner blocks>,<rx bytes>]` (senders read the last two
/// numbers as buffer sizes; rx is [`RX_WINDOW`] for character counting).
pub fn build_info(w: &mut impl Write, info: &BuildInfo<'_>) -> fmt::Result {
    write!(
        w,
        "[VER:{GRBL_VERSION}.burin-{}:{}]\r\n[OPT:{},{},{RX_WINDOW}]\r\n[AXS:{}:",
        info.firmware, info.board, info.options, info.planner_blocks, info.axes,
    )?;
    for l in crate::AXIS_NAMES.iter().take(info.axes) {
        w.write_char(*l)?;
    }
    w.write_str("]\r\n")
}

/// `$n=value` for one setting: whole-number settings without decimals.
pub fn setting(w: &mut impl Write, n: u16, value: f32) -> fmt::Result {
    if table::is_integer(n) {
        write!(w, "${n}={}\r\n", value as i64)
    } else {
        write!(w, "${n}=")?;
        write_fixed(w, value, 3)?;
        w.write_str("\r\n")
    }
}

/// `$$`: every setting in number order.
pub fn settings(w: &mut impl Write, s: &Settings) -> fmt::Result {
    for n in table::numbers() {
        if let Some(v) = s.get(n) {
            setting(w, n, v)?;
        }
    }
    Ok(())
}

/// How positions are printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Format {
    /// Axes printed (3 for X Y Z; 4 adds A).
    pub axes: usize,
    /// `$13`: inches with 4 decimals instead of mm with 3.
    pub inches: bool,
}

impl Format {
    pub fn from_settings(s: &Settings) -> Self {
        Format {
            axes: usize::from(s.report_axes).clamp(1, crate::AXES),
            inches: s.report_inches,
        }
    }
}

/// `x,y,z[,a]` in the report unit. Rotary axes (index 3 on) stay degrees.
pub fn coords(w: &mut impl Write, pos: &[f32], f: Format) -> fmt::Result {
    for (i, &v) in pos.iter().take(f.axes).enumerate() {
        if i > 0 {
            w.write_char(',')?;
        }
        let linear = i < 3;
        // write_fixed never prints "-0.000".
        if f.inches && linear {
            write_fixed(w, v / 25.4, 4)?;
        } else {
            write_fixed(w, v, 3)?;
        }
    }
    Ok(())
}

/// One `$#` line: `[G54:0.000,0.000,0.000]`.
pub fn param(w: &mut impl Write, name: &str, pos: &[f32], f: Format) -> fmt::Result {
    write!(w, "[{name}:")?;
    coords(w, pos, f)?;
    w.write_str("]\r\n")
}

/// `$#` tool length offset line: `[TLO:0.000]` (mm, or inches per `$13`).
pub fn tlo(w: &mut impl Write, offset: f32, f: Format) -> fmt::Result {
    w.write_str("[TLO:")?;
    coords(w, &[offset], Format { axes: 1, ..f })?;
    w.write_str("]\r\n")
}

/// `$#` probe line: `[PRB:x,y,z:1]`.
pub fn probe(w: &mut impl Write, pos: &[f32], ok: bool, f: Format) -> fmt::Result {
    w.write_str("[PRB:")?;
    coords(w, pos, f)?;
    write!(w, ":{}]\r\n", u8::from(ok))
}

/// Which optional fields a status report carries this time. GRBL repeats
/// `WCO:` and `Ov:` only now and then (they rarely change) to save
/// bandwidth; senders keep the last values. [`Cadence`] decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Extras {
    pub wco: bool,
    pub ov: bool,
}

/// `WCO:` every [`Cadence::EVERY`] reports and `Ov:` likewise (offset by
/// half), and either at once on the report after it changed.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cadence {
    count: u8,
    last: Option<([f32; protocol::WIRE_AXES], protocol::Overrides, u8)>,
}

impl Cadence {
    pub const EVERY: u8 = 10;

    /// Fields to include in the report about to be sent for `s`.
    pub fn next(&mut self, s: &Status) -> Extras {
        // `A:` rides with `Ov:` (GRBL's): a change of either sends both.
        let (wco_changed, ov_changed) = match &self.last {
            None => (true, true),
            Some((wco, ov, acc)) => (*wco != s.wco, *ov != s.overrides || *acc != s.accessories),
        };
        self.last = Some((s.wco, s.overrides, s.accessories));
        let c = self.count;
        self.count = (c + 1) % Self::EVERY;
        Extras {
            wco: wco_changed || c == 0,
            ov: ov_changed || c == Self::EVERY / 2,
        }
    }
}

/// The `<…>` status report. `$10` bit 0 picks MPos (set) or WPos, bit 1
/// adds `Bf:`; `Ln:`, `FS:`, `Pn:` follow when meaningful.
pub fn status(
    w: &mut impl Write,
    s: &Status,
    status_mask: u8,
    f: Format,
    extras: Extras,
) -> fmt::Result {
    write!(w, "<{}", s.state.name())?;
    if s.state.has_substate() {
        write!(w, ":{}", s.substate)?;
    }
    if status_mask & 1 != 0 {
        w.write_str("|MPos:")?;
        coords(w, &s.mpos, f)?;
    } else {
        w.write_str("|WPos:")?;
        coords(w, &s.wpos(), f)?;
    }
    if status_mask & 2 != 0 {
        write!(w, "|Bf:{},{}", s.planner_free, s.rx_free)?;
    }
    if let Some(n) = s.line {
        write!(w, "|Ln:{n}")?;
    }
    let feed = if f.inches { s.feed / 25.4 } else { s.feed };
    w.write_str("|FS:")?;
    write_fixed(w, feed, 0)?;
    w.write_char(',')?;
    write_fixed(w, s.spindle, 0)?;
    if s.pins != 0 {
        w.write_str("|Pn:")?;
        for (bit, letter) in pins::LETTERS {
            if s.pins & bit != 0 {
                w.write_char(letter)?;
            }
        }
    }
    if extras.wco {
        w.write_str("|WCO:")?;
        coords(w, &s.wco, f)?;
    }
    if extras.ov {
        let o = s.overrides;
        write!(w, "|Ov:{},{},{}", o.feed, o.rapid, o.spindle)?;
        // GRBL 1.1: the accessory state after the overrides, only when
        // something is on.
        if s.accessories != 0 {
            w.write_str("|A:")?;
            for (bit, letter) in protocol::msg::accessory::LETTERS {
                if s.accessories & bit != 0 {
                    w.write_char(letter)?;
                }
            }
        }
    }
    w.write_str(">\r\n")
}
