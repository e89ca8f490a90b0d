//! Running stored lines: loops, branches and calls inside a replay.

use super::oline::{self, Kw, OLine};
use super::{err, value, Flow, Frame, Mode, Step, END, MAX_ARGS, MAX_CALLS};
use crate::gcode::{GcodeError, Local, Name, OWord};
use crate::interp::Interpreter;

impl Flow {
    /// The replay's next step. Lines to interpret are copied to `out`
    /// (at least [`crate::gcode::MAX_LINE`] bytes).
    pub fn step(&mut self, interp: &mut Interpreter, out: &mut [u8]) -> Step {
        let Mode::Replay { pc, end, n, .. } = self.mode else {
            return Step::Idle;
        };
        if pc == end {
            let r = if self.frames.is_empty() {
                Ok(())
            } else {
                Err((n, err(OWord::Unclosed)))
            };
            return self.finish(interp, r);
        }
        let Some((ln, text, next)) = self.arena.line(pc) else {
            return self.finish(interp, Err((n, err(OWord::Unclosed))));
        };
        let len = text.len().min(out.len());
        if let (Some(d), Some(s)) = (out.get_mut(..len), text.get(..len)) {
            d.copy_from_slice(s);
        }
        let line = out.get(..len).unwrap_or(&[]);
        match oline::parse(line) {
            None => {
                self.set_pc(next);
                Step::Run { n: ln, len }
            }
            Some(Err(e)) => self.finish(interp, Err((ln, e))),
            Some(Ok(ol)) => {
                let mut copy = [0u8; crate::gcode::MAX_LINE];
                let c = copy.get_mut(..len).unwrap_or(&mut []);
                c.copy_from_slice(line);
                match self.control(&ol, c, pc, next, interp) {
                    Ok(pc) => {
                        self.set_pc(pc);
                        Step::Busy
                    }
                    Err(e) => self.finish(interp, Err((ln, e))),
                }
            }
        }
    }

    /// A line of the replay failed in the interpreter: the replay ends;
    /// returns the line to answer (the one that started it).
    pub fn abort(&mut self, interp: &mut Interpreter) -> Option<u32> {
        let Mode::Replay { n, .. } = self.mode else {
            return None;
        };
        let _ = self.finish(interp, Ok(()));
        Some(n)
    }

    fn finish(&mut self, interp: &mut Interpreter, result: Result<(), (u32, GcodeError)>) -> Step {
        let Mode::Replay { n, free_from, .. } = self.mode else {
            return Step::Idle;
        };
        self.unwind(interp);
        if let Some(f) = free_from {
            self.arena.cut(f, self.arena.top);
        }
        self.mode = Mode::Normal;
        Step::Done { n, result }
    }

    /// Closes every open loop and call, putting the outermost caller's
    /// locals back.
    pub(super) fn unwind(&mut self, interp: &mut Interpreter) {
        while let Some(f) = self.frames.pop() {
            if let Frame::Call { low, .. } = f {
                self.restore(interp, low);
            }
        }
    }

    fn restore(&mut self, interp: &mut Interpreter, low: u16) {
        interp.params_mut().clear_locals();
        while self.arena.low < low {
            match self.arena.pop_local() {
                // Room was there when they were saved.
                Some(l) => {
                    let _ = interp.put_param(l);
                }
                None => break,
            }
        }
    }

    /// The current body's end (a call's or the captured block's).
    fn end(&self) -> u16 {
        match self.mode {
            Mode::Replay { end, .. } => end,
            _ => END,
        }
    }

    fn set_end(&mut self, new: u16) {
        if let Mode::Replay { end, .. } = &mut self.mode {
            *end = new;
        }
    }

