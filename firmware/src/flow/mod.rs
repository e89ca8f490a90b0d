//! O-word subroutines and flow control for streamed programs, between the
//! session's line intake and the interpreter.
//!
//! A sender streams a program line by line and never sends it twice, so a
//! loop's or a subroutine's body must be kept to run again. The stage
//! keeps it in one fixed buffer ([`CAPTURE_BYTES`], compacted lines with
//! their source line numbers; `arena.rs`):
//!
//! * `sub` … `endsub`: the body is stored as it arrives; nothing runs. Each
//!   line is acknowledged when stored. The subroutine stays defined until
//!   a reset; defining it again replaces it; when a new block needs the
//!   room, the least recently used subroutine is dropped (a later `call`
//!   of it is then refused, never half run).
//! * `while`/`do`/`repeat`: the whole block is captured first, each line
//!   acknowledged when stored, then replayed from the buffer. Its closing
//!   line is answered when the replay has been interpreted (as any line is
//!   answered once its commands are queued), with the first error inside
//!   the replay if there is one. A block that does not fit is refused
//!   before any line of it runs: its lines up to its closer are answered
//!   with an error and never run.
//! * `call`: replays the subroutine's body with fresh locals (`#1`-`#30`
//!   from the arguments, names without `_` start undefined); `return` or
//!   `endsub` with a value set `#<_value>` (and `#<_value_returned>`).
//!   The caller's locals wait in the same buffer, from its top down.
//! * `if`/`elseif`/`else`/`endif` outside a captured block are decided as
//!   the lines arrive, without the buffer: a line in a branch not taken
//!   is acknowledged and never run, in check mode too.
//!
//! Conditions and arguments are evaluated when the line is reached, with
//! the interpreter's parameters as the lines before left them (as
//! LinuxCNC's read-ahead does). Replay runs no faster than the command
//! queue drains: the session asks for one [`Step`] at a time.
//!
//! LinuxCNC's O-codes are the reference (ideas only). Differences: the
//! bounded buffer and depths above; `continue` in a `do` loop tests the
//! condition (C's meaning).

mod arena;
mod drive;
mod intake;
pub mod oline;
mod replay;
#[cfg(test)]
mod tests;

pub use arena::CAPTURE_BYTES;
pub use drive::RunLine;

use crate::gcode::{ErrorKind, GcodeError, Name, OWord};
use crate::interp::Interpreter;
use arena::Arena;
use oline::{Kw, OLine};

/// Subroutines held at once.
pub const MAX_SUBS: usize = 16;
/// Loops and calls open at once in a replay.
pub const MAX_FRAMES: usize = 16;
/// Calls nested at once (LinuxCNC allows 10 as well).
pub const MAX_CALLS: usize = 10;
/// Streamed `if` blocks open at once.
pub const MAX_IFS: usize = 8;
/// Most arguments of a call: `#1`-`#30`.
pub const MAX_ARGS: usize = 30;

/// No position: the replay of a top-level `call` ends when it returns.
const END: u16 = u16::MAX;

fn err(k: OWord) -> GcodeError {
    GcodeError::new(ErrorKind::OWord(k), 1)
}

