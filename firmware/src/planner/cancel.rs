//! Corners settled by the chord after them.
//!
//! A chord polyline in inch decimals to four places (a 25 mm circle of
//! 0.0155 mm chords, circle_small) steps across its line by 0.00254 mm
//! every few chords: a fifth of a step at 80 steps/mm, but a 9° turn into
//! the step and another out of it. Judged one corner at a time, each turn
//! held the path for its whole change and capped it at the curvature rule
//! `v² ≤ a·l/φ` (7 mm/s), while the motors never see the step: the job
//! took 19.6 s, against 5.0 s without holds and within every limit. The
//! chord after a corner tells a step of rounding from a turn; this module
//! settles the newest queued corner once that chord is pushed.
//!
//! **Curvature.** A turn that keeps its chord within a quarter step of the
//! line before it ([`super::corner::ROUNDING_STEPS`]) leaves its curvature
//! rule pending: the block is queued with junction deviation's limit only.
//! That is safe while it is the newest block, which must stop within
//! itself (`v² ≤ 2·accel·len`): `planner::push` pends only a turn small
//! enough for that bound to lie under the rule's. When the next chord
//! comes, the corner gets the rule on the larger of its own radius `l/φ`
//! and the turn across two chords ([`super::corner::two_chords`]): from
//! the line before it to the new chord (the chord after the corner was
//! rounding), and, if the chord before it was rounding too, from the one
//! before that. A real curve turns alike at every vertex and keeps `l/φ`;
//! a step of rounding turns back at the next vertex, and the radius across
//! it is large. Settling only lowers the limit, as the backward pass does.
//!
//! **Holds.** Two corners a chord apart act on an axis as their net change
//! plus a velocity pulse between them: over the meter's window `W` (a
//! triangular kernel, height `1/W`, slope `1/W²`) they read at most
//! `|N|/W + P/W²`, `P = |Δu|·l` the pulse's area, a distance independent
//! of the speed. `Planner::hold_factor` gives the second corner the
//! pair's share of a hold (`net + m·t/W`, [`super::passes::kept_share`]);
//! the first had held in full, planned before the second was known. Here
//! the first gets that share too, but only where the pulse reads at most
//! [`PULSE_SHARE`] of every axis's limit (`P ≤ 0.02·a_i·W²`: 0.025 mm at
//! 500 mm/s², 0.005 mm at 100). The kernel's slope is the same across its
//! width, so a window whose far part is a ramp at full acceleration still
//! reads the pulse, and no hold near the corner takes that away: with the
//! first corner released for any pulse, Cereal.ngc's 0.013 mm Z step
//! between climbing chords (`P` = 0.024 mm) read 105 % of Z's limit; gated,
//! 102 %, as before.
//!
//! Lowering a limit is what the passes do anyway; a smaller hold lets
//! entries rise, which is left alone where the segment preparer may have
//! started (the oldest two blocks, as `planner::quiet` does), and for a
//! chord of a curve (the curve's own budget holds there).

use super::corner::two_chords;
use super::passes::{kept_share, Sides, CANCEL_WINDOW_S as W};
use super::*;

/// What [`Planner::hold_factor`] found at a corner besides its hold, for
/// settling the corner before it and itself later (`planner::cancel`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// The corner's largest change (`|Δu_i|/a_i`) where the pulse it
    /// would leave with the next corner is small on every axis, else 0.
    pub pulse_m: f32,
    /// What it and the corner before it leave together (as `m`), if
    /// that was weighed.
    pub net: Option<f32>,
    /// The share of its hold it kept for that.
    pub kept: f32,
    /// Chords of one curve that change an axis across its plane (a
    /// helix meeting its flat turn): the chord after keeps the corner's
    /// speed (`planner::push`).
    pub kink: bool,
}

impl Pair {
    pub const NONE: Pair = Pair {
        pulse_m: 0.0,
        net: None,
        kept: 1.0,
        kink: false,
    };
}

