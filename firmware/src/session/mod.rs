//! The device session: link events in, machine commands and replies out.
//!
//! This is the one place that decides what a line from the host does, so
//! the RTIC app and host-sim's virtual device behave identically. It sits
//! between two seams: a [`LinkPort`] (the link decoder: lines, `$`
//! commands, frames, realtime flags) and a [`MotionPort`] (the executor and
//! the realtime atomics). Replies go to a [`Tx`] byte sink.
//!
//! # Backpressure: nothing acknowledged is ever lost
//!
//! * Text mode: a line is taken from the link only when the command queue
//!   ([`CMD_SLOTS`]) has room for the most commands one line can produce
//!   ([`LINE_COMMANDS`], plus what cutter compensation held back:
//!   `Interpreter::max_line_output`), so interpreting never has to drop a
//!   command.
//!   Otherwise the link is left alone: its ring fills, then USB (or the
//!   pty) pushes back on the sender. `ok` means what it means in GRBL: the
//!   line was interpreted and its commands are queued.
//! * Framed mode: frames are always taken, so a handshake or a settings
//!   request is answered even while the machine is held with full queues.
//!   A line is acknowledged when it enters a free line slot ([`LINE_SLOTS`],
//!   the credits; "queued for execution"); without one the session refuses
//!   it (`Nak`, the host resends). Slots are interpreted in order as the
//!   command queue drains; a line that then fails is reported with
//!   `DeviceMsg::Error { seq, .. }`.
//!
//! # Choices
//!
//! * Errors found when a queued command reaches the executor (soft limits,
//!   bad arcs) come after the line's `ok`: text mode reports them as
//!   `[MSG:…]` (an extra `error:N` would break send-response counting),
//!   framed mode as `DeviceMsg::Error` with the line's sequence number,
//!   and they stop the job as an alarm (`late.rs`).
//! * The machine line number (`Ln:`, traces) is the sequence number in
//!   framed mode; in text mode the line's N word when it has one (GRBL's
//!   `Ln:`), else the count of text lines received.
//! * Soft reset while something moves raises alarm 3 (as GRBL; a
//!   finished hold or a dwell does not); `ALARM:3` comes before the
//!   banner. A port open at rest is a soft reset (`realtime.rs`). Soft reset keeps the framed session's sequence.
//! * Jog cancel is a feed hold followed, once stopped, by a flush; the
//!   executor can flush only through a reset, so the device resets and
//!   clears the resulting alarm itself (the position is kept exactly: the
//!   hold decelerated).

mod late;
mod lines;
mod out;
mod oword;
mod persist;
mod ports;
mod realtime;
mod reprap;
mod sys;

pub use out::{Out, Tx};
pub use ports::{LinkPort, MotionPort};
pub use sys::RT_REPLY_ROOM;

use crate::command::Command;
use crate::executor::{self, MachineError};
use crate::flow::{Flow, Intake};
use crate::interp::{Interpreter, LINE_COMMANDS};
use crate::link::{FramedAction, FramedPort, LinkEvent};
use crate::persist::{Persist, Report};
use crate::seams::{NoStorage, Storage};
use crate::settings::Settings;
use heapless::Deque;
use protocol::{DeviceInfo, DeviceMsg, HostMsg, LineText};

/// Command queue between the interpreter and the executor.
pub const CMD_SLOTS: usize = 2 * LINE_COMMANDS;
// A line's own commands plus what cutter compensation held.
const _: () = assert!(CMD_SLOTS >= LINE_COMMANDS + crate::comp::EXTRA_OUT);
/// Framed job lines acknowledged but not yet interpreted (the credits).
pub const LINE_SLOTS: usize = 8;

/// The session reads new input only with this much room for replies: it
/// holds the longest burst one event writes (a `$$` listing is about 600
/// bytes), so a reply is never dropped; reading the link just pauses while
/// the host is slow to read. Realtime commands do not wait for it
/// ([`Device::poll_realtime`]).
pub const TX_HEADROOM: usize = 768;

/// Replay steps (stored lines or O-word lines) one pass takes at most: an
/// O-word loop that moves nothing must not hold the task.
pub const REPLAY_STEPS: u32 = 32;

/// Static facts for `$I` and the handshake.
#[derive(Clone, Copy, Debug)]
pub struct Identity {
    pub board: &'static str,
    pub caps: u32,
}

