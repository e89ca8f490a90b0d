//! Real values: numbers, `#` parameters, `[expressions]` and unary functions.
//!
//! Operator precedence over an explicit stack (LinuxCNC's order: `**`
//! binds tightest, then `* / MOD`, then `+ -`, then the comparisons, then
//! `AND OR XOR`; all left-associative). No recursion per bracket: a line
//! may nest as deep as its length allows (LinuxCNC's own bound: about 125
//! brackets in its 256-byte line; here [`MAX_DEPTH`] pending brackets,
//! operators and prefixes), in 1 KiB of stack taken only when a value is
//! more than a number. Every result is checked to be
//! finite: NaN and infinity become errors here, never motion.
//!
//! Whitespace may stand anywhere, even inside numbers (`X1 0` is X10), as in
//! LinuxCNC, which strips spaces before parsing.

use super::error::{ErrorKind, Unsupported};
use super::lexer::{blank, Cursor, LexResult};
use super::params::{Name, ParamStore, PARAM_READ_MAX};
use crate::num::trig::{asin, sin_cos_deg};
use crate::num::Decimal;
use libm::{atan2f, ceilf, expf, floorf, fmodf, logf, powf, roundf};

/// Pending brackets, binary operators and prefixes (`-`, `#`) one value
/// may have open at once (8 bytes each on the stack): 127 brackets, as
/// many as a [`super::MAX_LINE`]-byte line can close, and LinuxCNC's
/// 256-byte line holds about 125.
pub const MAX_DEPTH: usize = 128;

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
    /// `_depth` is kept for callers; nesting lives on the explicit stack.
    pub(crate) fn real(&mut self, p: &mut dyn ParamStore, _depth: u8) -> LexResult<f32> {
        match self.peek() {
            Some(b) if b.is_ascii_digit() || b == b'.' => self.number(),
            _ => self.expression(p),
        }
    }

    /// A value that is more than a number. Out of line: its stack (1 KiB)
    /// is only taken when a line has an expression.
    #[inline(never)]
    fn expression(&mut self, p: &mut dyn ParamStore) -> LexResult<f32> {
        let mut stack: heapless::Vec<Frame, MAX_DEPTH> = heapless::Vec::new();
        loop {
            // An operand, after any prefixes.
            let mut v = loop {
                let col = self.pos;
                let frame = match self.peek() {
                    Some(b'+') => {
                        self.bump();
                        continue;
                    }
                    Some(b'-') => {
                        self.bump();
                        Frame::Neg
                    }
                    Some(b'[') => {
                        self.bump();
                        Frame::Plain
                    }
                    Some(b'#') => {
                        self.bump();
                        let at = self.pos;
                        match self.peek() {
                            Some(b) if b == b'<' || b.is_ascii_alphabetic() => {
                                let name = self.param_name()?;
                                break p.get_named(&name).map_err(|k| self.err_at(k, col))?;
                            }
                            _ => Frame::Param(at as u16),
                        }
                    }
                    Some(b) if b.is_ascii_digit() || b == b'.' => break self.number()?,
                    Some(b) if b.is_ascii_alphabetic() => {
                        let (w, end) = self.peek_word();
                        self.pos = end;
                        if self.peek() != Some(b'[') {
                            return Err(self.err_at(ErrorKind::BadNumber, col));
                        }
                        self.bump();
                        if w == *b"EXISTS" {
                            break self.exists(p)?;
                        }
                        let f =
                            Func::of(&w).ok_or(self.err_at(ErrorKind::UnknownOperation, col))?;
                        Frame::Func(f, col as u16)
                    }
                    Some(b']') => return Err(self.err(ErrorKind::UnbalancedBrackets)),
                    _ => return Err(self.err(ErrorKind::BadNumber)),
                };
                stack
                    .push(frame)
                    .map_err(|_| self.err(ErrorKind::ExpressionTooDeep))?;
            };
            // Fold the value into what waits for it, until an operator
            // asks for another operand or the value is complete.
            loop {
                while let Some(&top) = stack.last() {
                    match top {
                        Frame::Neg => v = -v,
                        Frame::Param(col) => v = self.param_value(p, v, usize::from(col))?,
                        _ => break,
                    }
                    stack.pop();
                }
                if stack.is_empty() {
                    return Ok(v);
                }
                if let Some((op, end)) = self.peek_op() {
                    let col = self.pos;
                    v = self.reduce(&mut stack, v, op.prec())?;
                    self.pos = end;
                    stack
                        .push(Frame::Bin(op, v, col as u16))
                        .map_err(|_| self.err(ErrorKind::ExpressionTooDeep))?;
                    break;
                }
                v = self.reduce(&mut stack, v, 0)?;
                let open = stack.pop();
                match self.peek() {
                    Some(b']') => self.bump(),
                    None => return Err(self.err(ErrorKind::UnbalancedBrackets)),
                    Some(_) => return Err(self.err(ErrorKind::UnknownOperation)),
                }
                v = match open {
                    Some(Frame::Plain) => v,
                    Some(Frame::Atan(a, col)) => {
                        finite(atan2f(a, v) / DEG).map_err(|k| self.err_at(k, usize::from(col)))?
                    }
                    Some(Frame::Func(Func::Atan, col)) => {
                        // `ATAN[a]/[b]`: the second bracket follows.
                        if self.peek() != Some(b'/') {
                            return Err(self.err(ErrorKind::UnknownOperation));
                        }
                        self.bump();
                        if self.peek() != Some(b'[') {
                            return Err(self.err(ErrorKind::UnknownOperation));
                        }
                        self.bump();
                        stack
                            .push(Frame::Atan(v, col))
                            .map_err(|_| self.err(ErrorKind::ExpressionTooDeep))?;
                        break;
                    }
                    Some(Frame::Func(f, col)) => {
                        f.apply(v).map_err(|k| self.err_at(k, usize::from(col)))?
                    }
                    _ => return Err(self.err(ErrorKind::UnbalancedBrackets)),
                };
            }
        }
    }

    /// Applies the pending binary operators on top of `stack` that bind
    /// at least as tightly as `prec` (left-associative), with `v` as the
    /// rightmost operand.
    fn reduce(
        &self,
        stack: &mut heapless::Vec<Frame, MAX_DEPTH>,
        mut v: f32,
        prec: u8,
    ) -> LexResult<f32> {
        while let Some(&Frame::Bin(op, a, col)) = stack.last() {
            if op.prec() < prec {
                break;
            }
            stack.pop();
            v = op
                .apply(a, v)
                .map_err(|k| self.err_at(k, usize::from(col)))?;
        }
        Ok(v)
    }

    /// `#n`: the value of parameter `v`, which must be an integer in range;
    /// `col` is where its number starts, one after the `#`.
    fn param_value(&self, p: &mut dyn ParamStore, v: f32, col: usize) -> LexResult<f32> {
        let n = roundf(v);
        if (v - n).abs() > 1e-4 {
            return Err(self.err_at(ErrorKind::NotInteger(b'#'), col));
        }
        if !(0.0..=PARAM_READ_MAX as f32).contains(&n) {
            return Err(self.err_at(ErrorKind::ParamOutOfRange, col));
        }
        p.get(n as u16)
            .map_err(|k| self.err_at(k, col.saturating_sub(1)))
    }

    /// After `EXISTS[`: `#<name>]`; 1 when the parameter is set, else 0
    /// (LinuxCNC's function; it takes a named parameter only).
    fn exists(&mut self, p: &mut dyn ParamStore) -> LexResult<f32> {
        if self.peek() != Some(b'#') {
            return Err(self.err(ErrorKind::BadNumber));
        }
        self.bump();
        let name = self.param_name()?;
        if self.peek() != Some(b']') {
            return Err(self.err(ErrorKind::UnbalancedBrackets));
        }
        self.bump();
        Ok(f32::from(u8::from(p.get_named(&name).is_ok())))
    }

    /// A named parameter after its `#`: `<name>` or BeagleG's bare `name`.
    fn param_name(&mut self) -> LexResult<Name> {
        match self.param_ref_named()? {
            Some(n) => Ok(n),
            None => Err(self.err(ErrorKind::BadNumber)),
        }
    }

    /// After `#`: which parameter. `#<name>` and BeagleG's bare `#name`
    /// (letters, digits, `_`; ends at a space or any other byte) are names,
    /// anything else is a real value that must be an integer 0..=5410.
    pub(crate) fn param_ref(&mut self, p: &mut dyn ParamStore, depth: u8) -> LexResult<ParamRef> {
        let col = self.pos;
        if let Some(name) = self.param_ref_named()? {
            return Ok(ParamRef::Named(name));
        }
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

    /// The named forms of [`Cursor::param_ref`]; `None` when a number follows.
    fn param_ref_named(&mut self) -> LexResult<Option<Name>> {
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
                Ok(Some(name))
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
                Ok(Some(name))
            }
            _ => Ok(None),
        }
    }

    /// Reads an alphabetic name (up to 6 letters, blanks skipped) without
    /// consuming it.
    fn peek_word(&self) -> ([u8; 6], usize) {
        let mut w = [0u8; 6];
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

    /// The binary operator at the cursor, and where it ends.
    fn peek_op(&mut self) -> Option<(Op, usize)> {
        let at = self.pos;
        Some(match self.peek()? {
            b'*' if self.peek2() == Some(b'*') => {
                let first = self.pos;
                let second = self
                    .line
                    .get(first + 1..)?
                    .iter()
                    .position(|&b| !blank(b))?;
                (Op::Pow, first + 1 + second + 1)
            }
            b'*' => (Op::Mul, self.pos + 1),
            b'/' => (Op::Div, self.pos + 1),
            b'+' => (Op::Add, self.pos + 1),
            b'-' => (Op::Sub, self.pos + 1),
            _ => {
                let (w, end) = self.peek_word();
                let op = match &w[..3] {
                    b"MOD" if w[3] == 0 => Op::Mod,
                    b"AND" if w[3] == 0 => Op::And,
                    b"XOR" if w[3] == 0 => Op::Xor,
                    [b'O', b'R', 0] => Op::Or,
                    [b'E', b'Q', 0] => Op::Eq,
                    [b'N', b'E', 0] => Op::Ne,
                    [b'G', b'T', 0] => Op::Gt,
                    [b'G', b'E', 0] => Op::Ge,
                    [b'L', b'T', 0] => Op::Lt,
                    [b'L', b'E', 0] => Op::Le,
                    _ => {
                        self.pos = at;
                        return None;
                    }
                };
                (op, end)
            }
        })
    }
}

