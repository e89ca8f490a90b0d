//! The time-optimal bound of `cargo xtask bench-motion`: how fast the
//! commanded path could be run at best under the machine's stated limits.
//! A small reference written apart from the planner (no ring, no step
//! rounding, no incremental replanning), so that the planner is judged
//! against something that does not share its mistakes.
//!
//! The path is the commanded one in millimetres, as the executor expands it
//! (arcs and splines as their chords, at the same `$12` tolerance), with the
//! stops the job asks for (dwells, synced commands). Constraints, and only
//! the stated ones (issue 31):
//!
//! * on each straight piece, every axis within its rate (`$110`…) and its
//!   acceleration (`$120`…): path speed `≤ min_i vmax_i/|u_i|`, path
//!   acceleration `≤ min_i amax_i/|u_i|` (`u` the unit direction);
//! * at each vertex, junction deviation (`$11`), with the acceleration the
//!   axes allow along the direction change, on the commanded geometry;
//! * the programmed feed; standstill at the start, the end and every stop.
//!
//! No rule of burin's own: not its curvature rule `v² ≤ a·l/φ` on chords,
//! not its corner holds (issue 12's bound had the first; GRBL, keeping
//! every window limit, beat it on circle_small and zigzag). So the bound is
//! the fastest that any controller can be that honours `$110`–`$122`,
//! `$11` and `$12` as GRBL states them. A controller that also keeps each
//! axis's centripetal acceleration on curves (the meter's curvature check,
//! [`super::curvature`]) cannot reach it where the chords turn faster than
//! that allows: the table's "bound curv" column shows by how much.
//!
//! Why it is a lower bound: one backward and one forward pass over the
//! whole job (unlimited look-ahead) give, at every point, the highest speed
//! that any profile meeting these constraints can have there (each pass only
//! lowers a speed that some constraint forbids, and the result is feasible).
//! A profile that is pointwise fastest takes the least time. The bound is
//! more permissive than the real machine in two ways, both of which only
//! make it smaller: on a curve it gives the tangential acceleration the
//! whole budget, as if the centripetal part were free, and it is the
//! faster of two profiles: on the commanded path, and on the path rounded
//! to whole steps. A controller may plan either: burin judges corners on
//! the commanded path, GRBL plans the rounded one, which is how GRBL beat
//! the commanded-only bound on zigzag (its 0.0508 mm swings round to 4
//! steps, 0.05 mm: a path 0.8 % shorter). So no planner that keeps the
//! same limits and corner rule on either geometry can be faster; a ratio
//! below 1.00 means a limit was broken.

use burin::settings::Settings;
use burin::AXES;

use crate::record::{PathEvent, PathKind};

/// One straight piece of the path.
#[derive(Clone, Copy, Debug)]
struct Piece {
    /// Its commanded geometry, and the one rounded to whole steps.
    cmd: Shape,
    step: Shape,
    /// Fixed duration (G93), if any: the piece runs at `len/seconds`.
    seconds: Option<f64>,
    /// Motion stops before this piece (a dwell or synced command).
    stop_before: bool,
    /// Dwell time just before this piece, s.
    dwell_before: f64,
    end: [f64; AXES],
    kind: PathKind,
}

/// A piece's length, direction and the limits along it.
#[derive(Clone, Copy, Debug)]
struct Shape {
    len: f64,
    unit: [f64; AXES],
    /// Highest speed on it, mm/s.
    cap: f64,
    /// Highest path acceleration on it, mm/s².
    accel: f64,
}

/// One piece of the bound's profile, for locating where a run loses time
/// against it ([`super::losses`]).
#[derive(Clone, Copy, Debug)]
pub struct PieceProfile {
    pub end_mm: [f64; AXES],
    pub unit: [f64; AXES],
    pub kind: PathKind,
    pub len: f64,
    /// Speeds at the piece's start and end, mm/s.
    pub v0: f64,
    pub v1: f64,
    /// Cruise speed and path acceleration it was timed with.
    pub cap: f64,
    pub accel: f64,
    /// When the piece ends, s from the first step (dwells included).
    pub end_s: f64,
}

