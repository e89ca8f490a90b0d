//! RepRap / Marlin line numbering in text mode, for hosts such as printcore
//! (Pronterface) and OctoPrint that stream `N<n> <line>*<checksum>`.
//!
//! What those hosts rely on (from the behaviour they expect, no code taken):
//!
//! * `M110 N<n>` sets the number of the last line (`N-1 M110 N-1*125` opens
//!   a printcore session: the next line is `N0`).
//! * A line with a number and a checksum must be numbered last + 1 and its
//!   checksum (XOR of every byte before `*`) must match; otherwise the reply
//!   is `Error:…`, `Resend: <last + 1>` and `ok`, and the line is not run.
//!   A line sent again after it ran (a duplicate) is refused the same way,
//!   so every line runs once.
//!
//! Lines without a checksum are plain GRBL lines: their `N` is a label and
//! is not checked (GRBL senders number lines freely, or not at all).
//!
//! Numbers are Marlin's: a 32-bit `long`, so up to 2^31 − 1 (and down to
//! −2^31). A number beyond is refused with an error of its own and no
//! `Resend:` (issue 35): asking for it again would only bring it back.

use core::fmt::Write;

/// The last accepted RepRap line number.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LineNumbers {
    last: i32,
}

/// A line number (or `M110`'s `N`) that does not fit Marlin's `long`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct OutOfRange;

/// What to do with a text line.
#[derive(Debug, PartialEq)]
pub(super) enum Numbered<'a> {
    /// No RepRap framing: run the line as it is.
    Plain,
    /// In order and intact: run `body` (without its number and checksum).
    Run(&'a [u8]),
    /// `M110`: the number was set; reply `ok`.
    Set,
    /// Refused; reply with [`resend`] and run nothing.
    Resend { checksum: bool },
    /// An intact line whose number (or `M110 N`) is beyond ±2^31: reply
    /// with [`out_of_range`] and run nothing.
    OutOfRange,
}

/// A signed decimal integer (any number of digits) and what follows it;
/// `None` without digits.
fn int(s: &[u8]) -> Option<(Result<i32, OutOfRange>, &[u8])> {
    let s = s.trim_ascii_start();
    let (neg, s) = match s.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, s),
    };
    let digits = s.iter().take_while(|b| b.is_ascii_digit()).count();
    if digits == 0 {
        return None;
    }
    let (num, rest) = s.split_at(digits);
    // Held at 2^32 once past it: out of range either way, and no overflow
    // however many digits follow.
    let v = num
        .iter()
        .fold(0i64, |v, d| (v * 10 + i64::from(d - b'0')).min(1 << 32));
    let v = if neg { -v } else { v };
    Some((i32::try_from(v).map_err(|_| OutOfRange), rest))
}

/// `M110` (not `M1100`), and its `N` parameter if any.
fn m110(body: &[u8]) -> Option<Option<Result<i32, OutOfRange>>> {
    let b = body.trim_ascii_start();
    let (head, rest) = b.split_at_checked(4)?;
    if !head.eq_ignore_ascii_case(b"M110") || rest.first().is_some_and(u8::is_ascii_digit) {
        return None;
    }
    let n = rest
        .iter()
        .position(|c| c.eq_ignore_ascii_case(&b'N'))
        .and_then(|i| rest.get(i + 1..))
        .and_then(int)
        .map(|(v, _)| v);
    Some(n)
}

/// A leading `N` word's number (GRBL's line label, `Ln:`), when above 0
/// and within `u32`.
pub(super) fn label(text: &[u8]) -> Option<u32> {
    let t = text.trim_ascii_start();
    let (first, rest) = t.split_first()?;
    if !first.eq_ignore_ascii_case(&b'N') {
        return None;
    }
    let digits = rest.iter().take_while(|b| b.is_ascii_digit()).count();
    let num = rest
        .get(..digits)
        .filter(|d| !d.is_empty() && d.len() <= 9)?;
    let n = num.iter().fold(0u32, |v, d| v * 10 + u32::from(d - b'0'));
    (n > 0).then_some(n)
}

