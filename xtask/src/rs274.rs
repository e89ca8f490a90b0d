//! `cargo xtask rs274`: burin's interpreter against LinuxCNC's `rs274`
//! (its standalone interpreter, canonical-output mode `-g`) on the shared
//! corpus and on `host-sim/tests/data/rs274/*.ngc`.
//!
//! Every file both accept must agree on every motion end point within
//! 0.003 mm; the rest are counted with the reason each side gave. rs274
//! is found at `$BURIN_RS274`, or in `target/rs274/` where `--install`
//! puts Debian's `linuxcnc-uspace` (and `libboost-python1.74.0`), unpacked
//! with `apt-get download` + `dpkg -x`, no root needed. Without it the
//! check says "skipped".
//!
//! Reading rs274's output: positions are program coordinates in the
//! program's units (`USE_LENGTH_UNITS`); machine = program + G5x + G92
//! (+ tool length offset), each offset as last announced. Zero-length
//! moves are dropped on both sides (LinuxCNC emits G28's intermediate move
//! even when it has no length; burin may not); `NURBS_FEED` (G5) prints no
//! end, so it matches any. After a probe the two differ by design (rs274
//! simulates a contact), so comparison stops there.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Agreement required on every end point, mm.
const TOL: f64 = 0.003;

type P = [f64; 4];

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
    let r = run_rs274(&bin, &libs, &f);
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
/// file and a tool table of tools 1-999 with no offsets.
fn run_rs274(bin: &Path, libs: &str, file: &Path) -> std::io::Result<String> {
    let dir = std::env::temp_dir().join(format!("burin-rs274-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let var = dir.join("sim.var");
    std::fs::write(&var, "")?;
    let tbl = dir.join("tool.tbl");
    let tools: String = (1..1000).map(|t| format!("T{t} P{t} Z0 D0\n")).collect();
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

fn args_of(line: &str) -> Vec<f64> {
    let (Some(a), Some(b)) = (line.find('('), line.rfind(')')) else {
        return Vec::new();
    };
    line.get(a + 1..b)
        .unwrap_or("")
        .split(',')
        .filter_map(|x| x.trim().parse::<f64>().ok())
        .collect()
}

/// rs274's verdict on one file.
enum Canon {
    /// End points (machine mm; `None` where rs274 prints none), cut at a probe.
    Ok(Vec<Option<P>>),
    Rejected(String),
}

fn parse(out: &str) -> Canon {
    let mut unit = 1.0;
    let (mut g5x, mut g92, mut tlo) = ([0.0; 4], [0.0; 4], [0.0; 4]);
    let mut plane = 0; // 0 XY, 1 XZ, 2 YZ
    let mut ends = Vec::new();
    for line in out.lines() {
        let t = line.trim_start();
        let body = match t.split_once(" N") {
            Some((n, rest)) if n.chars().all(|c| c.is_ascii_digit()) => {
                rest.split_once(' ').map_or("", |x| x.1).trim()
            }
            _ => {
                // rs274 wants M2 or `%` at the end; burin does not.
                if t.starts_with("File ended with no percent sign") {
                    return Canon::Ok(ends);
                }
                if t.is_empty() || t == "executing" {
                    continue;
                }
                return Canon::Rejected(t.to_string());
            }
        };
        let name = body.split('(').next().unwrap_or("");
        let a = args_of(body);
        let v = |i: usize| a.get(i).copied().unwrap_or(0.0);
        let machine = |p: [f64; 4]| -> P {
            let mut m = [0.0; 4];
            for i in 0..4 {
                let u = if i < 3 { unit } else { 1.0 };
                m[i] = (p[i] + g5x[i] + g92[i] + tlo[i]) * u;
            }
            m
        };
        match name {
            "USE_LENGTH_UNITS" => unit = if body.contains("INCHES") { 25.4 } else { 1.0 },
            "SET_G5X_OFFSET" => g5x = [v(1), v(2), v(3), v(4)],
            "SET_G92_OFFSET" => g92 = [v(0), v(1), v(2), v(3)],
            "USE_TOOL_LENGTH_OFFSET" => tlo = [v(0), v(1), v(2), v(3)],
            "SET_XY_ROTATION" if v(0) != 0.0 => {
                return Canon::Rejected("G10 R rotation (not in burin)".into())
            }
            "SELECT_PLANE" => {
                plane = if body.contains("XZ") {
                    1
                } else if body.contains("YZ") {
                    2
                } else {
                    0
                }
            }
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" | "STRAIGHT_PROBE" => {
                if v(4) != 0.0 || v(5) != 0.0 {
                    return Canon::Rejected("B/C axes (burin drives XYZA)".into());
                }
                ends.push(Some(machine([v(0), v(1), v(2), v(3)])));
                if name == "STRAIGHT_PROBE" {
                    return Canon::Ok(ends);
                }
            }
            "ARC_FEED" => {
                // (first_end, second_end, first_axis, second_axis, rot, axis_end, a, b, c)
                let (f, s, ax) = (v(0), v(1), v(5));
                let end = match plane {
                    0 => [f, s, ax, v(6)],
                    1 => [s, ax, f, v(6)],
                    _ => [ax, f, s, v(6)],
                };
                if v(7) != 0.0 || v(8) != 0.0 {
                    return Canon::Rejected("B/C axes (burin drives XYZA)".into());
                }
                ends.push(Some(machine(end)));
            }
            "NURBS_FEED" | "SPLINE_FEED" => ends.push(None),
            _ => {}
        }
    }
    Canon::Ok(ends)
}

/// Drops moves that end where the previous one did, the first one too
/// when it ends at the start (both run from machine zero; rs274 emits a
/// traverse to where it is for a bare `G00` after a tool change).
fn dedup<T: Copy>(v: Vec<Option<T>>, start: T, same: impl Fn(&T, &T) -> bool) -> Vec<Option<T>> {
    let mut out: Vec<Option<T>> = vec![Some(start)];
    for p in v {
        if let (Some(Some(a)), Some(b)) = (out.last(), p.as_ref()) {
            if same(a, b) {
                continue;
            }
        }
        out.push(p);
    }
    out.remove(0);
    out
}

/// One point for [`dedup`]: far below rs274's printed 0.0001 and the
/// agreement tolerance, so a 0.003 mm move (Cereal.ngc has them) is never
/// dropped on one side and kept on the other.
fn same_point(a: &P, b: &P) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 5e-4)
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
    let (mut agree, mut only_rs, mut only_burin, mut both) = (0, 0, 0, 0);
    let mut points = 0usize;
    let mut worst = 0.0f64;
    let mut bad = Vec::new();
    for f in files() {
        let name = f.display().to_string();
        let src =
            String::from_utf8_lossy(&std::fs::read(&f).with_context(|| name.clone())?).into_owned();
        let canon = parse(&run_rs274(&bin, &libs, &f).with_context(|| name.clone())?);
        let ours = host_sim::check::motion_ends(&src, &settings);
        let short = name
            .rsplit("corpus/")
            .next()
            .and_then(|n| n.rsplit("host-sim/").next())
            .unwrap_or(&name);
        match (canon, ours) {
            (Canon::Ok(theirs), Ok(ours)) => {
                let theirs = dedup(theirs, [0.0; 4], same_point);
                let ours: Vec<Option<P>> = ours
                    .iter()
                    .map(|p| Some([p[0] as f64, p[1] as f64, p[2] as f64, p[3] as f64]))
                    .collect();
                let ours = dedup(ours, [0.0; 4], same_point);
                // rs274 stops at a probe; compare that far.
                let n = theirs.len();
                let mut diff = None;
                for (i, t) in theirs.iter().enumerate() {
                    let (Some(t), Some(Some(o))) = (t, ours.get(i)) else {
                        if t.is_some() && ours.get(i).is_none() {
                            diff = Some(format!("move {i}: burin ends early"));
                            break;
                        }
                        continue;
                    };
                    let d = t
                        .iter()
                        .zip(o)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    worst = worst.max(d);
                    if d > TOL {
                        diff = Some(format!("move {i}: rs274 {t:?}, burin {o:?}"));
                        break;
                    }
                }
                let probe_cut = src.to_ascii_uppercase().contains("G38");
                if diff.is_none() && ours.len() != n && !probe_cut {
                    diff = Some(format!("{} moves in rs274, {} in burin", n, ours.len()));
                }
                match diff {
                    None => {
                        agree += 1;
                        points += n;
                        println!("agree     {short}: {n} end points");
                    }
                    Some(d) => {
                        println!("DISAGREE  {short}: {d}");
                        bad.push(short.to_string());
                    }
                }
            }
            (Canon::Ok(_), Err((l, e))) => {
                only_rs += 1;
                println!("burin rejects {short}:{l}: {e}");
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
    println!(
        "rs274 conformance: {agree} files agree ({points} end points, worst difference {worst:.4} mm, limit {TOL} mm); {only_rs} rejected by burin only, {only_burin} by rs274 only, {both} by both; {} disagree",
        bad.len()
    );
    if !bad.is_empty() {
        bail!("files where burin and rs274 disagree: {bad:?}");
    }
    Ok(())
}