impl PieceProfile {
    /// How long the piece's motion takes, s.
    pub fn time_s(&self) -> f64 {
        piece_time(self.v0, self.v1, self.cap, self.accel, self.len)
    }

    /// Distance along the piece `tau` s after its motion starts, mm.
    pub fn dist_at(&self, tau: f64) -> f64 {
        let (v0, v1, a, len) = (self.v0, self.v1, self.accel, self.len);
        let peak = peak_speed(v0, v1, self.cap, a, len);
        let t_up = (peak - v0) / a;
        let d_up = (peak * peak - v0 * v0) / (2.0 * a);
        let d_down = (peak * peak - v1 * v1) / (2.0 * a);
        let cruise = (len - d_up - d_down).max(0.0);
        let t_cruise = cruise / peak.max(1e-12);
        let d = if tau < t_up {
            v0 * tau + 0.5 * a * tau * tau
        } else if tau < t_up + t_cruise {
            d_up + peak * (tau - t_up)
        } else {
            let t = (tau - t_up - t_cruise).min((peak - v1) / a);
            d_up + cruise + peak * t - 0.5 * a * t * t
        };
        d.clamp(0.0, len)
    }
}

/// Builds the path from [`PathEvent`]s and answers its best time.
#[derive(Clone, Debug)]
pub struct Bound {
    settings: Settings,
    pos: Option<[f64; AXES]>,
    /// Where the motors stand: `pos` rounded to whole steps.
    pos_step: [f64; AXES],
    pieces: Vec<Piece>,
    stop_pending: bool,
    /// Dwells seen since the last piece (counted only if motion follows).
    dwell_pending: f64,
    /// Add burin's curvature rule at every vertex ([`Bound::with_curvature_rule`]).
    curvature_rule: bool,
}

impl Bound {
    /// `start_mm`: where the machine stands before the job.
    pub fn new(settings: Settings, start_mm: [f32; AXES]) -> Self {
        let start = start_mm.map(f64::from);
        Bound {
            pos_step: Self::stepped(&settings, &start),
            settings,
            pos: Some(start),
            pieces: Vec::new(),
            stop_pending: false,
            curvature_rule: false,
            dwell_pending: 0.0,
        }
    }

    pub fn push(&mut self, ev: &PathEvent) {
        match *ev {
            PathEvent::Stop { seconds } => {
                self.stop_pending = true;
                self.dwell_pending += f64::from(seconds.max(0.0));
            }
            PathEvent::To {
                to_mm,
                feed_mm_s,
                seconds,
                kind,
            } => {
                let to = to_mm.map(f64::from);
                let from = self.pos.replace(to).unwrap_or(to);
                let to_step = Self::stepped(&self.settings, &to);
                let from_step = std::mem::replace(&mut self.pos_step, to_step);
                let shape = |from: &[f64; AXES], to: &[f64; AXES]| {
                    let d: [f64; AXES] = std::array::from_fn(|i| to[i] - from[i]);
                    let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
                    let unit = d.map(|v| v / len.max(1e-300));
                    let (mut cap, mut accel) = (f64::from(feed_mm_s), f64::INFINITY);
                    for (u, ax) in unit.iter().zip(&self.settings.axes) {
                        if u.abs() > 1e-12 {
                            cap = cap.min(f64::from(ax.max_rate) / 60.0 / u.abs());
                            accel = accel.min(f64::from(ax.max_accel) / u.abs());
                        }
                    }
                    Shape {
                        len,
                        unit,
                        cap,
                        accel,
                    }
                };
                let (cmd, step) = (shape(&from, &to), shape(&from_step, &to_step));
                // No step, no motion (the planner drops such a move).
                if cmd.len < 1e-9 || step.len < 1e-9 {
                    return;
                }
                // Dwells before the first motion are not in the job time.
                let dwell = std::mem::take(&mut self.dwell_pending);
                let dwell_before = if self.pieces.is_empty() { 0.0 } else { dwell };
                self.pieces.push(Piece {
                    cmd,
                    step,
                    seconds: seconds.map(f64::from),
                    stop_before: std::mem::take(&mut self.stop_pending),
                    dwell_before,
                    end: to,
                    kind,
                });
            }
        }
    }

