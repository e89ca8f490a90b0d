//! Jobs of bench-motion's own (issue 31), generated so the repository
//! holds their recipe rather than megabytes of G-code: the kinds the
//! third-party corpus lacks. Pen plotters and line-art lasers send
//! thousands of G1 moves under half a millimetre at feeds near the axis
//! rates; 3-D finishing passes send line contours whose Z turns at every
//! vertex. Deterministic (a fixed linear congruential generator), so the
//! figures are the same on every run.

use std::f64::consts::TAU;
use std::fmt::Write;

/// The generated jobs as (name, G-code), in bench order.
pub fn all() -> Vec<(&'static str, String)> {
    vec![
        ("gen:plotter_sketch", plotter_sketch(8000)),
        ("gen:plotter_hatch", plotter_hatch(3000)),
        ("gen:contour_3d", contour_3d(40)),
    ]
}

/// A small deterministic generator (Knuth's MMIX constants), in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn header(feed: f64) -> String {
    format!("G21 G90 G94 G17\nG0 Z1\nG0 X10 Y10\nG1 Z0 F600\nG1 F{feed}\n")
}

/// A pen sketch: `n` moves of about 0.26 mm at F2500 along a wandering
/// curve whose heading turns smoothly (a random walk of the turn rate),
/// with a pen lift every few hundred moves, as plotter toolchains emit
/// curves as dense polylines.
pub fn plotter_sketch(n: usize) -> String {
    let mut s = header(2500.0);
    let mut rng = Lcg(31);
    let (mut x, mut y, mut h, mut turn) = (10.0f64, 10.0f64, 0.0f64, 0.0f64);
    for k in 0..n {
        turn = (turn + (rng.next() - 0.5) * 0.08).clamp(-0.35, 0.35);
        h += turn;
        let l = 0.2 + 0.12 * rng.next();
        x += l * h.cos();
        y += l * h.sin();
        // Stay on a 100 mm sheet: turn back towards the middle.
        if !(5.0..=95.0).contains(&x) || !(5.0..=95.0).contains(&y) {
            h = (50.0 - y).atan2(50.0 - x);
            turn = 0.0;
        }
        let _ = writeln!(s, "G1 X{x:.3} Y{y:.3}");
        if k % 400 == 399 {
            let (nx, ny) = (5.0 + 90.0 * rng.next(), 5.0 + 90.0 * rng.next());
            let _ = write!(s, "G0 Z1\nG0 X{nx:.3} Y{ny:.3}\nG1 Z0 F600\nG1 F2500\n");
            (x, y) = (nx, ny);
        }
    }
    s.push_str("G0 Z1\nG0 X0 Y0\nG0 Z0\n");
    s
}

/// Line art with corners: `n` strokes of 0.1 to 0.5 mm at F4500, each
/// turning by up to ±100° from the last (lettering, hatching, traced
/// bitmaps).
pub fn plotter_hatch(n: usize) -> String {
    let mut s = header(4500.0);
    let mut rng = Lcg(7);
    let (mut x, mut y, mut h) = (10.0f64, 10.0f64, 0.0f64);
    for _ in 0..n {
        h += (rng.next() - 0.5) * 3.5;
        let l = 0.1 + 0.4 * rng.next();
        x += l * h.cos();
        y += l * h.sin();
        if !(5.0..=95.0).contains(&x) || !(5.0..=95.0).contains(&y) {
            h = (50.0 - y).atan2(50.0 - x);
        }
        let _ = writeln!(s, "G1 X{x:.3} Y{y:.3}");
    }
    s.push_str("G0 Z1\nG0 X0 Y0\nG0 Z0\n");
    s
}

/// A 3-D finishing pass: `rows` raster rows 1 mm apart over a 60 mm
/// surface of bumps, sampled every 0.3 mm (200 G1 moves a row), at F3000:
/// Z turns at every vertex, and X/Y run near their rates between.
pub fn contour_3d(rows: usize) -> String {
    let mut s = String::from("G21 G90 G94 G17\nG0 Z5\nG0 X0 Y0\nG1 F3000\n");
    let z = |x: f64, y: f64| -2.0 + 1.5 * (TAU * x / 20.0).sin() * (TAU * y / 25.0).cos();
    for r in 0..rows {
        let y = r as f64;
        for k in 0..=200 {
            let k = if r % 2 == 0 { k } else { 200 - k };
            let x = k as f64 * 0.3;
            let _ = writeln!(s, "G1 X{x:.3} Y{y:.3} Z{:.4}", z(x, y));
        }
    }
    s.push_str("G0 Z5\nG0 X0 Y0\n");
    s
}

#[cfg(test)]
mod tests {
    #[test]
    fn generated_jobs_are_large_and_stable() {
        for (name, src) in super::all() {
            let lines = src.lines().filter(|l| l.starts_with("G1 X")).count();
            assert!(lines >= 3000, "{name}: {lines} moves");
            assert_eq!(
                src,
                super::all().into_iter().find(|j| j.0 == name).unwrap().1
            );
        }
    }
}
