//! Conformance over the shared corpus (`<workspace>/../shared/corpus`, or
//! `$BURIN_CORPUS`): every .ngc/.gcode/.nc file either interprets cleanly or
//! its FIRST error names an unsupported feature (later errors in such a file
//! follow from the rejected feature: a skipped G41, an O-word loop body...).
//! A few files have genuine faults; they are listed with the reason and the
//! exact first error, so any change in behaviour shows up here.

use burin::interp::Interpreter;
use std::path::{Path, PathBuf};

/// (file suffix, expected first error code, why)
const KNOWN_FAULTS: &[(&str, u16, &str)] = &[
    (
        "gcode-rs/_gcodeLexer_samples.ngc",
        103,
        "deliberately broken comments (lexer edge cases)",
    ),
    (
        "gcode-rs/plotter_owl.gcode",
        100,
        "a 300-byte comment line; lines are limited to 256 bytes",
    ),
    (
        "gcode-rs/reprap_cnc.gcode",
        311,
        "never sets F (RepRap firmware has a default feed; we refuse to guess)",
    ),
    (
        "grbl-sim/test.nc",
        101,
        "`$X` is a GRBL system command for the link layer, not G-code",
    ),
    (
        "gcode-rs/_mach3.gcode",
        318,
        "`G53 G90 G40` without G0/G1 or axis words: LinuxCNC refuses it too (issue 14)",
    ),
    (
        "linuxcnc/cds.ngc",
        330,
        "`G43 H1` with an empty tool table: LinuxCNC refuses an unknown tool too (issue 30)",
    ),
    (
        "linuxcnc-tp/Cereal.ngc",
        330,
        "`G43 H1` with an empty tool table: LinuxCNC refuses an unknown tool too (issue 30)",
    ),
    (
        "gcode-rs/program_2.gcode",
        321,
        "its profile lines are commented out, so `N90 G2 X15 Y62 I10 J0` ends 105 mm from a centre it starts 10 mm from (LinuxCNC refuses the radius too); with G41 supported (issue 33) the file now reaches that line",
    ),
    (
        "linuxcnc-tp/rgh.ngc",
        330,
        "`G43 H15` with an empty tool table: LinuxCNC refuses an unknown tool too (issue 30)",
    ),
];

fn corpus_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("BURIN_CORPUS") {
        return Some(PathBuf::from(d));
    }
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/corpus");
    d.is_dir().then_some(d)
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            walk(&p, out);
        } else if p
            .extension()
            .is_some_and(|x| x == "ngc" || x == "gcode" || x == "nc")
        {
            out.push(p);
        }
    }
}

#[test]
fn corpus_conformance() {
    let Some(dir) = corpus_dir() else {
        println!("corpus conformance: skipped (../shared/corpus not found)");
        return;
    };
    let mut files = Vec::new();
    walk(&dir, &mut files);
    files.sort();
    let mut bad = Vec::new();
    let (mut clean, mut unsupported, mut known) = (0, 0, 0);
    for f in &files {
        let name = f.strip_prefix(&dir).unwrap_or(f).display().to_string();
        let src = String::from_utf8_lossy(&std::fs::read(f).expect("read")).into_owned();
        let mut it = Interpreter::new();
        let (mut lines, mut cmds, mut errs) = (0, 0, 0);
        let mut first = None;
        for (i, line) in src.split('\n').enumerate() {
            lines += 1;
            match it.execute_line(line.as_bytes(), &mut |_| cmds += 1) {
                Ok(()) => {
                    if it.needs_sync() {
                        it.set_machine_position(it.state().pos);
                    }
                }
                Err(e) => {
                    errs += 1;
                    first.get_or_insert((i + 1, e));
                }
            }
        }
        let expected = KNOWN_FAULTS.iter().find(|k| name.ends_with(k.0));
        let verdict = match (first, expected) {
            (None, None) => {
                clean += 1;
                "clean".to_string()
            }
            (Some((l, e)), None) if e.kind.is_unsupported() => {
                unsupported += 1;
                format!("unsupported at {l}:{}: {e}", e.col)
            }
            (Some((l, e)), Some(k)) if e.code() == k.1 => {
                known += 1;
                format!("known fault at {l}:{}: {e} ({})", e.col, k.2)
            }
            (first, _) => {
                bad.push(name.clone());
                format!("UNEXPECTED: {first:?} (expected {expected:?})")
            }
        };
        println!("{name}: {lines} lines, {cmds} commands, {errs} errors; {verdict}");
    }
    println!(
        "corpus conformance: {} files: {clean} clean, {unsupported} stop on a named unsupported feature, {known} known faults",
        files.len()
    );
    assert!(!files.is_empty(), "corpus folder has no G-code files");
    assert!(bad.is_empty(), "files failing conformance: {bad:?}");
}
