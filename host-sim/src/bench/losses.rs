//! Where a job loses time against its bound (`cargo xtask bench-motion
//! --losses N`): the step trace's time at each path vertex against the
//! bound's, summed per source line. A tool for finding what to work on,
//! not a figure of the benchmark.
//!
//! A vertex is reached when the trace stands exactly on it in steps (every
//! block ends on its rounded end; a vertex inside a merged collinear run
//! may be passed between steps, and its time then goes to the next vertex
//! that is hit). The trace is matched forwards only, a few vertices ahead,
//! so a path that comes back to a point does not jump the count.

use std::collections::BTreeMap;

use burin::AXES;

use super::bound::{Bound, PieceProfile};
use crate::record::{PathEvent, PathKind, PinEvent, Recorder, RunInfo};

/// How many vertices ahead of the last one hit a step may match.
const LOOK: usize = 8;

/// Time lost on one source line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineLoss {
    pub line: u32,
    /// Run time minus bound time over the line's pieces, s.
    pub lost_s: f64,
    pub bound_s: f64,
    /// Pieces (chords) of the line.
    pub pieces: u32,
    pub kind: PathKind,
}

/// A [`Recorder`] that locates the losses (see the module doc).
pub struct Locator {
    bound: Bound,
    spm: [f64; AXES],
    tick_hz: f64,
    line: u32,
    lines: Vec<u32>,
    targets: Vec<[i64; AXES]>,
    hit: Vec<Option<u64>>,
    next: usize,
    t0: Option<u64>,
}

impl Locator {
    pub fn new(bound: Bound, steps_per_mm: [f32; AXES]) -> Self {
        Locator {
            bound,
            spm: steps_per_mm.map(f64::from),
            tick_hz: 1.0,
            line: 0,
            lines: Vec::new(),
            targets: Vec::new(),
            hit: Vec::new(),
            next: 0,
            t0: None,
        }
    }

    pub fn bound(&self) -> &Bound {
        &self.bound
    }

    /// The source line of each piece.
    pub fn lines(&self) -> &[u32] {
        &self.lines
    }

    /// When the trace stood on each piece's end, s from its first step
    /// (None where it passed the vertex between steps).
    pub fn hit_s(&self) -> Vec<Option<f64>> {
        let t0 = self.t0.unwrap_or(0);
        self.hit
            .iter()
            .map(|h| h.map(|t| (t - t0) as f64 / self.tick_hz))
            .collect()
    }

    /// Losses per source line, worst first, against `prof`, the bound's
    /// profile (`Bound::profile` of [`Locator::bound`]).
    pub fn losses(&self, prof: &[PieceProfile]) -> Vec<LineLoss> {
        let t0 = self.t0.unwrap_or(0);
        let mut per_line: BTreeMap<u32, LineLoss> = BTreeMap::new();
        let (mut last_run, mut last_bound) = (0.0, 0.0);
        let mut group: Vec<usize> = Vec::new();
        for (k, p) in prof.iter().enumerate() {
            group.push(k);
            let Some(tick) = self.hit.get(k).copied().flatten() else {
                continue;
            };
            let run = (tick - t0) as f64 / self.tick_hz;
            let lost = (run - last_run) - (p.end_s - last_bound);
            // Share a group's loss by the bound's time of each piece in it.
            let span = (p.end_s - last_bound).max(1e-12);
            let mut prev_end = last_bound;
            for &j in &group {
                let bt = prof[j].end_s - prev_end;
                prev_end = prof[j].end_s;
                let e = per_line.entry(self.lines[j]).or_insert(LineLoss {
                    line: self.lines[j],
                    lost_s: 0.0,
                    bound_s: 0.0,
                    pieces: 0,
                    kind: prof[j].kind,
                });
                e.lost_s += lost * bt / span;
                e.bound_s += bt;
                e.pieces += 1;
            }
            group.clear();
            (last_run, last_bound) = (run, p.end_s);
        }
        let mut v: Vec<LineLoss> = per_line.into_values().collect();
        v.sort_by(|a, b| b.lost_s.total_cmp(&a.lost_s));
        v
    }
}

impl Recorder for Locator {
    fn start(&mut self, info: &RunInfo) {
        self.tick_hz = f64::from(info.tick_hz);
    }
    fn commanded(&mut self, line: u32, _kind: PathKind, _to_mm: [f32; AXES]) {
        self.line = line;
    }
    fn path(&mut self, ev: &PathEvent) {
        let before = self.bound.pieces();
        self.bound.push(ev);
        if self.bound.pieces() > before {
            let end = self.bound.end_mm();
            self.lines.push(self.line);
            self.targets.push(std::array::from_fn(|i| {
                (end[i] * self.spm[i]).round() as i64
            }));
            self.hit.push(None);
        }
    }
    fn step_event(&mut self, ev: &PinEvent) {
        self.t0.get_or_insert(ev.tick);
        let end = (self.next + LOOK).min(self.targets.len());
        if let Some(j) = (self.next..end).find(|&j| self.targets[j] == ev.pos) {
            self.hit[j] = Some(ev.tick);
            self.next = j + 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::MachineConfig;

    #[test]
    fn every_line_is_located_and_none_gains_more_than_rounding() {
        let cfg = MachineConfig::default();
        let spm = cfg.settings.axes.map(|a| a.steps_per_mm);
        let mut loc = Locator::new(Bound::new(cfg.settings, cfg.start_position_mm), spm);
        let src = "G1 X10 F600\nG1 X20\nG1 X20 Y10\n";
        crate::offline::run_file(&cfg, src, &mut loc);
        let l = loc.losses(&loc.bound().profile());
        let lines: Vec<u32> = {
            let mut v: Vec<u32> = l.iter().map(|x| x.line).collect();
            v.sort();
            v
        };
        assert_eq!(lines, vec![1, 2, 3]);
        // The run keeps the limits the bound keeps, so it loses, never gains
        // more than rounding: its time starts at the first step, the
        // bound's a step's ramp earlier (about a millisecond).
        let total: f64 = l.iter().map(|x| x.lost_s).sum();
        assert!(total > -3e-3, "{total}");
        assert!(l.iter().all(|x| x.bound_s > 0.0));
    }
}
