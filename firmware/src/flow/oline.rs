//! Reading an O-word line (`O100 while [#1 LT 3]`, `o<probe> call [2]`)
//! and compacting the lines a block captures.

use crate::gcode::{ErrorKind, GcodeError, Name, OWord};

/// The flow-control keywords (LinuxCNC's O-codes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kw {
    Sub,
    EndSub,
    Call,
    Return,
    If,
    ElseIf,
    Else,
    EndIf,
    While,
    EndWhile,
    Do,
    Repeat,
    EndRepeat,
    Break,
    Continue,
}

const KEYWORDS: [(&[u8], Kw); 15] = [
    (b"sub", Kw::Sub),
    (b"endsub", Kw::EndSub),
    (b"call", Kw::Call),
    (b"return", Kw::Return),
    (b"if", Kw::If),
    (b"elseif", Kw::ElseIf),
    (b"else", Kw::Else),
    (b"endif", Kw::EndIf),
    (b"while", Kw::While),
    (b"endwhile", Kw::EndWhile),
    (b"do", Kw::Do),
    (b"repeat", Kw::Repeat),
    (b"endrepeat", Kw::EndRepeat),
    (b"break", Kw::Break),
    (b"continue", Kw::Continue),
];

/// One O-word line: its name (`100` for `O100`, `probe` for `O<probe>`),
/// keyword, and where its arguments start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OLine {
    pub name: Name,
    pub kw: Kw,
    pub args: usize,
}

fn blank(b: u8) -> bool {
    b == b' ' || b == b'\t' || b == b'\r'
}

fn skip_blanks(line: &[u8], mut i: usize) -> usize {
    while line.get(i).is_some_and(|&b| blank(b)) {
        i += 1;
    }
    i
}

fn syntax(i: usize) -> GcodeError {
    GcodeError::new(
        ErrorKind::OWord(OWord::Syntax),
        (i + 1).min(usize::from(u16::MAX)) as u16,
    )
}

/// `None` when the line is not an O-word line (its first word, after an
/// optional `N` number, is not `O`); otherwise the parsed line or why not.
pub fn parse(line: &[u8]) -> Option<Result<OLine, GcodeError>> {
    let mut i = skip_blanks(line, 0);
    if matches!(line.get(i), Some(b'N' | b'n')) {
        i = skip_blanks(line, i + 1);
        while line.get(i).is_some_and(|b| b.is_ascii_digit() || blank(*b)) {
            i += 1;
        }
    }
    if !matches!(line.get(i), Some(b'O' | b'o')) {
        return None;
    }
    Some(parse_at(line, i))
}

fn parse_at(line: &[u8], at: usize) -> Result<OLine, GcodeError> {
    let mut i = skip_blanks(line, at + 1);
    let mut name = Name::empty();
    let push = |name: &mut Name, b: u8, i: usize| name.push(b).map_err(|_| syntax(i));
    match line.get(i) {
        Some(b'<') => {
            i += 1;
            loop {
                match line.get(i) {
                    Some(b'>') => break,
                    Some(&b) if blank(b) => {}
                    Some(&b) if b.is_ascii_graphic() => push(&mut name, b, i)?,
                    _ => return Err(syntax(i)),
                }
                i += 1;
            }
            i += 1;
        }
        Some(b) if b.is_ascii_digit() => {
            // O0100 and O100 are one name.
            while let Some(&b) = line.get(i) {
                if !b.is_ascii_digit() {
                    break;
                }
                if b != b'0' || !name.as_bytes().is_empty() {
                    push(&mut name, b, i)?;
                }
                i += 1;
            }
            if name.as_bytes().is_empty() {
                push(&mut name, b'0', i)?;
            }
        }
        _ => return Err(syntax(i)),
    }
    if name.as_bytes().is_empty() {
        return Err(syntax(at));
    }
    let k = skip_blanks(line, i);
    let mut e = k;
    while line.get(e).is_some_and(u8::is_ascii_alphabetic) {
        e += 1;
    }
    let word = line.get(k..e).unwrap_or(&[]);
    let kw = KEYWORDS
        .iter()
        .find(|(w, _)| w.eq_ignore_ascii_case(word))
        .map(|&(_, kw)| kw)
        .ok_or_else(|| syntax(k))?;
    Ok(OLine { name, kw, args: e })
}

