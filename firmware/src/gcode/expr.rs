//! Real values: numbers, `#` parameters, `[expressions]` and unary functions.
//!
//! Recursive descent, one function per precedence level (LinuxCNC's order:
//! `**` binds tightest, then `* / MOD`, then `+ -`, then the comparisons, then
//! `AND OR XOR`; all left-associative). Nesting is bounded by [`MAX_DEPTH`]
//! so a hostile line cannot overflow the MCU's stack. Every result is checked
//! to be finite: NaN and infinity become errors here, never motion.
//!
//! Whitespace may stand anywhere, even inside numbers (`X1 0` is X10), as in
//! LinuxCNC, which strips spaces before parsing.

use super::error::{ErrorKind, Unsupported};
use super::lexer::{blank, Cursor, LexResult};
use super::params::{Name, ParamStore, PARAM_READ_MAX};
use crate::num::trig::{asin, sin_cos_deg};
use crate::num::Decimal;
use libm::{atan2f, ceilf, expf, floorf, fmodf, logf, powf, roundf, sqrtf};

/// Deepest bracket/parameter nesting accepted.
pub const MAX_DEPTH: u8 = 10;

const DEG: f32 = core::f32::consts::PI / 180.0;

/// Exact powers of ten: all of them are exactly representable in f32, so one
/// division of an exact mantissa gives a correctly rounded result.
const POW10: [f32; 11] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];

fn finite(v: f32) -> Result<f32, ErrorKind> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ErrorKind::NotFinite)
    }
}

/// Appends the decimal digits at `i` to `mant` and returns where they end.
/// Wrapping: the caller refuses runs long enough to overflow.
#[inline(always)]
fn digit_run(line: &[u8], mut i: usize, mant: &mut u32) -> usize {
    while let Some(&b) = line.get(i) {
        let d = b.wrapping_sub(b'0');
        if d >= 10 {
            break;
        }
        *mant = mant.wrapping_mul(10).wrapping_add(u32::from(d));
        i += 1;
    }
    i
}

/// The fast path for numbers: `digits[.digits]` at `i` with 1 to 9 digits
/// (a u32 cannot overflow), below 2^24 and at most 10 decimals, and not
/// continued after a blank (`X1 0` is X10). That is nearly every number in
/// real files, and the result is exact: an exact integer over an exact
/// power of ten, rounded once. Returns the value and the position after it
/// and any blanks; `None` sends the caller to the general path.
#[inline(always)]
pub(crate) fn plain_number(line: &[u8], start: usize) -> Option<(f32, usize)> {
    let mut mant: u32 = 0;
    let mut i = digit_run(line, start, &mut mant);
    let mut nd = i - start;
    let dot = line.get(i) == Some(&b'.');
    let mut frac = 0;
    if dot {
        let end = digit_run(line, i + 1, &mut mant);
        frac = end - (i + 1);
        nd += frac;
        i = end;
    }
    if nd == 0 || nd > 9 || mant >= 1 << 24 {
        return None;
    }
    // Blanks after the number are consumed here, once; if a digit (or a
    // first point) follows them, the number goes on: `X1 0`, `X1 .5`.
    let mut end = i;
    while line.get(end).is_some_and(|&b| blank(b)) {
        end += 1;
    }
    if end > i
        && line
            .get(end)
            .is_some_and(|&b| b.is_ascii_digit() || (b == b'.' && !dot))
    {
        return None;
    }
    let p = POW10.get(frac)?;
    Some((
        if frac == 0 {
            mant as f32
        } else {
            mant as f32 / p
        },
        end,
    ))
}

