//! The RS274NGC interpreter: lines in, [`Command`]s in machine mm out.
//!
//! A line either succeeds completely or leaves no trace: its commands are
//! collected in a small buffer and handed out only when the whole line
//! interpreted cleanly; on an error the modal state is restored from a
//! snapshot (it is `Copy` and under a hundred bytes), the offset tables
//! from the copy the line made when it first wrote them (if it did), and
//! the line's parameter writes are undone from the undo log. This is what lets check mode and the
//! GRBL `error:N` reply continue with the next line safely.
//!
//! Positions: the interpreter runs ahead of the machine, so after homing and
//! probing it only guesses where the tool stopped (homed axes at machine 0,
//! probes at their target). The executor must feed back the real position
//! with [`Interpreter::set_machine_position`] or [`Interpreter::probe_finished`]
//! before the next line; [`Interpreter::needs_sync`] says when.

mod block;
mod codes;
// `comp`'s paths through the whole interpreter (here: `comp` sits below
// `interp` and imports nothing of it)
#[cfg(test)]
mod comp_tests;
mod cutter;
pub mod cycles;
mod exec;
mod finite;
mod flowvals;
mod geom;
mod homes;
mod mcodes;
mod motion;
mod state;
pub mod tools;

pub use exec::{G30_PROBE_TRAVEL, LINE_COMMANDS};
pub use state::{Motion, Offsets, State, WCS_COUNT};
pub use tools::{ToolEntry, TOOLS};

use crate::command::{Command, Plane, Pos};
use crate::comp::Comp;
use crate::gcode::{ErrorKind, GcodeError, Lexer, Name, ParamStore, Params, Token};
use block::Block;
use core::fmt::{self, Write};
use finite::{cmd_finite, non_finite};
use state::{Saved, Tables};

/// The interpreter: modal state, offset tables and parameters. About 3.4 KiB
/// (the 64-tool table is 1.25 KiB of it).
#[derive(Clone, Debug)]
pub struct Interpreter {
    state: State,
    offsets: Offsets,
    params: Params,
    /// The cutter compensation stage the line's commands pass through.
    comp: Comp,
}

impl Default for Interpreter {
    fn default() -> Self {
        Self::new()
    }
}

/// Parameter access seen by the lexer: typed state first, then the table.
struct Env<'s, 't> {
    state: &'s mut State,
    tables: &'s mut Tables<'t>,
    params: &'s mut Params,
}

impl ParamStore for Env<'_, '_> {
    fn get(&self, n: u16) -> Result<f32, ErrorKind> {
        match n {
            0 => Ok(0.0),
            // The current tool (above the numbered table): `tools::param`.
            5400..=5410 => Ok(self.state.param(self.tables.get(), n).unwrap_or(0.0)),
            1..=crate::gcode::params::PARAM_MAX => Ok(self
                .state
                .param(self.tables.get(), n)
                .unwrap_or_else(|| self.params.get_num(n))),
            _ => Err(ErrorKind::ParamOutOfRange),
        }
    }
    fn set(&mut self, n: u16, v: f32) -> Result<(), ErrorKind> {
        match n {
            0 | 5400..=5410 => Err(ErrorKind::ParamReadOnly),
            1..=crate::gcode::params::PARAM_MAX => {
                if self.state.set_param(self.tables, n, v)? {
                    Ok(())
                } else {
                    self.params.set_num(n, v)
                }
            }
            _ => Err(ErrorKind::ParamOutOfRange),
        }
    }
    fn get_named(&self, name: &Name) -> Result<f32, ErrorKind> {
        self.params.get_name(name)
    }
    fn set_named(&mut self, name: &Name, v: f32) -> Result<(), ErrorKind> {
        self.params.set_name(name, v)
    }
}

impl Interpreter {
    pub const fn new() -> Self {
        Interpreter {
            state: State::new(),
            offsets: Offsets {
                wcs: [[0.0; crate::AXES]; WCS_COUNT],
                g28: [0.0; crate::AXES],
                g30: [0.0; crate::AXES],
                tools: [ToolEntry::EMPTY; TOOLS],
            },
            params: Params::new(),
            comp: Comp::new(),
        }
    }

    /// Interprets one line (terminator optional). On success the line's
    /// commands go to `out` in order; on error nothing is emitted and the
    /// interpreter is as it was before the line.
    pub fn execute_line(
        &mut self,
        line: &[u8],
        out: &mut dyn FnMut(Command),
    ) -> Result<(), GcodeError> {
        self.execute_line_at(line, 0, &mut |_, c| out(c))
    }

