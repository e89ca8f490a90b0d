//! A canned cycle as the machine runs it: one [`Cycle`] command expands,
//! step by step, into rapids, feeds, dwells, spindle switches and pauses.
//!
//! A cycle is one command rather than the moves themselves because a peck
//! cycle has no bound on its moves (G83 Q0.5 down 40 mm is 240 of them)
//! while a line's command buffer is fixed. The executor walks
//! [`CycleSteps`] as the planner has room; check mode and the tests walk
//! the same iterator, so both see the same points.
//!
//! The moves follow LinuxCNC's `rs274ngc` (its documentation is the
//! reference): with `n` the axis normal to the plane,
//! 1. once per block, if the run of cycles began below R, rapid along `n`
//!    to R;
//! 2. per hole: rapid to the hole at the current level, or at the clear
//!    level when the current one is below R, rapid along `n` down to R (unless there already), then the cycle's
//!    own moves, ending at the clear level (R under G99; under G98 the
//!    higher of R and the level the run of cycles began at).

use crate::command::{Command, Feed, Plane, Pos, SpindleDir};

/// How far G73 backs off between pecks and G83 stops short of the last
/// peck's bottom on its rapid return: 0.010 in (LinuxCNC's value, which is
/// 0.254 mm in either unit system).
pub const PECK_CLEARANCE: f32 = 0.254;

/// Which cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CycleKind {
    /// G73: peck with chip-breaking back-offs.
    G73,
    /// G81: drill.
    G81,
    /// G82: drill, dwell.
    G82,
    /// G83: peck, retracting to R each time.
    G83,
    /// G85: bore, feed out.
    G85,
    /// G86: bore, dwell, spindle stop, rapid out, spindle restart.
    G86,
    /// G88: bore, dwell, spindle stop, pause for the operator (an M0 hold
    /// here), rapid out, spindle restart (see `cycles`).
    G88,
    /// G89: bore, dwell, feed out to the clear level.
    G89,
}

impl CycleKind {
    pub const fn tenths(self) -> u16 {
        match self {
            CycleKind::G73 => 730,
            CycleKind::G81 => 810,
            CycleKind::G82 => 820,
            CycleKind::G83 => 830,
            CycleKind::G85 => 850,
            CycleKind::G86 => 860,
            CycleKind::G88 => 880,
            CycleKind::G89 => 890,
        }
    }
    pub const fn from_tenths(t: u16) -> Option<CycleKind> {
        Some(match t {
            730 => CycleKind::G73,
            810 => CycleKind::G81,
            820 => CycleKind::G82,
            830 => CycleKind::G83,
            850 => CycleKind::G85,
            860 => CycleKind::G86,
            880 => CycleKind::G88,
            890 => CycleKind::G89,
            _ => return None,
        })
    }
    /// The steps after the rapid to R, in order.
    const fn body(self) -> &'static [Op] {
        use Op::*;
        match self {
            CycleKind::G73 | CycleKind::G83 => &[Pecks, FeedBottom, RapidClear],
            CycleKind::G81 => &[FeedBottom, RapidClear],
            CycleKind::G82 => &[FeedBottom, Dwell, RapidClear],
            CycleKind::G85 => &[FeedBottom, FeedR, RapidClear],
            CycleKind::G86 => &[FeedBottom, Dwell, SpindleOff, RapidClear, SpindleOn],
            CycleKind::G88 => &[FeedBottom, Dwell, SpindleOff, Pause, RapidClear, SpindleOn],
            CycleKind::G89 => &[FeedBottom, Dwell, FeedClear],
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    Pecks,
    FeedBottom,
    FeedR,
    FeedClear,
    RapidClear,
    Dwell,
    SpindleOff,
    SpindleOn,
    Pause,
}

/// One canned-cycle block, resolved to machine mm. Levels are along the
/// plane's normal axis; hole positions are in the plane's two axes
/// (ordered as [`Plane::axes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cycle {
    pub kind: CycleKind,
    pub plane: Plane,
    /// The first hole.
    pub hole: [f32; 2],
    /// From one hole to the next (L repeats under G91; zero under G90).
    pub step: [f32; 2],
    /// Holes (L), at least 1.
    pub repeats: u16,
    /// The run of cycles began below R: go to R first, from wherever the
    /// tool is (LinuxCNC compares R with that initial level, not with the
    /// current one, so this can be a move down).
    pub rise: bool,
    pub r: f32,
    pub bottom: f32,
    pub clear: f32,
    /// G73/G83 peck depth, mm (> 0).
    pub q: f32,
    /// G82/G86/G88/G89 dwell, seconds.
    pub p: f32,
    pub feed: f32,
    /// G86/G88 restart the spindle like this afterwards.
    pub spindle: SpindleDir,
    pub speed: f32,
}

