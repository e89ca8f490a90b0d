//! GRBL `$` system commands. They are recognised on the link, before the
//! G-code parser, because they control the machine rather than move it and
//! several must work in the alarm state.

use protocol::Code;

/// What `$RST=` restores.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Restore {
    /// `$RST=$`: settings to defaults.
    Settings,
    /// `$RST=#`: work offsets to zero.
    Offsets,
    /// `$RST=*`: everything.
    All,
}

/// A parsed `$` command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SysCmd<'a> {
    /// `$`: help text.
    Help,
    /// `$$`: list settings.
    ListSettings,
    /// `$n`: one setting (grblHAL extension).
    GetSetting(u16),
    /// `$n=v`.
    SetSetting { n: u16, value: f32 },
    /// `$#`: work offsets, G28/G30, G92, TLO, probe.
    Params,
    /// `$G`: parser modal state (`[GC:…]`).
    ParserState,
    /// `$I`: build info.
    BuildInfo,
    /// `$N`: startup lines.
    StartupLines,
    /// `$H` (all axes, mask 0) or `$HX`, `$HXY`… (those axes).
    Home(u8),
    /// `$X`: clear the alarm lock.
    Unlock,
    /// `$C`: toggle check mode.
    CheckMode,
    /// `$J=…`: the jog line after `=`; validated by the G-code side.
    Jog(&'a [u8]),
    /// `$SLP`: sleep.
    Sleep,
    /// `$RST=…`.
    Restore(Restore),
}

/// Parse a line if it is a `$` command: `None` for G-code lines, else the
/// command or the error to report (`error:N`).
pub fn parse(line: &[u8]) -> Option<Result<SysCmd<'_>, Code>> {
    let line = trim(line);
    let rest = line.strip_prefix(b"$")?;
    Some(parse_rest(rest))
}

fn parse_rest(rest: &[u8]) -> Result<SysCmd<'_>, Code> {
    // Jog keeps its body verbatim (spaces and comments are the parser's job).
    if let Some(body) = strip_prefix_ci(rest, b"J=") {
        return Ok(SysCmd::Jog(body));
    }
    let mut buf = [0u8; 24];
    let n = compact(rest, &mut buf).ok_or(Code::InvalidStatement)?;
    let cmd = buf.get(..n).ok_or(Code::InvalidStatement)?;
    Ok(match cmd {
        b"" => SysCmd::Help,
        b"$" => SysCmd::ListSettings,
        b"#" => SysCmd::Params,
        b"G" => SysCmd::ParserState,
        b"I" => SysCmd::BuildInfo,
        b"N" => SysCmd::StartupLines,
        b"X" => SysCmd::Unlock,
        b"C" => SysCmd::CheckMode,
        b"SLP" => SysCmd::Sleep,
        b"RST=$" => SysCmd::Restore(Restore::Settings),
        b"RST=#" => SysCmd::Restore(Restore::Offsets),
        b"RST=*" => SysCmd::Restore(Restore::All),
        [b'H', axes @ ..] => SysCmd::Home(axis_mask(axes)?),
        [b'0'..=b'9', ..] => setting(cmd)?,
        _ => return Err(Code::InvalidStatement),
    })
}

fn setting(cmd: &[u8]) -> Result<SysCmd<'static>, Code> {
    let (num, value) = match cmd.iter().position(|&b| b == b'=') {
        Some(eq) => {
            let (num, rest) = cmd.split_at(eq);
            (num, Some(rest.get(1..).unwrap_or(&[])))
        }
        None => (cmd, None),
    };
    let n = parse_u16(num).ok_or(Code::InvalidStatement)?;
    match value {
        None => Ok(SysCmd::GetSetting(n)),
        Some(v) => Ok(SysCmd::SetSetting {
            n,
            value: parse_f32(v).ok_or(Code::BadNumber)?,
        }),
    }
}

fn axis_mask(letters: &[u8]) -> Result<u8, Code> {
    let mut mask = 0;
    for &l in letters {
        let i = crate::AXIS_NAMES
            .iter()
            .position(|&a| a as u32 == u32::from(l))
            .ok_or(Code::InvalidStatement)?;
        mask |= 1 << i;
    }
    Ok(mask)
}

fn parse_u16(digits: &[u8]) -> Option<u16> {
    if digits.is_empty() || digits.len() > 5 || !digits.iter().all(u8::is_ascii_digit) {
        return None;
    }
    core::str::from_utf8(digits).ok()?.parse().ok()
}

/// Plain decimal numbers only: GRBL's syntax, no `inf`, `nan` or exponents.
pub use crate::num::parse_f32;

/// Upper-case and drop spaces (GRBL is case- and space-insensitive in `$`
/// commands). `None` if it does not fit: no `$` command is that long.
fn compact(src: &[u8], out: &mut [u8]) -> Option<usize> {
    let mut n = 0;
    for &b in src.iter().filter(|b| !b.is_ascii_whitespace()) {
        *out.get_mut(n)? = b.to_ascii_uppercase();
        n += 1;
    }
    Some(n)
}

fn strip_prefix_ci<'a>(s: &'a [u8], prefix: &[u8]) -> Option<&'a [u8]> {
    let head = s.get(..prefix.len())?;
    head.eq_ignore_ascii_case(prefix)
        .then(|| s.get(prefix.len()..))
        .flatten()
}

fn trim(s: &[u8]) -> &[u8] {
    let start = s
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(s.len());
    let end = s
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(start, |e| e + 1);
    s.get(start..end).unwrap_or(&[])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands() {
        assert_eq!(parse(b"G1 X1"), None);
        assert_eq!(parse(b"$$"), Some(Ok(SysCmd::ListSettings)));
        assert_eq!(parse(b" $x "), Some(Ok(SysCmd::Unlock)));
        assert_eq!(parse(b"$H"), Some(Ok(SysCmd::Home(0))));
        assert_eq!(parse(b"$HZ"), Some(Ok(SysCmd::Home(4))));
        assert_eq!(parse(b"$HQ"), Some(Err(Code::InvalidStatement)));
        assert_eq!(
            parse(b"$110 = 5000.5"),
            Some(Ok(SysCmd::SetSetting {
                n: 110,
                value: 5000.5
            }))
        );
        assert_eq!(parse(b"$110=abc"), Some(Err(Code::BadNumber)));
        assert_eq!(parse(b"$110=inf"), Some(Err(Code::BadNumber)));
        assert_eq!(parse(b"$110="), Some(Err(Code::BadNumber)));
        assert_eq!(parse(b"$99999999=1"), Some(Err(Code::InvalidStatement)));
        assert_eq!(
            parse(b"$J=G91 X1 F100"),
            Some(Ok(SysCmd::Jog(b"G91 X1 F100")))
        );
        assert_eq!(parse(b"$RST=*"), Some(Ok(SysCmd::Restore(Restore::All))));
        assert_eq!(parse(b"$Q"), Some(Err(Code::InvalidStatement)));
        assert_eq!(parse(b"$"), Some(Ok(SysCmd::Help)));
    }
}
