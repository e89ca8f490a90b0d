//! The streaming loop: lines out as credits allow, replies and status in,
//! keys acted on, pauses explained, time left kept.

use super::eta::Eta;
use super::job::Job;
use super::pause::{alarm_text, is_pause, wpos_text, Reason};
use super::term::Ui;
use super::Outcome;
use anyhow::{bail, Result};
use protocol::client::{Client, ClientError, ClientEvent};
use protocol::{DeviceMsg, MachineState, Rt, Status};
use std::collections::HashMap;
use std::io::{Read, Write};
use std::time::{Duration, Instant};

/// A question waiting for its key.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Ask {
    Reset,
    Interrupt,
}

/// A status query unanswered this long is taken as lost.
const STATUS_LOST: Duration = Duration::from_millis(200);

/// What one streaming run saw.
pub struct Stream<'a, T> {
    pub client: Client<T>,
    pub job: &'a Job,
    pub ui: &'a Ui,
    pub eta: Option<Eta>,
    pub resume_pauses: bool,
    pub check: bool,
    pub status_every: Duration,
    /// file line -> errors: (line, code, text).
    pub errors: Vec<(usize, u16, String)>,
    pub alarms: Vec<(usize, u16)>,
    pub sent: usize,
    pub last: Option<Status>,
    /// Wall seconds paused, and the ETA samples (active s, shown s).
    pub paused_s: f64,
    pub samples: Vec<(f64, f64)>,
    pub started: Option<Instant>,
    pub(super) seq_line: HashMap<u32, usize>,
    pub(super) msg_part: String,
    pub(super) error_text: Option<String>,
    /// A board message not yet shown: it may be the next error's text.
    pub(super) held_msg: Option<String>,
    pub(super) alarm_wants_text: Option<(usize, u16)>,
    pub(super) last_msg: Option<(usize, String)>,
    pub(super) next_msg: usize,
    pub(super) next_pause: usize,
    pub(super) pause: Option<(Reason, Instant)>,
    pub(super) we_held: bool,
    pub(super) ask: Option<Ask>,
    pub(super) line_now: usize,
}

impl<'a, T: Read + Write> Stream<'a, T> {
    pub fn new(client: Client<T>, job: &'a Job, ui: &'a Ui, eta: Option<Eta>) -> Self {
        Stream {
            client,
            job,
            ui,
            eta,
            resume_pauses: false,
            check: false,
            status_every: Duration::from_millis(50),
            errors: Vec::new(),
            alarms: Vec::new(),
            sent: 0,
            last: None,
            paused_s: 0.0,
            samples: Vec::new(),
            started: None,
            seq_line: HashMap::new(),
            msg_part: String::new(),
            error_text: None,
            held_msg: None,
            alarm_wants_text: None,
            last_msg: None,
            next_msg: 0,
            next_pause: 0,
            pause: None,
            we_held: false,
            ask: None,
            line_now: 0,
        }
    }

    /// Wall seconds since the first line went out, pauses left out.
    pub fn active_s(&self) -> f64 {
        let Some(t0) = self.started else { return 0.0 };
        let paused_now = self
            .pause
            .as_ref()
            .map_or(0.0, |p| p.1.elapsed().as_secs_f64());
        t0.elapsed().as_secs_f64() - self.paused_s - paused_now
    }

