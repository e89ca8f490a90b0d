//! `--plot FILE.svg`: what the job did, for a person to look at.
//!
//! Top panel: the XY view in machine mm, the commanded path coloured by kind
//! (rapids dashed grey, feeds blue, arcs purple, splines pink, probing red,
//! homing orange) drawn over a translucent orange band that is the path the
//! steppers actually took. Where the two part, the band shows it.
//! Bottom panel: the path speed over time, from the steps (10 ms bins, the
//! same figure as the summary's max feed, see `crate::feed`).
//!
//! A job can have millions of chords and tens of millions of steps, so the
//! paths are simplified as they stream in (a point is dropped when it lies
//! within a tolerance of the line it extends) and the tolerance doubles
//! whenever a path grows past its point budget: the file stays under ~100k
//! points while every shape wider than a pixel survives.

mod frame;
mod svg;

use std::io::{self, Write};

use crate::feed::FeedMeter;
use crate::record::{PathKind, PinEvent, Recorder, RunInfo, Summary};

/// Point budget per path; past it the tolerance doubles.
const PATH_CAP: usize = 40_000;
/// Samples kept per time series; past it they fold into min/max buckets.
const SERIES_CAP: usize = 20_000;
/// Starting simplification tolerance, mm: far below a pixel at any sane zoom.
const START_TOL: f64 = 0.002;
/// Coarsest tolerance, mm: beyond it only kind changes are left to drop.
const MAX_TOL: f64 = 10_000.0;

/// A streaming line simplifier (Reumann–Witkam): a point is kept only when
/// the path leaves a corridor of half-width `tol` around the line through
/// the last kept point, or when its tag (move kind) changes.
#[derive(Clone, Debug)]
pub(crate) struct Simplifier {
    pub(crate) kept: Vec<([f64; 2], u8)>,
    tol: f64,
    dir: Option<[f64; 2]>,
    last: Option<([f64; 2], u8)>,
    last_kept: bool,
    cap: usize,
}

impl Simplifier {
    fn new() -> Self {
        Simplifier {
            kept: Vec::new(),
            tol: START_TOL,
            dir: None,
            last: None,
            last_kept: false,
            cap: PATH_CAP,
        }
    }

    fn keep(&mut self, p: [f64; 2], tag: u8) {
        self.kept.push((p, tag));
        self.dir = None;
        self.last = Some((p, tag));
        self.last_kept = true;
    }

    fn push(&mut self, p: [f64; 2], tag: u8) {
        let Some((last, ltag)) = self.last else {
            return self.keep(p, tag);
        };
        if ltag != tag && !self.last_kept {
            // The end of a run of one kind must survive.
            self.keep(last, ltag);
        }
        let anchor = self.kept.last().map_or(last, |k| k.0);
        let d = [p[0] - anchor[0], p[1] - anchor[1]];
        match self.dir {
            None => {
                let len = d[0].hypot(d[1]);
                if len > self.tol {
                    self.dir = Some([d[0] / len, d[1] / len]);
                }
            }
            Some(u) => {
                let off = (d[0] * u[1] - d[1] * u[0]).abs();
                let along = d[0] * u[0] + d[1] * u[1];
                let last_along = (last[0] - anchor[0]) * u[0] + (last[1] - anchor[1]) * u[1];
                if off > self.tol || along < last_along - self.tol {
                    // The path left the corridor: `last` becomes the anchor.
                    self.keep(last, ltag);
                    let d = [p[0] - last[0], p[1] - last[1]];
                    let len = d[0].hypot(d[1]);
                    if len > self.tol {
                        self.dir = Some([d[0] / len, d[1] / len]);
                    }
                }
            }
        }
        self.last = Some((p, tag));
        self.last_kept = false;
        if self.kept.len() > self.cap {
            self.coarsen();
        }
    }

