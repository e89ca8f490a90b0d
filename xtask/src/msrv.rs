//! The minimum Rust version (`rust-version` in the workspace Cargo.toml),
//! checked with the one toolchain CI has. Two halves: every member inherits
//! it, so clippy's `incompatible_msrv` (the clippy step, `-D warnings`)
//! flags a std API newer than it; and here, no package the build uses
//! declares a newer `rust-version` (issue 34 found heapless, proptest and
//! time needing 1.87-1.88 under a promise of 1.85). Packages only other
//! platforms use (Windows crates, loom under `cfg(loom)`) do not count.
//! Language features newer than it are not caught: that needs the old
//! compiler itself.

use crate::util::{cargo, TARGET};
use anyhow::{bail, Context, Result};
use std::process::Command;

pub fn check() -> Result<()> {
    let host = Command::new("rustc")
        .arg("-vV")
        .output()
        .context("running rustc -vV")?;
    let host = String::from_utf8_lossy(&host.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))
        .context("rustc -vV printed no host triple")?;
    let mut too_new = Vec::new();
    let mut min = String::new();
    for platform in [host.as_str(), TARGET] {
        let out = cargo()
            .args(["metadata", "--format-version", "1", "--locked"])
            .args(["--filter-platform", platform])
            .output()
            .context("running cargo metadata")?;
        if !out.status.success() {
            bail!("cargo metadata: {}", String::from_utf8_lossy(&out.stderr));
        }
        let meta: serde_json::Value =
            serde_json::from_slice(&out.stdout).context("cargo metadata's JSON")?;
        let (m, bad) = verdict(&meta)?;
        min = m;
        for b in bad {
            if !too_new.contains(&b) {
                too_new.push(b);
            }
        }
    }
    if !too_new.is_empty() {
        bail!(
            "the workspace promises Rust {min}, but these need newer: {}",
            too_new.join(", ")
        );
    }
    eprintln!("msrv: every package builds with Rust {min} by its rust-version");
    Ok(())
}

/// The workspace's promise and the packages that declare a newer version.
fn verdict(meta: &serde_json::Value) -> Result<(String, Vec<String>)> {
    let packages = meta["packages"]
        .as_array()
        .context("cargo metadata has no packages")?;
    let members: Vec<&str> = meta["workspace_members"]
        .as_array()
        .context("cargo metadata has no workspace_members")?
        .iter()
        .filter_map(|m| m.as_str())
        .collect();
    // The packages the resolve for this platform holds.
    let used: Vec<&str> = meta["resolve"]["nodes"]
        .as_array()
        .context("cargo metadata has no resolve")?
        .iter()
        .filter_map(|n| n["id"].as_str())
        .collect();
    let rv = |p: &serde_json::Value| p["rust_version"].as_str().map(str::to_string);
    let mut min = None;
    for p in packages
        .iter()
        .filter(|p| members.contains(&p["id"].as_str().unwrap_or("")))
    {
        let name = p["name"].as_str().unwrap_or("?");
        let Some(v) = rv(p) else {
            bail!(
                "workspace member {name} has no rust-version (add `rust-version.workspace = true`)"
            );
        };
        match &min {
            None => min = Some(v),
            Some(m) if *m != v => bail!("members disagree on rust-version: {m} and {v} ({name})"),
            _ => {}
        }
    }
    let min = min.context("no workspace members")?;
    let floor = version(&min).with_context(|| format!("rust-version {min}"))?;
    let mut too_new = Vec::new();
    for p in packages
        .iter()
        .filter(|p| used.contains(&p["id"].as_str().unwrap_or("")))
    {
        if let Some(v) = rv(p) {
            if version(&v).is_some_and(|x| x > floor) {
                let name = p["name"].as_str().unwrap_or("?");
                let ver = p["version"].as_str().unwrap_or("?");
                too_new.push(format!("{name} {ver} (rust-version {v})"));
            }
        }
    }
    Ok((min, too_new))
}

/// `1.85` / `1.85.1` as comparable numbers (a missing patch is 0).
fn version(s: &str) -> Option<(u32, u32, u32)> {
    let mut it = s.split('.').map(|x| x.parse::<u32>().ok());
    let major = it.next()??;
    let minor = it.next().flatten().unwrap_or(0);
    let patch = it.next().flatten().unwrap_or(0);
    Some((major, minor, patch))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta(dep_rv: &str) -> serde_json::Value {
        serde_json::json!({
            "workspace_members": ["a 0.1.0"],
            "packages": [
                {"id": "a 0.1.0", "name": "a", "version": "0.1.0", "rust_version": "1.85"},
                {"id": "d 1.0.0", "name": "d", "version": "1.0.0", "rust_version": dep_rv},
                {"id": "w 1.0.0", "name": "w", "version": "1.0.0", "rust_version": "1.99"},
            ],
            "resolve": {"nodes": [{"id": "a 0.1.0"}, {"id": "d 1.0.0"}]}
        })
    }

    #[test]
    fn a_dependency_newer_than_the_promise_is_named() {
        let (min, bad) = verdict(&meta("1.86")).unwrap();
        assert_eq!(min, "1.85");
        // `w` is in the lock file but not in this platform's resolve.
        assert_eq!(bad, ["d 1.0.0 (rust-version 1.86)"]);
        assert!(verdict(&meta("1.85.0")).unwrap().1.is_empty());
        assert!(verdict(&meta("1.60")).unwrap().1.is_empty());
    }

    #[test]
    fn versions_compare_numerically() {
        assert!(version("1.100").unwrap() > version("1.85.9").unwrap());
        assert_eq!(version("1.85"), Some((1, 85, 0)));
        assert_eq!(version("x"), None);
    }
}
