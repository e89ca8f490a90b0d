//! The motion envelope check of the `device` and `executor` targets: the
//! machine never steps outside the axis-aligned box of the moves it was
//! commanded, plus one step per axis (two around the end of a move it has
//! finished), whether or not the input ends idle.
//!
//! The moves are the executor's own account of what it committed to
//! ([`burin::executor::Note::Move`]: machine mm, an arc or spline as
//! commanded, homing and probing moves included), and the positions are the
//! virtual hardware's step events, so nothing here trusts the segmenter,
//! the planner or the preparer it checks. An arc's box is computed here
//! from its centre, radius and sweep (so a short arc run as a full circle,
//! issue 35, is caught a few steps past its end); a spline's is its
//! control polygon's, which holds the curve. Only an arc whose start and
//! end round to the same steps may be a full circle: the arc code must not
//! take more than that for one (a coupling with issue 35's arc fix).
//!
//! Which moves may be running: those committed since the machine was last
//! seen at rest ([`Envelope::settle`]), less those it has finished. A move
//! counts as finished when the position lands on its end, rounded to steps,
//! while it is the oldest one left, and only for moves that cannot pass
//! their end earlier: straight moves and arcs of at most half a turn. The
//! rest (longer arcs, splines, and moves a reset, probe or jog cancel cut
//! short) stay until the machine rests, which only widens the box.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use burin::command::{Arc, ArcDir, Pos, Spline};
use burin::executor::Geometry;
use burin::AXES;

use crate::record::{PinEvent, Recorder, RunInfo};

/// Window entries beyond this fold into one box that stays until the
/// machine rests (a long cut short program must not grow without bound).
const MAX_WINDOW: usize = 1024;
/// Moves kept for the failure message.
const RECENT: usize = 6;

/// An axis-aligned box, machine mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub lo: [f64; AXES],
    pub hi: [f64; AXES],
}

impl Bounds {
    pub fn point(p: &Pos) -> Self {
        let p = p.map(f64::from);
        Bounds { lo: p, hi: p }
    }
    fn add(&mut self, i: usize, v: f64) {
        self.lo[i] = self.lo[i].min(v);
        self.hi[i] = self.hi[i].max(v);
    }
    fn add_point(&mut self, p: &Pos) {
        for (i, v) in p.iter().enumerate() {
            self.add(i, f64::from(*v));
        }
    }
    fn union(&mut self, o: &Bounds) {
        for i in 0..AXES {
            self.lo[i] = self.lo[i].min(o.lo[i]);
            self.hi[i] = self.hi[i].max(o.hi[i]);
        }
    }
}

/// A move as committed (owned: the note borrows from the executor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Committed {
    Straight(Pos),
    Arc(Arc),
    Spline(Spline),
}

impl From<&Geometry<'_>> for Committed {
    fn from(g: &Geometry) -> Self {
        match *g {
            Geometry::Straight(e) => Committed::Straight(*e),
            Geometry::Arc(a) => Committed::Arc(*a),
            Geometry::Spline(s) => Committed::Spline(*s),
        }
    }
}

impl Committed {
    pub fn end(&self) -> Pos {
        match self {
            Committed::Straight(e) => *e,
            Committed::Arc(a) => a.end,
            Committed::Spline(s) => s.end,
        }
    }
}

/// `(box, finishes at its end)` of a move from `start`. `spm`: steps per
/// mm, for the one judgement that needs the machine's resolution: an arc
/// whose start and end round to the same steps in its plane, or lie
/// closer than half its finest step, may be taken as a full circle (RS274NGC's full circle, written with an end that
/// differs from the start by rounding only).
pub fn move_bounds(start: &Pos, m: &Committed, spm: &[f64; AXES]) -> (Bounds, bool) {
    let mut b = Bounds::point(start);
    b.add_point(&m.end());
    match m {
        Committed::Straight(_) => (b, true),
        Committed::Spline(s) => {
            for p in [s.p1, s.p2] {
                b.add(0, f64::from(p[0]));
                b.add(1, f64::from(p[1]));
            }
            (b, false)
        }
        Committed::Arc(a) => {
            let (bulge, short) = arc_bulge(start, a, spm);
            b.union(&bulge);
            (b, short)
        }
    }
}