    /// Doubles the tolerance until what is kept fits half the budget.
    fn coarsen(&mut self) {
        let pending = if self.last_kept { None } else { self.last };
        while self.kept.len() > self.cap / 2 && self.tol < MAX_TOL {
            let mut s = Simplifier::new();
            s.tol = self.tol * 2.0;
            for &(p, t) in &self.kept {
                s.push(p, t);
            }
            s.finish();
            self.tol = s.tol;
            self.kept = s.kept;
        }
        // Kind changes are kept whatever the tolerance; if they alone fill
        // the budget, grow it rather than re-simplifying on every point.
        if self.kept.len() > self.cap / 2 {
            self.cap = self.kept.len() * 2;
        }
        self.dir = None;
        self.last = self.kept.last().copied();
        self.last_kept = true;
        if let Some((p, t)) = pending {
            self.push(p, t);
        }
    }

    /// Keeps the final point.
    fn finish(&mut self) {
        if let Some((p, t)) = self.last {
            if !self.last_kept {
                self.kept.push((p, t));
                self.last_kept = true;
            }
        }
    }
}

/// A value over time (path speed, Z height), folded into min/max buckets
/// when it grows long. Each sample holds until the next.
#[derive(Clone, Debug)]
pub(crate) struct Series {
    pub(crate) samples: Vec<(u64, f32)>,
    pub(crate) min: f32,
    pub(crate) max: f32,
}

impl Default for Series {
    fn default() -> Self {
        Series {
            samples: Vec::new(),
            min: f32::INFINITY,
            max: f32::NEG_INFINITY,
        }
    }
}

impl Series {
    fn push(&mut self, tick: u64, v: f32) {
        if !v.is_finite() {
            return;
        }
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        self.samples.push((tick, v));
        if self.samples.len() > SERIES_CAP {
            // At most 4 points per bucket: half the cap, so folding is rare.
            self.samples = fold_min_max(&self.samples, SERIES_CAP / 8);
        }
    }
}

/// Keeps, per time bucket, the first, minimum, maximum and last sample in
/// time order, so peaks and plateaus survive any amount of folding.
pub(crate) fn fold_min_max(s: &[(u64, f32)], buckets: usize) -> Vec<(u64, f32)> {
    let (Some(first), Some(last)) = (s.first(), s.last()) else {
        return Vec::new();
    };
    let span = (last.0 - first.0).max(1);
    let width = span.div_ceil(buckets.max(1) as u64).max(1);
    let mut out = Vec::with_capacity(buckets * 4);
    let mut i = 0;
    while i < s.len() {
        let b = (s[i].0 - first.0) / width;
        let mut j = i;
        while j < s.len() && (s[j].0 - first.0) / width == b {
            j += 1;
        }
        let run = &s[i..j];
        let mut pick = [0, 0, 0, run.len() - 1];
        for (k, x) in run.iter().enumerate() {
            if x.1 < run[pick[1]].1 {
                pick[1] = k;
            }
            if x.1 > run[pick[2]].1 {
                pick[2] = k;
            }
        }
        pick.sort_unstable();
        let mut prev = usize::MAX;
        for k in pick {
            if k != prev {
                out.push(run[k]);
                prev = k;
            }
        }
        i = j;
    }
    out
}

pub(crate) fn kind_tag(k: PathKind) -> u8 {
    match k {
        PathKind::Rapid => 0,
        PathKind::Feed => 1,
        PathKind::Arc => 2,
        PathKind::Spline => 3,
        PathKind::Probe => 4,
        PathKind::Home => 5,
    }
}

/// The `--plot` recorder; the SVG is written by `finish`.
pub struct SvgPlot<W: Write> {
    out: Option<W>,
    job_name: String,
    info: Option<RunInfo>,
    mm_per_step: [f64; 3],
    /// Where the tool stood before the first step (from the first event).
    start: Option<[f64; 2]>,
    commanded: Simplifier,
    stepped: Simplifier,
    velocity: Series,
    /// The path speed the velocity panel draws: from the steps, in the
    /// same bins as the summary's max feed (`crate::feed`).
    feed: Option<FeedMeter>,
    z: Series,
    last_tick: u64,
    last_steps: Option<[i64; 3]>,
}