/// Work pending on [`Cursor::real`]'s stack: 8 bytes each.
#[derive(Clone, Copy, Debug)]
enum Frame {
    /// An open `[`.
    Plain,
    /// A function's argument `[`; its name's column.
    Func(Func, u16),
    /// `ATAN[a]/[`: the second argument's `[`, with `a`.
    Atan(f32, u16),
    /// A binary operator with its left operand and column.
    Bin(Op, f32, u16),
    /// A unary minus.
    Neg,
    /// A `#` whose parameter number is the next value (where it starts).
    Param(u16),
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Pow,
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

impl Op {
    const fn prec(self) -> u8 {
        match self {
            Op::Pow => 5,
            Op::Mul | Op::Div | Op::Mod => 4,
            Op::Add | Op::Sub => 3,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 2,
            Op::And | Op::Or | Op::Xor => 1,
        }
    }

    fn apply(self, a: f32, b: f32) -> Result<f32, ErrorKind> {
        let bool = |x: bool| f32::from(u8::from(x));
        let r = match self {
            Op::Pow => {
                if a < 0.0 && floorf(b) != b {
                    return Err(ErrorKind::DomainError);
                }
                powf(a, b)
            }
            Op::Mul => a * b,
            Op::Div | Op::Mod if b == 0.0 => return Err(ErrorKind::DivisionByZero),
            Op::Div => a / b,
            Op::Mod => {
                // LinuxCNC's MOD: the result takes the divisor's magnitude, never negative.
                let m = fmodf(a, b);
                if m < 0.0 {
                    m + b.abs()
                } else {
                    m
                }
            }
            Op::Add => a + b,
            Op::Sub => a - b,
            Op::Eq => bool(a == b),
            Op::Ne => bool(a != b),
            Op::Gt => bool(a > b),
            Op::Ge => bool(a >= b),
            Op::Lt => bool(a < b),
            Op::Le => bool(a <= b),
            Op::And => bool(a != 0.0 && b != 0.0),
            Op::Or => bool(a != 0.0 || b != 0.0),
            Op::Xor => bool((a != 0.0) ^ (b != 0.0)),
        };
        finite(r)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Func {
    Abs,
    Acos,
    Asin,
    Cos,
    Sin,
    Tan,
    Exp,
    Fix,
    Fup,
    Round,
    Ln,
    Sqrt,
    Atan,
}

impl Func {
    fn of(w: &[u8; 6]) -> Option<Func> {
        Some(match w {
            b"ABS\0\0\0" => Func::Abs,
            b"ACOS\0\0" => Func::Acos,
            b"ASIN\0\0" => Func::Asin,
            b"COS\0\0\0" => Func::Cos,
            b"SIN\0\0\0" => Func::Sin,
            b"TAN\0\0\0" => Func::Tan,
            b"EXP\0\0\0" => Func::Exp,
            b"FIX\0\0\0" => Func::Fix,
            b"FUP\0\0\0" => Func::Fup,
            b"ROUND\0" => Func::Round,
            b"LN\0\0\0\0" => Func::Ln,
            b"SQRT\0\0" => Func::Sqrt,
            b"ATAN\0\0" => Func::Atan,
            _ => return None,
        })
    }

    fn apply(self, a: f32) -> Result<f32, ErrorKind> {
        let dom = |ok: bool| {
            if ok {
                Ok(())
            } else {
                Err(ErrorKind::DomainError)
            }
        };
        let v = match self {
            Func::Abs => a.abs(),
            Func::Acos => {
                dom((-1.0..=1.0).contains(&a))?;
                libm::acosf(a) / DEG
            }
            Func::Asin => {
                dom((-1.0..=1.0).contains(&a))?;
                asin(a) / DEG
            }
            Func::Cos => sin_cos_deg(a).1,
            Func::Sin => sin_cos_deg(a).0,
            Func::Tan => {
                let (s, c) = sin_cos_deg(a);
                s / c
            }
            Func::Exp => expf(a),
            Func::Fix => floorf(a),
            Func::Fup => ceilf(a),
            Func::Round => roundf(a),
            Func::Ln => {
                dom(a > 0.0)?;
                logf(a)
            }
            Func::Sqrt => {
                dom(a >= 0.0)?;
                crate::num::sqrt(a)
            }
            // Handled by the caller: it takes a second bracket.
            Func::Atan => a,
        };
        finite(v)
    }
}

/// A parsed `#` reference.
#[derive(Clone, Copy, Debug)]
pub(crate) enum ParamRef {
    Num(u16),
    Named(Name),
}

#[cfg(test)]
mod tests {
    use super::super::lexer::Cursor;
    use super::super::params::Params;
    use super::*;

    fn eval(text: &str) -> Result<f32, ErrorKind> {
        let mut p = Params::new();
        let mut a = Name::empty();
        let _ = a.push(b'a');
        let _ = p.set_name(&a, 2.0);
        let _ = p.set_num(1, 3.0);
        let mut c = Cursor {
            line: text.as_bytes(),
            pos: 0,
        };
        c.real(&mut p, 0).map_err(|e| e.kind)
    }

    /// Precedence and the prefixes on the explicit stack (LinuxCNC's order).
    #[test]
    fn precedence_prefixes_and_functions() {
        assert_eq!(eval("[1+2*3**2]"), Ok(19.0));
        assert_eq!(eval("[2**3 MOD 5]"), Ok(3.0));
        assert_eq!(eval("[1 LT 2 AND 3 GT 2]"), Ok(1.0));
        assert_eq!(eval("[10-4-3]"), Ok(3.0), "left-associative");
        assert_eq!(eval("-#1"), Ok(-3.0));
        assert_eq!(eval("#[0+1]"), Ok(3.0));
        assert_eq!(eval("[#1+1]"), Ok(4.0), "# binds tighter than +");
        assert_eq!(eval("ATAN[1]/[1]"), Ok(45.0));
        assert_eq!(eval("[SQRT[16]+ABS[-2]]"), Ok(6.0));
        assert_eq!(eval("[EXISTS[#<a>]+EXISTS[#<b>]]"), Ok(1.0));
        assert_eq!(eval("[1/0]"), Err(ErrorKind::DivisionByZero));
        assert_eq!(eval("[1+2"), Err(ErrorKind::UnbalancedBrackets));
        assert_eq!(eval("[1 FOO 2]"), Err(ErrorKind::UnknownOperation));
    }

    /// Nesting is bounded by the frames, not by recursion: 127 brackets
    /// (more than a 256-byte line can hold) evaluate, 129 are refused.
    #[test]
    fn nesting_is_bounded_by_the_stack_of_frames() {
        let deep = |n: usize| format!("{}1{}", "[".repeat(n), "]".repeat(n));
        assert_eq!(eval(&deep(127)), Ok(1.0));
        assert_eq!(
            eval(&deep(MAX_DEPTH + 1)),
            Err(ErrorKind::ExpressionTooDeep)
        );
    }
}
