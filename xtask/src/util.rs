//! Small helpers shared by the tasks.

use anyhow::{bail, Context, Result};
use std::path::PathBuf;
use std::process::Command;

/// The workspace root (xtask lives one level below it).
pub fn root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map(PathBuf::from).unwrap_or(manifest)
}

/// `cargo` as invoked by this xtask (respects `$CARGO`).
pub fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

/// Run a command, echoing it, failing on a non-zero exit.
pub fn run(cmd: &mut Command) -> Result<()> {
    eprintln!("$ {}", show(cmd));
    let status = cmd
        .status()
        .with_context(|| format!("could not start {:?}", cmd.get_program()))?;
    if !status.success() {
        bail!("`{}` failed with {status}", show(cmd));
    }
    Ok(())
}

/// A command line as a person would type it.
pub fn show(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

/// Whether an executable is on PATH.
pub fn have(tool: &str) -> bool {
    std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).any(|d| d.join(tool).is_file()))
        .unwrap_or(false)
}

/// Held around every `apt-get install`: `cargo xtask ci` installs the
/// senders on a thread while its QEMU step may install QEMU, and dpkg takes
/// one at a time.
pub fn apt_lock() -> std::sync::MutexGuard<'static, ()> {
    static APT: std::sync::Mutex<()> = std::sync::Mutex::new(());
    APT.lock().unwrap_or_else(|e| e.into_inner())
}

/// The embedded target every firmware build uses.
pub const TARGET: &str = "thumbv7em-none-eabihf";
/// Cargo profile of every firmware image (Cargo.toml: size-optimised, unlike
/// `release`, which host benchmarks inherit).
pub const FW_PROFILE: &str = "firmware";

/// Install the thumb target when rustup lacks it (RUSTUP_AUTO_INSTALL=0 here).
pub fn ensure_target() -> Result<()> {
    let out = Command::new("rustup")
        .args(["target", "list", "--installed"])
        .current_dir(root())
        .output();
    match out {
        Ok(o)
            if String::from_utf8_lossy(&o.stdout)
                .lines()
                .any(|l| l.trim() == TARGET) =>
        {
            Ok(())
        }
        Ok(_) => run(Command::new("rustup")
            .args(["target", "add", TARGET])
            .current_dir(root())),
        Err(_) => {
            eprintln!("note: rustup not found; assuming the {TARGET} std is installed");
            Ok(())
        }
    }
}

/// Cargo's target directory: `$CARGO_TARGET_DIR` (relative to the workspace
/// root when relative) or `<root>/target`.
pub fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) => root().join(dir),
        None => root().join("target"),
    }
}

/// Builds firmware binary `bin` in the firmware profile with `features`
/// (`None`: the default board) and copies the ELF to `<bin>-<tag>.elf`
/// beside cargo's output, so images of different boards (same cargo path)
/// sit side by side and one cannot be mistaken for another.
pub fn build_firmware(bin: &str, features: Option<&str>, tag: &str) -> Result<PathBuf> {
    ensure_target()?;
    let mut cmd = cargo();
    cmd.args(["build", "--package", "firmware", "--bin", bin]);
    cmd.args(["--profile", FW_PROFILE, "--target", TARGET]);
    if let Some(features) = features {
        cmd.args(["--no-default-features", "--features", features]);
    }
    run(&mut cmd)?;
    let out = target_dir().join(TARGET).join(FW_PROFILE);
    let elf = out.join(format!("{bin}-{tag}.elf"));
    std::fs::copy(out.join(bin), &elf).with_context(|| format!("copying {bin}"))?;
    Ok(elf)
}
