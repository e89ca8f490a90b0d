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

use core::fmt::Write;

/// The last accepted RepRap line number.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LineNumbers {
    last: i32,
}

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
}

fn int(s: &[u8]) -> Option<(i32, &[u8])> {
    let s = s.trim_ascii_start();
    let (neg, s) = match s.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, s),
    };
    let digits = s.iter().take_while(|b| b.is_ascii_digit()).count();
    if digits == 0 || digits > 9 {
        return None;
    }
    let (num, rest) = s.split_at(digits);
    // At most 9 digits: no overflow.
    let v = num.iter().fold(0i32, |v, d| v * 10 + i32::from(d - b'0'));
    Some((if neg { -v } else { v }, rest))
}

/// `M110` (not `M1100`), and its `N` parameter if any.
fn m110(body: &[u8]) -> Option<Option<i32>> {
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
            if let Some(set) = m110(t) {
                if let Some(n) = set {
                    self.last = n;
                }
                return Numbered::Set;
            }
            return Numbered::Plain;
        };
        let (head, tail) = t.split_at(star);
        let want = tail.get(1..).and_then(int).map_or(-1, |(v, _)| v);
        let got = head.iter().fold(0u8, |x, b| x ^ b);
        if i32::from(got) != want {
            return Numbered::Resend { checksum: true };
        }
        let Some((n, body)) = head.get(1..).and_then(int) else {
            return Numbered::Resend { checksum: true };
        };
        if let Some(set) = m110(body) {
            self.last = set.unwrap_or(n);
            return Numbered::Set;
        }
        if n != self.last.wrapping_add(1) {
            return Numbered::Resend { checksum: false };
        }
        self.last = n;
        Numbered::Run(body)
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
            self.last.wrapping_add(1)
        );
    }
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
}
