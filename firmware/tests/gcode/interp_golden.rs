//! Golden tests in LinuxCNC's tests/interp style: every
//! `tests/data/golden/NAME.ngc` is interpreted and its canonical command
//! list compared with `NAME.expected`. `BLESS=1 cargo test -p firmware --test
//! gcode interp_golden` rewrites the expected files (review the diff!).

use crate::common_canon;

use std::path::Path;

#[test]
fn golden_files() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/golden");
    let bless = std::env::var_os("BLESS").is_some();
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .expect("golden dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ngc"))
        .collect();
    names.sort();
    assert!(
        names.len() >= 10,
        "expected at least 10 golden programs, found {}",
        names.len()
    );
    let mut failed = Vec::new();
    for ngc in &names {
        let src = std::fs::read_to_string(ngc).expect("read ngc");
        let got = common_canon::run(&src);
        let exp_path = ngc.with_extension("expected");
        if bless {
            std::fs::write(&exp_path, &got).expect("write expected");
            continue;
        }
        let want = std::fs::read_to_string(&exp_path).unwrap_or_default();
        if got != want {
            eprintln!(
                "=== {} differs\n--- got\n{got}--- want\n{want}",
                ngc.display()
            );
            failed.push(ngc.display().to_string());
        }
    }
    println!("golden: {} programs", names.len());
    assert!(failed.is_empty(), "golden mismatches: {failed:?}");
}