/// The byte after blanks and comments from `i`; an error if anything else
/// follows (an O-word line carries no other words).
pub fn end(line: &[u8], mut i: usize) -> Result<(), GcodeError> {
    loop {
        i = skip_blanks(line, i);
        match line.get(i) {
            None | Some(b';' | b'\n') => return Ok(()),
            Some(b'(') => match line
                .get(i..)
                .and_then(|r| r.iter().position(|&b| b == b')'))
            {
                Some(p) => i += p + 1,
                None => return Err(syntax(i)),
            },
            Some(_) => return Err(syntax(i)),
        }
    }
}

/// True when an argument (a value, not a comment) starts at or after `i`.
pub fn has_arg(line: &[u8], i: usize) -> bool {
    let i = skip_blanks(line, i);
    !matches!(line.get(i), None | Some(b';' | b'(' | b'\n'))
}

/// `src` as it is stored in a capture: comments other than `(MSG,…)` and
/// `;` tails dropped, runs of blanks made one space, ends trimmed. The
/// lexer ignores blanks outside comments, so the line means the same.
/// Lines with `M117` text or a top-level `*` (a checksum covers the bytes)
/// are only trimmed. Returns the length written to `dst`.
pub fn compact(src: &[u8], dst: &mut [u8]) -> usize {
    let verbatim = has_text(src);
    let mut n = 0;
    let mut put = |b: u8, n: &mut usize| {
        if let Some(d) = dst.get_mut(*n) {
            *d = b;
            *n += 1;
        }
    };
    let mut i = 0;
    let mut gap = false;
    while let Some(&b) = src.get(i) {
        if b == b'\n' {
            break;
        }
        if verbatim {
            put(b, &mut n);
            i += 1;
            continue;
        }
        match b {
            b';' => break,
            b'(' => {
                let close = src.get(i..).and_then(|r| r.iter().position(|&c| c == b')'));
                let body = src.get(i + 1..).unwrap_or(&[]);
                let msg = body
                    .iter()
                    .position(|&c| !blank(c))
                    .and_then(|s| body.get(s..s + 3))
                    .is_some_and(|m| m.eq_ignore_ascii_case(b"msg"));
                match close {
                    // Unclosed: kept for the lexer to refuse.
                    None => {
                        for &c in src.get(i..).unwrap_or(&[]) {
                            put(c, &mut n);
                        }
                        break;
                    }
                    Some(p) if msg => {
                        if gap && n > 0 {
                            put(b' ', &mut n);
                        }
                        gap = false;
                        for &c in src.get(i..=i + p).unwrap_or(&[]) {
                            put(c, &mut n);
                        }
                    }
                    Some(_) => gap = true,
                }
                i += close.unwrap_or(0) + 1;
                continue;
            }
            b if blank(b) => gap = true,
            b => {
                if gap && n > 0 {
                    put(b' ', &mut n);
                }
                gap = false;
                put(b, &mut n);
            }
        }
        i += 1;
    }
    while n > 0 && dst.get(n - 1).is_some_and(|&b| blank(b)) {
        n -= 1;
    }
    n
}

/// M117 free text or a top-level `*` (a RepRap checksum): keep the bytes.
fn has_text(src: &[u8]) -> bool {
    let mut depth = 0u32;
    let mut comment = false;
    for (i, &b) in src.iter().enumerate() {
        match b {
            b'(' => comment = true,
            b')' => comment = false,
            _ if comment => {}
            b'[' => depth += 1,
            b']' => depth = depth.saturating_sub(1),
            b'*' if depth == 0 => return true,
            b'M' | b'm' => {
                let rest = src.get(i + 1..).unwrap_or(&[]);
                let digits: heapless::Vec<u8, 4> = rest
                    .iter()
                    .copied()
                    .filter(|&c| !blank(c))
                    .take(4)
                    .collect();
                if digits.starts_with(b"117") && !digits.get(3).is_some_and(u8::is_ascii_digit) {
                    return true;
                }
            }
            _ => {}
        }
    }
    false
}
