//! The import rule of the `burin` library (firmware/DESIGN.md, "Pipeline"):
//! its top-level modules form no cycle, and each imports only modules
//! declared above it in `lib.rs`. Run as a test of `cargo test -p xtask`
//! (`imports::tests::burin_imports_follow_lib_rs_order`), so CI checks it.
//!
//! The compiler accepts cycles between modules of one crate, so nothing else
//! would notice one coming back; a reader of the pipeline would.
//!
//! The modules come from the `mod` declarations, from `lib.rs` down
//! (`#[path]` honoured), not from the file names. An edge A -> B is any
//! path in a file of A that names B: `crate::B…` (also in `use`,
//! `use crate::{B, …}`, inline paths and `$crate` in macros) and
//! `super::…::B` that climbs to the crate root. Comments and literals are
//! skipped: a doc link is not an import.

mod lex;
mod paths;
#[cfg(test)]
mod tests;

use anyhow::{bail, Context, Result};
use paths::read_file;
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Where a path naming another module was written.
#[derive(Debug, Clone)]
pub struct Site {
    pub file: PathBuf,
    pub line: usize,
    /// The path as written, e.g. `crate::interp::Cycle`.
    pub path: String,
}

/// The crate's top-level modules and the edges between them.
#[derive(Debug, Default)]
pub struct Graph {
    /// Top-level modules in `lib.rs` declaration order.
    pub modules: Vec<String>,
    /// from -> to -> every site.
    pub edges: BTreeMap<String, BTreeMap<String, Vec<Site>>>,
    /// Globs of the crate root in a module (`use super::*;` at its top):
    /// they bring every module's name into scope, so the paths below them
    /// no longer say which modules the file uses.
    pub root_globs: Vec<Site>,
}

/// Reads the crate whose root is `lib`.
pub fn scan(lib: &Path) -> Result<Graph> {
    let mut g = Graph::default();
    let root = lib.parent().map(Path::to_path_buf).unwrap_or_default();
    // (file, module path, directory its `mod x;` children live in)
    let mut todo = vec![(lib.to_path_buf(), Vec::new(), root)];
    while let Some((file, module, dir)) = todo.pop() {
        let src = std::fs::read_to_string(&file)
            .with_context(|| format!("reading {}", file.display()))?;
        let found = read_file(&lex::tokens(&src), &module);
        for decl in found.mods {
            let child_dir = dir.join(decl.inline.join("/"));
            let (child_file, grand_dir) = match &decl.path_attr {
                Some(p) => {
                    // `#[path]` is relative to the declaring file's directory
                    // (outside inline modules); the file then owns its directory
                    let base = if decl.inline.is_empty() {
                        file.parent().map(Path::to_path_buf).unwrap_or_default()
                    } else {
                        child_dir.clone()
                    };
                    let f = base.join(p);
                    let d = f.parent().map(Path::to_path_buf).unwrap_or_default();
                    (f, d)
                }
                None => {
                    let flat = child_dir.join(format!("{}.rs", decl.name));
                    let nested = child_dir.join(&decl.name).join("mod.rs");
                    let f = if flat.is_file() { flat } else { nested };
                    (f, child_dir.join(&decl.name))
                }
            };
            if !child_file.is_file() {
                bail!(
                    "{}:{}: `mod {};` has no file at {}",
                    file.display(),
                    decl.line,
                    decl.name,
                    child_file.display()
                );
            }
            let mut path = module.clone();
            path.extend(decl.inline.iter().cloned());
            path.push(decl.name.clone());
            if path.len() == 1 {
                g.modules.push(decl.name.clone());
            }
            todo.push((child_file, path, grand_dir));
        }
        if let Some(from) = module.first() {
            for (to, line, path) in found.roots {
                if to == "*" {
                    g.root_globs.push(Site {
                        file: file.clone(),
                        line,
                        path,
                    });
                    continue;
                }
                g.edges
                    .entry(from.clone())
                    .or_default()
                    .entry(to)
                    .or_default()
                    .push(Site {
                        file: file.clone(),
                        line,
                        path,
                    });
            }
        }
    }
    // Paths that name a root item (`crate::AXES`) or the module itself are not edges.
    let modules: BTreeSet<String> = g.modules.iter().cloned().collect();
    for (from, tos) in g.edges.iter_mut() {
        tos.retain(|to, _| to != from && modules.contains(to));
    }
    g.edges.retain(|_, tos| !tos.is_empty());
    Ok(g)
}