impl Cursor<'_> {
    /// An unsigned decimal number: digits with at most one point (blanks
    /// allowed between them). Up to 9 significant digits and 10 decimals take
    /// the exact path (integer mantissa over an exact power of ten, one
    /// rounding); anything longer goes to [`crate::num::Decimal`].
    pub(crate) fn number(&mut self) -> LexResult<f32> {
        match plain_number(self.line, self.pos) {
            Some((v, end)) => {
                self.pos = end;
                Ok(v)
            }
            None => self.number_slow(),
        }
    }

    /// Numbers with blanks inside or many significant digits: the same
    /// digits through [`crate::num::Decimal`], which keeps 19 of them.
    #[cold]
    #[inline(never)]
    fn number_slow(&mut self) -> LexResult<f32> {
        let start = self.pos;
        let line = self.line;
        let mut i = start;
        let mut d = Decimal::default();
        let mut dot = false;
        while let Some(&b) = line.get(i) {
            let digit = b.wrapping_sub(b'0');
            if digit < 10 {
                d.push(digit, dot);
            } else if b == b'.' && !dot {
                dot = true;
            } else if !blank(b) {
                break;
            }
            i += 1;
        }
        self.pos = i;
        let v = d.to_f32();
        if d.digits == 0 || !v.is_finite() {
            return Err(self.err_at(ErrorKind::BadNumber, start));
        }
        Ok(v)
    }

    /// Any real value: `[+-]* (number | [expr] | #param | FUNC[..])`.
    pub(crate) fn real(&mut self, p: &mut dyn ParamStore, depth: u8) -> LexResult<f32> {
        if depth > MAX_DEPTH {
            return Err(self.err(ErrorKind::ExpressionTooDeep));
        }
        let mut neg = false;
        while let Some(b @ (b'+' | b'-')) = self.peek() {
            neg ^= b == b'-';
            self.bump();
        }
        let v = match self.peek() {
            Some(b'[') => {
                self.bump();
                self.bracket(p, depth + 1)?
            }
            Some(b'#') => {
                let col = self.pos;
                self.bump();
                let v = match self.param_ref(p, depth + 1)? {
                    ParamRef::Num(n) => p.get(n),
                    ParamRef::Named(name) => p.get_named(&name),
                };
                v.map_err(|k| self.err_at(k, col))?
            }
            Some(b) if b.is_ascii_digit() || b == b'.' => self.number()?,
            Some(b) if b.is_ascii_alphabetic() => self.function(p, depth)?,
            Some(b']') => return Err(self.err(ErrorKind::UnbalancedBrackets)),
            _ => return Err(self.err(ErrorKind::BadNumber)),
        };
        Ok(if neg { -v } else { v })
    }

    /// After `#`: which parameter. `#<name>` and BeagleG's bare `#name`
    /// (letters, digits, `_`; ends at a space or any other byte) are names,
    /// anything else is a real value that must be an integer 0..=5410.
    pub(crate) fn param_ref(&mut self, p: &mut dyn ParamStore, depth: u8) -> LexResult<ParamRef> {
        let col = self.pos;
        match self.peek() {
            Some(b'<') => {
                self.bump();
                let mut name = Name::empty();
                loop {
                    match self.peek() {
                        Some(b'>') => {
                            self.bump();
                            break;
                        }
                        Some(b) if b.is_ascii_graphic() => {
                            name.push(b).map_err(|k| self.err(k))?;
                            self.bump();
                            let n = name.as_bytes();
                            if n.len() == 5 && (n == b"_hal[" || n == b"_ini[") {
                                return Err(self.err_at(
                                    ErrorKind::Unsupported(Unsupported::SystemParam),
                                    col,
                                ));
                            }
                        }
                        _ => return Err(self.err(ErrorKind::BadNumber)),
                    }
                }
                if name.as_bytes().is_empty() {
                    return Err(self.err_at(ErrorKind::BadNumber, col));
                }
                Ok(ParamRef::Named(name))
            }
            Some(b) if b.is_ascii_alphabetic() => {
                let mut name = Name::empty();
                while let Some(b) = self.peek_raw() {
                    if !(b.is_ascii_alphanumeric() || b == b'_') {
                        break;
                    }
                    name.push(b).map_err(|k| self.err(k))?;
                    self.pos += 1;
                }
                Ok(ParamRef::Named(name))
            }
            _ => {
                let v = self.real(p, depth)?;
                let n = roundf(v);
                if (v - n).abs() > 1e-4 {
                    return Err(self.err_at(ErrorKind::NotInteger(b'#'), col));
                }
                if !(0.0..=PARAM_READ_MAX as f32).contains(&n) {
                    return Err(self.err_at(ErrorKind::ParamOutOfRange, col));
                }
                Ok(ParamRef::Num(n as u16))
            }
        }
    }

    /// Inside `[`: a whole expression up to and including the matching `]`.
    fn bracket(&mut self, p: &mut dyn ParamStore, depth: u8) -> LexResult<f32> {
        let v = self.logical(p, depth)?;
        match self.peek() {
            Some(b']') => {
                self.bump();
                Ok(v)
            }
            None => Err(self.err(ErrorKind::UnbalancedBrackets)),
            Some(_) => Err(self.err(ErrorKind::UnknownOperation)),
        }
    }

    /// Reads an alphabetic operator name (up to 5 letters) without consuming it.
    fn peek_word(&self) -> ([u8; 5], usize) {
        let mut w = [0u8; 5];
        let mut n = 0;
        let mut i = self.pos;
        while let Some(&b) = self.line.get(i) {
            if b == b' ' || b == b'\t' {
                i += 1;
                continue;
            }
            if !b.is_ascii_alphabetic() || n == w.len() {
                break;
            }
            if let Some(s) = w.get_mut(n) {
                *s = b.to_ascii_uppercase();
            }
            n += 1;
            i += 1;
        }
        (w, i)
    }

    fn logical(&mut self, p: &mut dyn ParamStore, d: u8) -> LexResult<f32> {
        let mut a = self.relational(p, d)?;
        loop {
            let (w, end) = self.peek_word();
            let op = match &w {
                [b'A', b'N', b'D', 0, 0] => 0,
                [b'O', b'R', 0, 0, 0] => 1,
                [b'X', b'O', b'R', 0, 0] => 2,
                _ => return Ok(a),
            };
            self.pos = end;
            let b = self.relational(p, d)?;
            let (x, y) = (a != 0.0, b != 0.0);
            a = f32::from(u8::from(match op {
                0 => x && y,
                1 => x || y,
                _ => x ^ y,
            }));
        }
    }

    fn relational(&mut self, p: &mut dyn ParamStore, d: u8) -> LexResult<f32> {
        let mut a = self.additive(p, d)?;
        loop {
            let (w, end) = self.peek_word();
            let op = match &w {
                [b'E', b'Q', 0, 0, 0] => 0,
                [b'N', b'E', 0, 0, 0] => 1,
                [b'G', b'T', 0, 0, 0] => 2,
                [b'G', b'E', 0, 0, 0] => 3,
                [b'L', b'T', 0, 0, 0] => 4,
                [b'L', b'E', 0, 0, 0] => 5,
                _ => return Ok(a),
            };
            self.pos = end;
            let b = self.additive(p, d)?;
            let r = match op {
                0 => a == b,
                1 => a != b,
                2 => a > b,
                3 => a >= b,
                4 => a < b,
                _ => a <= b,
            };
            a = f32::from(u8::from(r));
        }
    }

    fn additive(&mut self, p: &mut dyn ParamStore, d: u8) -> LexResult<f32> {
        let mut a = self.multiplicative(p, d)?;
        loop {
            let op = match self.peek() {
                Some(b @ (b'+' | b'-')) => b,
                _ => return Ok(a),
            };
            self.bump();
            let col = self.pos;
            let b = self.multiplicative(p, d)?;
            a = finite(if op == b'+' { a + b } else { a - b }).map_err(|k| self.err_at(k, col))?;
        }
    }

    fn multiplicative(&mut self, p: &mut dyn ParamStore, d: u8) -> LexResult<f32> {
        let mut a = self.power(p, d)?;
        loop {
            let col = self.pos;
            let op = match self.peek() {
                Some(b'/') => b'/',
                Some(b'*') if self.peek2() != Some(b'*') => b'*',
                _ => {
                    let (w, end) = self.peek_word();
                    if w != [b'M', b'O', b'D', 0, 0] {
                        return Ok(a);
                    }
                    self.pos = end;
                    b'M'
                }
            };
            if op != b'M' {
                self.bump();
            }
            let b = self.power(p, d)?;
            let r = match op {
                b'*' => a * b,
                _ if b == 0.0 => return Err(self.err_at(ErrorKind::DivisionByZero, col)),
                b'/' => a / b,
                _ => {
                    // LinuxCNC's MOD: the result takes the divisor's magnitude, never negative.
                    let m = fmodf(a, b);
                    if m < 0.0 {
                        m + b.abs()
                    } else {
                        m
                    }
                }
            };
            a = finite(r).map_err(|k| self.err_at(k, col))?;
        }
    }

    fn power(&mut self, p: &mut dyn ParamStore, d: u8) -> LexResult<f32> {
        let mut a = self.real(p, d)?;
        while self.peek() == Some(b'*') && self.peek2() == Some(b'*') {
            let col = self.pos;
            self.bump();
            self.bump();
            let b = self.real(p, d)?;
            if a < 0.0 && floorf(b) != b {
                return Err(self.err_at(ErrorKind::DomainError, col));
            }
            a = finite(powf(a, b)).map_err(|k| self.err_at(k, col))?;
        }
        Ok(a)
    }

    /// `NAME[expr]`, or `ATAN[a]/[b]`.
    fn function(&mut self, p: &mut dyn ParamStore, depth: u8) -> LexResult<f32> {
        let col = self.pos;
        let (w, end) = self.peek_word();
        self.pos = end;
        if self.peek() != Some(b'[') {
            return Err(self.err_at(ErrorKind::BadNumber, col));
        }
        self.bump();
        let a = self.bracket(p, depth + 1)?;
        let dom = |ok: bool| {
            if ok {
                Ok(())
            } else {
                Err(self.err_at(ErrorKind::DomainError, col))
            }
        };
        let v = match &w {
            b"ABS\0\0" => a.abs(),
            b"ACOS\0" => {
                dom((-1.0..=1.0).contains(&a))?;
                libm::acosf(a) / DEG
            }
            b"ASIN\0" => {
                dom((-1.0..=1.0).contains(&a))?;
                asin(a) / DEG
            }
            b"COS\0\0" => sin_cos_deg(a).1,
            b"SIN\0\0" => sin_cos_deg(a).0,
            b"TAN\0\0" => {
                let (s, c) = sin_cos_deg(a);
                s / c
            }
            b"EXP\0\0" => expf(a),
            b"FIX\0\0" => floorf(a),
            b"FUP\0\0" => ceilf(a),
            b"ROUND" => roundf(a),
            b"LN\0\0\0" => {
                dom(a > 0.0)?;
                logf(a)
            }
            b"SQRT\0" => {
                dom(a >= 0.0)?;
                sqrtf(a)
            }
            b"ATAN\0" => {
                if self.peek() != Some(b'/') {
                    return Err(self.err(ErrorKind::UnknownOperation));
                }
                self.bump();
                if self.peek() != Some(b'[') {
                    return Err(self.err(ErrorKind::UnknownOperation));
                }
                self.bump();
                let b = self.bracket(p, depth + 1)?;
                atan2f(a, b) / DEG
            }
            _ => return Err(self.err_at(ErrorKind::UnknownOperation, col)),
        };
        finite(v).map_err(|k| self.err_at(k, col))
    }
}

/// A parsed `#` reference.
#[derive(Clone, Copy, Debug)]
pub(crate) enum ParamRef {
    Num(u16),
    Named(Name),
}