    /// An O-word line at `at` (the next record at `next`); returns where
    /// the replay goes on.
    pub(super) fn control(
        &mut self,
        ol: &OLine,
        text: &[u8],
        at: u16,
        next: u16,
        interp: &mut Interpreter,
    ) -> Result<u16, GcodeError> {
        match ol.kw {
            Kw::If => {
                if self.cond(ol, text, interp)? {
                    return Ok(next);
                }
                let mut from = next;
                loop {
                    let (rec, after, kw, o) =
                        self.scan(from, &ol.name, &[Kw::ElseIf, Kw::Else, Kw::EndIf])?;
                    if kw != Kw::ElseIf {
                        return Ok(after);
                    }
                    let mut copy = [0u8; crate::gcode::MAX_LINE];
                    let (_, t, _) = self.arena.line(rec).ok_or(err(OWord::Unclosed))?;
                    let len = t.len().min(copy.len());
                    let c = copy.get_mut(..len).unwrap_or(&mut []);
                    c.copy_from_slice(t.get(..len).unwrap_or(&[]));
                    if self.cond(&o, c, interp)? {
                        return Ok(after);
                    }
                    from = after;
                }
            }
            // Reached from a branch that ran.
            Kw::ElseIf | Kw::Else => Ok(self.scan(next, &ol.name, &[Kw::EndIf])?.1),
            Kw::EndIf => oline::end(text, ol.args).map(|()| next),
            Kw::While => {
                if let Some((
                    i,
                    Frame::Loop {
                        start, kw: Kw::Do, ..
                    },
                )) = self.loop_frame(&ol.name)
                {
                    if i + 1 == self.frames.len() {
                        if self.cond(ol, text, interp)? {
                            return self.after(start);
                        }
                        self.frames.pop();
                        return Ok(next);
                    }
                }
                if self.cond(ol, text, interp)? {
                    self.push(Frame::Loop {
                        start: at,
                        kw: Kw::While,
                        left: 0,
                    })?;
                    Ok(next)
                } else {
                    Ok(self.scan(next, &ol.name, &[Kw::EndWhile])?.1)
                }
            }
            Kw::EndWhile | Kw::EndRepeat => {
                oline::end(text, ol.args)?;
                let want = if ol.kw == Kw::EndWhile {
                    Kw::While
                } else {
                    Kw::Repeat
                };
                match self.loop_frame(&ol.name) {
                    Some((i, Frame::Loop { start, kw, left }))
                        if kw == want && i + 1 == self.frames.len() =>
                    {
                        if kw == Kw::While {
                            self.frames.pop();
                            return Ok(start);
                        }
                        if left > 1 {
                            if let Some(Frame::Loop { left, .. }) = self.frames.last_mut() {
                                *left -= 1;
                            }
                            return self.after(start);
                        }
                        self.frames.pop();
                        Ok(next)
                    }
                    _ => Err(err(OWord::Unmatched)),
                }
            }
            Kw::Do => {
                oline::end(text, ol.args)?;
                self.push(Frame::Loop {
                    start: at,
                    kw: Kw::Do,
                    left: 0,
                })?;
                Ok(next)
            }
            Kw::Repeat => {
                let v = value(ol, text, interp)?.ok_or(err(OWord::Syntax))?;
                let n = libm::roundf(v);
                if n < 1.0 {
                    return Ok(self.scan(next, &ol.name, &[Kw::EndRepeat])?.1);
                }
                self.push(Frame::Loop {
                    start: at,
                    kw: Kw::Repeat,
                    left: if n >= u32::MAX as f32 {
                        u32::MAX
                    } else {
                        n as u32
                    },
                })?;
                Ok(next)
            }
            Kw::Break | Kw::Continue => {
                oline::end(text, ol.args)?;
                let Some((i, Frame::Loop { kw, .. })) = self.loop_frame(&ol.name) else {
                    return Err(err(OWord::Outside));
                };
                let (at_closer, after, _, _) = self.scan(next, &ol.name, &[super::closer(kw)])?;
                if ol.kw == Kw::Break {
                    self.frames.truncate(i);
                    Ok(after)
                } else {
                    // The closer decides: back to the top, or out.
                    self.frames.truncate(i + 1);
                    Ok(at_closer)
                }
            }
            Kw::Call => self.call(ol, text, next, interp),
            Kw::Return | Kw::EndSub => {
                let v = value(ol, text, interp)?;
                let i = self
                    .frames
                    .iter()
                    .rposition(|f| matches!(f, Frame::Call { .. }))
                    .ok_or(err(OWord::Outside))?;
                let Some(Frame::Call { ret, ret_end, low }) = self.frames.get(i).copied() else {
                    return Err(err(OWord::Outside));
                };
                self.frames.truncate(i);
                self.restore(interp, low);
                let named = |s: &[u8]| {
                    let mut n = Name::empty();
                    for &b in s {
                        let _ = n.push(b);
                    }
                    n
                };
                interp.put_param(Local::Named(named(b"_value"), v.unwrap_or(0.0)))?;
                let got = if v.is_some() { 1.0 } else { 0.0 };
                interp.put_param(Local::Named(named(b"_value_returned"), got))?;
                self.set_end(ret_end);
                Ok(ret)
            }
            Kw::Sub => Err(err(OWord::NestedSub)),
        }
    }

