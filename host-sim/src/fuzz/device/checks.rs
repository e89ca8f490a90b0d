//! The device target's timed checks: `?` answered, `$I` after a reset,
//! and realtime bytes in their UTF-8 form.

use super::super::{
    CHECK_LINE_RIGHT_AFTER_RESET, CHECK_MODE_AFTER_RESET, CHECK_PROMPT_AFTER_RESET,
    CHECK_RESET_WITH_FULL_RING, CHECK_UTF8_REALTIME,
};
use super::{Harness, RESET_BOUND_MS, RESET_BOUND_SLOW_MS, STATUS_BOUND_MS};

impl Harness<'_, '_> {
    /// Send `buf` and wait for `want` in the text output, at most `bound` ms.
    pub(super) fn answered(&mut self, bound: u64, want: &[u8], what: &str) {
        let mut seen = Vec::new();
        let end = self.dev.sim.now() + bound * self.ms;
        let mut step = self.ms;
        while self.dev.sim.now() < end {
            // 1 ms steps first, growing to 100 ms (bounds of seconds).
            let t = (self.dev.sim.now() + step).min(end);
            step = (step + self.ms / 10).min(100 * self.ms);
            self.dev.advance_to(t);
            seen.extend_from_slice(&self.dev.tx.0);
            self.read_output();
            if seen.windows(want.len()).any(|w| w == want) {
                return;
            }
        }
        panic!(
            "{what}: no {:?} within {bound} ms; got {:?}; rx pending {}, room {}, \
             state {:?}, drained {}, link {:?}/{}, op {}",
            String::from_utf8_lossy(want),
            String::from_utf8_lossy(&seen),
            self.dev.rx_pending(),
            self.dev.room(),
            self.dev.sim.machine.state(&self.dev.sim.rt),
            self.dev.controller.session.drained(),
            self.dev.link_mode(),
            self.dev.framed(),
            self.op
        );
    }

    pub(super) fn status_check(&mut self) {
        if !self.text_mode() || self.send(b"?") != 1 {
            return;
        }
        self.answered(STATUS_BOUND_MS, b"<", "status query");
    }

    pub(super) fn reset_check(&mut self) {
        if !self.text_mode() {
            return;
        }
        let full = self.dev.room() < 64;
        if self.send(&[0x18]) != 1 {
            return;
        }
        self.voided_at = self.op;
        self.dev.poll();
        let pos = self.dev.position_steps();
        if full && !CHECK_RESET_WITH_FULL_RING {
            return;
        }
        if !CHECK_LINE_RIGHT_AFTER_RESET {
            // Let the reset be taken first (its banner), then ask.
            self.answered(RESET_BOUND_MS, b"Grbl 1.1", "banner after reset");
            assert_eq!(self.dev.position_steps(), pos, "moved after a reset");
        }
        let split = self.dev.link_mode() == burin::link::LinkMode::Framed;
        if split && !CHECK_MODE_AFTER_RESET {
            return;
        }
        if self.send(b"$I\n") == 3 {
            let bound = if CHECK_PROMPT_AFTER_RESET {
                RESET_BOUND_MS
            } else {
                RESET_BOUND_SLOW_MS
            };
            self.answered(bound, b"[VER:", "$I after reset");
            assert_eq!(self.dev.position_steps(), pos, "moved after a reset");
        }
    }

    /// A realtime byte in its UTF-8 form, as some senders send it: it acts
    /// and leaves nothing in the line buffer, so a `$I` right behind it is
    /// answered. Only while the session takes lines at once (nothing received or
    /// queued ahead of the `$I`): behind a full queue in a hold, `$I`
    /// waits its turn, as in GRBL; inside an O-word block being captured
    /// or skipped it belongs to the block (issue 30).
    pub(super) fn utf8_realtime(&mut self, r: u8) {
        let session = &self.dev.controller.session;
        let text = self.text_mode()
            && self.dev.rx_pending() == 0
            && session.drained()
            && session.lines_run_directly();
        if self.send(&[0xC2, r]) != 2 || !CHECK_UTF8_REALTIME || !text {
            return;
        }
        // Jog cancel and reset answer in their own time; overrides at once.
        if matches!(r, 0x90..=0x9D) && self.send(b"$I\n") == 3 {
            self.answered(STATUS_BOUND_MS, b"[VER:", "$I after a UTF-8 realtime byte");
        }
    }
}
