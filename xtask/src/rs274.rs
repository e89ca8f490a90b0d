//! `cargo xtask rs274`: burin's interpreter against LinuxCNC's `rs274`
//! (its standalone interpreter, canonical-output mode `-g`) on the shared
//! corpus and on `host-sim/tests/data/rs274/` (its subfolders too:
//! `oword/` is where O-word programs go).
//!
//! The whole canonical sequence is compared (`canon.rs`): every move's kind
//! (traverse, feed, arc, spline, probe), end point, arc plane, centre and
//! rotation (direction and turns), feed rate and the tool length offset in
//! force, within 0.003 mm. A canned cycle is its moves. rs274 is found at
//! `$BURIN_RS274`, or in `target/rs274/` where `--install` puts Debian's
//! `linuxcnc-uspace` (and `libboost-python1.74.0`), unpacked with
//! `apt-get download` + `dpkg -x`, no root needed. Without it the check
//! says "skipped".
//!
//! Both sides start from the same tool table: every tool number the file
//! names after T, H or D (or M61 Q), with no offsets or diameter, or the list in a
//! `(rs274-tools: 1 3)` comment (`(rs274-tools:)`: none). rs274 reads it
//! with `-t`, burin runs `G10 L1 P<n> Z0` for each first.
//!
//! A file that rs274 accepts must be accepted by burin and agree; one that
//! burin refuses or that differs fails the run unless [`KNOWN`] names it
//! with the reason. After a probe the two differ by design (rs274
//! simulates a contact), so comparison stops there.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

mod canon;

use canon::{Canon, TOL};

/// Agreement the cutter compensation files (`rs274/comp/`) need, mm.
const COMP_TOL: f64 = 0.001;

/// Files allowed to differ or to be refused by burin only:
/// `path suffix<TAB>burin-rejects|differs<TAB>reason` per line.
const KNOWN: &str = "host-sim/tests/data/rs274/known.tsv";

fn root_rs274() -> PathBuf {
    crate::util::root().join("target/rs274")
}

fn lib_dirs(base: &Path) -> String {
    [base.join("usr/lib"), base.join("usr/lib/x86_64-linux-gnu")]
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(":")
}