    /// `mm` rounded to whole steps of each axis, as the planner's
    /// `to_steps` rounds, back in mm.
    fn stepped(s: &Settings, mm: &[f64; AXES]) -> [f64; AXES] {
        std::array::from_fn(|i| {
            let spm = f64::from(s.axes[i].steps_per_mm);
            if spm > 0.0 {
                (mm[i] * spm).round() / spm
            } else {
                mm[i]
            }
        })
    }

    /// The commanded end of the path, mm.
    pub fn end_mm(&self) -> [f64; AXES] {
        self.pos.unwrap_or([0.0; AXES])
    }

    /// A reference, not the bound: the same path with burin's curvature
    /// rule `v² ≤ a·l/φ` at every vertex too (issue 12's bound). No limit
    /// states it, so it bounds nothing; the gap between it and the bound
    /// is what the curves' own centripetal acceleration costs a controller
    /// that keeps it (which the bound's "curv" figure says the bound does
    /// not), and the gap between burin and it what burin loses elsewhere.
    pub fn with_curvature_rule(&self) -> Self {
        Bound {
            curvature_rule: true,
            ..self.clone()
        }
    }

    /// Corner limit between shapes `a` and `b` (mm/s).
    fn corner(&self, a: &Shape, b: &Shape) -> f64 {
        self.vertex(&a.unit, &b.unit, a.len.min(b.len))
    }

    /// Corner limit from direction `a` to `b`, the shorter piece `len` mm.
    fn vertex(&self, a: &[f64; AXES], b: &[f64; AXES], len: f64) -> f64 {
        let cos = a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        if cos > 1.0 - 1e-12 {
            return f64::INFINITY;
        }
        let d: [f64; AXES] = std::array::from_fn(|i| b[i] - a[i]);
        let dn = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut acc = f64::INFINITY;
        for (di, ax) in d.iter().zip(&self.settings.axes) {
            let c = di.abs() / dn;
            if c > 1e-9 {
                acc = acc.min(f64::from(ax.max_accel) / c);
            }
        }
        // Junction deviation, with θ the angle between the moves' reversed
        // first and second directions (π when straight on).
        let sin_half = (0.5 * (1.0 + cos)).sqrt();
        if sin_half >= 1.0 {
            return f64::INFINITY;
        }
        let r = f64::from(self.settings.junction_deviation) * sin_half / (1.0 - sin_half);
        let jd = (acc * r).sqrt();
        if !self.curvature_rule {
            return jd;
        }
        let phi = cos.clamp(-1.0, 1.0).acos().max(1e-12);
        jd.min((acc * len / phi).sqrt())
    }

    /// Number of pieces so far (zero-length moves make none).
    pub fn pieces(&self) -> usize {
        self.pieces.len()
    }

    /// Seconds from the first step to the last: the time-optimal profile
    /// plus the dwells in between, on the faster geometry.
    pub fn time_s(&self) -> f64 {
        self.profile().last().map_or(0.0, |p| p.end_s)
    }

    /// The time-optimal profile, piece by piece, on the faster of the two
    /// geometries (the commanded path, or the one rounded to steps).
    pub fn profile(&self) -> Vec<PieceProfile> {
        self.profiles().0
    }

