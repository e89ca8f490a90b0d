//! One line of G-code into words, without allocating.
//!
//! The lexer walks the line once. Comments are dropped (except `(MSG,…)`),
//! `N` numbers and RepRap `*nn` checksums are checked and consumed, and
//! parameter assignments `#n=…` are executed on the spot (BeagleG semantics),
//! so the caller only ever sees [`Token::Word`]s with final values and
//! operator messages.
//!
//! Choices, documented because other dialects differ:
//! - spaces and tabs may stand anywhere outside comments, even inside a
//!   number (`X1 0` is X10), as LinuxCNC strips them before parsing;
//! - a `/` first on the line marks it for block delete; whether it is
//!   skipped is the interpreter's switch (on by default, as in LinuxCNC);
//! - `%` alone on a line (comments allowed) is a program delimiter;
//! - `N` must come first, be an integer 0-99999999, and is otherwise ignored;
//! - `*nn` is only a checksum at top level (inside `[ ]` it multiplies) and
//!   must end the line; its XOR covers every byte before the `*`.

use super::error::{ErrorKind, GcodeError, Unsupported};
use super::params::ParamStore;
use super::{Word, MAX_LINE};

pub(crate) type LexResult<T> = Result<T, GcodeError>;

/// A byte cursor that skips blanks when peeking.
#[derive(Debug)]
pub(crate) struct Cursor<'a> {
    pub(crate) line: &'a [u8],
    pub(crate) pos: usize,
}

pub(crate) fn blank(b: u8) -> bool {
    b == b' ' || b == b'\t' || b == b'\r'
}

impl<'a> Cursor<'a> {
    /// Next non-blank byte (the cursor moves past the blanks).
    pub(crate) fn peek(&mut self) -> Option<u8> {
        while let Some(&b) = self.line.get(self.pos) {
            if !blank(b) {
                return Some(b);
            }
            self.pos += 1;
        }
        None
    }
    /// The byte at the cursor, blank or not.
    pub(crate) fn peek_raw(&self) -> Option<u8> {
        self.line.get(self.pos).copied()
    }
    /// The non-blank byte after the one [`Cursor::peek`] returns.
    pub(crate) fn peek2(&mut self) -> Option<u8> {
        self.peek()?;
        self.line
            .get(self.pos + 1..)?
            .iter()
            .copied()
            .find(|&b| !blank(b))
    }
    pub(crate) fn bump(&mut self) {
        self.pos += 1;
    }
    pub(crate) fn err(&self, k: ErrorKind) -> GcodeError {
        self.err_at(k, self.pos)
    }
    pub(crate) fn err_at(&self, k: ErrorKind, pos: usize) -> GcodeError {
        GcodeError::new(k, (pos + 1).min(u16::MAX as usize) as u16)
    }
}

/// What the lexer hands to the interpreter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Token<'a> {
    Word(Word),
    /// `(MSG, text)`: the text after the comma, leading blanks removed.
    Message {
        text: &'a [u8],
        col: u16,
    },
    /// A parameter alone at the end of a line (`#1`, `#<x>`): BeagleG
    /// prints its value. `text` is the reference as written.
    Value {
        text: &'a [u8],
        value: f32,
        col: u16,
    },
}

/// Lexer over one line (without its line terminator).
#[derive(Debug)]
pub struct Lexer<'a> {
    cur: Cursor<'a>,
    /// The line starts with `/`.
    pub block_delete: bool,
    /// The line is a `%` program delimiter.
    pub percent: bool,
    /// The `N` number, when present.
    pub line_number: Option<u32>,
    done: bool,
    seen_word: bool,
}

const KEYWORDS: [&[u8]; 16] = [
    b"if",
    b"else",
    b"elseif",
    b"endif",
    b"while",
    b"endwhile",
    b"do",
    b"repeat",
    b"endrepeat",
    b"sub",
    b"endsub",
    b"call",
    b"return",
    b"break",
    b"continue",
    b"end",
];

impl<'a> Lexer<'a> {
    /// Checks the length and reads the `/` and `%` markers.
    pub fn new(line: &'a [u8]) -> LexResult<Self> {
        let mut end = line.len();
        while end > 0 && matches!(line.get(end - 1), Some(b'\n' | b'\r')) {
            end -= 1;
        }
        let line = line.get(..end).unwrap_or(&[]);
        let mut cur = Cursor { line, pos: 0 };
        if line.len() > MAX_LINE {
            return Err(cur.err_at(ErrorKind::LineTooLong, MAX_LINE));
        }
        let mut lx = Lexer {
            cur: Cursor { line, pos: 0 },
            block_delete: false,
            percent: false,
            line_number: None,
            done: false,
            seen_word: false,
        };
        match cur.peek() {
            Some(b'/') => {
                cur.bump();
                lx.block_delete = true;
            }
            Some(b'%') => {
                cur.bump();
                lx.percent = true;
            }
            _ => {}
        }
        lx.cur.pos = cur.pos;
        Ok(lx)
    }