#[derive(Clone, Copy, Debug)]
struct Sub {
    /// The `sub` line's record; the body follows it.
    start: u16,
    /// Past the `endsub` line's record.
    end: u16,
    used: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum IfState {
    /// The branch being streamed runs.
    Taking,
    /// No branch taken yet: skip to the next `elseif`/`else`.
    Seeking,
    /// A branch ran: skip to `endif`.
    Done,
}

#[derive(Clone, Copy, Debug)]
struct OpenIf {
    name: Name,
    state: IfState,
}

#[derive(Clone, Copy, Debug)]
enum Mode {
    Normal,
    /// Storing a block from its opener's record at `start`.
    Capture {
        start: u16,
    },
    /// Every line up to `name`'s `until` is refused.
    Refuse {
        name: Name,
        until: Kw,
    },
    /// Running stored lines: `pc` next, `end` the current body's end;
    /// `n` is the line that started it (answered when it ends).
    Replay {
        pc: u16,
        end: u16,
        free_from: Option<u16>,
        n: u32,
    },
}

#[derive(Clone, Copy, Debug)]
enum Frame {
    /// A loop whose opener's record is at `start`; `left` passes of a
    /// `repeat`.
    Loop { start: u16, kw: Kw, left: u32 },
    /// A call: where to go on return and the caller's body end; `low` is
    /// where the caller's saved locals end.
    Call { ret: u16, ret_end: u16, low: u16 },
}

/// What the session does with a line it received.
#[derive(Debug, PartialEq)]
pub enum Intake {
    /// Not a flow line: interpret and answer it as usual.
    Run,
    /// Handled here (stored, skipped or refused): answer with this.
    Reply(Result<(), GcodeError>),
    /// A replay starts; answer this line when [`Step::Done`] comes.
    Replay,
}

/// One step of a replay.
#[derive(Debug, PartialEq)]
pub enum Step {
    /// No replay running.
    Idle,
    /// An O-word line was handled; ask again.
    Busy,
    /// Interpret the `len` bytes written to the buffer; `n` is the source
    /// line (for `Ln:` and messages).
    Run { n: u32, len: usize },
    /// The replay ended: answer line `n` (the one that started it) with
    /// `result`; an error names the source line it came from.
    Done {
        n: u32,
        result: Result<(), (u32, GcodeError)>,
    },
}

/// The flow-control stage's state: the buffer, the subroutines, the open
/// streamed `if`s and a replay's loops and calls.
#[derive(Clone, Debug)]
pub struct Flow {
    arena: Arena,
    subs: heapless::Vec<Sub, MAX_SUBS>,
    ifs: heapless::Vec<OpenIf, MAX_IFS>,
    frames: heapless::Vec<Frame, MAX_FRAMES>,
    mode: Mode,
    clock: u32,
}

impl Default for Flow {
    fn default() -> Self {
        Self::new()
    }
}

fn closer(opener: Kw) -> Kw {
    match opener {
        Kw::Sub => Kw::EndSub,
        Kw::Do => Kw::While,
        Kw::Repeat => Kw::EndRepeat,
        Kw::If => Kw::EndIf,
        _ => Kw::EndWhile,
    }
}

impl Flow {
    pub const fn new() -> Self {
        Flow {
            arena: Arena::new(),
            subs: heapless::Vec::new(),
            ifs: heapless::Vec::new(),
            frames: heapless::Vec::new(),
            mode: Mode::Normal,
            clock: 0,
        }
    }

    /// A replay is running: the session takes no new lines until it ends.
    pub fn replaying(&self) -> bool {
        matches!(self.mode, Mode::Replay { .. })
    }

    /// Nothing open: no capture, refusal, replay or streamed `if`.
    pub fn idle(&self) -> bool {
        matches!(self.mode, Mode::Normal) && self.ifs.is_empty()
    }

    /// A line given now would run as it is (no capture, refusal, replay,
    /// or streamed `if` skipping).
    pub fn runs_directly(&self) -> bool {
        matches!(self.mode, Mode::Normal) && self.ifs.iter().all(|i| i.state == IfState::Taking)
    }

    /// Bytes of the buffer in use (subroutines, a capture, saved locals).
    pub fn used(&self) -> usize {
        CAPTURE_BYTES - self.arena.free()
    }

    /// A reset: the caller's locals come back, everything else is
    /// forgotten (subroutines, captures, open blocks).
    pub fn reset(&mut self, interp: &mut Interpreter) {
        self.unwind(interp);
        // In place: a new `Flow` would be a 2.6 KB temporary on the stack.
        self.arena.top = 0;
        self.arena.low = CAPTURE_BYTES as u16;
        self.subs.clear();
        self.ifs.clear();
        self.frames.clear();
        self.mode = Mode::Normal;
        self.clock = 0;
    }

    /// The O-word line stored at `at`, if that record is one.
    fn oline_at(&self, at: u16) -> Option<OLine> {
        let (_, text, _) = self.arena.line(at)?;
        oline::parse(text)?.ok()
    }

    /// The condition of an `if`/`elseif`/`while`: one value, non-zero true.
    fn cond(&self, ol: &OLine, text: &[u8], interp: &mut Interpreter) -> Result<bool, GcodeError> {
        Ok(value(ol, text, interp)?.ok_or(err(OWord::Syntax))? != 0.0)
    }

    fn set_pc(&mut self, new: u16) {
        if let Mode::Replay { pc, .. } = &mut self.mode {
            *pc = new;
        }
    }
}

/// The optional single argument after the keyword, then the line's end.
fn value(ol: &OLine, text: &[u8], interp: &mut Interpreter) -> Result<Option<f32>, GcodeError> {
    if !oline::has_arg(text, ol.args) {
        oline::end(text, ol.args)?;
        return Ok(None);
    }
    let (v, after) = interp.eval_at(text, ol.args)?;
    oline::end(text, after)?;
    Ok(Some(v))
}
