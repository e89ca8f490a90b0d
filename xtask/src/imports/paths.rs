//! One file's module declarations and the paths in it that reach the
//! crate root, read from its tokens.

use super::lex::{Kind, Token};

/// A `mod name;` declaration.
pub struct ModDecl {
    pub name: String,
    /// inline `mod a { … }` blocks it sits in
    pub inline: Vec<String>,
    pub path_attr: Option<String>,
    pub line: usize,
}

/// What one file declares and which crate-root names it reaches.
pub struct FileScan {
    pub mods: Vec<ModDecl>,
    /// (first segment after the crate root, line, path as written)
    pub roots: Vec<(String, usize, String)>,
}

fn ident(t: Option<&Token>) -> Option<&str> {
    match t.map(|t| &t.kind) {
        Some(Kind::Ident(s)) => Some(s),
        _ => None,
    }
}

fn is(t: Option<&Token>, k: &Kind) -> bool {
    t.is_some_and(|t| &t.kind == k)
}

pub fn read_file(toks: &[Token], module: &[String]) -> FileScan {
    let mut out = FileScan {
        mods: Vec::new(),
        roots: Vec::new(),
    };
    // inline modules we are inside: (name, brace depth inside it)
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut path_attr: Option<String> = None;
    let mut i = 0;
    while i < toks.len() {
        let t = &toks[i];
        match &t.kind {
            Kind::Punct('{') => depth += 1,
            Kind::Punct('}') => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
                path_attr = None;
            }
            Kind::Punct(';') => path_attr = None,
            Kind::Punct('#')
                if is(toks.get(i + 1), &Kind::Punct('['))
                    && ident(toks.get(i + 2)) == Some("path")
                    && is(toks.get(i + 3), &Kind::Punct('=')) =>
            {
                if let Some(Kind::Str(p)) = toks.get(i + 4).map(|t| &t.kind) {
                    path_attr = Some(p.clone());
                }
            }
            Kind::Ident(kw) if kw == "mod" => {
                if let Some(name) = ident(toks.get(i + 1)) {
                    if is(toks.get(i + 2), &Kind::Punct(';')) {
                        out.mods.push(ModDecl {
                            name: name.to_string(),
                            inline: inline.iter().map(|(n, _)| n.clone()).collect(),
                            path_attr: path_attr.take(),
                            line: t.line,
                        });
                        i += 3;
                        continue;
                    }
                    if is(toks.get(i + 2), &Kind::Punct('{')) {
                        depth += 1;
                        inline.push((name.to_string(), depth));
                        path_attr = None;
                        i += 3;
                        continue;
                    }
                }
            }
            Kind::Ident(kw)
                if matches!(kw.as_str(), "crate" | "super" | "self")
                    && is(toks.get(i + 1), &Kind::PathSep)
                    && !(i > 0 && is(toks.get(i - 1), &Kind::PathSep)) =>
            {
                let here = module.len() + inline.len();
                let (climb, next) = climb(toks, i);
                let at_root = match kw.as_str() {
                    "crate" => true,
                    "super" => climb >= here,
                    _ => here == 0,
                };
                if at_root {
                    for (name, line) in first_segments(toks, next) {
                        let written = written(toks, i);
                        out.roots.push((name, line, written));
                    }
                }
                i = next;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// How many `super::` a path starting at `i` climbs, and the index of the
/// token after its last leading `crate::`/`self::`/`super::`.
fn climb(toks: &[Token], mut i: usize) -> (usize, usize) {
    let mut n = 0;
    while let Some(kw) = ident(toks.get(i)) {
        if !matches!(kw, "crate" | "super" | "self") || !is(toks.get(i + 1), &Kind::PathSep) {
            break;
        }
        if kw == "super" {
            n += 1;
        }
        i += 2;
    }
    (n, i)
}

/// The names a path continues with at `i`: one identifier, or the first
/// identifier of each item of a `{ … }` use group; `*` for a glob.
fn first_segments(toks: &[Token], i: usize) -> Vec<(String, usize)> {
    if let Some(name) = ident(toks.get(i)) {
        return vec![(name.to_string(), toks[i].line)];
    }
    if is(toks.get(i), &Kind::Punct('*')) {
        return vec![("*".to_string(), toks[i].line)];
    }
    let mut out = Vec::new();
    if !is(toks.get(i), &Kind::Punct('{')) {
        return out;
    }
    let mut depth = 0;
    let mut item_start = true;
    for t in &toks[i..] {
        match &t.kind {
            Kind::Punct('{') => {
                depth += 1;
                if depth == 1 {
                    item_start = true;
                }
            }
            Kind::Punct('}') => {
                depth -= 1;
                if depth == 0 {
                    break;
                }
            }
            Kind::Punct(',') if depth == 1 => item_start = true,
            Kind::Ident(name) if depth == 1 && item_start => {
                out.push((name.clone(), t.line));
                item_start = false;
            }
            Kind::Punct('*') if depth == 1 && item_start => {
                out.push(("*".to_string(), t.line));
                item_start = false;
            }
            _ if depth == 1 => item_start = false,
            _ => {}
        }
    }
    out
}

/// A path as written from `i`, up to three segments past its root (enough
/// to find it in the file).
fn written(toks: &[Token], i: usize) -> String {
    let mut s = String::new();
    let mut segs = 0;
    let mut want_ident = true;
    for t in &toks[i..] {
        match (&t.kind, want_ident) {
            (Kind::Ident(name), true) => {
                if !matches!(name.as_str(), "crate" | "super" | "self") {
                    segs += 1;
                }
                s.push_str(name);
                if segs == 3 {
                    break;
                }
            }
            (Kind::PathSep, false) => s.push_str("::"),
            (Kind::Punct('{'), true) => {
                s.push_str("{…}");
                break;
            }
            (Kind::Punct('*'), true) => {
                s.push('*');
                break;
            }
            _ => break,
        }
        want_ident = !want_ident;
    }
    s
}