/// The extreme points of an arc's circle that its sweep passes, as a box
/// (with the start), and whether the arc is at most half a turn (then it
/// nears its end only at the end). The radius is the larger of the start's
/// and the end's (a spiral blends between them).
fn arc_bulge(start: &Pos, a: &Arc, spm: &[f64; AXES]) -> (Bounds, bool) {
    let mut b = Bounds::point(start);
    let (ia, ib, _) = a.plane.axes();
    let [ca, cb] = a.center.map(f64::from);
    let s = (f64::from(start[ia]) - ca, f64::from(start[ib]) - cb);
    let e = (f64::from(a.end[ia]) - ca, f64::from(a.end[ib]) - cb);
    let r = s.0.hypot(s.1).max(e.0.hypot(e.1));
    if !r.is_finite() {
        return (b, false);
    }
    let cell = |i: usize, v: f32| (f64::from(v) * spm[i]).round();
    // A full circle is allowed where the machine cannot tell start from
    // end: the same steps, or closer than half the plane's finest step
    // (the arc code's rule, `burin::arc::same_point`, is within both).
    let half_step = 0.5 / spm[ia].max(spm[ib]);
    let chord = (f64::from(a.end[ia]) - f64::from(start[ia]))
        .hypot(f64::from(a.end[ib]) - f64::from(start[ib]));
    let coincide = (cell(ia, start[ia]) == cell(ia, a.end[ia])
        && cell(ib, start[ib]) == cell(ib, a.end[ib]))
        || chord < half_step;
    let (t0, t1) = (s.1.atan2(s.0), e.1.atan2(e.0));
    // Angle swept in the arc's own direction, in (0, 2π].
    let fwd = match a.dir {
        ArcDir::Ccw => (t1 - t0).rem_euclid(TAU),
        ArcDir::Cw => (t0 - t1).rem_euclid(TAU),
    };
    let full = coincide || a.turns > 0 || fwd == 0.0;
    let sweep = if full { TAU } else { fwd };
    for k in 0..4 {
        let ang = f64::from(k) * FRAC_PI_2;
        let rel = match a.dir {
            ArcDir::Ccw => (ang - t0).rem_euclid(TAU),
            ArcDir::Cw => (t0 - ang).rem_euclid(TAU),
        };
        if rel <= sweep {
            let (sin, cos) = [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)][k as usize];
            b.add(ia, ca + r * cos);
            b.add(ib, cb + r * sin);
        }
    }
    (b, !full && sweep <= PI)
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    line: u32,
    bounds: Bounds,
    end: Pos,
    /// Finished once the position is on its end's steps (see the module doc).
    finishes: bool,
}

/// The check's state; shared (a `RefCell`) between the recorder the engine
/// drives and the target, which tells it when the machine rests.
#[derive(Debug)]
pub struct Envelope {
    spm: [f64; AXES],
    /// Moves that may be running, oldest first.
    window: VecDeque<Entry>,
    /// Window entries folded together past [`MAX_WINDOW`].
    folded: Option<Bounds>,
    /// Where the machine was last seen at rest, or the end of the last
    /// finished move (the steps that close a move land there), and the
    /// slack around it in steps.
    anchor: Option<(Pos, f64)>,
    /// Allowed step range per axis (cached; None: recompute).
    allowed: Option<[(f64, f64); AXES]>,
    recent: VecDeque<(u32, Pos, Committed)>,
    /// Step events checked (a target's smoke test asserts it saw some).
    pub checked: u64,
}

impl Envelope {
    pub fn new(steps_per_mm: [f32; AXES]) -> Self {
        Envelope {
            spm: steps_per_mm.map(f64::from),
            window: VecDeque::new(),
            folded: None,
            anchor: None,
            allowed: None,
            recent: VecDeque::new(),
            checked: 0,
        }
    }

    /// The machine is at rest at `pos` (steps) with nothing queued: only a
    /// move committed after this may move it.
    pub fn settle(&mut self, pos: [i32; AXES]) {
        let mm = std::array::from_fn(|i| (f64::from(pos[i]) / self.spm[i]) as f32);
        self.window.clear();
        self.folded = None;
        self.anchor = Some((mm, 1.0));
        self.allowed = None;
    }

    pub fn motion(&mut self, line: u32, start: Pos, m: Committed) {
        let (bounds, finishes) = move_bounds(&start, &m, &self.spm);
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back((line, start, m));
        self.window.push_back(Entry {
            line,
            bounds,
            end: m.end(),
            finishes,
        });
        if self.window.len() > MAX_WINDOW {
            // The oldest entry stays until the machine rests.
            if let Some(e) = self.window.pop_front() {
                self.folded.get_or_insert(e.bounds).union(&e.bounds);
            }
        }
        if let Some(a) = &mut self.allowed {
            widen(a, &bounds, &self.spm);
        }
    }

