//! Jerk in `cargo xtask bench-motion` (issue 31, item 4): a meter on the
//! segments' own speed profile, and a jerk-limited lower bound on the
//! job's time.
//!
//! `$203` is burin's jerk limit along the path (`planner::ramp`): the rate
//! of change of the path acceleration. Both figures here are about that.
//!
//! **The meter** ([`JerkMeter`]). The step trace's windows
//! (`bench::limits`) cannot see it: their jerk is a third difference of
//! step positions over 50 ms, whose quantisation alone is 400 mm/s³, and
//! which reads a trapezoid's acceleration step of 500 mm/s² as about
//! 7,500 mm/s³, so 50,000 mm/s³ and a trapezoid read alike. The segments
//! carry their own mean path speed (`Segment::speed_mm_min`, recorded as
//! the running speed at each step interrupt that changes it), and a
//! segment ends at a step's instant, so the path position at each change
//! is the integral of those speeds, exact but for where the last step of
//! a segment lies. The meter takes the third divided difference of that
//! position over points at least [`JerkMeter::window_s`] apart: a weighted
//! mean of the path jerk with a B-spline kernel of unit weight, so never
//! above the true peak, while a step `Δa` in the acceleration reads up to
//! `0.75·Δa/W`. The window is chosen so that a step of the machine's
//! largest axis acceleration reads twice the limit
//! (`W = 0.75·a/(2·j)`, 3 to 50 ms): a trapezoid then reads at least 200 %.
//!
//! **The bound** ([`jerk_bound`]): the same limits as `bench::bound` plus
//! the path jerk `$203`, as a time no controller that keeps them can beat.
//! The trapezoid bound's profile `V(s)` is the pointwise fastest under
//! the other limits, so every admissible profile runs below it. Jerk adds
//! that the acceleration cannot jump: passing a point `s_k` at `w ≤ V(s_k)`
//! with acceleration `α`, the speed `τ` seconds later is at most
//! `w + ∫₀^τ min(α + j·u, a) du`, and `τ` seconds earlier at most
//! `w + ∫₀^τ min(j·u − α, a) du` (`a` the largest path acceleration near
//! `s_k`). The path is cut at the peaks of `V` into pieces each holding
//! one valley `s_k` of `V` (a corner or a stop; at a stop `w = 0`); in each,
//! the time is at least that of the fastest motion under both `V` and
//! these two envelopes, minimised over `α`, and the job's time at least
//! the sum. Each step of the computation errs on the fast side: `V` is
//! taken at its largest over cells of at most 0.05 mm, the envelope at its
//! largest over each cell's time, times are solved from below, and the
//! minimum over `α ∈ [−a, a]` is taken over a grid by pairing each
//! interval's ends (the time after `s_k` falls with `α`, the time before
//! it rises). So it is a lower bound, and a loose one where the jerk
//! matters between valleys (rounding a peak of `V` is free here) or on
//! curves (the turn's own jerk, `v³/r²` per axis, is not counted).

use super::bound::PieceProfile;
use crate::record::Recorder;

/// Third divided differences of the path position at the segments'
/// speed changes.
#[derive(Clone, Debug)]
pub struct JerkMeter {
    /// Points at least this far apart, s.
    pub window_s: f64,
    tick_hz: f64,
    last: Option<(u64, f64)>,
    pos: f64,
    /// Points kept (time s, path mm), newest last, at least `window_s`
    /// apart.
    pts: Vec<(f64, f64)>,
    /// Highest |jerk| seen, mm/s³, and when (s).
    pub peak: f64,
    pub peak_s: f64,
}

impl JerkMeter {
    /// `accel`: the machine's largest axis acceleration, mm/s²; `jerk`:
    /// `$203`, mm/s³.
    pub fn new(tick_hz: u32, accel: f64, jerk: f64) -> Self {
        JerkMeter {
            window_s: (accel / (4.0 * jerk.max(1.0))).clamp(0.002, 0.05),
            tick_hz: f64::from(tick_hz),
            last: None,
            pos: 0.0,
            pts: Vec::new(),
            peak: 0.0,
            peak_s: 0.0,
        }
    }

    fn point(&mut self, t: f64, s: f64) {
        if let Some(&(t0, _)) = self.pts.last() {
            if t - t0 < self.window_s {
                return;
            }
        }
        self.pts.push((t, s));
        let n = self.pts.len();
        if n < 4 {
            return;
        }
        let w = &self.pts[n - 4..];
        let dd = |a: (f64, f64), b: (f64, f64)| (b.1 - a.1) / (b.0 - a.0);
        let d1 = [dd(w[0], w[1]), dd(w[1], w[2]), dd(w[2], w[3])];
        let d2 = [
            (d1[1] - d1[0]) / (w[2].0 - w[0].0),
            (d1[2] - d1[1]) / (w[3].0 - w[1].0),
        ];
        let j = 6.0 * (d2[1] - d2[0]) / (w[3].0 - w[0].0);
        if j.abs() > self.peak {
            self.peak = j.abs();
            self.peak_s = 0.5 * (w[1].0 + w[2].0);
        }
        self.pts.drain(..n - 3);
    }
}

