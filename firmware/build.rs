//! Linker setup for the firmware binary, and only for the MCU.
//!
//! The host build (library tests, host-sim, the stub `burin-fw`) must link like
//! any other Rust program, so everything here is skipped unless the target has
//! no OS. On the MCU the board feature picks the memory map: cortex-m-rt's
//! `link.x` `INCLUDE`s a file named `memory.x`, so the board's file is copied
//! under that name into OUT_DIR, which goes first on the search path.
use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let boards = [
        ("CARGO_FEATURE_BOARD_F411", "memory-f411.x"),
        ("CARGO_FEATURE_BOARD_F401", "memory-f401.x"),
        ("CARGO_FEATURE_BOARD_QEMU", "memory-f405.x"),
    ];
    let chosen: Vec<&str> = boards
        .iter()
        .filter(|(feature, _)| env::var_os(feature).is_some())
        .map(|(_, file)| *file)
        .collect();
    // Zero or two boards is reported by the binary's compile_error!, which
    // names the features; here we only avoid a confusing linker error first.
    let Some(&memory) = chosen.first() else {
        return;
    };
    // The benchmark keeps the stack at the top of RAM (memory-f405-bench.x).
    let memory = if env::var_os("CARGO_FEATURE_BENCH_TARGET").is_some() {
        "memory-f405-bench.x"
    } else {
        memory
    };
    let manifest =
        PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let text = fs::read(manifest.join(memory)).expect("board memory file exists");
    fs::write(out.join("memory.x"), text).expect("OUT_DIR is writable");
    println!("cargo:rerun-if-changed={memory}");
    println!("cargo:rerun-if-env-changed=CARGO_FEATURE_BENCH_TARGET");
    println!("cargo:rustc-link-search={}", out.display());
    // Bins only: the library's own (host-style) tests never see these.
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
