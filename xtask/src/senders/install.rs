//! Bringing the senders in from their registries, into caches that outlive
//! a run: PyPI into `target/senders/venv`, npm into `target/senders/npm`,
//! Debian's packages into the system (apt, as root). A second run finds
//! them all and installs nothing. Each install writes its output to a log
//! beside its cache; a sender that could not be installed is skipped with
//! the reason, never failed (CI does not fail for the network's sake).
//!
//! `cargo xtask ci` starts [`prepare`] on a thread before its first step, so
//! the downloads overlap the builds; the apt installs take the same lock as
//! the QEMU step's.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::util::{apt_lock, have, target_dir};

/// PyPI, pinned (what the scripts were written against).
const PYPI: [(&str, &[&str]); 2] = [
    ("grbl-streamer", &["grbl-streamer==2.0.2", "pyserial==3.5"]),
    ("printrun", &["--no-deps", "printrun==2.2.0"]),
];
/// npm, pinned.
pub const CNCJS: &str = "1.11.5";
/// Where Debian's `bcnc` puts its Python modules.
pub const BCNC_DIR: &str = "/usr/share/bcnc/bCNC";
/// Debian's interpreter: the one `bcnc`'s dependencies (pyserial, numpy,
/// Tk) are installed for, whatever `python3` is first on PATH.
pub const SYSTEM_PYTHON: &str = "/usr/bin/python3";

/// What each registry gave: a path to run from, or why not.
pub struct Ready {
    /// The venv's python, with grbl-streamer and printrun.
    pub pypi: Result<PathBuf, String>,
    /// bCNC's module directory.
    pub bcnc: Result<PathBuf, String>,
    /// The npm prefix holding `node_modules/cncjs`.
    pub cncjs: Result<PathBuf, String>,
}

fn cache() -> PathBuf {
    target_dir().join("senders")
}

/// All three side by side; npm after apt only when apt must bring node.
pub fn prepare() -> Ready {
    let _ = std::fs::create_dir_all(cache());
    let pypi = std::thread::spawn(pypi);
    let npm = node_there().then(|| std::thread::spawn(cncjs));
    let (bcnc, node) = apt();
    let cncjs = match npm {
        Some(npm) => npm
            .join()
            .unwrap_or_else(|_| Err("the npm install panicked".into())),
        None => node.and_then(|()| cncjs()),
    };
    let pypi = pypi
        .join()
        .unwrap_or_else(|_| Err("the PyPI install panicked".into()));
    Ready { pypi, bcnc, cncjs }
}

/// Run `cmd` (a `what` for messages) with its output in `log`; Err names
/// the log.
fn logged(what: &str, cmd: &mut Command, log: &Path) -> Result<(), String> {
    let file = std::fs::File::create(log).map_err(|e| format!("{}: {e}", log.display()))?;
    let err = file.try_clone().map_err(|e| e.to_string())?;
    match cmd.stdout(file).stderr(err).stdin(Stdio::null()).status() {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(format!("{what} failed ({s}; see {})", log.display())),
        Err(e) => Err(format!("{what} did not start: {e}")),
    }
}

fn pypi() -> Result<PathBuf, String> {
    let dir = cache().join("venv");
    let python = dir.join("bin").join("python");
    // Written once pip has installed every pin (asking pip costs seconds).
    let pins: Vec<&str> = PYPI
        .iter()
        .flat_map(|(_, a)| a.iter().copied())
        .filter(|a| !a.starts_with('-'))
        .collect();
    let done = dir.join(format!("installed-{}", pins.join(",")));
    if python.exists() && done.is_file() {
        return Ok(python);
    }
    if !python.exists() {
        logged(
            "python3 -m venv",
            Command::new("python3").args(["-m", "venv"]).arg(&dir),
            &cache().join("venv.log"),
        )?;
    }
    for (name, args) in PYPI {
        let log = cache().join(format!("pip-{name}.log"));
        let mut pip = Command::new(&python);
        pip.args(["-m", "pip", "install", "--disable-pip-version-check"])
            .args(["--timeout", "30"])
            .args(args);
        logged(&format!("pip install {name} (PyPI)"), &mut pip, &log)?;
    }
    std::fs::write(&done, "").map_err(|e| e.to_string())?;
    Ok(python)
}

fn bcnc_there() -> bool {
    Path::new(BCNC_DIR).join("Sender.py").is_file() && Path::new(SYSTEM_PYTHON).is_file()
}

fn node_there() -> bool {
    have("node") && have("npm")
}

/// bCNC, and node with npm when missing, in one apt-get run.
fn apt() -> (Result<PathBuf, String>, Result<(), String>) {
    let mut want = Vec::new();
    if !bcnc_there() {
        want.push("bcnc");
    }
    if !node_there() {
        want.extend(["nodejs", "npm"]);
    }
    let mut why = String::new();
    if !want.is_empty() {
        if let Err(e) = apt_install(&want) {
            why = e;
        }
    }
    let bcnc = if bcnc_there() {
        Ok(PathBuf::from(BCNC_DIR))
    } else {
        Err(format!("no Debian bcnc: {why}"))
    };
    let node = if node_there() {
        Ok(())
    } else {
        Err(format!("no node and npm: {why}"))
    };
    (bcnc, node)
}

fn apt_install(pkgs: &[&str]) -> Result<(), String> {
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if !root {
        return Err(format!("not root; `apt-get install {}`", pkgs.join(" ")));
    }
    let log = cache().join("apt.log");
    let _lock = apt_lock();
    let what = format!("apt-get install {}", pkgs.join(" "));
    let install = || {
        logged(
            &what,
            Command::new("apt-get")
                .env("DEBIAN_FRONTEND", "noninteractive")
                .args(["install", "-y", "--no-install-recommends"])
                .args(pkgs),
            &log,
        )
    };
    if install().is_ok() {
        return Ok(());
    }
    logged(
        "apt-get update",
        Command::new("apt-get").arg("update"),
        &cache().join("apt-update.log"),
    )?;
    install()
}

fn cncjs() -> Result<PathBuf, String> {
    let dir = cache().join("npm");
    let manifest = dir.join("node_modules").join("cncjs").join("package.json");
    let pinned = format!("\"version\": \"{CNCJS}\"");
    let there = || std::fs::read_to_string(&manifest).is_ok_and(|t| t.contains(&pinned));
    // Written once npm has finished: an install cut short is done again.
    let done = dir.join(format!("installed-cncjs-{CNCJS}"));
    if done.is_file() && there() {
        return Ok(dir);
    }
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    // A package.json of our own, so npm keeps to this prefix.
    let pkg = dir.join("package.json");
    if !pkg.exists() {
        std::fs::write(&pkg, "{\"private\": true}\n").map_err(|e| e.to_string())?;
    }
    logged(
        &format!("npm install cncjs@{CNCJS}"),
        Command::new("npm")
            .arg("install")
            .arg("--prefix")
            .arg(&dir)
            .args(["--no-audit", "--no-fund", "--omit=dev"])
            .arg(format!("cncjs@{CNCJS}")),
        &cache().join("npm.log"),
    )?;
    if there() {
        std::fs::write(&done, "").map_err(|e| e.to_string())?;
        Ok(dir)
    } else {
        Err(format!(
            "npm installed no cncjs {CNCJS} in {}",
            dir.display()
        ))
    }
}
