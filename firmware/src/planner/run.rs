//! S-curve runs: where one S ramp may go on across junctions.
//!
//! An S ramp starts and ends at zero acceleration. Planned one block at a
//! time, a chain of short blocks slows in block-long S ramps, each from no
//! acceleration: the backward pass let a block be entered only as fast as
//! such a chain stops from, and on circle_small.ngc's 0.016 mm chords at
//! 5000 mm/s³ that was 4 mm/s where one ramp over the same 64 queued
//! blocks stops from 15. So blocks are grouped into runs, and the segment
//! preparer may plan the rest of a run as one S ramp (`stepper::prep::run`),
//! its acceleration going on across the junctions inside.
//!
//! **Runs are fixed when a block is queued** ([`next_pos`]): a block goes
//! into its predecessor's run if both are lines watching the same inputs,
//! with nominal speeds alike (or both a few steps long, [`SHORT_MM`]), and
//! the run has fewer than [`RUN_BLOCKS`] blocks. Appending, releasing a
//! corner and popping leave a run as it is; only the newest block leaves
//! its run when a merge makes it no longer fit ([`Planner::regroup_newest`]),
//! which closes the run before it.
//!
//! **What the backward pass promises** ([`RunAhead::promise`]). For every
//! block `k`, the rest of its run, from `k` to the next run's first block
//! `e`, as one ramp: entered at zero acceleration no faster than its cap
//! ([`RunAhead::cap`]: the least nominal speed and corner limit inside, so
//! it passes no junction inside too fast and needs no check there),
//! slowing to `e`'s entry at zero acceleration within its length, the
//! corner holds at both ends kept. A block may be entered as fast as the
//! faster of that and the block alone. Only a run whose `e` is queued
//! counts: the last one may still grow.
//!
//! **Corners inside.** A run's ramp does not stop for a corner hold inside
//! it (`planner::passes`, corner holds): the corners' velocity changes
//! instead take at most [`HOLD_SHARE`] of any of the meter's windows at
//! the cap, and the ramp keeps to the rest of the acceleration, so a window
//! sees at most the axis's limit. A window sees all the run's corners where
//! the run takes less than a window, else its share of them and one more,
//! the largest, for where they bunch ([`RunAhead::cap`]). Summed over the
//! whole run instead, a pen plotter's 17 corners of 0.26 mm capped its
//! runs at 2 mm/s, and no run counted there; without the one more, Cereal
//! read Z 110 % after a feed override drop (host-sim `override_limits`).
//! On circle_small the holds left after `planner::tube` are 10⁻⁷ s²/mm a
//! corner, and the cap is far above any speed there.
//!
//! **Turns inside.** The ramp keeps half the jerk where it turns
//! ([`CURVE_RUN_JERK`]): on the plotter polylines the tangential ramp's
//! jerk added to the turns' and read X 110 % of `$203` at 5000 mm/s³. The
//! turns keep the other half: going round a radius `r` at `v`, each axis's
//! acceleration turns with a jerk of `v³/r²`, so the cap keeps
//! `v ≤ cbrt(j·r²/2)` at the least radius inside (`Block::turn_v`). Without
//! it, the plotter runs read Y 112 % once their corners took 0.3 of the
//! window.
//!
//! **Why the preparer can keep it.** Entered at `v` no faster than block
//! `k`'s entry, either the block alone fits or `v` is within the run's
//! promise and cap, and the one ramp to `e` fits: the entries inside the
//! run are each at least the smaller of `v` and `e`'s, and the forward pass
//! only lowers an entry to what the block before it reaches from its own,
//! so `e`'s planned entry is at least `v` (nothing to slow for) or the
//! backward pass's, which the promise reaches. That holds while the limits
//! it was planned against stand, and they can fall a little later: an S
//! ramp's length is not monotone in where it ends (from 83 mm/s a stop
//! takes 11.1 mm and a ramp to 28 mm/s 11.7, `Shape::reach_down_to`), so a
//! later entry that rose can lower a promise before it, and a stretch that
//! `planner::tube` releases ramps at less. The preparer then slows over the
//! rest of the run, where one block's ramp barely slows at all.
//!
//! The forward pass reckons each entry with one S ramp over the run up to
//! it as well ([`RunAcc`]), from the entry of the run's first block: a
//! reach only ever raises a forward reach, and a run that cannot reach a
//! planned entry (the preparer started it elsewhere) enters the next block
//! slower, which is always safe. It is carried block by block; counting it
//! afresh at every block cost 150,000 more instructions a chord on a full
//! ring (`cargo xtask bench-target`, `plan_chord_scurve_insns`).