impl Recorder for JerkMeter {
    fn velocity(&mut self, tick: u64, mm_per_min: f32) {
        if let Some((t0, v)) = self.last {
            self.pos += v * (tick - t0) as f64 / self.tick_hz;
        }
        self.point(tick as f64 / self.tick_hz, self.pos);
        self.last = Some((tick, f64::from(mm_per_min) / 60.0));
    }
}

/// Cells of at most this length, mm.
const CELL_MM: f64 = 0.05;
/// Accelerations tried at a valley: `2·GRID + 1` from `−a` to `a`.
const GRID: usize = 12;

/// One cell of the path: length, the trapezoid bound's highest speed
/// over it, and the time the trapezoid bound's own profile takes over it
/// (no motion under that profile is faster there).
#[derive(Clone, Copy)]
struct Cell {
    h: f64,
    vmax: f64,
    tv: f64,
}

/// The jerk-limited lower bound of a job whose trapezoid bound's profile
/// is `prof` (`Bound::profile`, dwells included), at path jerk `jerk`
/// mm/s³; seconds. See the module doc.
pub fn jerk_bound(prof: &[PieceProfile], jerk: f64) -> f64 {
    bound_with(prof, jerk, true)
}

/// A reference, not a bound: [`jerk_bound`] with the path acceleration
/// zero at every valley (each corner or stop that is the slowest point
/// between two peaks of the trapezoid bound's profile), as where each S
/// ramp starts and ends at a corner. What the bound has below it is what
/// carrying acceleration through those corners could gain at most.
pub fn jerk_rest_ref(prof: &[PieceProfile], jerk: f64) -> f64 {
    bound_with(prof, jerk, false)
}