    pub fn run(&mut self) -> Result<Outcome> {
        let lines = &self.job.lines;
        let check_seq = if self.check {
            Some(super::board::send_wait(&mut self.client, b"$C")?)
        } else {
            None
        };
        let mut last_poll = Instant::now();
        let mut asked: Option<Instant> = None;
        let mut done_sent = false;
        self.started = Some(Instant::now());
        loop {
            if let Some(k) = self.ui.key() {
                if let Some(end) = self.on_key(k)? {
                    return Ok(end);
                }
            }
            while self.sent < lines.len() && self.client.can_send() {
                let seq = match self.client.send_line(lines[self.sent].as_bytes()) {
                    Ok(s) => s,
                    Err(ClientError::LineTooLong) => {
                        let text = format!("line longer than {} bytes", protocol::MAX_LINE);
                        self.error(self.sent + 1, 0, text);
                        self.client.send_line(b"")?
                    }
                    Err(e) => return Err(e.into()),
                };
                self.seq_line.insert(seq, self.sent + 1);
                self.sent += 1;
            }
            if self.check && !done_sent && self.sent == lines.len() && self.client.in_flight() == 0
            {
                // `$C` again leaves check mode; its "Disabled" comes after
                // every line's errors.
                self.client.send_line(b"$C")?;
                done_sent = true;
            }
            // One status query in flight at a time (a lost reply is asked
            // again), so a short interval never floods the link.
            let answered = asked.is_none_or(|t| t.elapsed() >= STATUS_LOST);
            if answered && last_poll.elapsed() >= self.status_every {
                last_poll = Instant::now();
                asked = Some(last_poll);
                self.client.realtime(Rt::StatusQuery)?;
            }
            let ev = match self.client.poll() {
                Ok(Some(ev)) => ev,
                Ok(None) => continue,
                Err(e) => bail!("{e}"),
            };
            let ClientEvent::Device(msg) = ev else {
                continue;
            };
            // A board message right before an error is that error's text;
            // before anything else it is for the operator.
            if let Some(text) = self.held_msg.take() {
                match msg {
                    DeviceMsg::Error { .. } => self.error_text = Some(text),
                    _ => self.board_message(text),
                }
            }
            match msg {
                DeviceMsg::Msg(m) => {
                    if let Some(end) = self.on_msg(&m, check_seq.is_some() && done_sent) {
                        return Ok(end);
                    }
                }
                DeviceMsg::Error { seq, code, .. } => {
                    let line = seq
                        .and_then(|s| self.seq_line.get(&s))
                        .copied()
                        .unwrap_or(0);
                    self.flush_messages(line.saturating_sub(1));
                    let text = self.error_text.take().unwrap_or_else(|| {
                        protocol::Code::from_code(code)
                            .map_or("device error", |c| c.message())
                            .to_string()
                    });
                    self.error(line, code, text);
                }
                DeviceMsg::Alarm { code } => {
                    self.alarms.push((self.line_now, code));
                    self.alarm_wants_text = Some((self.line_now, code));
                }
                DeviceMsg::Status(st) => {
                    asked = None;
                    if let Some(end) = self.on_status(st)? {
                        return Ok(end);
                    }
                }
                _ => {}
            }
        }
    }

    fn error(&mut self, line: usize, code: u16, text: String) {
        self.ui
            .say(format!("{}: error[{code}]: {text}", self.job.at(line)));
        self.errors.push((line, code, text));
    }

    /// One `Msg` frame; a full frame continues in the next.
    fn on_msg(&mut self, m: &str, leaving_check: bool) -> Option<Outcome> {
        self.msg_part.push_str(m);
        if m.len() == protocol::msg::MsgText::new().capacity() {
            return None;
        }
        let whole = std::mem::take(&mut self.msg_part);
        let text = whole
            .trim()
            .trim_start_matches("[MSG:")
            .trim_end_matches(']')
            .trim()
            .to_string();
        if let Some((mut line, code)) = self.alarm_wants_text.take() {
            // The line that was running when it stopped (a report in Alarm
            // still names it).
            if let Ok(Some(st)) = super::board::query_status(&mut self.client) {
                if let Some(&l) = st.line.and_then(|s| self.seq_line.get(&s)) {
                    line = l;
                    if let Some(a) = self.alarms.last_mut() {
                        a.0 = l;
                    }
                }
                self.last = Some(st);
            }
            let what = alarm_text(code);
            self.ui.say(format!(
                "{}: alarm[{code}]: {text}: {what}",
                self.job.at(line)
            ));
            return Some(Outcome::Alarm);
        }
        if let Some(rest) = text.strip_prefix("line ") {
            // A late error's text; its `Error` frame follows.
            if let Some((_, e)) = rest.split_once(": error ") {
                let e = e.split_once(": ").map_or(e, |(_, t)| t);
                self.error_text = Some(e.to_string());
                return None;
            }
        }
        if text == "Enabled" || text == "Disabled" {
            return (leaving_check && text == "Disabled").then_some(Outcome::Done);
        }
        self.held_msg = Some(text);
        None
    }

    /// A message from the board for the operator: the board's copy of a
    /// `(MSG,…)` in the file is shown with that file line.
    fn board_message(&mut self, text: String) {
        let same = |t: &String| t.starts_with(text.as_str()) || text.starts_with(t.as_str());
        let job = self.job;
        let ahead = &job.messages[self.next_msg.min(job.messages.len())..];
        if let Some(i) = ahead.iter().position(|(_, t)| same(t)) {
            self.flush_messages(ahead[i].0);
            return;
        }
        if job.messages[..self.next_msg].iter().any(|(_, t)| same(t)) {
            return;
        }
        self.ui
            .say(format!("{}: message: {text}", self.job.at(self.line_now)));
        self.last_msg = Some((self.line_now, text));
    }

