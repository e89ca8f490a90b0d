//! A line from the sender: run it, store it in the block being captured,
//! skip it in a branch not taken, or refuse it.

use super::oline::{self, Kw, OLine};
use super::{arena, closer, err, Flow, IfState, Intake, Mode, OpenIf, Sub, CAPTURE_BYTES, END};
use crate::gcode::{ErrorKind, GcodeError, Name, OWord};
use crate::interp::Interpreter;

impl Flow {
    /// One line from the sender. `n` is its line number (text count or
    /// sequence number).
    pub fn intake(&mut self, text: &[u8], n: u32, interp: &mut Interpreter) -> Intake {
        // After a program's closing `%` nothing runs: the interpreter skips
        // every line up to the next `%`, O-word lines included.
        if matches!(self.mode, Mode::Normal) && interp.state().percent == 2 {
            return Intake::Run;
        }
        let o = oline::parse(text);
        match self.mode {
            Mode::Replay { .. } => return Intake::Reply(Err(err(OWord::Unmatched))),
            Mode::Refuse { name, until } => {
                if let Some(Ok(ol)) = &o {
                    if ol.name == name && ol.kw == until {
                        self.mode = Mode::Normal;
                    }
                }
                return Intake::Reply(Err(err(OWord::InRefusedBlock)));
            }
            Mode::Capture { start } => return self.capture(text, n, o, start),
            Mode::Normal => {}
        }
        if let Some(top) = self.ifs.last().copied() {
            if top.state != IfState::Taking {
                return Intake::Reply(self.skipping(top, o, text, interp));
            }
        }
        let ol = match o {
            None => return Intake::Run,
            Some(Err(e)) => return Intake::Reply(Err(e)),
            Some(Ok(ol)) => ol,
        };
        let r = match ol.kw {
            Kw::If => {
                let r = self.cond(&ol, text, interp).and_then(|c| {
                    let state = if c { IfState::Taking } else { IfState::Seeking };
                    self.ifs
                        .push(OpenIf {
                            name: ol.name,
                            state,
                        })
                        .map_err(|_| err(OWord::TooDeep))
                });
                if r.is_err() {
                    // Its lines must not run as if it were not there.
                    self.mode = Mode::Refuse {
                        name: ol.name,
                        until: Kw::EndIf,
                    };
                }
                r
            }
            Kw::ElseIf | Kw::Else | Kw::EndIf => match self.ifs.last_mut() {
                Some(top) if top.name == ol.name => {
                    if ol.kw == Kw::EndIf {
                        self.ifs.pop();
                    } else {
                        top.state = IfState::Done;
                    }
                    Ok(())
                }
                _ => Err(err(OWord::Unmatched)),
            },
            Kw::Sub | Kw::While | Kw::Do | Kw::Repeat => {
                if ol.kw == Kw::Sub {
                    self.forget_sub(&ol.name);
                }
                let start = self.arena.top;
                self.mode = Mode::Capture { start };
                return self.capture(text, n, Some(Ok(ol)), start);
            }
            Kw::Call => {
                self.mode = Mode::Replay {
                    pc: END,
                    end: END,
                    free_from: None,
                    n,
                };
                match self.control(&ol, text, END, END, interp) {
                    Ok(pc) => {
                        self.set_pc(pc);
                        return Intake::Replay;
                    }
                    Err(e) => {
                        self.unwind(interp);
                        self.mode = Mode::Normal;
                        Err(e)
                    }
                }
            }
            _ => Err(err(OWord::Outside)),
        };
        Intake::Reply(r)
    }

    /// A line while the innermost streamed `if` skips.
    fn skipping(
        &mut self,
        top: OpenIf,
        o: Option<Result<OLine, GcodeError>>,
        text: &[u8],
        interp: &mut Interpreter,
    ) -> Result<(), GcodeError> {
        let Some(Ok(ol)) = o else { return Ok(()) };
        if ol.name != top.name {
            return Ok(());
        }
        let state = match (ol.kw, top.state) {
            (Kw::EndIf, _) => {
                self.ifs.pop();
                return oline::end(text, ol.args);
            }
            (Kw::Else, IfState::Seeking) => IfState::Taking,
            (Kw::ElseIf, IfState::Seeking) => match self.cond(&ol, text, interp) {
                Ok(true) => IfState::Taking,
                Ok(false) => IfState::Seeking,
                Err(e) => {
                    self.ifs.pop();
                    self.mode = Mode::Refuse {
                        name: ol.name,
                        until: Kw::EndIf,
                    };
                    return Err(e);
                }
            },
            _ => return Ok(()),
        };
        if let Some(t) = self.ifs.last_mut() {
            t.state = state;
        }
        Ok(())
    }