/// `free`: the valley's acceleration minimised over `[−a, a]`, else 0.
fn bound_with(prof: &[PieceProfile], jerk: f64, free: bool) -> f64 {
    let n = prof.len();
    if n == 0 || jerk <= 0.0 {
        return prof.last().map_or(0.0, |p| p.end_s);
    }
    // Dwells: what the profile's end time has beyond its motion.
    let motion: f64 = prof.iter().map(|p| p.time_s()).sum();
    let dwell = (prof[n - 1].end_s - motion).max(0.0);
    let mut cells: Vec<Cell> = Vec::new();
    // Per piece: first cell, cell at its peak, peak speed, acceleration.
    let mut first = Vec::with_capacity(n + 1);
    let mut peak_cell = Vec::with_capacity(n);
    let mut peak_v = Vec::with_capacity(n);
    for p in prof {
        let (a, len) = (p.accel.max(1e-9), p.len);
        let v_at = |u: f64| {
            let up = (p.v0 * p.v0 + 2.0 * a * u).max(0.0).sqrt();
            let down = (p.v1 * p.v1 + 2.0 * a * (len - u)).max(0.0).sqrt();
            up.min(down).min(p.cap).max(p.v0.min(p.v1))
        };
        let top = ((p.v1 * p.v1 - p.v0 * p.v0 + 2.0 * a * len) / (4.0 * a)).clamp(0.0, len);
        // Time under `v_at` from `0` to `u`: the ramp up, the cruise, the
        // ramp down, each exact.
        let vt = v_at(top);
        let u_up = ((vt * vt - p.v0 * p.v0) / (2.0 * a)).clamp(0.0, top);
        let u_down = (len - (vt * vt - p.v1 * p.v1) / (2.0 * a)).clamp(top, len);
        let t_at = |u: f64| {
            let up = u.min(u_up);
            let mut t = ((p.v0 * p.v0 + 2.0 * a * up).sqrt() - p.v0) / a;
            let flat = (u.min(u_down) - u_up).max(0.0);
            t += flat / vt.max(1e-12);
            if u > u_down {
                let w0 = (p.v1 * p.v1 + 2.0 * a * (len - u_down)).sqrt();
                let w1 = (p.v1 * p.v1 + 2.0 * a * (len - u)).max(0.0).sqrt();
                t += (w0 - w1) / a;
            }
            t
        };
        first.push(cells.len());
        for (lo, hi, rising) in [(0.0, top, true), (top, len, false)] {
            let m = ((hi - lo) / CELL_MM).ceil().max(1.0) as usize;
            if hi - lo <= 0.0 {
                if rising {
                    peak_cell.push(cells.len());
                }
                continue;
            }
            let h = (hi - lo) / m as f64;
            for i in 0..m {
                // Unimodal: a cell's largest speed is at its end nearer the top.
                let (c0, c1) = (lo + i as f64 * h, lo + (i + 1) as f64 * h);
                let u = if rising { c1 } else { c0 };
                cells.push(Cell {
                    h,
                    vmax: v_at(u),
                    tv: (t_at(c1) - t_at(c0)).max(0.0),
                });
            }
            if rising {
                peak_cell.push(cells.len());
            }
        }
        peak_v.push(v_at(top));
    }
    first.push(cells.len());
    let vertex_v = |k: usize| if k < n { prof[k].v0 } else { prof[n - 1].v1 };
    // Regions: cut at the pieces whose peak is a local maximum of the
    // peaks; each holds the vertices between two cuts.
    let mut cuts = Vec::new();
    for p in 0..n {
        let left = p == 0 || peak_v[p] >= peak_v[p - 1];
        let right = p + 1 == n || peak_v[p] >= peak_v[p + 1];
        if left && right {
            cuts.push(p);
        }
    }
    let mut total = dwell;
    // Region edges in cells and the vertices inside.
    let mut lo_cell = 0;
    let mut lo_vertex = 0;
    for r in 0..=cuts.len() {
        let (hi_cell, hi_vertex) = match cuts.get(r) {
            Some(&p) => (peak_cell[p], p),
            None => (cells.len(), n),
        };
        // Vertex k lies between pieces k-1 and k: region vertices are
        // lo_vertex..=hi_vertex.
        let valley = (lo_vertex..=hi_vertex)
            .min_by(|&x, &y| vertex_v(x).total_cmp(&vertex_v(y)))
            .unwrap_or(lo_vertex);
        let at = first[valley].clamp(lo_cell, hi_cell);
        let a = prof[lo_vertex.saturating_sub(1).min(n - 1)..hi_vertex.min(n - 1) + 1]
            .iter()
            .map(|p| p.accel)
            .fold(0.0f64, f64::max);
        total += region_time(
            &cells[lo_cell..at],
            &cells[at..hi_cell],
            vertex_v(valley),
            a,
            jerk,
            free,
        );
        lo_cell = hi_cell;
        lo_vertex = hi_vertex + 1;
    }
    total
}

/// Least time over `before` (walked backwards from the valley) and
/// `after`, the valley passed at `w` with some acceleration in `[−a, a]`
/// (`free`), or none.
fn region_time(before: &[Cell], after: &[Cell], w: f64, a: f64, j: f64, free: bool) -> f64 {
    if w <= 0.0 || !free {
        // At speed zero the acceleration is zero too (it cannot be
        // negative after, nor positive before, a point where the speed is
        // zero).
        let w = w.max(0.0);
        return walk(before.iter().rev(), w, 0.0, a, j) + walk(after.iter(), w, 0.0, a, j);
    }
    let alphas: Vec<f64> = (0..=2 * GRID)
        .map(|i| a * (i as f64 / GRID as f64 - 1.0))
        .collect();
    let fwd: Vec<f64> = alphas
        .iter()
        .map(|&al| walk(after.iter(), w, al, a, j))
        .collect();
    let back: Vec<f64> = alphas
        .iter()
        .map(|&al| walk(before.iter().rev(), w, -al, a, j))
        .collect();
    (0..2 * GRID)
        .map(|i| back[i] + fwd[i + 1])
        .fold(f64::INFINITY, f64::min)
        .min(back[2 * GRID] + fwd[2 * GRID])
}

/// Envelope speed `tau` s after the valley: `w + ∫₀^τ min(α + j·u, a) du`.
fn envelope(w: f64, al: f64, a: f64, j: f64, tau: f64) -> f64 {
    // The acceleration reaches `a` at `tc`.
    let tc = ((a - al) / j).max(0.0);
    if tau <= tc {
        w + al * tau + 0.5 * j * tau * tau
    } else {
        w + al * tc + 0.5 * j * tc * tc + a * (tau - tc)
    }
}

