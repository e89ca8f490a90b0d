//! Homing (G28/`$H`) and verify-home (G27) as a state machine.
//!
//! Each cycle of `$206` (a nibble of axes, low nibble first) runs: seek the
//! switches fast, pull off, locate them slowly, then either redefine the
//! position (the locate trip point becomes machine 0) or, for G27, compare
//! the trip point against 0 within `$205`; finally pull off again. Axes of
//! one cycle move together; when one switch closes the stepper stops and the
//! others seek on.

use super::MachineError;
use crate::command::{AxisMask, ALL_AXES};
use crate::planner::Watch;
use crate::settings::Settings;
use crate::AXES;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Start,
    Seek,
    PullOff,
    Locate,
    Redefined,
    Final,
}

/// What the executor should do next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Move to `target` steps at `rate` mm/s, stopping on `watch`.
    Move {
        target: [i32; AXES],
        rate: f32,
        watch: Watch,
    },
    /// Redefine the machine position, steps.
    Redefine { position: [i32; AXES] },
    /// Stand still while the switch stops bouncing (`$26`).
    Settle { seconds: f32 },
    /// All cycles done.
    Done { axes: AxisMask, verified: bool },
}

/// Progress through the homing cycles.
#[derive(Clone, Debug)]
pub struct Homing {
    cycles: [u8; 4],
    idx: usize,
    phase: Phase,
    remaining: u8,
    tripped_this_move: bool,
    located: [i32; AXES],
    verify: bool,
    line: u32,
    settled: bool,
}

impl Homing {
    /// `axes` 0 means every axis with a homing cycle.
    pub fn new(
        s: &Settings,
        axes: AxisMask,
        verify: bool,
        line: u32,
    ) -> Result<Self, MachineError> {
        if !s.homing_enable {
            return Err(MachineError::HomingDisabled);
        }
        let want = if axes == 0 { ALL_AXES } else { axes };
        let cycles: [u8; 4] =
            core::array::from_fn(|i| ((s.homing_order >> (4 * i)) & 0x0f) as u8 & want);
        if cycles.iter().all(|c| *c == 0) {
            return Err(MachineError::HomingDisabled);
        }
        Ok(Homing {
            cycles,
            idx: 0,
            phase: Phase::Start,
            remaining: 0,
            tripped_this_move: false,
            located: [0; AXES],
            verify,
            line,
            settled: false,
        })
    }

    pub fn line(&self) -> u32 {
        self.line
    }
    /// Every axis this run homes.
    pub fn axes(&self) -> AxisMask {
        self.cycles.iter().fold(0, |a, c| a | c)
    }

    /// The stepper stopped because switches in `mask` closed at `at` steps.
    pub fn tripped(&mut self, mask: u8, at: &[i32; AXES]) {
        self.tripped_this_move = true;
        for (i, p) in at.iter().enumerate() {
            if mask & self.remaining & (1 << i) != 0 {
                self.located[i] = *p;
            }
        }
        self.remaining &= !mask;
    }

    fn dir(s: &Settings, axis: usize) -> f32 {
        if s.homing_dir_invert & (1 << axis) != 0 {
            -1.0
        } else {
            1.0
        }
    }

    /// A move of the axes in `mask` by `mm` towards (positive) or away from
    /// (negative) their switches; `rate` is per axis, mm/min.
    fn mv(
        s: &Settings,
        pos: &[i32; AXES],
        mask: u8,
        mm: impl Fn(usize) -> f32,
        rate: f32,
        watch: u8,
    ) -> Action {
        let mut target = *pos;
        let mut n = 0;
        for (i, t) in target.iter_mut().enumerate() {
            if mask & (1 << i) != 0 {
                let d = Self::dir(s, i) * mm(i) * s.axes[i].steps_per_mm;
                *t = t.saturating_add(libm::roundf(d) as i32);
                n += 1;
            }
        }
        let rate = rate / 60.0 * crate::num::sqrt(n.max(1) as f32);
        Action::Move {
            target,
            rate,
            watch: Watch {
                limits: watch,
                probe: 0,
                homing: true,
            },
        }
    }

