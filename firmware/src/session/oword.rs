//! The session's side of the O-word stage (`crate::flow`): job lines pass
//! it before the interpreter, a replay runs a bounded number of steps per
//! pass, and the line that started a replay is answered when it ends.

use super::{Device, MotionPort, Out, Tx};
use crate::flow::{Intake, Step};
use crate::gcode::GcodeError;
use crate::seams::Storage;
use protocol::DeviceMsg;

impl<S: Storage> Device<S> {
    /// One job line (text mode) or one framed line leaving its slot, through
    /// the O-word stage. `n` is its machine line number (text count or
    /// sequence number).
    pub(super) fn job_line(
        &mut self,
        text: &[u8],
        n: u32,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) {
        // A `$` line runs at once unless it stands in a branch not taken
        // or a block being captured: the stage skips or refuses it there.
        let sys = crate::link::syscmd::parse(text).is_some();
        if sys && self.flow.runs_directly() || self.locked(text) {
            return self.line(text, n, m, o);
        }
        match self.flow.intake(text, n, &mut self.interp) {
            Intake::Run => self.line(text, n, m, o),
            Intake::Reply(r) => {
                let seq = o.framed().then_some(n);
                match r {
                    Ok(()) => self.reply_line(Ok(()), seq, o),
                    Err(e) => self.reply_error(e, None, seq, o),
                }
            }
            // Answered when the replay ends (`replay_step`).
            Intake::Replay => self.replay_framed = o.framed(),
        }
    }

    /// The stage's answer to a text-mode `$` command it held back.
    pub(super) fn reply_error_or_ok(
        &mut self,
        r: Result<(), GcodeError>,
        o: &mut Out<'_, impl Tx>,
    ) {
        match r {
            Ok(()) => self.reply_line(Ok(()), None, o),
            Err(e) => self.reply_error(e, None, None, o),
        }
    }

    /// One step of a running replay; the line that started it is answered
    /// when it ends, with the first error inside it.
    pub(super) fn replay_step(&mut self, m: &mut impl MotionPort, o: &mut Out<'_, impl Tx>) {
        let mut buf = [0u8; crate::gcode::MAX_LINE];
        let done = match self.flow.step(&mut self.interp, &mut buf) {
            Step::Idle | Step::Busy => return,
            Step::Run { n, len } => {
                let text = buf.get(..len).unwrap_or(&[]);
                match self.interpret(text, n, m, o) {
                    Ok(()) => return,
                    Err(e) => self
                        .flow
                        .abort(&mut self.interp)
                        .map(|at| (at, Err((n, e)))),
                }
            }
            Step::Done { n, result } => Some((n, result)),
        };
        let Some((at, result)) = done else { return };
        let seq = o.framed().then_some(at);
        match result {
            Ok(()) => self.reply_line(Ok(()), seq, o),
            Err((line, e)) => self.reply_error(e, Some(line), seq, o),
        }
    }

    /// A G-code error as the answer to a line; `at` is the source line a
    /// replay failed on, told first (`[MSG:line N: …]`).
    pub(super) fn reply_error(
        &mut self,
        e: GcodeError,
        at: Option<u32>,
        seq: Option<u32>,
        o: &mut Out<'_, impl Tx>,
    ) {
        if o.framed() {
            let mut t = protocol::msg::MsgText::new();
            if let Some(l) = at {
                let _ = core::fmt::write(&mut t, format_args!("line {l}: "));
            }
            let _ = core::fmt::write(&mut t, format_args!("{e}"));
            o.frame(&DeviceMsg::Msg(t));
        } else if let Some(l) = at {
            let _ = core::fmt::Write::write_fmt(o, format_args!("[MSG:line {l}: {e}]\r\n"));
        }
        let code = if o.framed() {
            e.code()
        } else {
            u16::from(e.grbl_code())
        };
        self.reply_line(Err(code), seq, o)
    }
}
