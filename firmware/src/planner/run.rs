//! S-curve runs as the forward pass sees them.
//!
//! The segment preparer carries one S ramp across the junctions of a run
//! (`stepper::prep::run`): blocks joined by junctions that hold nothing,
//! with nominal speeds within 5 % of each other, at most [`RUN_BLOCKS`].
//! Planned one block at a time, the forward pass would only let each block
//! be entered as fast as an S ramp within the block before it reaches, and
//! a run's ramp, which ends on such an entry, would climb in block-long
//! steps. So the pass also reckons each entry with one S ramp over the run
//! that ends there, from the entry of the run's first block.
//!
//! That reach only ever raises a forward reach. Every entry stays within
//! what the backward pass allows for stopping, and a run that cannot reach
//! a planned entry (it starts elsewhere, or fewer blocks are queued) enters
//! the next block slower, which is always safe.
//!
//! The run is carried through the pass block by block ([`RunAcc::step`]);
//! counting it afresh at every block cost 150,000 more instructions a
//! chord on a full ring (`cargo xtask bench-target`,
//! `plan_chord_scurve_insns`).

use super::*;

/// Most blocks an S-curve run spans: the running one and
/// `stepper::prep::run::MAX_RUN` after it.
pub const RUN_BLOCKS: usize = 17;

/// Two nominal speeds close enough for one S-curve run to take both in
/// (it cruises at the lower): chords of an arc whose direction turns the
/// axes' rate caps differ by a little from chord to chord, and a run that
/// stopped at each of them restarted its ramp every 0.6 mm.
pub fn nominal_near(a: f32, b: f32) -> bool {
    a.min(b) >= 0.95 * a.max(b)
}

/// The share of the jerk a run keeps when it spans a curve's chords: the
/// tangential ramp's jerk adds to the turning acceleration's own (`v³/r²`,
/// and `3·v·a_t/r`).
pub const CURVE_RUN_JERK: f32 = 0.5;

/// Whether a run that `p` is in may take in the block `n` after it (the
/// preparer asks it of the run's first block, the forward pass of each
/// junction).
pub fn joins(p: &Block, n: &Block) -> bool {
    p.kind == BlockKind::Line
        && n.kind == BlockKind::Line
        && n.hold_m <= 0.0
        && n.hold_pre_m <= 0.0
        && nominal_near(n.nominal, p.nominal)
        && n.watch == p.watch
}

/// The run that ends before the block the forward pass is at.
#[derive(Clone, Copy, Debug)]
pub(super) struct RunAcc {
    /// Entry speed and entry hold factor of the run's first block.
    entry: f32,
    hold_m: f32,
    len: f32,
    accel: f32,
    curve: bool,
    blocks: usize,
}

impl RunAcc {
    fn start(b: &Block) -> Self {
        RunAcc {
            entry: b.entry,
            hold_m: b.hold_m,
            len: b.length,
            accel: b.accel,
            curve: b.curve_ar > 0.0,
            blocks: 1,
        }
    }

    fn add(&mut self, b: &Block) {
        self.len += b.length;
        self.accel = self.accel.min(b.accel);
        self.curve |= b.curve_ar > 0.0;
        self.blocks += 1;
    }

    /// Move on past `prev` to the block `b` after it: the reach of the run
    /// that `prev` ends or continues at `b`'s entry, once it spans two
    /// blocks or more. The run's ramp ends at `b`'s entry whether or not
    /// the junction there joins; if it does not, `b` starts the next run.
    #[inline(never)]
    pub(super) fn step(&mut self, prev: &Block, b: &Block, s: &Settings) -> Option<f32> {
        if self.blocks == 0 || self.blocks >= RUN_BLOCKS {
            *self = RunAcc::start(prev);
        } else {
            self.add(prev);
        }
        let reach = (self.blocks >= 2).then(|| {
            let jerk = s.jerk.max(1e-3) * if self.curve { CURVE_RUN_JERK } else { 1.0 };
            let avail = self.len - 0.5 * self.hold_m * self.entry * self.entry;
            Shape {
                accel: self.accel,
                jerk,
                drop: 0.0,
            }
            .reach(self.entry, avail)
        });
        if !joins(prev, b) {
            self.blocks = 0;
        }
        reach
    }
}

impl<const N: usize> Planner<N> {
    /// The run the forward pass carries into block `k`: the blocks before
    /// `k - 1` that one run may span with it, counted back once per pass
    /// (`None` in trapezoid mode).
    #[inline(never)]
    pub(super) fn run_before(&self, k: usize) -> Option<RunAcc> {
        if self.settings.profile != crate::settings::Profile::SCurve {
            return None;
        }
        let at = |i: usize| &self.blocks[(self.tail + i) % N];
        let mut acc = RunAcc {
            blocks: 0,
            ..RunAcc::start(&Block::EMPTY)
        };
        if k < 2 || k > self.len {
            return Some(acc);
        }
        // The run's first block: back from `k - 2` while the junctions
        // join, at most RUN_BLOCKS - 2 of them (`step` adds `k - 1`).
        let mut j = k - 2;
        while j > 0 && k - 1 - j < RUN_BLOCKS - 1 && joins(at(j - 1), at(j)) {
            j -= 1;
        }
        if !joins(at(k - 2), at(k - 1)) {
            return Some(acc);
        }
        acc = RunAcc::start(at(j));
        for i in j + 1..k - 1 {
            acc.add(at(i));
        }
        Some(acc)
    }
}