    /// [`execute_line`](Self::execute_line) for line `n`: what comes out
    /// is tagged with the line it belongs to, which differs from `n` for
    /// moves cutter compensation held back until this line showed where
    /// they end. A path compensation cannot follow refuses the line.
    pub fn execute_line_at(
        &mut self,
        line: &[u8],
        n: u32,
        out: &mut dyn FnMut(u32, Command),
    ) -> Result<(), GcodeError> {
        // Most lines meet compensation off with nothing held: they pass
        // straight through, without the copy and the buffer.
        // An idle stage is a new one, so only an engaged one is copied.
        let mut pass: Option<Comp> = (!self.comp.idle()).then(|| self.comp.clone());
        let idle = pass.is_none();
        let mut held: heapless::Vec<(u32, Command), { LINE_COMMANDS + crate::comp::EXTRA_OUT }> =
            heapless::Vec::new();
        self.execute_line_then(line, &mut |cmds| {
            if idle && !cmds.iter().any(|c| matches!(c, Command::CutterComp(_))) {
                for c in cmds {
                    out(n, c.clone());
                }
                return Ok(());
            }
            let p = pass.get_or_insert_with(Comp::new);
            let mut full = false;
            for c in cmds {
                p.push(n, c.clone(), &mut |l, c| full |= held.push((l, c)).is_err())
                    .map_err(|k| GcodeError::new(k, 0))?;
            }
            if full {
                return Err(GcodeError::new(ErrorKind::TooManyCommands, 0));
            }
            Ok(())
        })?;
        if let Some(p) = pass {
            self.comp = p;
            for (l, c) in held {
                out(l, c);
            }
        }
        Ok(())
    }

    /// Commands one line may hand on at most, compensation's held ones
    /// included: the room a caller keeps for a line.
    pub fn max_line_output(&self) -> usize {
        LINE_COMMANDS + self.comp.max_extra()
    }

    /// [`execute_line`](Self::execute_line) with the line's commands handed
    /// over as a whole to `take`, which may still refuse the line (the
    /// cutter compensation stage finds a path it cannot compensate): the
    /// interpreter is then as it was before the line.
    pub fn execute_line_then(
        &mut self,
        line: &[u8],
        take: &mut dyn FnMut(&[Command]) -> Result<(), GcodeError>,
    ) -> Result<(), GcodeError> {
        let snapshot = self.state;
        let mut saved = Saved::default();
        self.params.begin_line();
        let mut buf = exec::Out::new();
        let r = self.run(line, &mut buf, &mut saved).and_then(|()| {
            let writes = (self.state.offsets_changed && !snapshot.offsets_changed)
                || buf.iter().any(|c| matches!(c, Command::SaveSettings));
            if writes && self.outputs_on() {
                Err(GcodeError::new(ErrorKind::FlashWriteOutputsOn, 0))
            } else {
                Ok(())
            }
        });
        // By reference: moving the whole buffer would copy all its slots
        // (1.3 KB) on every line.
        match r.and_then(|()| take(&buf)) {
            Ok(()) => Ok(()),
            Err(e) => {
                self.state = snapshot;
                saved.restore(&mut self.offsets);
                self.params.rollback();
                Err(e)
            }
        }
    }

    /// Spindle or coolant on, as the lines so far leave them (and as the
    /// outputs will be when this line's storage write comes due: writes
    /// wait for the motion and commands before them). A flash write stalls
    /// the CPU for up to 0.8 s per sector erase, e-stop and limit handlers
    /// included, so the session writes nothing while they are on.
    pub fn outputs_on(&self) -> bool {
        self.state.spindle != crate::command::SpindleDir::Off || self.state.flood || self.state.mist
    }

    /// A coolant toggle (0xA0, 0xA1) changed the outputs out of program
    /// order: the modal state follows (`$G`), as GRBL's does.
    pub fn set_coolant(&mut self, mist: bool, flood: bool) {
        self.state.mist = mist;
        self.state.flood = flood;
    }

    fn run_block(
        &mut self,
        b: &Block,
        buf: &mut exec::Out,
        saved: &mut Saved,
    ) -> Result<(), GcodeError> {
        let before = buf.len();
        let mut tables = Tables::new(&mut self.offsets, saved);
        exec::execute(&mut self.state, &mut tables, b, buf)?;
        let bad = buf
            .get(before..)
            .is_some_and(|s| s.iter().any(|c| !cmd_finite(c)));
        // A line that wrote the offset tables (G10, G28.1, #5221=) must
        // leave them finite too: `G10 L20 X4e38` overflowed to inf
        // (found by the gcode_program fuzz target).
        let o = &self.offsets;
        let tables_bad = saved.any()
            && (o.wcs.iter().any(|w| non_finite(w) != 0)
                || non_finite(&o.g28) != 0
                || non_finite(&o.g30) != 0
                || o.tools
                    .iter()
                    .any(|t| non_finite(&t.offset) != 0 || !t.diameter.is_finite()));
        let pos_bad = non_finite(&self.state.pos) | non_finite(&self.state.tlo) != 0;
        if bad || tables_bad || pos_bad {
            return Err(GcodeError::new(ErrorKind::NotFinite, b.first_col));
        }
        Ok(())
    }