use super::*;

/// Most blocks in an S-curve run.
pub const RUN_BLOCKS: usize = 17;

/// Blocks this long or shorter (mm, a few steps) join a run whatever their
/// nominal speeds: those come from the step pattern's rate caps there (a
/// diagonal step against a straight one, `interval`), not from the
/// program, and a run of them is capped at the least anyway.
const SHORT_MM: f32 = 0.1;

/// Two nominal speeds close enough for one S-curve run to take both in
/// (it cruises at the lower): chords of an arc whose direction turns the
/// axes' rate caps differ by a little from chord to chord, and a run that
/// stopped at each of them restarted its ramp every 0.6 mm.
pub fn nominal_near(a: f32, b: f32) -> bool {
    a.min(b) >= 0.95 * a.max(b)
}

/// The share of the jerk a run keeps when it spans a curve's chords, or
/// corners it does not hold for: the tangential ramp's jerk adds to the
/// turning acceleration's own (`v³/r²`, and `3·v·a_t/r`).
pub const CURVE_RUN_JERK: f32 = 0.5;

/// `cbrt(1 − CURVE_RUN_JERK)`: the speed at which a turn takes the share of
/// the jerk a run's ramp leaves it, as a share of the speed at which it
/// takes all of it (`v³/r² ≤ share·j`).
const TURN_SHARE_V: f32 = 0.793_700_5;
const _: () = assert!(CURVE_RUN_JERK == 0.5);

/// A block's `turn_v`, infinite for none.
const fn turn_v(b: &Block) -> f32 {
    if b.turn_v > 0.0 {
        b.turn_v
    } else {
        f32::INFINITY
    }
}

/// The most of the meter's window the corners inside a run may take,
/// whose holds it does not keep (module doc).
const HOLD_SHARE: f32 = 0.3;

/// The least share of the acceleration a run leaves its corners, however
/// few: a margin for their holds falling unevenly over the run.
const HOLD_MARGIN: f32 = 0.1;

/// Whether `n`, queued after `p`, goes into `p`'s run (module doc). A
/// run's ramp keeps going across its junctions, so it may not start or
/// stop watching an input inside.
fn groups(p: &Block, n: &Block) -> bool {
    p.kind == BlockKind::Line
        && n.kind == BlockKind::Line
        && n.watch == p.watch
        && (nominal_near(n.nominal, p.nominal)
            || (p.programmed == n.programmed && p.length.max(n.length) <= SHORT_MM))
}

/// `n`'s place in its run, queued after `p` (0: it starts one).
pub(super) fn next_pos(p: &Block, n: &Block) -> u8 {
    if groups(p, n) && usize::from(p.run_pos) + 1 < RUN_BLOCKS {
        p.run_pos + 1
    } else {
        0
    }
}

/// The rest of a run from one of its blocks, as one ramp (module doc).
#[derive(Clone, Copy, Debug)]
pub struct RunAhead {
    /// Blocks after the first.
    pub extra: usize,
    /// Length of them all, mm.
    pub len: f32,
    accel: f32,
    curve: bool,
    /// Least nominal speed and least corner limit inside, mm/s.
    cruise: f32,
    corner: f32,
    /// The corner holds inside, summed: at speed `v` they would take
    /// `v·held` seconds.
    held: f32,
    /// The largest of them.
    hold_max: f32,
    /// Least `Block::turn_v`, mm/s (infinite: none).
    turn_v: f32,
}

impl RunAhead {
    pub const fn start(b: &Block) -> Self {
        RunAhead {
            extra: 0,
            len: b.length,
            accel: b.accel,
            curve: b.curve_ar > 0.0,
            cruise: b.nominal,
            corner: f32::INFINITY,
            held: 0.0,
            hold_max: 0.0,
            turn_v: turn_v(b),
        }
    }