    pub fn rescaled(&mut self, spm: [f32; AXES]) {
        self.spm = spm.map(f64::from);
        self.allowed = None;
    }

    fn on_end(&self, e: &Entry, pos: &[i64; AXES]) -> bool {
        (0..AXES).all(|i| (f64::from(e.end[i]) * self.spm[i]).round() == pos[i] as f64)
    }

    fn compute_allowed(&self) -> [(f64, f64); AXES] {
        let mut a = [(f64::INFINITY, f64::NEG_INFINITY); AXES];
        let boxes = self.window.iter().map(|e| &e.bounds).chain(&self.folded);
        for b in boxes {
            widen(&mut a, b, &self.spm);
        }
        if let Some((p, steps)) = self.anchor {
            for (i, r) in a.iter_mut().enumerate() {
                let v = f64::from(p[i]) * self.spm[i];
                r.0 = r.0.min(v - steps - slack(v) + 1.0);
                r.1 = r.1.max(v + steps + slack(v) - 1.0);
            }
        }
        a
    }

    /// One step event: retire finished moves, then check the position.
    pub fn step(&mut self, pos: &[i64; AXES]) {
        self.checked += 1;
        while let Some(e) = self.window.front() {
            if !(e.finishes && self.on_end(e, pos)) {
                break;
            }
            // Its last steps land around its end: two steps of slack there.
            self.anchor = Some((e.end, 2.0));
            self.window.pop_front();
            self.allowed = None;
        }
        let allowed = match self.allowed {
            Some(a) => a,
            None => {
                let a = self.compute_allowed();
                self.allowed = Some(a);
                a
            }
        };
        for i in 0..AXES {
            let p = pos[i] as f64;
            if p < allowed[i].0 || p > allowed[i].1 {
                self.fail(i, pos, &allowed);
            }
        }
    }

    fn fail(&self, axis: usize, pos: &[i64; AXES], allowed: &[(f64, f64); AXES]) -> ! {
        let mm: Vec<f64> = (0..AXES).map(|i| pos[i] as f64 / self.spm[i]).collect();
        let lines: Vec<u32> = self.window.iter().map(|e| e.line).collect();
        panic!(
            "moved outside the commanded path: axis {axis} at step {} ({:.4} mm), allowed \
             steps {:.1}..={:.1}; position {mm:?} mm; moves that may run (lines) {lines:?}, \
             anchor {:?}; last moves committed (line, start, move): {:?}",
            pos[axis], mm[axis], allowed[axis].0, allowed[axis].1, self.anchor, self.recent
        );
    }
}

/// Widen allowed step ranges to take in `b` (mm) with its slack.
fn widen(a: &mut [(f64, f64); AXES], b: &Bounds, spm: &[f64; AXES]) {
    for (i, (r, s)) in a.iter_mut().zip(spm).enumerate() {
        let (lo, hi) = (b.lo[i] * s, b.hi[i] * s);
        r.0 = r.0.min(lo - slack(lo));
        r.1 = r.1.max(hi + slack(hi));
    }
}

/// One step, plus room for `f32` rounding in the commanded numbers.
fn slack(steps: f64) -> f64 {
    1.0 + 1e-3 + steps.abs() * 1e-6
}

/// The recorder half: step events and committed moves from the engine.
pub struct EnvelopeRec<'a>(pub &'a RefCell<Envelope>);

impl Recorder for EnvelopeRec<'_> {
    fn start(&mut self, info: &RunInfo) {
        self.0
            .borrow_mut()
            .rescaled(info.axes.clone().map(|a| a.steps_per_mm));
    }
    fn step_event(&mut self, ev: &PinEvent) {
        self.0.borrow_mut().step(&ev.pos);
    }
    fn motion(&mut self, line: u32, start: Pos, geometry: &Geometry) {
        self.0.borrow_mut().motion(line, start, geometry.into());
    }
    fn rescaled(&mut self, steps_per_mm: [f32; AXES]) {
        self.0.borrow_mut().rescaled(steps_per_mm);
    }
}

mod run;
pub use run::run_gcode;

#[cfg(test)]
mod tests;