/// Earliest time through `cells` from the valley, each cell's speed at
/// most its `vmax` and the envelope's largest over its time (the envelope
/// is convex in time, so that is at one end), and never less than the
/// trapezoid bound's own time over it.
fn walk<'a>(cells: impl Iterator<Item = &'a Cell>, w: f64, al: f64, a: f64, j: f64) -> f64 {
    let mut tau = 0.0;
    let cells: Vec<&Cell> = cells.collect();
    // Past the point where the envelope is above every cell left, only
    // the cells' own speeds count.
    let mut rest_max = vec![0.0f64; cells.len() + 1];
    let mut rest_time = vec![0.0f64; cells.len() + 1];
    for i in (0..cells.len()).rev() {
        rest_max[i] = rest_max[i + 1].max(cells[i].vmax);
        rest_time[i] = rest_time[i + 1] + cells[i].tv;
    }
    for (i, c) in cells.iter().enumerate() {
        let e0 = envelope(w, al, a, j, tau);
        if e0 >= rest_max[i] {
            return tau + rest_time[i];
        }
        let speed = |t: f64| c.vmax.min(e0.max(envelope(w, al, a, j, tau + t)));
        // Smallest t with t·speed(t) ≥ h, from below.
        let mut hi = c.h / c.vmax.max(1e-12);
        while hi * speed(hi) < c.h {
            hi *= 2.0;
            if hi > 1e6 {
                return f64::INFINITY;
            }
        }
        let mut lo = 0.0;
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if mid * speed(mid) < c.h {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        tau += lo.max(c.tv);
    }
    tau
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::PathKind;

    fn line(len: f64, cap: f64, a: f64) -> PieceProfile {
        let p = PieceProfile {
            end_mm: [0.0; burin::AXES],
            unit: [0.0; burin::AXES],
            kind: PathKind::Feed,
            len,
            v0: 0.0,
            v1: 0.0,
            cap,
            accel: a,
            end_s: 0.0,
        };
        PieceProfile {
            end_s: p.time_s(),
            ..p
        }
    }

    /// One line from rest to rest: the jerk-limited time is two S ramps
    /// and a cruise; the bound is below it, and close.
    #[test]
    fn a_line_is_bounded_by_its_s_curve_time() {
        let (len, v, a, j) = (100.0, 50.0, 500.0, 5000.0);
        let ramp_t = v / a + a / j;
        let exact = 2.0 * ramp_t + (len - v * ramp_t) / v;
        let b = jerk_bound(&[line(len, v, a)], j);
        assert!(b <= exact + 1e-9, "{b} over {exact}");
        assert!(b >= 0.99 * exact, "{b} far below {exact}");
        // And above the trapezoid's.
        assert!(b > line(len, v, a).end_s + 0.5 * a / j);
    }

    /// The reference with no acceleration at the valleys is the bound
    /// itself where the valley is a stop, and above it at a corner passed
    /// at speed, where the bound may carry acceleration through.
    #[test]
    fn the_rest_reference_pins_the_valleys_acceleration() {
        let (a, j) = (500.0, 5000.0);
        let one = [line(20.0, 50.0, a)];
        assert_eq!(jerk_bound(&one, j), jerk_rest_ref(&one, j));
        // Two 2 mm lines meeting at 10 mm/s.
        let first = PieceProfile {
            v1: 10.0,
            ..line(2.0, 50.0, a)
        };
        let first = PieceProfile {
            end_s: first.time_s(),
            ..first
        };
        let second = PieceProfile {
            v0: 10.0,
            ..line(2.0, 50.0, a)
        };
        let second = PieceProfile {
            end_s: first.end_s + second.time_s(),
            ..second
        };
        let prof = [first, second];
        let (b, r) = (jerk_bound(&prof, j), jerk_rest_ref(&prof, j));
        assert!(r > b * 1.001, "reference {r} not above the bound {b}");
    }

    /// A meter fed a trapezoid's speed reads its acceleration step as far
    /// above the limit it was built for; an S ramp within it reads below.
    #[test]
    fn the_meter_tells_a_trapezoid_from_an_s_ramp() {
        let (a, j, hz) = (500.0, 50_000.0, 1_000_000u32);
        let run = |jerk_limited: bool| {
            let mut m = JerkMeter::new(hz, a, j);
            let dt = 0.002;
            let mut v: f64 = 0.0;
            let mut acc: f64 = 0.0;
            for k in 0..200 {
                let target = if k < 100 { a } else { 0.0 };
                acc = if jerk_limited {
                    target.min(acc + j * dt).max(acc - j * dt)
                } else {
                    target
                };
                let v0 = v;
                v += acc * dt;
                // A segment's mean speed, as recorded.
                let mean = 0.5 * (v0 + v);
                m.velocity((k as f64 * dt * f64::from(hz)) as u64, (mean * 60.0) as f32);
            }
            m.peak
        };
        assert!(run(false) > 1.2 * j, "{}", run(false));
        assert!(run(true) < 1.1 * j, "{}", run(true));
    }
}