    /// [`Self::profile`], and the time-optimal profile on the commanded
    /// path, whose piece lengths are the commanded ones: the curvature
    /// check divides them by the trace's times to get its speeds
    /// (`bench::curvature`). Both from the two profiles computed once.
    pub fn profiles(&self) -> (Vec<PieceProfile>, Vec<PieceProfile>) {
        let cmd = self.profile_on(|p| &p.cmd);
        let step = self.profile_on(|p| &p.step);
        let end = |p: &[PieceProfile]| p.last().map_or(0.0, |q| q.end_s);
        if end(&step) < end(&cmd) {
            (step, cmd)
        } else {
            (cmd.clone(), cmd)
        }
    }

    /// The time-optimal profile on one geometry.
    fn profile_on(&self, geometry: impl Fn(&Piece) -> &Shape) -> Vec<PieceProfile> {
        let p = &self.pieces;
        let n = p.len();
        if n == 0 {
            return Vec::new();
        }
        let cap = |q: &Piece| {
            let g = geometry(q);
            match q.seconds {
                Some(t) if t > 0.0 => g.cap.min(q.cmd.len / t),
                _ => g.cap,
            }
        };
        // v[k]: speed at the start of piece k; v[n] the end of the job.
        let mut v = vec![0.0f64; n + 1];
        for k in 1..n {
            v[k] = if p[k].stop_before {
                0.0
            } else {
                self.corner(geometry(&p[k - 1]), geometry(&p[k]))
                    .min(cap(&p[k - 1]))
                    .min(cap(&p[k]))
            };
        }
        for k in (0..n).rev() {
            let g = geometry(&p[k]);
            v[k] = v[k].min((v[k + 1] * v[k + 1] + 2.0 * g.accel * g.len).sqrt());
        }
        for k in 0..n {
            let g = geometry(&p[k]);
            v[k + 1] = v[k + 1].min((v[k] * v[k] + 2.0 * g.accel * g.len).sqrt());
        }
        let mut t = 0.0;
        p.iter()
            .enumerate()
            .map(|(k, q)| {
                let g = geometry(q);
                t += q.dwell_before + piece_time(v[k], v[k + 1], cap(q), g.accel, g.len);
                PieceProfile {
                    end_mm: q.end,
                    unit: g.unit,
                    cap: cap(q),
                    accel: g.accel,
                    kind: q.kind,
                    len: g.len,
                    v0: v[k],
                    v1: v[k + 1],
                    end_s: t,
                }
            })
            .collect()
    }
}

/// Where the up and down ramps meet, capped by the cruise speed.
fn peak_speed(v0: f64, v1: f64, vc: f64, a: f64, len: f64) -> f64 {
    ((2.0 * a * len + v0 * v0 + v1 * v1) / 2.0)
        .sqrt()
        .min(vc)
        .max(v0.max(v1))
}