    fn first_axis(mask: u8) -> u8 {
        mask.trailing_zeros().min(AXES as u32 - 1) as u8
    }

    /// Next action, called whenever motion is idle. `limits` are the closed
    /// switches (after inversion).
    pub fn step(
        &mut self,
        s: &Settings,
        pos: &[i32; AXES],
        limits: u8,
    ) -> Result<Action, MachineError> {
        loop {
            let Some(&mask) = self.cycles.get(self.idx) else {
                return Ok(Action::Done {
                    axes: self.axes(),
                    verified: self.verify,
                });
            };
            if mask == 0 {
                self.idx += 1;
                continue;
            }
            let seek_len = |i: usize| s.axes[i].max_travel.max(10.0) * 1.5;
            let pull = s.homing_pulloff.max(0.01);
            match self.phase {
                Phase::Start => {
                    self.remaining = mask;
                    self.tripped_this_move = false;
                    self.phase = Phase::Seek;
                    return Ok(Self::mv(
                        s,
                        pos,
                        self.remaining,
                        seek_len,
                        s.homing_seek,
                        self.remaining,
                    ));
                }
                Phase::Seek | Phase::Locate => {
                    if !self.tripped_this_move {
                        return Err(MachineError::HomingNoSwitch {
                            axis: Self::first_axis(self.remaining),
                        });
                    }
                    if !self.settled && s.homing_debounce_ms > 0 {
                        self.settled = true;
                        return Ok(Action::Settle {
                            seconds: s.homing_debounce_ms as f32 / 1000.0,
                        });
                    }
                    self.settled = false;
                    self.tripped_this_move = false;
                    if self.remaining != 0 {
                        let (len, rate) = if self.phase == Phase::Seek {
                            (seek_len(0).max(seek_len(1)), s.homing_seek)
                        } else {
                            (pull * 3.0, s.homing_feed)
                        };
                        return Ok(Self::mv(
                            s,
                            pos,
                            self.remaining,
                            |_| len,
                            rate,
                            self.remaining,
                        ));
                    }
                    if self.phase == Phase::Seek {
                        self.phase = Phase::PullOff;
                        return Ok(Self::mv(s, pos, mask, |_| -pull, s.homing_seek, 0));
                    }
                    if self.verify {
                        for i in 0..AXES {
                            if mask & (1 << i) == 0 {
                                continue;
                            }
                            let dev = libm::fabsf(self.located[i] as f32 / s.axes[i].steps_per_mm);
                            if dev > s.verify_home_tolerance {
                                return Err(MachineError::VerifyHome {
                                    axis: i as u8,
                                    deviation_mm: dev,
                                });
                            }
                        }
                        self.phase = Phase::Final;
                        return Ok(Self::mv(s, pos, mask, |_| -pull, s.homing_seek, 0));
                    }
                    let mut position = *pos;
                    for i in 0..AXES {
                        if mask & (1 << i) != 0 {
                            position[i] = pos[i].saturating_sub(self.located[i]);
                        }
                    }
                    self.phase = Phase::Redefined;
                    return Ok(Action::Redefine { position });
                }
                Phase::PullOff => {
                    if limits & mask != 0 {
                        return Err(MachineError::HomingPullOff {
                            axis: Self::first_axis(limits & mask),
                        });
                    }
                    self.remaining = mask;
                    self.tripped_this_move = false;
                    self.phase = Phase::Locate;
                    return Ok(Self::mv(s, pos, mask, |_| pull * 3.0, s.homing_feed, mask));
                }
                Phase::Redefined => {
                    self.phase = Phase::Final;
                    return Ok(Self::mv(s, pos, mask, |_| -pull, s.homing_seek, 0));
                }
                Phase::Final => {
                    if limits & mask != 0 {
                        return Err(MachineError::HomingPullOff {
                            axis: Self::first_axis(limits & mask),
                        });
                    }
                    self.idx += 1;
                    self.phase = Phase::Start;
                }
            }
        }
    }
}
