//! Just enough of Rust's lexer to read module paths: comments and literals
//! are skipped so a path in a doc comment or a string is not an import.

/// One token and the line it starts on.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    pub kind: Kind,
    pub line: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    Ident(String),
    /// `::`
    PathSep,
    /// A string literal's text between its quotes, escapes left as written
    /// (enough for `#[path = "..."]`).
    Str(String),
    /// Any other single character outside comments and literals.
    Punct(char),
}

/// Tokens of one source file. Never fails: an unterminated comment or
/// literal ends the file, which at worst hides a path after it.
pub fn tokens(src: &str) -> Vec<Token> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line = 1;
    while i < c.len() {
        let ch = c[i];
        let start = line;
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i = block_comment(&c, i, &mut line);
        } else if let Some((end, text)) = string(&c, i, &mut line) {
            out.push(Token {
                kind: Kind::Str(text),
                line: start,
            });
            i = end;
        } else if ch == '\'' || (ch == 'b' && c.get(i + 1) == Some(&'\'')) {
            i = quote(&c, if ch == 'b' { i + 1 } else { i });
        } else if ch == 'r'
            && c.get(i + 1) == Some(&'#')
            && c.get(i + 2).is_some_and(|&n| ident_start(n))
        {
            // raw identifier r#name
            let (end, name) = ident(&c, i + 2);
            out.push(Token {
                kind: Kind::Ident(name),
                line,
            });
            i = end;
        } else if ident_start(ch) {
            let (end, name) = ident(&c, i);
            out.push(Token {
                kind: Kind::Ident(name),
                line,
            });
            i = end;
        } else if ch.is_ascii_digit() {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push(Token {
                kind: Kind::PathSep,
                line,
            });
            i += 2;
        } else {
            out.push(Token {
                kind: Kind::Punct(ch),
                line,
            });
            i += 1;
        }
    }
    out
}

fn ident_start(c: char) -> bool {
    c.is_alphabetic() || c == '_'
}

fn ident(c: &[char], mut i: usize) -> (usize, String) {
    let start = i;
    while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
        i += 1;
    }
    (i, c[start..i].iter().collect())
}

/// `/* … */`, nested as Rust nests them.
fn block_comment(c: &[char], mut i: usize, line: &mut usize) -> usize {
    let mut depth = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            depth += 1;
            i += 2;
        } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            if c[i] == '\n' {
                *line += 1;
            }
            i += 1;
        }
    }
    i
}

/// A string literal at `i` (plain, byte, C, or raw with any number of `#`):
/// where it ends and its text; `None` if none starts here.
fn string(c: &[char], i: usize, line: &mut usize) -> Option<(usize, String)> {
    let mut j = i;
    // prefixes: b, c, r, br, cr
    if matches!(c.get(j), Some('b' | 'c')) {
        j += 1;
    }
    let raw = c.get(j) == Some(&'r');
    if raw {
        j += 1;
    }
    let mut hashes = 0;
    while raw && c.get(j) == Some(&'#') {
        hashes += 1;
        j += 1;
    }
    if c.get(j) != Some(&'"') {
        return None;
    }
    // a prefix letter must not be the end of a longer identifier (`ab"` is not a literal start)
    if j > i && i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_') {
        return None;
    }
    j += 1;
    let body = j;
    while j < c.len() {
        match c[j] {
            '\\' if !raw => j += 2,
            '"' if c[j + 1..]
                .iter()
                .take(hashes)
                .filter(|&&h| h == '#')
                .count()
                == hashes =>
            {
                let text = c[body..j].iter().collect();
                return Some((j + 1 + hashes, text));
            }
            ch => {
                if ch == '\n' {
                    *line += 1;
                }
                j += 1;
            }
        }
    }
    Some((c.len(), c[body..].iter().collect()))
}

/// A char literal or a lifetime/label starting at the `'` at `i`; where it ends.
fn quote(c: &[char], i: usize) -> usize {
    match (c.get(i + 1), c.get(i + 2)) {
        (Some('\\'), _) => {
            let mut j = i + 1;
            while j < c.len() && c[j] != '\'' && c[j] != '\n' {
                j += if c[j] == '\\' { 2 } else { 1 };
            }
            j + 1
        }
        (Some(_), Some('\'')) => i + 3,
        // a lifetime or label: skip the quote, the name lexes as an ident
        _ => i + 1,
    }
}