/// The rs274 binary and its library path, if there is one that runs.
fn find(install: bool) -> Result<Option<(PathBuf, String)>, String> {
    let (bin, libs) = match std::env::var_os("BURIN_RS274") {
        Some(b) => {
            let b = PathBuf::from(b);
            let base = b
                .parent()
                .and_then(|p| p.parent())
                .and_then(|p| p.parent())
                .map(Path::to_path_buf)
                .unwrap_or_default();
            (b, lib_dirs(&base))
        }
        None => {
            let base = root_rs274();
            let bin = base.join("usr/bin/rs274");
            if !bin.exists() {
                if !install {
                    return Ok(None);
                }
                self::install(&base)?;
            }
            (bin, lib_dirs(&base))
        }
    };
    // A run on an empty program proves the libraries load.
    let dir = std::env::temp_dir().join(format!("burin-rs274-probe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let f = dir.join("empty.ngc");
    std::fs::write(&f, "M2\n").map_err(|e| e.to_string())?;
    let r = run_rs274(&bin, &libs, &f, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    match r {
        Ok(o) if o.contains("PROGRAM_END") => Ok(Some((bin, libs))),
        Ok(o) => Err(format!("{} does not run: {}", bin.display(), o.trim())),
        Err(e) => Err(format!("{} does not run: {e}", bin.display())),
    }
}

fn install(base: &Path) -> Result<(), String> {
    let dl = base.join("deb");
    std::fs::create_dir_all(&dl).map_err(|e| e.to_string())?;
    eprintln!(
        "rs274: apt-get download linuxcnc-uspace libboost-python1.74.0 into {}",
        dl.display()
    );
    let ok = Command::new("apt-get")
        .args(["download", "linuxcnc-uspace", "libboost-python1.74.0"])
        .current_dir(&dl)
        .status()
        .map_err(|e| format!("apt-get: {e}"))?;
    if !ok.success() {
        return Err("apt-get download failed".into());
    }
    for e in std::fs::read_dir(&dl).map_err(|e| e.to_string())?.flatten() {
        let p = e.path();
        if p.extension().is_some_and(|x| x == "deb") {
            let ok = Command::new("dpkg")
                .arg("-x")
                .arg(&p)
                .arg(base)
                .status()
                .map_err(|e| format!("dpkg: {e}"))?;
            if !ok.success() {
                return Err(format!("dpkg -x {} failed", p.display()));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dl);
    Ok(())
}

/// rs274's canonical output for `file`, from a fresh, empty parameter
/// file and a tool table of `tools` with no offsets, started in G98 as
/// burin starts (rs274 alone starts in G99; a LinuxCNC machine starts as
/// its ini's `RS274NGC_STARTUP_CODE` says): the file runs after a line
/// `G98`, inserted first (or after an opening `%` line).
fn run_rs274(bin: &Path, libs: &str, file: &Path, tools: &[u32]) -> std::io::Result<String> {
    let dir = std::env::temp_dir().join(format!("burin-rs274-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let src = std::fs::read(file)?;
    // After a `%` line: a program delimited by `%` must open with it.
    let first = src
        .iter()
        .position(|&b| b == b'\n')
        .map_or(src.len(), |i| i + 1);
    let at = if src.trim_ascii_start().starts_with(b"%") {
        first
    } else {
        0
    };
    let mut text = src[..at].to_vec();
    text.extend(b"G98\n");
    text.extend(&src[at..]);
    let file = &dir.join("program.ngc");
    std::fs::write(file, text)?;
    let var = dir.join("sim.var");
    std::fs::write(&var, "")?;
    let tbl = dir.join("tool.tbl");
    let tools: String = tools
        .iter()
        .enumerate()
        .map(|(i, t)| format!("T{t} P{} Z0 D0\n", i + 1))
        .collect();
    std::fs::write(&tbl, tools)?;
    let out = Command::new(bin)
        .env("LD_LIBRARY_PATH", libs)
        .arg("-t")
        .arg(&tbl)
        .arg("-v")
        .arg(&var)
        .arg("-g")
        .arg(file)
        .stdin(Stdio::null())
        .output()?;
    let mut s = String::from_utf8_lossy(&out.stdout).into_owned();
    s.push_str(&String::from_utf8_lossy(&out.stderr));
    Ok(s)
}

/// The comparison's tool table for `src` (see the module docs).
fn tools_of(src: &str) -> Vec<u32> {
    let up = src.to_ascii_uppercase();
    if let Some(i) = up.find("(RS274-TOOLS:") {
        let rest = &up[i + 13..];
        let list = &rest[..rest.find(')').unwrap_or(rest.len())];
        return list
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
    }
    let b = up.as_bytes();
    let mut out: Vec<u32> = Vec::new();
    for (i, &c) in b.iter().enumerate() {
        let m61 = c == b'Q' && up[..i].trim_end().ends_with("M61");
        if c != b'T' && c != b'H' && c != b'D' && !m61 {
            continue;
        }
        // A word letter, not a letter inside a name (`PATH`, `#<tool>`).
        if i > 0 && b[i - 1].is_ascii_alphabetic() {
            continue;
        }
        let digits: String = up[i + 1..]
            .trim_start()
            .chars()
            .take_while(char::is_ascii_digit)
            .collect();
        if let Ok(n) = digits.parse::<u32>() {
            if n > 0 && n <= burin::interp::tools::TOOL_MAX && !out.contains(&n) {
                out.push(n);
            }
        }
    }
    out.truncate(burin::interp::TOOLS);
    out
}

/// A listed refusal's check: the lines before line `l`, then `M2`, run
/// through both and compared whole. `Err` says how they differ.
fn before_line(
    bin: &Path,
    libs: &str,
    src: &str,
    l: usize,
    tools: &[u32],
    prelude: &str,
    settings: &burin::settings::Settings,
) -> Result<std::result::Result<canon::Verdict, String>> {
    let head: String = src
        .split('\n')
        .take(l.saturating_sub(1))
        .flat_map(|line| [line, "\n"])
        .chain(["M2\n"])
        .collect();
    let dir = std::env::temp_dir().join(format!("burin-rs274-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let f = dir.join("before.ngc");
    std::fs::write(&f, &head)?;
    let theirs = canon::parse(&run_rs274(bin, libs, &f, tools)?);
    let ours = host_sim::check::canon_moves(&head, prelude, settings);
    Ok(match (theirs, ours) {
        (Canon::Ok(theirs), Ok(ours)) => {
            let mut v = canon::compare_program(theirs, &ours, &head);
            match v.diff.take() {
                Some(d) => Err(d),
                None => Ok(v),
            }
        }
        (Canon::Rejected(r), _) => Err(format!("rs274 rejects the lines before it: {r}")),
        (_, Err((l, e))) => Err(format!("burin rejects line {l} before it: {e}")),
    })
}

/// The known list: (path suffix, verdict, reason).
fn known() -> Result<Vec<(String, String, String)>> {
    let path = crate::util::root().join(KNOWN);
    let text = std::fs::read_to_string(&path).with_context(|| path.display().to_string())?;
    let mut v = Vec::new();
    for line in text.lines() {
        if line.trim().is_empty() || line.starts_with('#') {
            continue;
        }
        let mut f = line.splitn(3, '\t');
        let (Some(file), Some(kind), Some(why)) = (f.next(), f.next(), f.next()) else {
            bail!("{KNOWN}: `{line}`: want path<TAB>burin-rejects|differs<TAB>reason");
        };
        if kind != "burin-rejects" && kind != "differs" {
            bail!("{KNOWN}: `{line}`: verdict must be burin-rejects or differs");
        }
        v.push((file.to_string(), kind.to_string(), why.to_string()));
    }
    Ok(v)
}

fn files() -> Vec<PathBuf> {
    let mut v = Vec::new();
    let corpus = std::env::var_os("BURIN_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| crate::util::root().join("../shared/corpus"));
    walk(&corpus, &mut v);
    walk(
        &crate::util::root().join("host-sim/tests/data/rs274"),
        &mut v,
    );
    v.sort();
    v
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

/// Runs the comparison; `install` lets it fetch rs274 into `target/`.
/// Returns Ok when every file both accept agrees (or rs274 is missing).
pub fn run(install: bool) -> Result<()> {
    let (bin, libs) = match find(install) {
        Ok(Some(x)) => x,
        Ok(None) => {
            eprintln!("rs274 conformance: skipped (no rs274: set BURIN_RS274, or `cargo xtask rs274 --install`)");
            return Ok(());
        }
        Err(e) => {
            eprintln!("rs274 conformance: skipped ({e})");
            return Ok(());
        }
    };
    let settings = burin::settings::Settings::default();
    let known = known()?;
    let (mut agree, mut only_rs, mut only_burin, mut both, mut listed) = (0, 0, 0, 0, 0);
    let mut moves = 0usize;
    let mut worst = 0.0f64;
    let mut bad = Vec::new();
    let mut used = vec![false; known.len()];
    for f in files() {
        let name = f.display().to_string();
        let src =
            String::from_utf8_lossy(&std::fs::read(&f).with_context(|| name.clone())?).into_owned();
        let tools = tools_of(&src);
        let prelude: String = tools.iter().map(|t| format!("G10 L1 P{t} Z0\n")).collect();
        let theirs =
            canon::parse(&run_rs274(&bin, &libs, &f, &tools).with_context(|| name.clone())?);
        let ours = host_sim::check::canon_moves(&src, &prelude, &settings);
        let short = name
            .rsplit("corpus/")
            .next()
            .and_then(|n| n.rsplit("host-sim/").next())
            .unwrap_or(&name)
            .to_string();
        let listed_as = |kind: &str, used: &mut Vec<bool>| {
            let i = known
                .iter()
                .position(|k| short.ends_with(&k.0) && k.1 == kind)?;
            used[i] = true;
            known.get(i).map(|k| k.2.clone())
        };
        match (theirs, ours) {
            (Canon::Ok(theirs), Ok(ours)) => {
                let v = canon::compare_program(theirs, &ours, &src);
                match (v.diff, listed_as("differs", &mut used)) {
                    // Cutter compensation's own files (issue 33) must agree
                    // within 0.001 mm on every end point and arc centre.
                    (None, _) if short.contains("rs274/comp/") && v.worst > COMP_TOL => {
                        println!(
                            "DISAGREE  {short}: worst difference {:.4} mm, over {COMP_TOL} mm",
                            v.worst
                        );
                        bad.push(short.clone());
                    }
                    (None, _) => {
                        agree += 1;
                        moves += v.moves;
                        worst = worst.max(v.worst);
                        println!(
                            "agree     {short}: {} moves (worst {:.4} mm)",
                            v.moves, v.worst
                        );
                    }
                    (Some(d), Some(why)) => {
                        listed += 1;
                        println!("listed    {short}: {d} ({why})");
                    }
                    (Some(d), None) => {
                        println!("DISAGREE  {short}: {d}");
                        bad.push(short.clone());
                    }
                }
            }
            (Canon::Ok(_), Err((l, e))) => {
                only_rs += 1;
                match listed_as("burin-rejects", &mut used) {
                    Some(why) => {
                        listed += 1;
                        // What comes before the refused line must still agree.
                        match before_line(&bin, &libs, &src, l, &tools, &prelude, &settings)? {
                            Ok(v) => println!(
                                "listed    {short}:{l}: burin rejects: {e} ({why}); the {} moves \
                                 before it agree (worst {:.4} mm)",
                                v.moves, v.worst
                            ),
                            Err(d) => {
                                println!("DISAGREE  {short}: before line {l}: {d}");
                                bad.push(short.clone());
                            }
                        }
                    }
                    None => {
                        println!("BURIN REJECTS {short}:{l}: {e}");
                        bad.push(short.clone());
                    }
                }
            }
            (Canon::Rejected(r), Ok(_)) => {
                only_burin += 1;
                println!("rs274 rejects {short}: {r}");
            }
            (Canon::Rejected(r), Err((l, e))) => {
                both += 1;
                println!("both reject   {short}: rs274: {r}; burin line {l}: {e}");
            }
        }
    }
    for (k, u) in known.iter().zip(&used) {
        if !u {
            println!(
                "stale entry in {KNOWN}: {} ({}) no longer happens",
                k.0, k.1
            );
        }
    }
    println!(
        "rs274 conformance: {agree} files agree on whole sequences ({moves} moves, worst difference {worst:.4} mm, limit {TOL} mm); {only_rs} rejected by burin only, {only_burin} by rs274 only, {both} by both; {listed} listed in {KNOWN}; {} unexplained",
        bad.len()
    );
    if !bad.is_empty() {
        bail!("files where burin and rs274 differ, not in {KNOWN}: {bad:?}");
    }
    Ok(())
}