/// Walks a [`Cycle`] from `start`. Small and `Clone`: the executor keeps one.
#[derive(Clone, Debug)]
pub struct CycleSteps {
    c: Cycle,
    pos: Pos,
    hole: u16,
    /// 0: rise to R, 1: to the hole, 2: down to R, 3..: body op `stage - 3`.
    stage: u8,
    /// Pecks done in this hole, and where in a peck (0 feed, 1 up, 2
    /// back down). Depths are computed from the count, never accumulated,
    /// so a peck too small for `f32` cannot stall the walk.
    pecks: u32,
    peck: u8,
}

/// Most pecks one hole may take (the interpreter refuses more): with
/// [`MAX_MOVES`] a bound on every walk, for check mode as for the machine.
pub const MAX_PECKS: u32 = 10_000;
/// Most moves one cycle block may expand to (holes x moves per hole).
pub const MAX_MOVES: u32 = 200_000;

impl Cycle {
    /// The machine position after the whole block.
    pub fn end(&self, start: &Pos) -> Pos {
        let (a0, a1, n) = self.plane.axes();
        let mut p = *start;
        let k = f32::from(self.repeats.max(1) - 1);
        p[a0] = self.hole[0] + k * self.step[0];
        p[a1] = self.hole[1] + k * self.step[1];
        p[n] = self.clear;
        p
    }

    pub fn steps(&self, start: &Pos) -> CycleSteps {
        CycleSteps {
            c: *self,
            pos: *start,
            hole: 0,
            stage: 0,
            pecks: 0,
            peck: 0,
        }
    }
}

impl CycleSteps {
    fn at(&mut self, level: f32) -> Pos {
        let (_, _, n) = self.c.plane.axes();
        self.pos[n] = level;
        self.pos
    }
    fn rapid(&mut self, level: f32) -> Command {
        Command::Rapid {
            end: self.at(level),
        }
    }
    fn feed(&mut self, level: f32) -> Command {
        Command::Line {
            end: self.at(level),
            feed: Feed::PerMin(self.c.feed),
        }
    }
}

impl Iterator for CycleSteps {
    type Item = Command;

    fn next(&mut self) -> Option<Command> {
        let c = self.c;
        let (a0, a1, n) = c.plane.axes();
        loop {
            if self.hole >= c.repeats.max(1) {
                return None;
            }
            let stage = self.stage;
            self.stage = stage.saturating_add(1);
            match stage {
                0 => {
                    if c.rise {
                        return Some(self.rapid(c.r));
                    }
                }
                1 => {
                    let k = f32::from(self.hole);
                    self.pos[a0] = c.hole[0] + k * c.step[0];
                    self.pos[a1] = c.hole[1] + k * c.step[1];
                    // Never in the plane below R: from below it is one
                    // rapid to the hole at the clear level (rs274 does the
                    // same; under G98 after a G99 block with a lower R that
                    // is the level the run began at, issue 30).
                    if self.pos[n] < c.r {
                        self.pos[n] = c.clear;
                    }
                    return Some(Command::Rapid { end: self.pos });
                }
                2 => {
                    if self.pos[n] != c.r {
                        return Some(self.rapid(c.r));
                    }
                }
                _ => {
                    let Some(&op) = c.kind.body().get(usize::from(stage - 3)) else {
                        // Next hole: from the clear level, no rise.
                        self.hole += 1;
                        self.stage = 1;
                        self.pecks = 0;
                        continue;
                    };
                    match op {
                        Op::Pecks => {
                            let d = c.r - (self.pecks + 1) as f32 * c.q;
                            if d > c.bottom && self.pecks < MAX_PECKS {
                                // Stay on this op until the pecks reach the bottom.
                                self.stage = stage;
                                let step = self.peck;
                                self.peck = (step + 1) % 3;
                                match (step, c.kind) {
                                    (0, _) => return Some(self.feed(d)),
                                    (1, CycleKind::G83) => return Some(self.rapid(c.r)),
                                    _ => {
                                        self.peck = 0;
                                        self.pecks += 1;
                                        return Some(self.rapid(d + PECK_CLEARANCE));
                                    }
                                }
                            }
                        }
                        Op::FeedBottom => return Some(self.feed(c.bottom)),
                        Op::FeedR => return Some(self.feed(c.r)),
                        Op::FeedClear => return Some(self.feed(c.clear)),
                        Op::RapidClear => return Some(self.rapid(c.clear)),
                        Op::Dwell => {
                            if c.p > 0.0 {
                                return Some(Command::Dwell { seconds: c.p });
                            }
                        }
                        Op::SpindleOff => {
                            return Some(Command::Spindle {
                                dir: SpindleDir::Off,
                                speed: c.speed,
                            })
                        }
                        Op::SpindleOn => {
                            if c.spindle != SpindleDir::Off {
                                return Some(Command::Spindle {
                                    dir: c.spindle,
                                    speed: c.speed,
                                });
                            }
                        }
                        Op::Pause => return Some(Command::Pause { optional: false }),
                    }
                }
            }
        }
    }
}