    fn run(
        &mut self,
        line: &[u8],
        buf: &mut exec::Out,
        saved: &mut Saved,
    ) -> Result<(), GcodeError> {
        let mut lx = Lexer::new(line)?;
        if lx.percent {
            self.state.percent = homes::percent_line(self.state.percent);
        }
        if lx.block_delete && self.state.block_delete || self.state.percent == 2 {
            return Ok(());
        }
        let mut block = Block {
            line,
            ..Block::default()
        };
        let mut split = false;
        loop {
            let tok = {
                let mut tables = Tables::new(&mut self.offsets, saved);
                let mut env = Env {
                    state: &mut self.state,
                    tables: &mut tables,
                    params: &mut self.params,
                };
                lx.next_token(&mut env)?
            };
            match tok {
                None => break,
                Some(Token::Message { text, col }) => {
                    if block.msg.is_some() {
                        buf.push(Command::Message(exec::message(text)))
                            .map_err(|_| GcodeError::new(ErrorKind::TooManyCommands, col))?;
                    } else {
                        block.msg = Some((text, col));
                    }
                }
                Some(Token::Value { text, value, col }) => {
                    let c = Command::Message(mcodes::value_text(text, value));
                    buf.push(c)
                        .map_err(|_| GcodeError::new(ErrorKind::TooManyCommands, col))?;
                }
                Some(Token::Word(w)) => {
                    if block.splits_on(&w) {
                        self.run_block(&block, buf, saved)?;
                        block = Block {
                            line,
                            ..Block::default()
                        };
                        split = true;
                    }
                    block.add(&w)?;
                    if w.letter == b'M' && w.tenths() == Some(1170) {
                        block.text = Some(lx.rest_text()?);
                    }
                }
            }
        }
        if split && block.is_mode_only() {
            return Err(GcodeError::new(ErrorKind::AmbiguousOrder, block.first_col));
        }
        if !block.is_empty() {
            self.run_block(&block, buf, saved)?;
        }
        Ok(())
    }

    /// The modal state, positions and offsets (read-only).
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The parameter tables.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Where the machine really is (after homing, probing, a hold or a jog).
    pub fn set_machine_position(&mut self, pos: Pos) {
        self.state.pos = pos;
        self.state.needs_sync = false;
        self.state.last_g5 = None;
    }

    /// A probe move ended at `pos`; `contact` says whether the probe tripped.
    /// Sets #5061.. and #5070, and applies a pending G30 plate thickness as
    /// a G92 Z offset so that work Z at the contact equals the thickness.
    pub fn probe_finished(&mut self, pos: Pos, contact: bool) {
        self.set_machine_position(pos);
        self.state.probe = pos;
        self.state.probe_ok = contact;
        if let Some(t) = self.state.pending_probe_z.take() {
            if contact {
                let base = self
                    .offsets
                    .wcs
                    .get(usize::from(self.state.wcs))
                    .map_or(0.0, |o| o[2]);
                if !self.state.g92_active {
                    self.state.g92 = [0.0; crate::AXES];
                }
                self.state.g92[2] = pos[2] - base - self.state.tlo[2] - t;
                self.state.g92_active = true;
            }
        }
    }

    /// True after a command whose end only the machine knows.
    pub fn needs_sync(&self) -> bool {
        self.state.needs_sync
    }

    /// The offsets that persist.
    pub fn offsets(&self) -> Offsets {
        self.offsets
    }

    /// Replaces the offsets that persist (boot, M501, `$RST=#`).
    pub fn set_offsets(&mut self, o: &Offsets) {
        self.offsets = *o;
    }

    /// [`new`](Self::new) with stored offsets: one struct literal, so a
    /// caller's field can be built in place (the boot stack).
    #[inline(always)]
    pub fn with_offsets(o: Option<&Offsets>) -> Self {
        match o {
            Some(o) => Interpreter {
                offsets: *o,
                ..Self::new()
            },
            None => Self::new(),
        }
    }

    /// True once after G10 L2/L20, G28.1 or G30.1: the lines GRBL saves at
    /// once. Offsets changed through their parameters (`#5221=…`) wait
    /// for M500, like any other parameter.
    pub fn take_offsets_changed(&mut self) -> bool {
        core::mem::take(&mut self.state.offsets_changed)
    }