    fn call(
        &mut self,
        ol: &OLine,
        text: &[u8],
        next: u16,
        interp: &mut Interpreter,
    ) -> Result<u16, GcodeError> {
        let i = self.find_sub(&ol.name).ok_or(err(OWord::UndefinedSub))?;
        let mut args: heapless::Vec<f32, MAX_ARGS> = heapless::Vec::new();
        let mut p = ol.args;
        while oline::has_arg(text, p) {
            let (v, after) = interp.eval_at(text, p)?;
            args.push(v).map_err(|_| err(OWord::Syntax))?;
            p = after;
        }
        oline::end(text, p)?;
        let calls = self
            .frames
            .iter()
            .filter(|f| matches!(f, Frame::Call { .. }))
            .count();
        if calls >= MAX_CALLS || self.frames.is_full() {
            return Err(err(OWord::TooDeep));
        }
        let low = self.arena.low;
        // Save the caller's locals; without room, none is lost.
        let mut ok = true;
        for l in interp.params_mut().locals() {
            if !self.arena.push_local(&l) {
                ok = false;
                break;
            }
        }
        if !ok {
            self.arena.low = low;
            return Err(err(OWord::TooDeep));
        }
        interp.params_mut().clear_locals();
        for (k, v) in args.iter().enumerate() {
            interp.put_param(Local::Num(k as u16 + 1, *v))?;
        }
        let ret_end = self.end();
        self.push(Frame::Call {
            ret: next,
            ret_end,
            low,
        })?;
        self.clock += 1;
        let clock = self.clock;
        let s = self.subs.get_mut(i).ok_or(err(OWord::UndefinedSub))?;
        s.used = clock;
        let (start, end) = (s.start, s.end);
        self.set_end(end);
        let (_, _, body) = self.arena.line(start).ok_or(err(OWord::UndefinedSub))?;
        Ok(body)
    }

    fn push(&mut self, f: Frame) -> Result<(), GcodeError> {
        self.frames.push(f).map_err(|_| err(OWord::TooDeep))
    }

    /// The innermost loop named `name` within the current call.
    fn loop_frame(&self, name: &Name) -> Option<(usize, Frame)> {
        for (i, f) in self.frames.iter().enumerate().rev() {
            match *f {
                Frame::Call { .. } => return None,
                Frame::Loop { start, .. } => {
                    if self.oline_at(start).is_some_and(|o| o.name == *name) {
                        return Some((i, *f));
                    }
                }
            }
        }
        None
    }

    /// The record after the one at `at`.
    fn after(&self, at: u16) -> Result<u16, GcodeError> {
        self.arena.line(at).map(|l| l.2).ok_or(err(OWord::Unclosed))
    }

    /// The first line from `from` in the current body named `name` with
    /// one of `kws`: its record, the next record, its keyword and line.
    fn scan(
        &self,
        from: u16,
        name: &Name,
        kws: &[Kw],
    ) -> Result<(u16, u16, Kw, OLine), GcodeError> {
        let end = self.end();
        let mut at = from;
        while at < end {
            let Some((_, text, next)) = self.arena.line(at) else {
                break;
            };
            if let Some(Ok(o)) = oline::parse(text) {
                if o.name == *name && kws.contains(&o.kw) {
                    return Ok((at, next, o.kw, o));
                }
            }
            at = next;
        }
        Err(err(OWord::Unclosed))
    }
}