/// The most a pair of corners' pulse may read on an axis, as a share of
/// its limit (`planner::cancel`).
pub(super) const PULSE_SHARE: f32 = 0.02;

impl<const N: usize> Planner<N> {
    /// Settle the newest queued block's corner now that the block after
    /// it is known, entered at most at `next_corner` mm/s, its direction
    /// turned by `phi2` from the chord before the newest and its corner's
    /// change and the newest's leaving `net` together (`Pair::net`): the
    /// newest's curvature limit if it was pending, and the share of its
    /// hold it keeps if the new corner takes it back. `before`: a chord
    /// before the newest's was queued since the last stop. Returns the
    /// lowest block the backward pass must reach (`len` if none).
    pub(super) fn release_taken_back(
        &mut self,
        next_corner: f32,
        phi2: Option<f32>,
        net: Option<f32>,
        before: bool,
    ) -> usize {
        let none = self.len;
        // The oldest block is the preparer's; the next one's limit may
        // only fall (as the passes' may), so its hold stays.
        let k = match self.len.checked_sub(1) {
            Some(k) if k >= 1 => k,
            _ => return none,
        };
        if self.prev_curve.is_some() || !before {
            return none;
        }
        let (plain, length, corner, nominal) = {
            let b = &self.blocks[(self.tail + k) % N];
            (
                b.kind == BlockKind::Line && !b.takeup,
                b.length,
                b.corner,
                b.nominal,
            )
        };
        if !plain {
            return none;
        }
        // A pending corner's curvature: the chord after it was rounding of
        // the line before it, so the tool turns from that line to the new
        // chord across two chords; and the chord before the corner may
        // have been rounding too (its own turn across two chords).
        let mut settled = corner;
        if self.pending & 1 != 0 {
            let l = self.prev_turn.l;
            let ahead = phi2.map_or(0.0, |p| two_chords(l, p));
            // (The chord before pending means its push took that turn.)
            let behind = if self.pending & 2 != 0 {
                two_chords(l, self.prev_phi2)
            } else {
                0.0
            };
            settled = corner.min(self.prev_turn.speed(ahead.max(behind)));
        }
        // The share of its hold it keeps, if the pulse the two corners
        // leave is small on every axis (module doc). A new direction that
        // does not turn back keeps it all (`net ≥ m`).
        let mut r = 1.0;
        let m = self.prev_pulse_m;
        if let Some(net) = net.filter(|&n| m > n && k >= 2) {
            // The chord's time at the most it can run between the two
            // corners (slower, the speeds at the two differ more). At a
            // stop there is no pulse, but two separate changes.
            let v = settled.min(next_corner).min(nominal);
            let t = if v.is_finite() { length / v } else { 0.0 };
            if v > 0.0 && t <= W {
                let kept = kept_share(m, net, t);
                let had = 1.0 - self.prev_given_up;
                if kept < had {
                    r = kept / had;
                    self.prev_given_up = 1.0 - kept;
                }
            }
        }
        if r >= 1.0 && settled == corner {
            return none;
        }
        // A lower limit only lowers entries, which the backward pass does
        // wherever it reaches; a smaller hold lets this block's entry and
        // the one's before it rise, so the forward pass goes over them.
        let lowest = if r < 1.0 {
            self.planned = self.planned.min(k.saturating_sub(2));
            k - 1
        } else {
            k
        };
        let (room, prev_nominal) = {
            let p = self.at(k - 1);
            (p.length, p.nominal)
        };
        let b = self.at(k);
        let scale = |s: Sides| Sides {
            pre: s.pre * r,
            post: s.post * r,
        };
        b.hold_fixed = scale(b.hold_fixed);
        let held = scale(Sides {
            pre: b.hold_pre_m,
            post: b.hold_m,
        });
        b.set_corner(settled, held, room.min(b.length), prev_nominal);
        lowest
    }
}