/// The session state. `S` is where settings and offsets persist.
#[derive(Debug)]
pub struct Device<S: Storage = NoStorage> {
    pub interp: Interpreter,
    /// O-word flow control between the line intake and the interpreter.
    flow: Flow,
    /// The line whose replay runs came framed (its answer is a frame).
    replay_framed: bool,
    port: FramedPort,
    ident: Identity,
    cmds: Deque<(u32, Command), CMD_SLOTS>,
    slots: Deque<(u32, LineText), LINE_SLOTS>,
    cadence: crate::link::reply::Cadence,
    check: bool,
    /// `$SLP`: outputs and drivers off, only a soft reset wakes it.
    sleep: bool,
    jogging: bool,
    jog_cancel: bool,
    /// Wait for motion to stop, then take the machine's position.
    sync: bool,
    probe_sync: bool,
    /// Alarm already reported (or expected and to be handled silently).
    seen_alarm: Option<MachineError>,
    quiet_alarm: bool,
    text_lines: u32,
    /// RepRap `N…*cs` numbering (`M110`, `Resend:`), text mode.
    numbers: reprap::LineNumbers,
    spindle_ov: u8,
    /// `$C` turned check mode off: a soft reset follows its `ok` (GRBL's).
    reset_due: bool,
    /// The port closed during a framed job; tell the next client.
    link_lost: LinkLost,
    /// Counters for tests and reports.
    pub stats: Stats,
    persist: Persist<S>,
    /// Writes (and an M501) waiting for the machine to be idle.
    pending: persist::Pending,
    /// What the boot's load found, told once after the banner.
    boot_report: Report,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LinkLost {
    No,
    /// Tell whoever sends the next message.
    Report,
}

/// What the device did, for tests and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    pub lines_ok: u32,
    pub lines_err: u32,
    pub commands: u32,
    pub resets: u32,
}

impl Device {
    /// A session without storage: settings and offsets live until reset.
    pub fn new(ident: Identity) -> Self {
        Device::with_storage(ident, Persist::new(NoStorage, Settings::default()), None)
    }
}

impl<S: Storage> Device<S> {
    /// The banner, as after power-up or a reset (text mode only).
    pub fn hello(&mut self, tx: &mut impl Tx) {
        let mut o = Out::new(tx, false);
        let _ = crate::link::reply::banner(&mut o);
        let report = core::mem::take(&mut self.boot_report);
        persist::tell(&report, &mut o);
    }

    /// The port was closed or reopened: the link is back in text mode.
    /// A framed session (our streamer) that loses its port mid-job is held
    /// (it reconnects, resends what was not acknowledged and resumes with
    /// cycle start); the next client is told so. A text session keeps
    /// running, as GRBL does when its sender goes away: those senders do
    /// not expect a hold they did not ask for. An O-word replay holds in
    /// either mode: it may have no end.
    ///
    /// The receive side (the USB interrupt, host-sim's port) has already
    /// reset its splitter; the controller then discards the old client's
    /// unread input up to the splitter's marker, so a new client never
    /// gets an `ok` for a line it did not send.
    pub fn port_reset(&mut self, link: &mut impl LinkPort, m: &impl MotionPort) {
        let busy = !m.motion_idle()
            || !self.cmds.is_empty()
            || !self.slots.is_empty()
            || self.flow.replaying();
        // The splitter is back in text mode already; the assembler switches
        // only at the marker, so it still tells what the old client spoke.
        // An O-word replay would go on with no one to stop it (a `while
        // [1]` never ends): it holds too, in either mode, and `~` resumes.
        if (link.framed() || link.events_framed()) && busy || self.flow.replaying() {
            m.rt().feed_hold();
            // The old client's unread input is discarded right after this
            // (the shell's pass flushes the link), so the next message is
            // the new client's.
            self.link_lost = LinkLost::Report;
        }
    }

    /// Free framed line slots (the credits).
    pub fn free_slots(&self) -> u16 {
        (LINE_SLOTS - self.slots.len()) as u16
    }

    /// `$SLP` put the machine to sleep (drivers, spindle, coolant off).
    pub fn sleeping(&self) -> bool {
        self.sleep
    }

    /// A line's commands wait for the machine to stop (a sync: `G10`,
    /// a `(debug,…)` reading the position, a probe): a stop now was
    /// commanded, not a starved planner.
    pub fn syncing(&self) -> bool {
        self.sync
    }

    /// True when nothing is queued in the device.
    pub fn drained(&self) -> bool {
        self.cmds.is_empty() && self.slots.is_empty() && !self.sync && !self.flow.replaying()
    }

    /// A line sent now runs as it is: no O-word block is being captured
    /// or refused, and no streamed `if` skips it (a `$` command there is
    /// part of the block, not run at once).
    pub fn lines_run_directly(&self) -> bool {
        self.flow.runs_directly()
    }

