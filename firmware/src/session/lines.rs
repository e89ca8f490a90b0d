//! One job line: a `$` command or G-code through the interpreter into the
//! command queue, and its `ok` / `error`.

use super::{persist, sys, Device, MotionPort, Out, Tx};
use crate::command::Command;
use crate::gcode::GcodeError;

impl<S: crate::seams::Storage> Device<S> {
    /// Sleep, or an alarm outside check mode: only blank lines pass.
    pub(super) fn locked(&self, text: &[u8]) -> bool {
        let blank = text.iter().all(u8::is_ascii_whitespace);
        (self.sleep || self.seen_alarm.is_some() && !self.check) && !blank
    }

    /// One line to the interpreter, answered (a job line the O-word stage
    /// lets run, or one of its replayed lines). `n` is its machine line
    /// number (text count or N word, or sequence number).
    pub(super) fn line(
        &mut self,
        text: &[u8],
        n: u32,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) {
        let seq = o.framed().then_some(n);
        if let Some(cmd) = crate::link::syscmd::parse(text) {
            let r = cmd.map_err(|c| c.code()).and_then(|c| self.system(c, m, o));
            self.reply_line(r, seq, o);
            return self.reset_if_due(m, o);
        }
        if self.locked(text) {
            return self.reply_line(Err(protocol::Code::Locked.code()), seq, o);
        }
        if !self.check && !self.can_take() {
            // Only text that precedes a switch to frames gets here.
            return self.reply_line(Err(protocol::Code::RxOverflow.code()), seq, o);
        }
        match self.interpret(text, n, m, o) {
            Ok(()) => self.reply_line(Ok(()), seq, o),
            Err(e) => self.reply_error(e, None, seq, o),
        }
    }

    /// Interprets one line and queues its commands as line `n`; no answer.
    pub(super) fn interpret(
        &mut self,
        text: &[u8],
        n: u32,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) -> Result<(), GcodeError> {
        let check = self.check;
        self.interp.set_g28_homes(m.settings().g28_homes);
        let cmds = &mut self.cmds;
        let mut probe = false;
        let mut store = persist::Pending::default();
        // What comes out carries its own line: a move cutter compensation
        // held back runs as the line that commanded it.
        self.interp.execute_line_at(text, n, &mut |l, c| {
            // Operator text shows when the line is read, as GRBL's
            // `(MSG,…)` does: `[MSG:…]` (a frame in framed mode).
            if let Command::Message(t) = &c {
                let _ = crate::link::reply::msg(o, t);
            }
            if !check && !store.take_command(&c) {
                probe |= matches!(c, Command::Probe { .. });
                // Room for a whole line (and what compensation held) was
                // checked before taking it.
                let _ = cmds.push_back((l, c));
            }
        })?;
        if let Some(t) = self.interp.take_tool_warning() {
            sys::no_tool_entry(t, o);
        }
        if let Some(l) = self.interp.take_arc_warning() {
            sys::off_plane_zero(l, o);
        }
        if !check && self.interp.needs_sync() {
            self.sync = true;
            self.probe_sync = probe;
        }
        self.after_line(store, m, o);
        Ok(())
    }

    /// The soft reset `$C` asked for, after its `ok`.
    pub(super) fn reset_if_due(&mut self, m: &mut impl MotionPort, o: &mut Out<'_, impl Tx>) {
        if core::mem::take(&mut self.reset_due) {
            self.soft_reset(m, o);
        }
    }

    pub(super) fn reply_line(
        &mut self,
        r: Result<(), u16>,
        seq: Option<u32>,
        o: &mut Out<'_, impl Tx>,
    ) {
        match r {
            Ok(()) => self.stats.lines_ok += 1,
            Err(_) => self.stats.lines_err += 1,
        }
        sys::reply(r, seq, o);
    }
}