impl Graph {
    /// Every elementary cycle through an edge that lies in a cycle, each the
    /// shortest through that edge, written from its smallest module.
    pub fn cycles(&self) -> Vec<Vec<String>> {
        let mut found = BTreeSet::new();
        for (from, tos) in &self.edges {
            for to in tos.keys() {
                if let Some(mut back) = self.shortest(to, from) {
                    back.pop(); // `from` again
                    let mut cycle = vec![from.clone()];
                    cycle.extend(back);
                    let k = (0..cycle.len()).min_by_key(|&k| &cycle[k]).unwrap_or(0);
                    cycle.rotate_left(k);
                    found.insert((cycle.len(), cycle));
                }
            }
        }
        found.into_iter().map(|(_, c)| c).collect()
    }

    /// Shortest chain of modules from `a` to `b` along the edges.
    fn shortest(&self, a: &str, b: &str) -> Option<Vec<String>> {
        let mut prev: BTreeMap<&str, &str> = BTreeMap::new();
        let mut queue = VecDeque::from([a]);
        prev.insert(a, a);
        while let Some(m) = queue.pop_front() {
            if m == b {
                let mut chain = vec![b.to_string()];
                let mut at = b;
                while at != a {
                    at = prev[at];
                    chain.push(at.to_string());
                }
                chain.reverse();
                return Some(chain);
            }
            for next in self.edges.get(m).into_iter().flat_map(|t| t.keys()) {
                if !prev.contains_key(next.as_str()) {
                    prev.insert(next, m);
                    queue.push_back(next);
                }
            }
        }
        None
    }

    /// Edges from a module to one declared below it in `lib.rs`.
    pub fn upward(&self) -> Vec<(&str, &str)> {
        let rank = |m: &str| self.modules.iter().position(|x| x == m);
        let mut out = Vec::new();
        for (from, tos) in &self.edges {
            for to in tos.keys() {
                if rank(to) > rank(from) {
                    out.push((from.as_str(), to.as_str()));
                }
            }
        }
        out
    }

    /// The first site of an edge, as `file:line path`, relative to `base`.
    fn site(&self, from: &str, to: &str, base: &Path) -> String {
        match self
            .edges
            .get(from)
            .and_then(|t| t.get(to))
            .and_then(|s| s.first())
        {
            Some(s) => {
                let f = s.file.strip_prefix(base).unwrap_or(&s.file);
                let more = self.edges[from][to].len() - 1;
                let more = if more > 0 {
                    format!(" (+{more} more)")
                } else {
                    String::new()
                };
                format!("{}:{} {}{more}", f.display(), s.line, s.path)
            }
            None => String::new(),
        }
    }

    /// What breaks the rule, one line per cycle or upward edge, each edge
    /// with where it is written; empty when the rule holds.
    pub fn report(&self, base: &Path) -> String {
        let mut s = String::new();
        for c in self.cycles() {
            let _ = writeln!(s, "cycle: {} -> {}", c.join(" -> "), c[0]);
            for k in 0..c.len() {
                let (a, b) = (&c[k], &c[(k + 1) % c.len()]);
                let _ = writeln!(s, "    {a} -> {b}: {}", self.site(a, b, base));
            }
        }
        for glob in &self.root_globs {
            let f = glob.file.strip_prefix(base).unwrap_or(&glob.file);
            let _ = writeln!(
                s,
                "glob: {}:{} {} imports every module's name; name the ones it uses",
                f.display(),
                glob.line,
                glob.path
            );
        }
        for (a, b) in self.upward() {
            let _ = writeln!(
                s,
                "upward: {a} imports {b}, declared below it in lib.rs: {}",
                self.site(a, b, base)
            );
        }
        s
    }
}

/// `cargo xtask imports`: each module of the library with the modules it
/// imports, then what breaks the rule; exit code 1 if anything does.
pub fn run() -> Result<i32> {
    let root = crate::util::root();
    let g = scan(&root.join("firmware/src/lib.rs"))?;
    for m in &g.modules {
        let deps: Vec<&str> = g
            .modules
            .iter()
            .filter(|d| g.edges.get(m).is_some_and(|t| t.contains_key(*d)))
            .map(String::as_str)
            .collect();
        println!("{m:<12} <- {}", deps.join(" "));
    }
    let report = g.report(&root);
    if report.is_empty() {
        println!("no cycle; every module imports only modules declared above it in lib.rs");
        Ok(0)
    } else {
        print!("{report}");
        Ok(1)
    }
}