    /// `$210`: true for BeagleG's G28 (home) and G30 (probe), false for
    /// RS274NGC's stored positions (the default).
    pub fn set_g28_homes(&mut self, on: bool) {
        self.state.g28_homes = on;
    }

    /// Block delete switch (`/` lines skipped while on; on by default).
    pub fn set_block_delete(&mut self, on: bool) {
        self.state.block_delete = on;
    }

    /// GRBL's soft reset: modal state back to defaults; offsets, stored
    /// positions, parameters, the position, the current tool and its
    /// length offset survive.
    pub fn reset(&mut self) {
        let s = self.state;
        self.state = State {
            g92: s.g92,
            g92_active: s.g92_active,
            pos: s.pos,
            probe: s.probe,
            probe_ok: s.probe_ok,
            tool: s.tool,
            loaded: s.loaded,
            tlo: s.tlo,
            block_delete: s.block_delete,
            g28_homes: s.g28_homes,
            ..State::new()
        };
        self.comp.reset();
    }

    /// Work coordinate offset (active G54.. plus G92), machine mm: GRBL's WCO.
    pub fn wco(&self) -> Pos {
        self.state.wco(&self.offsets)
    }

    /// The body of GRBL's `$G` report, e.g. `G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0`
    /// (the link layer wraps it in `[GC:` … `]`). F is in the active units.
    pub fn write_gc_state(&self, w: &mut dyn Write) -> fmt::Result {
        let s = &self.state;
        crate::gcode::error::write_code(w, b'G', s.motion.tenths())?;
        let wcs = match s.wcs {
            k @ 0..=5 => 540 + 10 * u16::from(k),
            k => 591 + u16::from(k) - 6,
        };
        w.write_char(' ')?;
        crate::gcode::error::write_code(w, b'G', wcs)?;
        let plane = match s.plane {
            Plane::XY => 17,
            Plane::ZX => 18,
            Plane::YZ => 19,
        };
        write!(
            w,
            " G{plane} G{} G{} G{} ",
            if s.inch { 20 } else { 21 },
            if s.incremental { 91 } else { 90 },
            if s.inverse_time { 93 } else { 94 },
        )?;
        match s.comp {
            Some(crate::command::CompSide::Left) => w.write_str("G41 ")?,
            Some(crate::command::CompSide::Right) => w.write_str("G42 ")?,
            None => {}
        }
        w.write_str(match s.spindle {
            crate::command::SpindleDir::Cw => "M3",
            crate::command::SpindleDir::Ccw => "M4",
            crate::command::SpindleDir::Off => "M5",
        })?;
        match (s.mist, s.flood) {
            (false, false) => w.write_str(" M9")?,
            (true, false) => w.write_str(" M7")?,
            (false, true) => w.write_str(" M8")?,
            (true, true) => w.write_str(" M7 M8")?,
        }
        // Short numbers (`F10`, `S300`, `F12.5`): at most 3 decimals.
        write!(w, " T{} F", s.tool)?;
        crate::num::write_short(w, s.feed / s.unit(), 3)?;
        w.write_str(" S")?;
        crate::num::write_short(w, s.speed, 3)
    }

    /// GRBL's `$#` report lines (G54..G59.3, G28, G30, G92, TLO, the tool
    /// table as `[T:n|length|diameter]`, PRB), all axes, machine mm with
    /// three decimals, each followed by `eol`.
    pub fn write_offsets(&self, w: &mut dyn Write, eol: &str, axes: usize) -> fmt::Result {
        let s = &self.state;
        let pos = |w: &mut dyn Write, p: &Pos| -> fmt::Result {
            for (i, v) in p.iter().take(axes.max(1)).enumerate() {
                if i > 0 {
                    w.write_char(',')?;
                }
                crate::num::write_fixed(w, *v, 3)?;
            }
            Ok(())
        };
        for (k, o) in self.offsets.wcs.iter().enumerate() {
            w.write_char('[')?;
            let code = if k < 6 {
                540 + 10 * k as u16
            } else {
                591 + k as u16 - 6
            };
            crate::gcode::error::write_code(w, b'G', code)?;
            w.write_char(':')?;
            pos(w, o)?;
            write!(w, "]{eol}")?;
        }
        let o = &self.offsets;
        for (label, p) in [("G28", &o.g28), ("G30", &o.g30), ("G92", &s.g92)] {
            write!(w, "[{label}:")?;
            pos(w, p)?;
            write!(w, "]{eol}")?;
        }
        w.write_str("[TLO:")?;
        crate::num::write_fixed(w, s.tlo[2], 3)?;
        write!(w, "]{eol}")?;
        tools::write_table(w, &o.tools, eol)?;
        w.write_str("[PRB:")?;
        pos(w, &s.probe)?;
        write!(w, ":{}]{eol}", u8::from(s.probe_ok))
    }
}