    fn info(&self, m: &impl MotionPort) -> DeviceInfo {
        let mut s = protocol::ShortText::new();
        let _ = s.push_str(crate::VERSION);
        let mut b = protocol::ShortText::new();
        let _ = b.push_str(self.ident.board);
        DeviceInfo {
            protocol: protocol::PROTOCOL_VERSION,
            firmware: s,
            board: b,
            axes: m.settings().report_axes,
            line_slots: LINE_SLOTS as u16,
            planner_blocks: m.planner_blocks(),
            rx_bytes: protocol::RX_WINDOW as u16,
            caps: self.ident.caps,
            next_seq: 0,
            credits: 0,
        }
    }

    /// One pass of the parse/plan task: realtime first, then alarms, then
    /// feeding the executor, then new input as far as there is room.
    pub fn poll(&mut self, link: &mut impl LinkPort, m: &mut impl MotionPort, tx: &mut impl Tx) {
        self.poll_realtime(link, m, tx);
        self.watch(m, &mut Out::new(tx, link.framed()));
        loop {
            self.feed(m, tx, link.framed());
            // Each event may write a burst (a `$$` listing): take the next
            // one only while the longest burst still fits.
            if tx.room() < TX_HEADROOM {
                break;
            }
            // The splitter runs ahead: when it is framed, a switch to frames
            // is on its way and whatever text precedes it has no listener.
            let framed = link.events_framed() || link.framed();
            if !(framed || self.can_take() && !self.flow.replaying()) {
                break;
            }
            // GRBL asleep reads nothing: lines wait for the reset, which
            // discards them.
            if self.sleep && !(link.events_framed() || link.framed()) {
                break;
            }
            let free = self.free_slots();
            let info = self.info(m);
            let Some(ev) = link.poll() else { break };
            let mut o = Out::new(
                tx,
                matches!(ev, LinkEvent::Frame(_) | LinkEvent::BadFrame(_)),
            );
            // The report goes to whoever sends the next message.
            match (self.link_lost, &ev) {
                (LinkLost::Report, LinkEvent::Mode(_)) | (LinkLost::No, _) => {}
                (LinkLost::Report, _) => {
                    self.link_lost = LinkLost::No;
                    let _ = crate::link::reply::msg(&mut o, "Link lost: feed hold, '~' resumes");
                }
            }
            self.event(ev, free, &info, m, &mut o);
        }
        let free = self.free_slots();
        let mut o = Out::new(tx, true);
        if link.framed() {
            self.port.refresh(free, &mut |msg| o.frame(msg));
        }
    }

    fn can_take(&self) -> bool {
        !self.sync && self.cmds.capacity() - self.cmds.len() >= self.interp.max_line_output()
    }

    /// Alarms and the end of jogs and syncs.
    fn watch(&mut self, m: &mut impl MotionPort, o: &mut Out<'_, impl Tx>) {
        self.faults(m, o);
        let alarm = m.alarm();
        // Until the executor has done a requested reset its alarm state is
        // stale (the reset's own alarm is already reported, once).
        if alarm != self.seen_alarm && !m.rt().reset_requested() {
            self.seen_alarm = alarm;
            if let Some(e) = alarm {
                self.cmds.clear();
                self.slots.clear();
                self.flow.reset(&mut self.interp);
                self.pending.cancel_queued();
                self.sync = true;
                if core::mem::take(&mut self.quiet_alarm) {
                    // Our own flush (jog cancel, reset in a hold): clear it.
                    let _ = self.cmds.push_back((0, Command::ClearAlarm));
                } else {
                    sys::report_alarm(e, o);
                }
            }
        }
        if let Some(ev) = m.take_tool_event() {
            self.tool_event(ev, o);
        }
        if self.jog_cancel && m.state() == executor::State::Hold && m.rt().stepper_idle() {
            self.jog_cancel = false;
            self.quiet_alarm = true;
            m.rt().request_reset();
        }
        if m.motion_idle() && self.cmds.is_empty() {
            if self.jogging {
                self.jogging = false;
                self.jog_cancel = false;
                self.sync = true;
            }
            // After a soft reset, wait until the executor has done it: a
            // line taken before would be flushed by it (acknowledged, then
            // lost, and an alarm for a reset "during motion").
            if self.sync && m.ready() && !m.rt().reset_requested() {
                self.flush_storage(m, o);
                self.sync = false;
                // Any alarm of our own flush has come and gone by now.
                self.quiet_alarm = false;
                // The probe result holds the trip point (for #5061..); the
                // machine stopped past it, after its deceleration.
                if let (true, Some((p, c))) = (self.probe_sync, m.probe_result()) {
                    self.interp.probe_finished(p, c);
                }
                self.interp.set_machine_position(m.commanded_position());
                self.probe_sync = false;
            }
        }
    }