    /// Take in block `b` (before or after the others).
    pub fn block(&mut self, b: &Block) {
        self.extra += 1;
        self.len += b.length;
        self.accel = self.accel.min(b.accel);
        self.curve |= b.curve_ar > 0.0;
        self.cruise = self.cruise.min(b.nominal);
        self.turn_v = self.turn_v.min(turn_v(b));
    }

    /// Take in the junction at the start of block `n`, inside the run.
    pub fn junction(&mut self, n: &Block) {
        self.corner = self.corner.min(n.max_entry);
        let h = 0.5 * (n.hold_m + n.hold_pre_m);
        self.held += h;
        self.hold_max = self.hold_max.max(h);
    }

    /// The least nominal speed of its blocks, mm/s.
    pub fn cruise(&self) -> f32 {
        self.cruise
    }

    /// The speed the ramp may neither start nor pass a junction above: the
    /// least nominal speed and corner limit inside; where it turns, the
    /// turns' share of the jerk; and where corners inside would hold, the
    /// speed at which they take at most `HOLD_SHARE` of any window
    /// (module doc).
    pub fn cap(&self) -> f32 {
        let mut c = self.cruise.min(self.corner);
        if self.turns() {
            c = c.min(TURN_SHARE_V * self.turn_v);
        }
        if self.held > 0.0 {
            // `v·held ≤ s·W`, or `v·(h + held·W·v/L) ≤ s·W`: the larger root
            // of `(held·W/L)·v² + h·v − s·W = 0`.
            let w = super::passes::CANCEL_WINDOW_S;
            let all = HOLD_SHARE * w / self.held;
            let a = self.held * w / self.len.max(1e-6);
            let (b, c4) = (self.hold_max, 4.0 * a * HOLD_SHARE * w);
            let spread = (crate::num::sqrt(b * b + c4) - b) / (2.0 * a);
            c.min(all.max(spread))
        } else {
            c
        }
    }

    /// The share of a window the corners' holds take at speed `v`: all of
    /// them if the run takes less than a window, else a window's share of
    /// them (spread over blocks of alike speeds) and one corner more, the
    /// largest, for where they bunch (module doc).
    fn window_holds(&self, v: f32) -> f32 {
        let w = super::passes::CANCEL_WINDOW_S;
        let spread = self.hold_max + self.held * w * v / self.len.max(1e-6);
        v * self.held.min(spread) / w
    }

    fn turns(&self) -> bool {
        self.curve || self.held > 0.0
    }

    /// The ramp's shape (`cap`: [`RunAhead::cap`]): the least
    /// acceleration, less the share of a window the corners take at the
    /// cap (at least `HOLD_MARGIN` where they would hold), and a share of
    /// the jerk where it turns.
    pub fn shape(&self, s: &Settings, cap: f32) -> Shape {
        let jerk = s.jerk.max(1e-3) * if self.turns() { CURVE_RUN_JERK } else { 1.0 };
        let share = if self.held > 0.0 {
            1.0 - self.window_holds(cap).clamp(HOLD_MARGIN, 1.0)
        } else {
            1.0
        };
        Shape {
            accel: self.accel * share,
            jerk,
            drop: 0.0,
        }
    }

    /// The fastest entry the run promises (module doc): slowing to
    /// `exit` (its hold factor `exit_m`) with the first block's entry hold
    /// `entry_m`, within its `cap` ([`RunAhead::cap`]); `None` for a
    /// single block.
    pub(super) fn promise(
        &self,
        cap: f32,
        exit: f32,
        exit_m: f32,
        entry_m: f32,
        s: &Settings,
    ) -> Option<f32> {
        if self.extra == 0 {
            return None;
        }
        let reach = self
            .shape(s, cap)
            .reach_held(exit, self.len, exit_m, entry_m);
        Some(reach.min(cap))
    }
}

impl<const N: usize> Planner<N> {
    /// After a merge made the newest block longer: it starts a run of its
    /// own if it no longer goes into its predecessor's (a 0.025 mm step
    /// grouped with the short one before it grew to 25 mm, and the run's
    /// cap, the short one's, held it all). Only ever a split: the run
    /// before it was still open, and is now closed, so no promise goes.
    pub(super) fn regroup_newest(&mut self) {
        let Some(k) = self.len.checked_sub(1) else {
            return;
        };
        if k >= 1 && self.at(k).run_pos != 0 {
            let p = *self.at(k - 1);
            let n = self.at(k);
            if !groups(&p, n) {
                n.run_pos = 0;
            }
        }
    }