impl LineNumbers {
    pub(super) fn check<'a>(&mut self, text: &'a [u8]) -> Numbered<'a> {
        let t = text.trim_ascii();
        // The checksum: a top-level `*` followed by digits only.
        let star = t.iter().rposition(|&b| b == b'*');
        let sum = star.and_then(|i| {
            let digits = t.get(i + 1..)?;
            let ok = !digits.is_empty() && digits.iter().all(u8::is_ascii_digit);
            ok.then_some(i)
        });
        let numbered = t.first().is_some_and(|b| b.eq_ignore_ascii_case(&b'N'));
        let (Some(star), true) = (sum, numbered) else {
            // Plain M110 (no number, no checksum) still sets the number.
            return match m110(t) {
                Some(Some(Err(OutOfRange))) => Numbered::OutOfRange,
                Some(set) => {
                    if let Some(Ok(n)) = set {
                        self.last = n;
                    }
                    Numbered::Set
                }
                None => Numbered::Plain,
            };
        };
        let (head, tail) = t.split_at(star);
        let want = tail
            .get(1..)
            .and_then(int)
            .map_or(Err(OutOfRange), |(v, _)| v);
        let got = head.iter().fold(0u8, |x, b| x ^ b);
        if want != Ok(i32::from(got)) {
            return Numbered::Resend { checksum: true };
        }
        let Some((n, body)) = head.get(1..).and_then(int) else {
            return Numbered::Resend { checksum: true };
        };
        let Ok(n) = n else {
            return Numbered::OutOfRange;
        };
        if let Some(set) = m110(body) {
            return match set.unwrap_or(Ok(n)) {
                Ok(v) => {
                    self.last = v;
                    Numbered::Set
                }
                Err(OutOfRange) => Numbered::OutOfRange,
            };
        }
        // In i64: after 2^31 − 1 nothing is next (no wrap to −2^31).
        if i64::from(n) != self.next() {
            return Numbered::Resend { checksum: false };
        }
        self.last = n;
        Numbered::Run(body)
    }

    /// The number the next line must carry; 2^31 after the last number.
    fn next(&self) -> i64 {
        i64::from(self.last) + 1
    }

    /// The reply to a refused line: an error, `Resend:` and `ok`, as
    /// Marlin answers, so send-response hosts stay in step.
    pub(super) fn resend(&self, checksum: bool, o: &mut impl Write) {
        let why = if checksum {
            "checksum mismatch"
        } else {
            "Line Number is not Last Line Number+1"
        };
        let _ = write!(
            o,
            "Error:{why}, Last Line: {}\r\nResend: {}\r\nok\r\n",
            self.last,
            self.next()
        );
    }
}