    /// The next word or message; `None` at the end of the line.
    ///
    /// The hot path (blanks, a letter, a plain number) is kept small so it
    /// compiles to a tight loop; everything else is out of line. Inlined
    /// into its caller so the token never makes a round trip through memory.
    #[inline(always)]
    pub fn next_token(&mut self, p: &mut dyn ParamStore) -> LexResult<Option<Token<'a>>> {
        loop {
            if self.done {
                return Ok(None);
            }
            let Some(b) = self.cur.peek() else {
                self.done = true;
                return Ok(None);
            };
            let (line, i) = (self.cur.line, self.cur.pos);
            if b.is_ascii_alphabetic() && !self.percent {
                let l = b.to_ascii_uppercase();
                let fast = if l != b'N' && l != b'O' {
                    let (neg, at) = match line.get(i + 1) {
                        Some(b'-') => (true, i + 2),
                        _ => (false, i + 1),
                    };
                    super::expr::plain_number(line, at)
                        .map(|(v, end)| (if neg { -v } else { v }, end))
                } else {
                    None
                };
                // Both paths meet in scalars, so the word is built once, in
                // registers (an aggregate merged in memory and reloaded whole
                // stalls store forwarding on every word).
                let (value, bare) = match fast {
                    Some((v, end)) => {
                        self.cur.pos = end;
                        (v, false)
                    }
                    None => {
                        self.cur.bump();
                        match self.word(p, l, i)? {
                            Some(vb) => vb,
                            None => continue,
                        }
                    }
                };
                self.seen_word = true;
                return Ok(Some(Token::Word(Word {
                    letter: l,
                    value,
                    col: (i + 1) as u16,
                    bare,
                })));
            }
            if let Some(t) = self.other(p, b, i)? {
                return Ok(Some(t));
            }
        }
    }

    /// Anything but a word: comments, checksums, assignments, errors.
    #[inline(never)]
    fn other(&mut self, p: &mut dyn ParamStore, b: u8, col: usize) -> LexResult<Option<Token<'a>>> {
        match b {
            b'(' => return self.comment(),
            b';' => self.done = true,
            b'*' => self.checksum()?,
            _ if self.percent => return Err(self.cur.err(ErrorKind::ExpectedLetter(b'%'))),
            b'#' => {
                self.cur.bump();
                let v = self.assignment(p, col)?;
                self.seen_word = true;
                if v.is_some() {
                    return Ok(v);
                }
            }
            _ if !b.is_ascii() => return Err(self.cur.err(ErrorKind::NonAscii)),
            _ => return Err(self.cur.err(ErrorKind::ExpectedLetter(b))),
        }
        Ok(None)
    }

    /// The general word after letter `l` (cursor past it): expressions,
    /// parameters, signs, bare axis letters, `N` and the refusals.
    /// `None` for an `N` word, which is consumed.
    #[inline(never)]
    fn word(
        &mut self,
        p: &mut dyn ParamStore,
        l: u8,
        col: usize,
    ) -> LexResult<Option<(f32, bool)>> {
        if l == b'O' {
            return Err(self
                .cur
                .err_at(ErrorKind::Unsupported(Unsupported::OWord), col));
        }
        let value = match self.cur.peek_raw() {
            Some(b'0'..=b'9' | b'.') => self.cur.number()?,
            _ => {
                if self.keyword_at(col) {
                    return Err(self
                        .cur
                        .err_at(ErrorKind::Unsupported(Unsupported::ControlFlow), col));
                }
                let next = self.cur.peek();
                let ends = matches!(next, None | Some(b';' | b'(' | b'*'))
                    || next.is_some_and(|b| b.is_ascii_alphabetic());
                if ends && is_axis_letter(l) {
                    return Ok(Some((0.0, true)));
                }
                self.cur.real(p, 0)?
            }
        };
        if !value.is_finite() {
            return Err(self.cur.err_at(ErrorKind::NotFinite, col));
        }
        if l == b'N' {
            if self.seen_word || self.line_number.is_some() {
                return Err(self.cur.err_at(ErrorKind::LineNumberMisplaced, col));
            }
            if !(0.0..=99_999_999.0).contains(&value) || libm::floorf(value) != value {
                return Err(self.cur.err_at(ErrorKind::InvalidLineNumber, col));
            }
            self.line_number = Some(value as u32);
            return Ok(None);
        }
        Ok(Some((value, false)))
    }

    /// A letter run starting at `col` that spells a control-flow keyword.
    fn keyword_at(&self, col: usize) -> bool {
        let rest = self.cur.line.get(col..).unwrap_or(&[]);
        let n = rest.iter().take_while(|b| b.is_ascii_alphabetic()).count();
        n >= 2
            && rest
                .get(..n)
                .is_some_and(|w| KEYWORDS.iter().any(|k| k.eq_ignore_ascii_case(w)))
    }

    fn assignment(&mut self, p: &mut dyn ParamStore, col: usize) -> LexResult<Option<Token<'a>>> {
        let r = self.cur.param_ref(p, 1)?;
        let end = self.cur.pos;
        match self.cur.peek() {
            Some(b'=') => self.cur.bump(),
            None | Some(b';') => {
                let value = match &r {
                    super::expr::ParamRef::Num(n) => p.get(*n),
                    super::expr::ParamRef::Named(name) => p.get_named(name),
                }
                .map_err(|k| self.cur.err_at(k, col))?;
                let text = self.cur.line.get(col..end).unwrap_or(&[]);
                let col = (col + 1) as u16;
                return Ok(Some(Token::Value { text, value, col }));
            }
            Some(b'+' | b'-' | b'*' | b'/') if self.cur.peek2() == Some(b'=') => {
                return Err(self
                    .cur
                    .err(ErrorKind::Unsupported(Unsupported::ControlFlow)));
            }
            _ => return Err(self.cur.err(ErrorKind::BadNumber)),
        }
        let v = self.cur.real(p, 0)?;
        let res = match r {
            super::expr::ParamRef::Num(n) => p.set(n, v),
            super::expr::ParamRef::Named(name) => p.set_named(&name, v),
        };
        res.map_err(|k| self.cur.err_at(k, col)).map(|()| None)
    }

    /// At `(`: skips the comment, or returns it as a message.
    fn comment(&mut self) -> LexResult<Option<Token<'a>>> {
        let start = self.cur.pos;
        let body_start = start + 1;
        let line = self.cur.line;
        let mut i = body_start;
        loop {
            match line.get(i) {
                None => return Err(self.cur.err_at(ErrorKind::UnclosedComment, start)),
                Some(b')') => break,
                Some(b'(') => return Err(self.cur.err_at(ErrorKind::NestedComment, i)),
                Some(_) => i += 1,
            }
        }
        self.cur.pos = i + 1;
        let body = line.get(body_start..i).unwrap_or(&[]);
        let t = trim_start(body);
        if t.len() >= 3 && t.get(..3).is_some_and(|m| m.eq_ignore_ascii_case(b"msg")) {
            let after = trim_start(t.get(3..).unwrap_or(&[]));
            if let Some(text) = after.strip_prefix(b",") {
                return Ok(Some(Token::Message {
                    text: trim_end(trim_start(text)),
                    col: (start + 1) as u16,
                }));
            }
        }
        Ok(None)
    }

    /// At a top-level `*`: the RepRap checksum, which must end the line.
    fn checksum(&mut self) -> LexResult<()> {
        let star = self.cur.pos;
        self.cur.bump();
        let computed = self
            .cur
            .line
            .get(..star)
            .unwrap_or(&[])
            .iter()
            .fold(0u8, |a, &b| a ^ b);
        let mut v: u32 = 0;
        let mut digits = 0;
        while let Some(b) = self.cur.peek() {
            if !b.is_ascii_digit() || digits == 3 {
                break;
            }
            v = v * 10 + u32::from(b - b'0');
            digits += 1;
            self.cur.bump();
        }
        if digits == 0 || v > 255 || self.cur.peek().is_some() {
            return Err(self.cur.err_at(ErrorKind::BadChecksum, star));
        }
        if v as u8 != computed {
            return Err(self.cur.err_at(
                ErrorKind::ChecksumMismatch {
                    expected: v as u8,
                    computed,
                },
                star,
            ));
        }
        self.done = true;
        Ok(())
    }

    /// The rest of the line as free text (M117), minus a trailing checksum,
    /// which is verified. Ends the line.
    pub fn rest_text(&mut self) -> LexResult<&'a [u8]> {
        self.cur.peek();
        let line = self.cur.line;
        let start = self.cur.pos;
        let mut end = line.len();
        while end > start && line.get(end - 1).is_some_and(|&b| blank(b)) {
            end -= 1;
        }
        let digits = line
            .get(start..end)
            .unwrap_or(&[])
            .iter()
            .rev()
            .take_while(|b| b.is_ascii_digit())
            .count();
        if digits > 0 && end - digits > start && line.get(end - digits - 1) == Some(&b'*') {
            self.cur.pos = end - digits - 1;
            self.checksum()?;
            end -= digits + 1;
        }
        self.done = true;
        let text = line.get(start..end).unwrap_or(&[]);
        let mut n = text.len();
        while n > 0 && text.get(n - 1).is_some_and(|&b| blank(b)) {
            n -= 1;
        }
        Ok(text.get(..n).unwrap_or(&[]))
    }
}

fn trim_start(s: &[u8]) -> &[u8] {
    let n = s.iter().take_while(|&&b| blank(b)).count();
    s.get(n..).unwrap_or(&[])
}

fn trim_end(s: &[u8]) -> &[u8] {
    let n = s.iter().rev().take_while(|&&b| blank(b)).count();
    s.get(..s.len() - n).unwrap_or(&[])
}

/// An axis word's letter (`crate::AXIS_NAMES`), upper case.
pub(crate) fn is_axis_letter(l: u8) -> bool {
    const BITS: u32 = {
        let mut m = 0;
        let mut i = 0;
        while i < crate::AXES {
            m |= 1 << (crate::AXIS_NAMES[i] as u32 - 'A' as u32);
            i += 1;
        }
        m
    };
    l.is_ascii_uppercase() && BITS & (1 << (l - b'A')) != 0
}