    /// The rest of the oldest block's run, from `first` (the preparer's
    /// copy of it): `None` while the next run's first block is not queued.
    pub fn run_ahead(&self, first: &Block) -> Option<RunAhead> {
        let mut run = RunAhead::start(first);
        for k in 1.. {
            let n = self.block(k)?;
            if n.run_pos == 0 {
                return Some(run);
            }
            run.junction(n);
            run.block(n);
        }
        None
    }
}

/// The rest of block `k`'s run for the backward pass: `ahead` (the rest of
/// block `k + 1`'s, and its run's next first block) with block `k` put in
/// front when both are in one run, else block `k` alone; and the queued
/// block after the run, if any (the last run may still grow).
pub(super) fn run_down<const N: usize>(
    blocks: &[Block; N],
    tail: usize,
    k: usize,
    len: usize,
    ahead: Option<(RunAhead, Option<usize>)>,
) -> (RunAhead, Option<usize>) {
    let b = &blocks[(tail + k) % N];
    match ahead {
        Some((mut run, exit)) if blocks[(tail + k + 1) % N].run_pos != 0 => {
            run.junction(&blocks[(tail + k + 1) % N]);
            run.block(b);
            (run, exit)
        }
        _ => (RunAhead::start(b), (k + 1 < len).then_some(k + 1)),
    }
}

/// The run that ends before the block the forward pass is at.
#[derive(Clone, Copy, Debug)]
pub(super) struct RunAcc {
    /// Entry speed and entry hold factor of the run's first block.
    entry: f32,
    hold_m: f32,
    run: RunAhead,
    open: bool,
}

impl RunAcc {
    const NONE: RunAcc = RunAcc {
        entry: 0.0,
        hold_m: 0.0,
        run: RunAhead::start(&Block::EMPTY),
        open: false,
    };

    fn start(b: &Block) -> Self {
        RunAcc {
            entry: b.entry,
            hold_m: b.hold_m,
            run: RunAhead::start(b),
            open: true,
        }
    }

    fn add(&mut self, b: &Block) {
        self.run.junction(b);
        self.run.block(b);
    }

    /// Move on past `prev` to the block `b` after it: the reach of the run
    /// that `prev` ends or continues at `b`'s entry, once it spans two
    /// blocks or more, within the run's caps. The run's ramp ends at `b`'s
    /// entry whether or not `b` starts the next run.
    /// Only reckoned where `needed` (the block alone reaches less than the
    /// entry): an S ramp's reach is most of what the passes cost.
    #[inline(never)]
    pub(super) fn step(
        &mut self,
        prev: &Block,
        b: &Block,
        s: &Settings,
        needed: bool,
    ) -> Option<f32> {
        if self.open {
            self.add(prev);
        } else {
            *self = RunAcc::start(prev);
        }
        let run = &self.run;
        let reach = (needed && run.extra >= 1).then(|| {
            let avail = run.len - 0.5 * self.hold_m * self.entry * self.entry;
            let cap = run.cap();
            run.shape(s, cap).reach(self.entry, avail).min(cap)
        });
        self.open = b.run_pos != 0;
        reach
    }
}

impl<const N: usize> Planner<N> {
    /// The run the forward pass carries into block `k`: the blocks of
    /// `k - 1`'s run before it, counted back once per pass (`None` in
    /// trapezoid mode).
    #[inline(never)]
    pub(super) fn run_before(&self, k: usize) -> Option<RunAcc> {
        if self.settings.profile != crate::settings::Profile::SCurve {
            return None;
        }
        if k < 2 || k > self.len || self.blocks[(self.tail + k - 1) % N].run_pos == 0 {
            return Some(RunAcc::NONE);
        }
        let at = |i: usize| &self.blocks[(self.tail + i) % N];
        let mut j = k - 2;
        while j > 0 && at(j).run_pos != 0 {
            j -= 1;
        }
        let mut acc = RunAcc::start(at(j));
        for i in j + 1..k - 1 {
            acc.add(at(i));
        }
        Some(acc)
    }
}
