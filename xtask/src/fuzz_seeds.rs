//! Seeds for `cargo xtask fuzz`: G-code from `../shared/corpus` (when it is
//! there; never copied into the repo) and the project's own jobs and test
//! data, shaped into each target's input format (see `host_sim::fuzz`).
//! Written to `firmware/fuzz/seeds/<target>/` (ignored by git).

use anyhow::Result;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::util::root;

const MAX_FILES: usize = 400;
const MAX_BYTES: usize = 4096;

fn files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = rd.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if out.len() >= MAX_FILES {
            return;
        }
        if p.is_dir() {
            files_under(&p, out);
        } else if p.file_name().is_some_and(|n| n != "MANIFEST.tsv") {
            out.push(p);
        }
    }
}

/// G-code texts to seed from, with a note of where they came from.
fn sources() -> Vec<Vec<u8>> {
    let mut files = Vec::new();
    let shared = root().join("../shared/corpus");
    if shared.is_dir() {
        files_under(&shared, &mut files);
        eprintln!(
            "fuzz seeds: {} files from {}",
            files.len(),
            shared.display()
        );
    } else {
        eprintln!("fuzz seeds: ../shared/corpus skipped (not found)");
    }
    let n = files.len();
    files_under(&root().join("host-sim/jobs"), &mut files);
    files_under(&root().join("firmware/tests/data"), &mut files);
    eprintln!(
        "fuzz seeds: {} files from host-sim/jobs and firmware/tests/data",
        files.len() - n
    );
    files
        .iter()
        .filter_map(|p| std::fs::read(p).ok())
        .map(|mut d| {
            cut(&mut d, MAX_BYTES);
            d
        })
        .collect()
}

/// Shorten to at most `max` bytes at a line end.
fn cut(d: &mut Vec<u8>, max: usize) {
    if d.len() > max {
        let end = d[..max]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(max, |i| i + 1);
        d.truncate(end);
    }
}

fn first_lines(d: &[u8], n: usize) -> Vec<u8> {
    let mut out = Vec::new();
    for l in d.split(|&b| b == b'\n').take(n) {
        out.extend_from_slice(l);
        out.push(b'\n');
    }
    out
}

/// Device ops: each line as text (op 0, length, bytes) then time (op 11).
fn device_ops(d: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    for l in d.split(|&b| b == b'\n').take(12) {
        let l = &l[..l.len().min(63)];
        out.extend_from_slice(&[0, (l.len() + 1) as u8]);
        out.extend_from_slice(l);
        out.extend_from_slice(&[b'\n', 11, 20, 9]);
    }
    out
}

/// Issue 35's runaway, on the fuzz targets' machine (5 steps/mm, at
/// X-10 Y-10): a short arc on a huge radius, which the arc code before the
/// fix ran as a full circle. The chord is 1 mm (5 steps: start and end do
/// not round to the same steps, so no reading of it is a full circle), as
/// the 0.01 mm chord rounds to the start's steps on this machine.
/// Each line waits for the one before to finish (the device target's
/// seed adds the time), so the arc runs from a known point.
pub const RUNAWAY: &[&str] = &[
    "G21 G90 G53 G0 X-15 Y-15\nG17 G91 G2 X1 Y0 R3000000 F600\n",
    "G17 G91 G2 X1 Y0 I0.5 J-3000000 F600\n",
    "G17 G91 G3 X1 Y0 I0.5 J3000000 F600\n",
];

/// A runaway as device ops: each line, then `wait_ms` of virtual time.
pub fn device_runaway(text: &str, wait_ms: u32) -> Vec<u8> {
    let mut out = Vec::new();
    for l in text.lines() {
        out.extend_from_slice(&[0, (l.len() + 1) as u8]);
        out.extend_from_slice(l.as_bytes());
        out.push(b'\n');
        for _ in 0..wait_ms / 39 {
            out.extend_from_slice(&[11, 39]);
        }
    }
    out
}

/// A runaway as the executor target's input (flags 0: no soft limits).
pub fn executor_runaway(text: &str) -> Vec<u8> {
    [&[0u8][..], text.as_bytes()].concat()
}

const SETTINGS: &[&str] = &[
    "$$\n$100=5\n$110=3000\n$120=50\n$130=20\n",
    "$0=10\n$1=255\n$11=0.5\n$12=0.1\n$202=1\n$203=100\n$201=1000\n",
    "$22=1\n$23=3\n$24=10\n$25=100\n$27=0.5\n$206=12\n$20=1\n$130=0\n",
    "$32=1\n$30=1000\n$31=0\n$2=15\n$3=5\n$N\n$G\n$RST=*\n$J=G91X1F100\n",
];

fn write_seeds(dir: &Path, seeds: &[Vec<u8>]) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    for (i, s) in seeds.iter().enumerate() {
        std::fs::write(dir.join(format!("seed-{i:05}")), s)?;
    }
    Ok(())
}

/// Write `target`'s seeds; returns their directory.
pub fn write(target: &str) -> Result<PathBuf> {
    let dir = crate::fuzz::seed_dir(target);
    let _ = std::fs::remove_dir_all(&dir);
    let texts = sources();
    let seeds: Vec<Vec<u8>> = match target {
        "gcode_line" => {
            let lines: BTreeSet<&[u8]> = texts
                .iter()
                .flat_map(|t| t.split(|&b| b == b'\n'))
                .filter(|l| !l.is_empty() && l.len() < 200)
                .collect();
            lines
                .into_iter()
                .take(3000)
                .enumerate()
                .map(|(i, l)| [&[i as u8][..], l].concat())
                .collect()
        }
        "gcode_program" => texts,
        "executor" => texts
            .iter()
            .map(|t| [&[0u8][..], &first_lines(t, 24)].concat())
            .chain(RUNAWAY.iter().map(|t| executor_runaway(t)))
            .collect(),
        "device" => texts
            .iter()
            .map(|t| device_ops(t))
            .chain(RUNAWAY.iter().map(|t| device_runaway(t, 2000)))
            .collect(),
        "settings" => SETTINGS
            .iter()
            .map(|s| [&[0u8, 8, 8, 8, 1][..], s.as_bytes()].concat())
            .collect(),
        _ => vec![
            vec![0],
            vec![1, 1, 0, 0, 0, 0, 4, b'G', b'1', b'X', b'1'],
            vec![2, 1, 0, 0, 0],
        ],
    };
    write_seeds(&dir, &seeds)?;
    eprintln!("fuzz seeds: {} for {target}", seeds.len());
    Ok(dir)
}
