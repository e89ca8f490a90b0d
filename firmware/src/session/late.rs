//! Errors found after a line's `ok` (issue 35): a command the executor
//! refused when it reached it (soft limit, step rate, feed too slow, an
//! arc's geometry), or a chord, probe move or script step it refused later.
//!
//! A GRBL sender counts the `ok` and streams on, so a message alone lets
//! the job run past the missing move, from the wrong place. Every such
//! error therefore stops the job as an alarm: the executor ramps the
//! motion down along its path (the position stays exact) and then raises
//! the error as its alarm (`ALARM:2` for a soft limit, as GRBL does;
//! `ALARM:21` for the others); the session drops everything queued behind
//! the line and reads no new line until the alarm is up, so the lines a
//! sender has in flight meet it (`error:9`). A feed hold would not do: `~`
//! would resume the job without the refused move. A jog is not a job and
//! is refused as GRBL refuses one, without an alarm.

use super::{Device, MotionPort, Out, Tx};
use crate::command::Command;
use crate::executor::MachineError;
use core::fmt::Write;
use protocol::DeviceMsg;

/// Text `[MSG:line N: error C: …]`; framed, the same as a `Msg` frame and
/// the line's `Error` frame.
fn report(e: MachineError, line: u32, o: &mut Out<'_, impl Tx>) {
    let _ = write!(o, "[MSG:line {line}: error {}: {e}]\r\n", e.code());
    o.frame(&DeviceMsg::Error {
        seq: Some(line),
        line: Some(line),
        code: e.code(),
    });
}

impl<S: crate::seams::Storage> Device<S> {
    /// The executor refused `cmd` of machine line `line`, already
    /// acknowledged.
    pub(super) fn refused(
        &mut self,
        cmd: &Command,
        line: u32,
        e: MachineError,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) {
        if line == 0 && self.jogging && matches!(cmd, Command::Line { .. }) {
            report(e, line, o);
        } else {
            m.fault(e, line);
            self.faults(m, o);
        }
    }

    /// Report the executor's faults; while it stops, nothing queued runs
    /// and no new line is read.
    pub(super) fn faults(&mut self, m: &mut impl MotionPort, o: &mut Out<'_, impl Tx>) {
        while let Some((e, line)) = m.take_fault() {
            report(e, line, o);
            self.cmds.clear();
            self.slots.clear();
            self.flow.reset(&mut self.interp);
            self.pending.cancel_queued();
            self.sync = true;
            // A probe behind the line never runs: no result to take.
            self.probe_sync = false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::sys;

    #[test]
    fn a_late_soft_limit_is_alarm_2_the_others_alarm_21() {
        use protocol::codes::alarm;
        let soft = MachineError::SoftLimit { axis: 0 };
        assert_eq!(sys::alarm_code(soft), alarm::SOFT_LIMIT);
        let slow = MachineError::FeedTooSlow;
        assert_eq!(sys::alarm_code(slow), alarm::LATE_ERROR);
        let rate = MachineError::StepRateTooHigh { axis: 1 };
        assert_eq!(sys::alarm_code(rate), alarm::LATE_ERROR);
        let probe = MachineError::ProbeNoContact;
        assert_eq!(sys::alarm_code(probe), alarm::PROBE_FAIL_CONTACT);
    }
}
