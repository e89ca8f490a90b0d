//! Task side of the link: turns ring tokens into lines, `$` commands and
//! frames. Runs in the parse/plan task, so it may take its time; it only
//! pulls the next token when the caller asks for the next event, which is
//! how a full job queue pushes back on the sender (the ring, then USB, fill).

use super::rt::RtFlags;
use super::syscmd::{self, SysCmd};
use super::{LinkMode, TokenSource, TOKEN_OVERFLOW, TOKEN_RESET, TOKEN_TEXT_MODE};
use protocol::{Code, FrameDecoder, FrameError, HostMsg, MAX_LINE};

/// One thing that arrived. Text-mode variants borrow the assembler's line
/// buffer until the next call. Frames are carried inline (no heap).
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum LinkEvent<'a> {
    /// A G-code line in text mode (without terminator; may be empty). Reply
    /// `ok` or `error:N` once it was handled: that keeps send-response
    /// senders in step.
    Line(&'a [u8]),
    /// A `$` command in text mode.
    System(SysCmd<'a>),
    /// A text line that was discarded; reply `error:N` with this code.
    Error(Code),
    /// A message in framed mode. Realtime frames normally never get here
    /// (the splitter acts on them); if one does, act on it the same way.
    Frame(HostMsg),
    /// A frame that could not be read; reply with `Session::on_bad_frame`.
    BadFrame(FrameError),
    /// The link changed mode (0x00 in text mode, `Bye`, or a port reset).
    Mode(LinkMode),
}

/// What one token produced, before borrowing the line buffer.
#[allow(clippy::large_enum_variant)]
enum Step {
    Nothing,
    LineDone,
    Owned(LinkEvent<'static>),
}

/// Reassembles lines and frames from tokens, with fixed buffers only.
#[derive(Clone, Debug)]
pub struct LineAssembler {
    mode: LinkMode,
    line: [u8; MAX_LINE],
    len: usize,
    /// The current line is being discarded, and why.
    discard: Option<Code>,
    /// Last terminator was `\r`: a `\n` right after it ends nothing.
    after_cr: bool,
    frames: FrameDecoder,
    /// Soft-reset markers taken from the ring (compare `RtFlags::reset_marks`).
    marks_seen: u32,
    /// Markers up to which input is void: everything before the marker of
    /// the last reset the task acted on is discarded, also what is still
    /// on its way (held back by a full ring) when the task acts.
    flush_to: u32,
}

impl Default for LineAssembler {
    fn default() -> Self {
        Self::new()
    }
}

impl LineAssembler {
    pub const fn new() -> Self {
        LineAssembler {
            mode: LinkMode::Text,
            line: [0; MAX_LINE],
            len: 0,
            discard: None,
            after_cr: false,
            frames: FrameDecoder::new(),
            marks_seen: 0,
            flush_to: 0,
        }
    }

    /// Call after taking [`protocol::Rt::SoftReset`]: discards everything
    /// received before the reset (up to its marker in the ring), keeping
    /// mode switches in step, and forgets any partial line or frame.
    pub fn flush_reset(&mut self, rx: &mut impl TokenSource, flags: &RtFlags) {
        self.flush_to = flags.reset_marks();
        self.discard(rx);
        // Only once the marker is reached: a frame cut off by an empty ring
        // (the rest still in the backlog) must still be decoded to its end,
        // or a `Bye` in it is missed and the modes part (the splitter back
        // in text, this side still framed). `poll` clears when it gets there.
        if !self.flushing() {
            self.clear_partial();
        }
    }

    /// Markers of resets already acted on are still to come.
    fn flushing(&self) -> bool {
        (self.flush_to.wrapping_sub(self.marks_seen) as i32) > 0
    }

    /// Drop tokens up to the marker of the last reset acted on (if it is
    /// not in the ring yet, [`Self::poll`] goes on dropping until it is).
    fn discard(&mut self, rx: &mut impl TokenSource) {
        while self.flushing() {
            let Some(t) = rx.pop() else { break };
            // Run the state machine so 0x00 / `Bye` still switch modes,
            // but drop what it produces.
            if let Step::LineDone = self.token(t) {
                self.len = 0;
            }
        }
    }

    fn clear_partial(&mut self) {
        self.len = 0;
        self.discard = None;
        self.after_cr = false;
        self.frames.reset();
    }

    pub fn mode(&self) -> LinkMode {
        self.mode
    }

    /// Bytes of a partial text line held here (they count as received but
    /// unprocessed, like the ring's).
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Pull tokens until something happens; `None` when the ring is empty.
    pub fn poll(&mut self, rx: &mut impl TokenSource) -> Option<LinkEvent<'_>> {
        if self.flushing() {
            self.discard(rx);
            if self.flushing() {
                return None;
            }
            self.clear_partial();
        }
        loop {
            let t = rx.pop()?;
            match self.token(t) {
                Step::Nothing => continue,
                Step::Owned(ev) => return Some(ev),
                Step::LineDone => break,
            }
        }
        let len = core::mem::take(&mut self.len);
        let line = self.line.get(..len).unwrap_or(&[]);
        Some(match syscmd::parse(line) {
            None => LinkEvent::Line(line),
            Some(Ok(cmd)) => LinkEvent::System(cmd),
            Some(Err(code)) => LinkEvent::Error(code),
        })
    }

    fn token(&mut self, t: u16) -> Step {
        match t {
            TOKEN_TEXT_MODE => self.switch(LinkMode::Text),
            TOKEN_RESET => {
                self.marks_seen = self.marks_seen.wrapping_add(1);
                self.clear_partial();
                Step::Nothing
            }
            TOKEN_OVERFLOW => {
                if self.mode == LinkMode::Text {
                    self.discard = Some(Code::RxOverflow);
                }
                // In framed mode the damaged frame fails its CRC.
                Step::Nothing
            }
            _ => {
                let b = t as u8;
                match self.mode {
                    LinkMode::Text => self.text(b),
                    LinkMode::Framed => self.framed(b),
                }
            }
        }
    }

    fn switch(&mut self, mode: LinkMode) -> Step {
        self.mode = mode;
        self.clear_partial();
        Step::Owned(LinkEvent::Mode(mode))
    }

    fn text(&mut self, b: u8) -> Step {
        let after_cr = core::mem::replace(&mut self.after_cr, b == b'\r');
        match b {
            0 => self.switch(LinkMode::Framed),
            b'\n' if after_cr => Step::Nothing,
            b'\n' | b'\r' => match self.discard.take() {
                Some(code) => {
                    self.len = 0;
                    Step::Owned(LinkEvent::Error(code))
                }
                None => Step::LineDone,
            },
            _ if self.discard.is_some() => Step::Nothing,
            _ => {
                match self.line.get_mut(self.len) {
                    Some(slot) => {
                        *slot = b;
                        self.len += 1;
                    }
                    // Never truncate and execute: drop the whole line.
                    None => self.discard = Some(Code::LineOverflow),
                }
                Step::Nothing
            }
        }
    }

    fn framed(&mut self, b: u8) -> Step {
        match self.frames.push::<HostMsg>(b) {
            None => Step::Nothing,
            Some(Ok(HostMsg::Bye)) => {
                self.switch(LinkMode::Text);
                Step::Owned(LinkEvent::Frame(HostMsg::Bye))
            }
            Some(Ok(msg)) => Step::Owned(LinkEvent::Frame(msg)),
            Some(Err(e)) => Step::Owned(LinkEvent::BadFrame(e)),
        }
    }
}
