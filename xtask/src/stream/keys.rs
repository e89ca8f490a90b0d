//! Keys while streaming: hold, resume, overrides, a status line, and the
//! two questions (reset? what now after Ctrl-C?) answered by the next key.

use super::pause::wpos_text;
use super::run::{Ask, Stream};
use super::term::Key;
use super::Outcome;
use anyhow::Result;
use protocol::{MachineState, Rt};
use std::io::{Read, Write};
use std::time::Duration;

/// A reset with motion left in the planner is an alarm (3) on burin, as on
/// GRBL: the held motion is gone and the position is not trusted.
const AFTER_RESET: &str =
    "soft reset: job aborted; the machine is in alarm if motion was left: unlock with $X or home with $H";

impl<T: Read + Write> Stream<'_, T> {
    pub(super) fn on_key(&mut self, k: Key) -> Result<Option<Outcome>> {
        if let Some(ask) = self.ask.take() {
            match (ask, k) {
                (Ask::Reset, Key::Other('y')) | (Ask::Interrupt, Key::Other('r')) => {
                    self.stop_and_reset()?;
                    self.ui.say(AFTER_RESET);
                    return Ok(Some(Outcome::Reset));
                }
                (Ask::Interrupt, Key::Other('q')) | (Ask::Interrupt, Key::Interrupt) => {
                    self.ui.say("quit: the machine is left in feed hold");
                    return Ok(Some(Outcome::Interrupted));
                }
                (Ask::Interrupt, Key::Other('c')) | (Ask::Interrupt, Key::Resume) => {
                    self.client.realtime(Rt::CycleStart)?;
                    return Ok(None);
                }
                // The menu stays open; other keys do what they always do.
                (Ask::Interrupt, _) => self.ask = Some(Ask::Interrupt),
                (Ask::Reset, _) => {
                    self.ui.say("(reset cancelled)");
                    return Ok(None);
                }
            }
        }
        let held = self.pause.is_some();
        match k {
            Key::Hold => self.hold()?,
            Key::Resume => self.client.realtime(Rt::CycleStart)?,
            Key::Toggle if held => self.client.realtime(Rt::CycleStart)?,
            Key::Toggle => self.hold()?,
            Key::FeedUp => self.client.realtime(Rt::FeedOvPlus10)?,
            Key::FeedDown => self.client.realtime(Rt::FeedOvMinus10)?,
            Key::Feed100 => self.client.realtime(Rt::FeedOv100)?,
            Key::Status => self.detail(),
            Key::Reset => {
                self.ui
                    .say("soft reset aborts the job (the machine then needs $X or $H): y confirms, any other key keeps it");
                self.ask = Some(Ask::Reset);
            }
            Key::Interrupt if !self.ui.interactive() => {
                // No one to ask: stop the motion, then the job.
                self.stop_and_reset()?;
                self.ui.say(AFTER_RESET);
                return Ok(Some(Outcome::Interrupted));
            }
            Key::Interrupt => {
                self.hold()?;
                self.ui
                    .say("feed hold. [c]ontinue, [r]eset (abort the job), [q]uit leaving it held?");
                self.ask = Some(Ask::Interrupt);
            }
            Key::Other(_) => {}
        }
        Ok(None)
    }

    /// Hold, wait until the hold has stopped (`Hold:0`), then reset: a
    /// reset while still moving would lose the position (alarm 3).
    fn stop_and_reset(&mut self) -> Result<()> {
        self.client.realtime(Rt::FeedHold)?;
        let t0 = std::time::Instant::now();
        while t0.elapsed() < Duration::from_secs(10) {
            match super::board::query_status(&mut self.client)? {
                Some(st) if st.state == MachineState::Hold && st.substate == 0 => break,
                Some(st) if st.state != MachineState::Run && st.state != MachineState::Hold => {
                    break
                }
                _ => std::thread::sleep(Duration::from_millis(20)),
            }
        }
        self.client.realtime(Rt::SoftReset)?;
        Ok(())
    }

    fn hold(&mut self) -> Result<()> {
        if self.pause.is_none() {
            self.we_held = true;
        }
        self.client.realtime(Rt::FeedHold)?;
        Ok(())
    }

    fn detail(&self) {
        let Some(st) = &self.last else { return };
        let m = st.mpos;
        self.ui.say(format!(
            "{}: {}{} MPos X{:.3} Y{:.3} Z{:.3} WPos {} F{:.0} S{:.0} Ov:{},{},{} Bf:{},{} lines sent {}/{}",
            self.job.at(self.line_now),
            st.state.name(),
            if st.state.has_substate() { format!(":{}", st.substate) } else { String::new() },
            m[0],
            m[1],
            m[2],
            wpos_text(st),
            st.feed,
            st.spindle,
            st.overrides.feed,
            st.overrides.rapid,
            st.overrides.spindle,
            st.planner_free,
            st.rx_free,
            self.sent,
            self.job.lines.len()
        ));
    }
}
