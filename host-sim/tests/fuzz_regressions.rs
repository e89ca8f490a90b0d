//! Every input that ever broke a fuzz target (kept minimised in
//! `firmware/fuzz/regressions/<target>/`) replayed through the same checks
//! (`host_sim::fuzz`), on stable, with no fuzzer. Also a smoke run of every
//! target over the project's own jobs, so the checks themselves stay sound.

use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("repo root")
}

#[test]
fn fuzz_regressions_replay() {
    let mut n = 0;
    for (name, f) in host_sim::fuzz::TARGETS {
        let dir = root().join("firmware/fuzz/regressions").join(name);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<_> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        for p in files {
            if p.file_name()
                .is_some_and(|f| f.to_string_lossy().starts_with('.'))
            {
                continue;
            }
            let data = std::fs::read(&p).expect("read regression input");
            eprintln!("{name}: {}", p.display());
            f(&data);
            n += 1;
        }
    }
    eprintln!("{n} regression inputs replayed");
}

#[test]
fn fuzz_targets_accept_project_jobs() {
    let dir = root().join("host-sim/jobs");
    for e in std::fs::read_dir(dir).expect("jobs").flatten() {
        let data = std::fs::read(e.path()).expect("job");
        let head = &data[..data.len().min(2000)];
        for (name, f) in host_sim::fuzz::TARGETS {
            eprintln!("{name}: {}", e.path().display());
            f(head);
        }
    }
}

/// Each starting state of `gcode_line` is valid G-code on its own.
#[test]
fn fuzz_gcode_line_preludes() {
    for i in 0..=255u8 {
        host_sim::fuzz::gcode_line(&[i]);
    }
}