    /// A line while a block is captured from `start`.
    fn capture(
        &mut self,
        text: &[u8],
        n: u32,
        o: Option<Result<OLine, GcodeError>>,
        start: u16,
    ) -> Intake {
        let Some(opener) = self.oline_at(start).or(match &o {
            Some(Ok(ol)) => Some(*ol),
            _ => None,
        }) else {
            return Intake::Reply(Err(err(OWord::Syntax)));
        };
        let until = closer(opener.kw);
        let is_opener = self.arena.top == start;
        let ends =
            matches!(&o, Some(Ok(ol)) if !is_opener && ol.name == opener.name && ol.kw == until);
        let dollar = text.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'$');
        let bad = match &o {
            Some(Err(e)) => Some(*e),
            // A `$` command is no G-code to replay.
            None if dollar => Some(GcodeError::new(ErrorKind::ExpectedLetter(b'$'), 1)),
            Some(Ok(ol)) if ol.kw == Kw::Sub && !is_opener => Some(err(OWord::NestedSub)),
            _ => None,
        };
        let mut line = [0u8; crate::gcode::MAX_LINE];
        let len = oline::compact(text, &mut line);
        let stored = bad.is_none()
            && (len == 0 && !is_opener || self.store(n, line.get(..len).unwrap_or(&[])));
        // Evicting a subroutine moves the capture down.
        let start = match self.mode {
            Mode::Capture { start } => start,
            _ => start,
        };
        if !stored {
            // Whatever was stored goes; its closer ends the refusal.
            self.arena.cut(start, self.arena.top);
            let e = bad.unwrap_or(err(OWord::TooLarge));
            self.mode = if ends {
                Mode::Normal
            } else {
                Mode::Refuse {
                    name: opener.name,
                    until,
                }
            };
            return Intake::Reply(Err(e));
        }
        if !ends {
            return Intake::Reply(Ok(()));
        }
        if opener.kw == Kw::Sub {
            if self.subs.is_full() {
                self.evict();
            }
            let start = match self.mode {
                Mode::Capture { start } => start,
                _ => start,
            };
            self.clock += 1;
            let sub = Sub {
                start,
                end: self.arena.top,
                used: self.clock,
            };
            self.mode = Mode::Normal;
            let _ = self.subs.push(sub);
            return Intake::Reply(Ok(()));
        }
        self.mode = Mode::Replay {
            pc: start,
            end: self.arena.top,
            free_from: Some(start),
            n,
        };
        Intake::Replay
    }

    /// Stores a line of the block being captured, dropping the least
    /// recently used subroutines for room (nothing runs from them while a
    /// block is captured).
    fn store(&mut self, n: u32, text: &[u8]) -> bool {
        loop {
            if self.arena.push_line(n, text) {
                return true;
            }
            let start = match self.mode {
                Mode::Capture { start } => start,
                _ => self.arena.top,
            };
            // The block alone does not fit: keep the subroutines.
            let block = usize::from(self.arena.top - start) + arena::HEADER + text.len();
            if block > CAPTURE_BYTES || !self.evict() {
                return false;
            }
        }
    }

    /// Drops the least recently used subroutine; false when none is held.
    fn evict(&mut self) -> bool {
        let Some(i) = (0..self.subs.len()).min_by_key(|&i| self.subs.get(i).map_or(0, |s| s.used))
        else {
            return false;
        };
        self.remove_sub(i);
        true
    }

    fn forget_sub(&mut self, name: &Name) {
        if let Some(i) = self.find_sub(name) {
            self.remove_sub(i);
        }
    }

    fn remove_sub(&mut self, i: usize) {
        let Some(s) = self.subs.get(i).copied() else {
            return;
        };
        self.subs.remove(i);
        let size = s.end - s.start;
        self.arena.cut(s.start, s.end);
        for o in self.subs.iter_mut() {
            if o.start >= s.end {
                o.start -= size;
                o.end -= size;
            }
        }
        if let Mode::Capture { start } = &mut self.mode {
            if *start >= s.end {
                *start -= size;
            }
        }
    }

    pub(super) fn find_sub(&self, name: &Name) -> Option<usize> {
        self.subs
            .iter()
            .position(|s| self.oline_at(s.start).is_some_and(|o| o.name == *name))
    }
}