impl<W: Write> SvgPlot<W> {
    pub fn new(out: W, job_name: &str) -> Self {
        SvgPlot {
            out: Some(out),
            job_name: job_name.to_string(),
            info: None,
            mm_per_step: [1.0; 3],
            start: None,
            commanded: Simplifier::new(),
            stepped: Simplifier::new(),
            velocity: Series::default(),
            feed: None,
            z: Series::default(),
            last_tick: 0,
            last_steps: None,
        }
    }

    fn xy_mm(&self, steps: [i64; 2]) -> [f64; 2] {
        [
            steps[0] as f64 * self.mm_per_step[0],
            steps[1] as f64 * self.mm_per_step[1],
        ]
    }
}

impl<W: Write> Recorder for SvgPlot<W> {
    fn start(&mut self, info: &RunInfo) {
        for (i, m) in self.mm_per_step.iter_mut().enumerate() {
            let spm = f64::from(info.axes[i].steps_per_mm);
            *m = if spm > 0.0 { 1.0 / spm } else { 1.0 };
        }
        // Bresenham staircases wander up to a step off the line they follow;
        // detail finer than one step is quantisation, not shape.
        let step = self.mm_per_step[0].max(self.mm_per_step[1]);
        self.stepped.tol = self.stepped.tol.max(step);
        self.feed = Some(FeedMeter::new(
            info.tick_hz,
            info.axes.clone().map(|a| a.steps_per_mm),
            info.axes.clone().map(|a| a.max_rate_mm_min),
        ));
        self.info = Some(info.clone());
    }

    fn step_event(&mut self, ev: &PinEvent) {
        self.last_tick = self.last_tick.max(ev.tick);
        if let Some(v) = self.feed.as_mut().and_then(|f| f.step(ev.tick, ev.pos)) {
            self.velocity.push(ev.tick, v as f32);
        }
        let now = [ev.pos[0], ev.pos[1], ev.pos[2]];
        let prev = match self.last_steps {
            Some(p) => p,
            None => {
                // Undo this event's own steps to find where the tool started.
                let mut before = now;
                for (i, b) in before.iter_mut().enumerate() {
                    if ev.step_mask & (1 << i) != 0 {
                        *b += if ev.dir_mask & (1 << i) != 0 { 1 } else { -1 };
                    }
                }
                let xy = self.xy_mm([before[0], before[1]]);
                self.start = Some(xy);
                self.stepped.push(xy, 0);
                self.z
                    .push(ev.tick, before[2] as f32 * self.mm_per_step[2] as f32);
                before
            }
        };
        self.last_steps = Some(now);
        if now[2] != prev[2] {
            self.z
                .push(ev.tick, (now[2] as f64 * self.mm_per_step[2]) as f32);
        }
        if now[..2] != prev[..2] {
            let p = self.xy_mm([now[0], now[1]]);
            self.stepped.push(p, 0);
        }
    }

    fn commanded(&mut self, _line: u32, kind: PathKind, to_mm: [f32; burin::AXES]) {
        let p = [f64::from(to_mm[0]), f64::from(to_mm[1])];
        self.commanded.push(p, kind_tag(kind));
    }

    /// Only the stops of the planned speed: the panel draws the speed
    /// measured on the steps, which learns of a standstill only at the
    /// next step.
    fn velocity(&mut self, tick: u64, mm_per_min: f32) {
        self.last_tick = self.last_tick.max(tick);
        if mm_per_min <= 0.0 {
            self.velocity.push(tick, 0.0);
            if let Some(f) = self.feed.as_mut() {
                f.stop();
            }
        }
    }

    fn finish(&mut self, summary: &Summary) -> io::Result<()> {
        let Some(out) = self.out.take() else {
            return Err(io::Error::other("SVG plot finished twice"));
        };
        self.commanded.finish();
        self.stepped.finish();
        let info = self.info.clone().unwrap_or_else(svg::fallback_info);
        let plot = svg::Plot {
            job_name: &self.job_name,
            info: &info,
            summary,
            start: self.start,
            commanded: &self.commanded.kept,
            stepped: &self.stepped.kept,
            velocity: &self.velocity,
            z: &self.z,
            end_tick: self.last_tick,
        };
        svg::write(out, &plot)
    }
}