/// Time of the fastest trapezoid over `len` from `v0` to `v1` (both
/// reachable), cruising at most at `vc`, accelerating at most at `a`.
fn piece_time(v0: f64, v1: f64, vc: f64, a: f64, len: f64) -> f64 {
    let peak = peak_speed(v0, v1, vc, a, len);
    let up = (peak * peak - v0 * v0) / (2.0 * a);
    let down = (peak * peak - v1 * v1) / (2.0 * a);
    let cruise = (len - up - down).max(0.0);
    (peak - v0) / a + (peak - v1) / a + cruise / peak.max(1e-12)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn to(x: f32, y: f32, f: f32) -> PathEvent {
        PathEvent::To {
            kind: PathKind::Feed,
            to_mm: burin::pad([x, y, 0.0, 0.0]),
            feed_mm_s: f,
            seconds: None,
        }
    }

    #[test]
    fn straight_line_is_one_trapezoid() {
        let s = Settings::default();
        let a = f64::from(s.axes[0].max_accel);
        let mut b = Bound::new(s, [0.0; AXES]);
        b.push(&to(100.0, 0.0, 10.0));
        // 10 mm/s: ramps of 10/a s each way, cruise for the rest.
        let ramp = 10.0 / a;
        let want = 2.0 * ramp + (100.0 - 10.0 * ramp) / 10.0;
        assert!((b.time_s() - want).abs() < 1e-9, "{} vs {want}", b.time_s());
    }

    #[test]
    fn collinear_split_costs_nothing_and_a_stop_costs_a_ramp() {
        let s = Settings::default();
        let mut one = Bound::new(s, [0.0; AXES]);
        one.push(&to(100.0, 0.0, 10.0));
        let mut two = Bound::new(s, [0.0; AXES]);
        two.push(&to(50.0, 0.0, 10.0));
        two.push(&to(100.0, 0.0, 10.0));
        assert!((one.time_s() - two.time_s()).abs() < 1e-9);
        let mut stop = Bound::new(s, [0.0; AXES]);
        stop.push(&to(50.0, 0.0, 10.0));
        stop.push(&PathEvent::Stop { seconds: 1.0 });
        stop.push(&to(100.0, 0.0, 10.0));
        assert!(stop.time_s() > one.time_s() + 1.0);
    }

    /// Chords of a small circle turning by φ each: the bound passes each
    /// vertex at the junction deviation speed alone, faster than burin's
    /// own curvature rule `v² ≤ a·l/φ` would (issue 31: that rule is no
    /// stated limit, so a bound with it was no lower bound).
    #[test]
    fn chord_vertices_run_at_junction_deviation_alone() {
        let s = Settings::default();
        let (r, n) = (0.5f64, 64);
        let mut b = Bound::new(s, burin::pad([r as f32, 0.0, 0.0, 0.0]));
        // Four turns: the third is past the ramp from rest.
        for k in 1..=4 * n {
            let t = k as f64 / n as f64 * std::f64::consts::TAU;
            b.push(&to((r * t.cos()) as f32, (r * t.sin()) as f32, 1e4));
        }
        let prof = b.profile();
        // Piece `j` starts at vertex `j`: at 2n + n/2, the far side (-r, 0).
        let j = 2 * n + n / 2;
        let v = prof[j].v0;
        let phi = std::f64::consts::TAU / n as f64;
        let l = prof[j].len;
        let a = f64::from(s.axes[0].max_accel);
        assert!(
            v > 1.5 * (a * l / phi).sqrt(),
            "{v} against {}",
            (a * l / phi).sqrt()
        );
        // Junction deviation along the radial change (X here, at the far
        // side: the change lies along one axis).
        let sin_half = (phi / 2.0).cos();
        let rjd = f64::from(s.junction_deviation) * sin_half / (1.0 - sin_half);
        assert!(
            (v - (a * rjd).sqrt()).abs() < 0.02 * v,
            "{v} against {}",
            (a * rjd).sqrt()
        );
    }

    /// zigzag_0.002_0.001's swings, 0.0508 mm across, round to 4 steps at
    /// 80 steps/mm (0.05 mm): GRBL, which plans the rounded path, ran it
    /// faster than a bound on the commanded path alone. The bound is the
    /// faster of the two, which is the rounded path's profile here.
    #[test]
    fn a_path_that_rounds_shorter_is_bounded_by_its_steps() {
        let zig = |s: Settings, amp: f32, pitch: f32| {
            let mut b = Bound::new(s, [0.0; AXES]);
            for k in 1..=200 {
                let y = if k % 2 == 1 { amp } else { -amp };
                b.push(&to(k as f32 * pitch, y, 1e4));
            }
            b.time_s()
        };
        let s = Settings::default();
        let mut fine = s;
        for ax in fine.axes.iter_mut() {
            ax.steps_per_mm = 1e5;
        }
        let commanded = zig(fine, 0.0254, 0.05);
        let stepped = zig(s, 0.025, 0.05);
        let bound = zig(s, 0.0254, 0.05);
        assert!(bound < 0.995 * commanded, "{bound} against {commanded}");
        assert!((bound - stepped).abs() < 1e-9, "{bound} against {stepped}");
    }
}