    /// Queued commands to the executor; framed lines to the interpreter.
    /// `framed` is the port's mode for unprompted reports; lines from the
    /// slots are framed lines and are answered with frames.
    fn feed(&mut self, m: &mut impl MotionPort, tx: &mut impl Tx, framed: bool) {
        let mut budget = REPLAY_STEPS;
        loop {
            while m.may_plan() {
                let Some((line, cmd)) = self.cmds.pop_front() else {
                    break;
                };
                self.stats.commands += 1;
                if let Err(e) = m.submit(&cmd, line) {
                    self.refused(&cmd, line, e, m, &mut Out::new(&mut *tx, framed));
                }
            }
            if !self.can_take() {
                return;
            }
            if self.flow.replaying() {
                if budget == 0 {
                    return;
                }
                budget -= 1;
                self.replay_step(m, &mut Out::new(&mut *tx, self.replay_framed));
                continue;
            }
            let Some((seq, text)) = self.slots.pop_front() else {
                return;
            };
            self.job_line(&text, seq, m, &mut Out::new(&mut *tx, true));
        }
    }

    fn event(
        &mut self,
        ev: LinkEvent<'_>,
        free: u16,
        info: &DeviceInfo,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) {
        match ev {
            LinkEvent::Line(text) => {
                let text = match self.numbers.check(text) {
                    reprap::Numbered::Plain => text,
                    reprap::Numbered::Run(body) => body,
                    reprap::Numbered::Set => return self.reply_line(Ok(()), None, o),
                    reprap::Numbered::Resend { checksum } => {
                        self.stats.lines_err += 1;
                        return self.numbers.resend(checksum, o);
                    }
                    reprap::Numbered::OutOfRange => {
                        self.stats.lines_err += 1;
                        return reprap::out_of_range(o);
                    }
                };
                self.text_lines = self.text_lines.wrapping_add(1);
                // `Ln:` is the line's N word when it has one (GRBL's),
                // else the count of lines.
                let n = reprap::label(text).unwrap_or(self.text_lines);
                self.job_line(text, n, m, o);
            }
            LinkEvent::System(cmd) => {
                // Not in a branch not taken, nor stored in a block.
                if !self.flow.runs_directly() {
                    let n = self.text_lines;
                    if let Intake::Reply(r) = self.flow.intake(b"$", n, &mut self.interp) {
                        return self.reply_error_or_ok(r, o);
                    }
                }
                let r = self.system(cmd, m, o);
                sys::reply(r, None, o);
                self.reset_if_due(m, o);
            }
            LinkEvent::Error(code) => sys::reply(Err(code.code()), None, o),
            // Ends whatever text the host's decoder holds (the banner of a
            // port open) as a frame of its own: a framed client sees its
            // `Welcome` intact.
            LinkEvent::Mode(crate::link::LinkMode::Framed) => o.raw(&[0]),
            LinkEvent::Mode(_) => {}
            LinkEvent::BadFrame(e) => self.port.on_bad_frame(e, &mut |msg| o.frame(msg)),
            LinkEvent::Frame(msg) => self.frame(msg, free, info, m, o),
        }
    }

    fn frame(
        &mut self,
        msg: HostMsg,
        free: u16,
        info: &DeviceInfo,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) {
        let action = self.port.on_frame(msg, free, info, &mut |r| o.frame(r));
        match action {
            None | Some(FramedAction::Closed) => {}
            Some(FramedAction::Execute { seq, text }) => {
                // A slot was free: the session executes only with `free > 0`.
                let _ = self.slots.push_back((seq, text));
            }
            Some(FramedAction::Realtime(r)) => self.realtime(r, protocol::RX_WINDOW as u16, m, o),
            Some(FramedAction::GetSetting(n)) => match m.settings().get(n) {
                Some(value) => o.frame(&DeviceMsg::Setting { n, value }),
                None => sys::reply(Err(protocol::Code::InvalidStatement.code()), None, o),
            },
            Some(FramedAction::SetSetting { n, value }) => {
                let r = self.set_setting(n, value, m, o);
                match r {
                    Ok(()) => o.frame(&DeviceMsg::Setting { n, value }),
                    Err(c) => sys::reply(Err(c), None, o),
                }
            }
            Some(FramedAction::ListSettings) => {
                for n in crate::settings::table::numbers() {
                    if let Some(value) = m.settings().get(n) {
                        o.frame(&DeviceMsg::Setting { n, value });
                    }
                }
                o.frame(&DeviceMsg::SettingsEnd);
            }
        }
    }

    /// `$n=`: only while idle (GRBL's rule), and persisted at once.
    fn set_setting(
        &mut self,
        n: u16,
        value: f32,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) -> Result<(), u16> {
        if !m.motion_idle() {
            return Err(protocol::Code::NotIdle.code());
        }
        if self.interp.outputs_on() {
            return Err(protocol::Code::OutputsOn.code());
        }
        m.set_setting(n, value).map_err(|e| e.code().code())?;
        self.save_settings(m, o);
        Ok(())
    }
}
