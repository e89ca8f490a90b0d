use super::*;

fn burin() -> (Graph, PathBuf) {
    let root = crate::util::root();
    let g = scan(&root.join("firmware/src/lib.rs")).expect("firmware/src reads");
    (g, root)
}

/// The rule itself, on the real library: firmware/DESIGN.md states it.
#[test]
fn burin_imports_follow_lib_rs_order() {
    let (g, root) = burin();
    let report = g.report(&root);
    assert!(
        report.is_empty(),
        "the burin library breaks its import rule (firmware/DESIGN.md, \"Pipeline\"):\n{report}"
    );
}

/// The check above would pass on a scan that found nothing: it must see
/// every module and the edges everyone knows are there.
#[test]
fn burin_scan_sees_the_modules_and_known_edges() {
    let (g, _) = burin();
    for m in [
        "seams",
        "command",
        "interp",
        "planner",
        "stepper",
        "executor",
        "controller",
    ] {
        assert!(
            g.modules.iter().any(|x| x == m),
            "{m} missing from {:?}",
            g.modules
        );
    }
    let has = |a: &str, b: &str| g.edges.get(a).is_some_and(|t| t.contains_key(b));
    assert!(has("executor", "planner"));
    assert!(has("controller", "session"));
    assert!(has("planner", "settings"));
    // `super::` from a nested file: stepper/prep.rs names `super::super::…`
    // or `crate::…`; either way the stepper reads the settings or the chip
    assert!(g.edges.get("stepper").is_some_and(|t| t.len() >= 2));
}

/// A throwaway crate under the temp dir; removed when dropped.
struct Tree(PathBuf);

impl Tree {
    fn new(name: &str, files: &[(&str, &str)]) -> Tree {
        let dir = std::env::temp_dir().join(format!("xtask-imports-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for (path, text) in files {
            let p = dir.join(path);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, text).unwrap();
        }
        Tree(dir)
    }

    fn graph(&self) -> Graph {
        scan(&self.0.join("lib.rs")).unwrap()
    }
}

impl Drop for Tree {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn edges(g: &Graph) -> Vec<String> {
    g.edges
        .iter()
        .flat_map(|(a, t)| t.keys().map(move |b| format!("{a}->{b}")))
        .collect()
}

#[test]
fn a_cycle_is_reported_with_its_chain_and_sites() {
    let t = Tree::new(
        "cycle",
        &[
            ("lib.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
            ("a.rs", "pub struct A;\n"),
            ("b.rs", "use crate::c::C;\npub struct B(C);\n"),
            ("c/mod.rs", "mod inner;\npub struct C;\n"),
            ("c/inner.rs", "fn f() -> crate::b::B { todo!() }\n"),
        ],
    );
    let g = t.graph();
    assert_eq!(g.cycles(), vec![vec!["b".to_string(), "c".to_string()]]);
    let report = g.report(&t.0);
    assert!(report.contains("cycle: b -> c -> b"), "{report}");
    assert!(report.contains("b -> c: b.rs:1 crate::c::C"), "{report}");
    assert!(
        report.contains("c -> b: c/inner.rs:1 crate::b::B"),
        "{report}"
    );
    // the same edge is also upward: b imports c, declared below it
    assert!(report.contains("upward: b imports c"), "{report}");
}

#[test]
fn an_upward_edge_fails_without_a_cycle() {
    let t = Tree::new(
        "upward",
        &[
            ("lib.rs", "pub mod low;\npub mod high;\n"),
            ("low.rs", "pub fn f() { crate::high::g() }\n"),
            ("high.rs", "pub fn g() {}\n"),
        ],
    );
    let g = t.graph();
    assert!(g.cycles().is_empty());
    assert_eq!(g.upward(), vec![("low", "high")]);
    // the other way round is the rule kept
    let ok = Tree::new(
        "downward",
        &[
            ("lib.rs", "pub mod low;\npub mod high;\n"),
            ("low.rs", "pub fn g() {}\n"),
            ("high.rs", "pub fn f() { crate::low::g() }\n"),
        ],
    );
    assert_eq!(ok.graph().report(&ok.0), "");
}

#[test]
fn every_way_of_naming_a_module_is_an_edge() {
    let t = Tree::new(
        "forms",
        &[
            (
                "lib.rs",
                "pub mod a; pub mod b; pub mod c; pub mod d; pub mod e; pub mod f; pub mod top;\n",
            ),
            ("a.rs", ""),
            ("b.rs", ""),
            ("c.rs", ""),
            ("d.rs", ""),
            ("e.rs", ""),
            ("f.rs", ""),
            (
                "top/mod.rs",
                "use crate::{a::X, b};\n\
                 #[path = \"elsewhere.rs\"]\nmod moved;\n\
                 mod nested;\n\
                 macro_rules! m { () => { $crate::c::go() } }\n\
                 mod inline { mod deeper { use super::super::super::d::Y; } }\n",
            ),
            ("top/elsewhere.rs", "use super::super::e;\n"),
            ("top/nested/mod.rs", "mod leaf;\n"),
            (
                "top/nested/leaf.rs",
                "pub(crate) fn g() -> super::super::super::f::Z { todo!() }\n",
            ),
        ],
    );
    assert_eq!(
        edges(&t.graph()),
        ["top->a", "top->b", "top->c", "top->d", "top->e", "top->f"]
    );
}

#[test]
fn comments_literals_and_inner_paths_are_not_edges() {
    let t = Tree::new(
        "quiet",
        &[
            (
                "lib.rs",
                "pub mod a;\npub mod b;\npub const N: usize = 1;\n",
            ),
            ("b.rs", "pub struct B;\n"),
            (
                "a.rs",
                "//! See [`crate::b::B`].\n\
                 /* crate::b /* nested */ crate::b */\n\
                 const S: &str = \"crate::b::B\";\n\
                 const R: &str = r#\"crate::b \"quoted\" \"#;\n\
                 const C: char = '\\'';\n\
                 fn f<'a>(x: &'a str) -> usize { crate::N + super::N }\n\
                 mod inner { pub fn g() {} fn h() { super::inner::g(); self::g(); } }\n",
            ),
        ],
    );
    let g = t.graph();
    assert_eq!(edges(&g), Vec::<String>::new());
}

#[test]
fn a_missing_module_file_is_an_error() {
    let t = Tree::new("missing", &[("lib.rs", "pub mod gone;\n")]);
    let err = scan(&t.0.join("lib.rs")).unwrap_err().to_string();
    assert!(err.contains("`mod gone;` has no file"), "{err}");
}

#[test]
fn a_glob_of_the_crate_root_is_reported() {
    let t = Tree::new(
        "glob",
        &[
            ("lib.rs", "pub mod a;\npub mod b;\n"),
            ("a.rs", "pub fn f() {}\n"),
            // the root glob hides `a::f()`; the test module's glob is b's own
            (
                "b.rs",
                "use super::*;\npub fn g() { a::f() }\n#[cfg(test)]\nmod tests { use super::*; }\n",
            ),
        ],
    );
    let g = t.graph();
    assert_eq!(g.root_globs.len(), 1);
    let report = g.report(&t.0);
    assert!(
        report.contains("glob: b.rs:1 super::* imports every module's name"),
        "{report}"
    );
}