    /// The job's own messages up to file line `upto`: the board runs lines
    /// in order, so once it moves for a line (or pauses at one) the
    /// messages before it have been executed.
    fn flush_messages(&mut self, upto: usize) {
        let job = self.job;
        while let Some((line, text)) = job.messages.get(self.next_msg) {
            if *line > upto {
                break;
            }
            self.ui
                .say(format!("{}: message: {text}", self.job.at(*line)));
            self.last_msg = Some((*line, text.clone()));
            self.next_msg += 1;
        }
    }

    fn on_status(&mut self, st: Status) -> Result<Option<Outcome>> {
        if let Some(seq) = st.line {
            if let Some(&l) = self.seq_line.get(&seq) {
                self.line_now = l;
                self.ui.bar.set_position(l as u64);
                self.flush_messages(l);
            }
        }
        self.ui.bar.set_message(format!(
            "{:<5} {} F{:.0} {}%",
            st.state.name(),
            wpos_text(&st),
            st.feed,
            st.overrides.feed
        ));
        self.last = Some(st);
        if st.state == MachineState::Alarm {
            // An alarm whose text never came, or none announced at all.
            let (line, code) = self.alarm_wants_text.take().unwrap_or((self.line_now, 0));
            if self.alarms.is_empty() || code != 0 {
                if self.alarms.is_empty() {
                    self.alarms.push((line, code));
                }
                let at = self.job.at(line);
                self.ui
                    .say(format!("{at}: alarm[{code}]: {}", alarm_text(code)));
            }
            return Ok(Some(Outcome::Alarm));
        }
        let paused = is_pause(&st);
        match (&self.pause, paused) {
            (None, true) => self.enter_pause(&st)?,
            (Some((_, since)), false) => {
                self.paused_s += since.elapsed().as_secs_f64();
                self.pause = None;
                self.we_held = false;
                self.ui
                    .say(format!("{}: running again", self.job.at(self.line_now)));
            }
            _ => {}
        }
        let active = self.active_s();
        if let Some(eta) = &mut self.eta {
            if !paused {
                let running = st.state == MachineState::Run;
                let line = if running { self.line_now } else { 0 };
                eta.observe(active, line, &st.mpos);
            }
            match eta.remaining(active) {
                Some(left) => {
                    if !paused {
                        self.samples.push((active, left));
                    }
                    let tag = if paused { " (paused)" } else { "" };
                    self.ui.bar.set_prefix(format!("ETA {}{tag}", clock(left)));
                }
                None => self
                    .ui
                    .bar
                    .set_prefix(format!("sim {}", clock(eta.simulated_s()))),
            }
        }
        let all_in = self.sent == self.job.lines.len() && self.client.in_flight() == 0;
        if !self.check && all_in && st.state == MachineState::Idle {
            self.flush_messages(usize::MAX);
            return Ok(Some(Outcome::Done));
        }
        Ok(None)
    }

    fn enter_pause(&mut self, st: &Status) -> Result<()> {
        // Program pauses already passed (the running line is beyond them)
        // are not this one.
        let pauses = &self.job.pauses;
        while self.next_pause < pauses.len() && pauses[self.next_pause].line < self.line_now {
            self.next_pause += 1;
        }
        let program = pauses
            .get(self.next_pause)
            .filter(|p| p.line <= self.sent)
            .map(|p| (p.line, p.kind));
        let reason = Reason::from_status(st, program, self.we_held);
        let at = match reason {
            Reason::Program { line, .. } if line > 0 => {
                self.next_pause += 1;
                line
            }
            _ => self.line_now,
        };
        self.flush_messages(at);
        let last = self.last_msg.as_ref().map(|(_, m)| m.as_str());
        let mut text = format!(
            "{}: paused: {} at {}",
            self.job.at(at),
            reason.describe(last),
            wpos_text(st)
        );
        if let Some((l, m)) = &self.last_msg {
            text += &format!("\n  last message ({}): {m}", self.job.at(*l));
        }
        if self.ui.interactive() {
            text +=
                "\n  Enter, space or ~ continues; x resets (aborts the job); Ctrl-C for the menu";
        } else if self.resume_pauses {
            text += "\n  continuing (--resume-pauses)";
            self.client.realtime(Rt::CycleStart)?;
        } else {
            text +=
                "\n  waiting for cycle start (the board's start input, or ~ from another sender)";
        }
        self.ui.say(text);
        self.pause = Some((reason, Instant::now()));
        Ok(())
    }
}

/// `1:02:03`, `2:03` or `4.2 s`.
pub fn clock(s: f64) -> String {
    let t = s.max(0.0).round() as u64;
    match t {
        0..60 => format!("{:.1} s", s.max(0.0)),
        60..3600 => format!("{}:{:02}", t / 60, t % 60),
        _ => format!("{}:{:02}:{:02}", t / 3600, t / 60 % 60, t % 60),
    }
}