/// The reply to [`Numbered::OutOfRange`]: an error and `ok`, no `Resend:`
/// (the host would send the same number again, for ever). The wording
/// avoids "line number" and "checksum", which hosts such as OctoPrint take
/// for a transmission error that a resend repairs.
pub(super) fn out_of_range(o: &mut impl Write) {
    let _ = write!(
        o,
        "Error:N out of range ({}..{}), not run; renumber with M110\r\nok\r\n",
        i32::MIN,
        i32::MAX
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cs(line: &str) -> String {
        let x = line.bytes().fold(0u8, |x, b| x ^ b);
        format!("{line}*{x}")
    }

    #[test]
    fn printcore_session() {
        let mut n = LineNumbers::default();
        assert_eq!(n.check(b"N-1 M110 N-1*125"), Numbered::Set);
        assert_eq!(n.check(cs("N0 G1 X1").as_bytes()), Numbered::Run(b" G1 X1"));
        // Lost line 1: line 2 is refused, 1 is asked for.
        assert_eq!(
            n.check(cs("N2 G1 X3").as_bytes()),
            Numbered::Resend { checksum: false }
        );
        let mut s = String::new();
        n.resend(false, &mut s);
        assert!(s.contains("Resend: 1\r\nok\r\n"), "{s}");
        assert_eq!(n.check(b"N1 G1 X2*0"), Numbered::Resend { checksum: true });
        assert_eq!(n.check(cs("N1 G1 X2").as_bytes()), Numbered::Run(b" G1 X2"));
        // A duplicate of a line that ran is not run again.
        assert_eq!(
            n.check(cs("N1 G1 X2").as_bytes()),
            Numbered::Resend { checksum: false }
        );
        assert_eq!(n.check(b"N10 G1 X5"), Numbered::Plain);
        assert_eq!(n.check(b"G1 X5"), Numbered::Plain);
        assert_eq!(n.check(b"M110 N100"), Numbered::Set);
        assert_eq!(
            n.check(cs("N101 M1100").as_bytes()),
            Numbered::Run(b" M1100")
        );
        assert_eq!(n.check(b"#1=[2*3]"), Numbered::Plain);
    }

    /// Issue 35 item 4: numbers of 10 digits were refused as a checksum
    /// mismatch, for ever. Marlin's range is a 32-bit `long`.
    #[test]
    fn numbers_up_to_2_pow_31_minus_1() {
        let mut n = LineNumbers::default();
        assert_eq!(cs("N2147483647 G4 P0"), "N2147483647 G4 P0*87");
        assert_eq!(n.check(b"M110 N2147483646"), Numbered::Set);
        assert_eq!(n.check(b"N2147483647 G4 P0*87"), Numbered::Run(b" G4 P0"));
        // Nothing comes after 2^31 - 1: not 2^31 (out of range, no resend
        // of it) and not -2^31 (no wrap).
        assert_eq!(
            n.check(cs("N2147483648 G4 P0").as_bytes()),
            Numbered::OutOfRange
        );
        assert_eq!(
            n.check(cs("N-2147483648 G4 P0").as_bytes()),
            Numbered::Resend { checksum: false }
        );
        let mut s = String::new();
        n.resend(false, &mut s);
        assert!(
            s.contains("Last Line: 2147483647\r\nResend: 2147483648\r\n"),
            "{s}"
        );
        let mut e = String::new();
        out_of_range(&mut e);
        assert!(e.starts_with("Error:") && e.ends_with("\r\nok\r\n"), "{e}");
        assert!(
            !e.contains("Resend") && !e.to_lowercase().contains("line number"),
            "{e}"
        );
        // M110 takes any such number, in both forms, and refuses beyond.
        assert_eq!(n.check(b"M110 N2147483648"), Numbered::OutOfRange);
        assert_eq!(
            n.check(b"M110 N99999999999999999999999"),
            Numbered::OutOfRange
        );
        assert_eq!(
            n.check(cs("N7 M110 N2147483648").as_bytes()),
            Numbered::OutOfRange
        );
        assert_eq!(
            n.check(cs("N7 M110 N-2147483649").as_bytes()),
            Numbered::OutOfRange
        );
        assert_eq!(
            n.check(cs("N7 M110 N-2147483648").as_bytes()),
            Numbered::Set
        );
        assert_eq!(
            n.check(cs("N-2147483647 G1 X1").as_bytes()),
            Numbered::Run(b" G1 X1")
        );
        assert_eq!(n.check(cs("N1 M110 N0999999999").as_bytes()), Numbered::Set);
        assert_eq!(
            n.check(cs("N1000000000 G1").as_bytes()),
            Numbered::Run(b" G1")
        );
        assert_eq!(n.check(b"M110 N2147483647"), Numbered::Set);
        // An out-of-range number with a bad checksum is a damaged line.
        assert_eq!(
            n.check(b"N2147483648 G4 P0*1"),
            Numbered::Resend { checksum: true }
        );
        assert_eq!(
            n.check(b"N2147483648 G4 P0*99999999999"),
            Numbered::Resend { checksum: true }
        );
    }
}
