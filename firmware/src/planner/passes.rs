//! Junction limits, overrides, and the backward/forward planning passes.

use super::*;

impl<const N: usize> Planner<N> {
    /// Cornering speed at the junction with the previous block.
    ///
    /// Junction deviation: round the corner by a circle tangent to both moves
    /// whose closest approach to the corner is `δ`. With `c = sin(θ/2)` of the
    /// corner's half angle (θ = π when straight), the circle's radius is
    /// `R = δ·c/(1 − c)` and `v = sqrt(a·R)` keeps the centripetal
    /// acceleration within `a`.
    ///
    /// Chords of a curve turn by a small angle φ every chord length `l`, so
    /// the tool really follows a curve of radius about `l/φ`. Junction
    /// deviation alone allows `a·δ/tol` there (5× the limit with GRBL's
    /// defaults); the second limit `v² ≤ a·l/φ` keeps curves honest.
    ///
    /// Both judge the commanded geometry (`unit_mm`, `length` in mm), not
    /// the step-rounded one: a G1 chord of a step or two can look like a
    /// 45° corner in steps (a radius of 0.016 mm on a 25 mm circle), which
    /// it is not; the motors' one-step jitter around the commanded line
    /// averages out like that of any Bresenham line.
    ///
    /// `a` is the acceleration the axes allow along the direction change
    /// (the difference of the two unit vectors), not along either move.
    pub(super) fn junction_speed(&self, unit_mm: &[f32; AXES], length: f32, curve: bool) -> f32 {
        if self.prev_nominal <= 0.0 {
            return 0.0;
        }
        let (cos, a) = self.turn(unit_mm, &self.prev_unit_mm);
        if cos > 0.999_999 {
            return 0.0;
        }
        if cos < -0.999_999 {
            // Straight on: no corner to limit.
            return f32::INFINITY;
        }
        let sin_half = libm::sqrtf(0.5 * (1.0 - cos));
        let r = self.settings.junction_deviation * sin_half / (1.0 - sin_half);
        let v_jd = libm::sqrtf(a * r);
        let phi = libm::acosf(crate::num::clamp(-cos, -1.0, 1.0)).max(1e-9);
        let l = length.min(self.prev_length);
        let a_curve = if curve { super::curve::C_MAX * a } else { a };
        let v_curve = libm::sqrtf(a_curve * l / phi);
        v_jd.min(v_curve)
    }

    /// Cosine of the corner between the reversed previous direction and
    /// `unit` (-1: straight on), and the acceleration the axes allow along
    /// the direction change.
    fn turn(&self, unit: &[f32; AXES], prev: &[f32; AXES]) -> (f32, f32) {
        let cos = -unit.iter().zip(prev).map(|(a, b)| a * b).sum::<f32>();
        let d: [f32; AXES] = core::array::from_fn(|i| unit[i] - prev[i]);
        let dn = libm::sqrtf(d.iter().map(|v| v * v).sum());
        let mut a = f32::INFINITY;
        for (di, ax) in d.iter().zip(&self.settings.axes) {
            let c = libm::fabsf(*di) / dn;
            if c > 1e-6 {
                a = a.min(ax.max_accel / c);
            }
        }
        (cos, a)
    }

    /// Apply new override percentages: every block's nominal speed and
    /// junction limit change, so the whole ring is replanned.
    pub fn set_overrides(&mut self, feed_pct: u8, rapid_pct: u8) {
        self.feed_pct = feed_pct as f32 / 100.0;
        self.rapid_pct = rapid_pct as f32 / 100.0;
        let mut prev_nominal = None;
        for k in 0..self.len {
            let mut b = *self.at(k);
            b.nominal = self.nominal(&b);
            Self::curve_limits(&mut b);
            if b.kind == BlockKind::Line {
                let pn = prev_nominal.unwrap_or(b.entry);
                b.max_entry = b.junction.min(b.nominal).min(pn);
                prev_nominal = Some(b.nominal);
            } else {
                prev_nominal = Some(0.0);
            }
            *self.at(k) = b;
        }
        if self.prev_nominal > 0.0 {
            if let Some(p) = prev_nominal {
                self.prev_nominal = p;
            }
        }
        self.replan(true);
    }

    /// Backward then forward pass. `full` ignores the early stop.
    pub fn replan(&mut self, full: bool) {
        if self.len == 0 {
            return;
        }
        if full {
            self.planned = 0;
        }
        let shape_of = |b: &Block, s: &Settings| b.shape(s);
        // Backward: the newest block must be able to stop at its end.
        let mut next_entry = 0.0f32;
        let mut k = self.len;
        while k > self.planned + 1 {
            k -= 1;
            let st = self.settings;
            let b = self.at(k);
            let new = if b.kind == BlockKind::Line {
                b.max_entry
                    .min(shape_of(b, &st).reach(next_entry, b.length))
            } else {
                0.0
            };
            let unchanged = new == b.entry;
            b.entry = new;
            next_entry = new;
            if unchanged && !full && k + 1 < self.len {
                break;
            }
        }
        // Forward: no block may be entered faster than the previous can reach.
        for k in self.planned + 1..self.len {
            let st = self.settings;
            let prev = *self.at(k - 1);
            let reach = match prev.kind {
                BlockKind::Line => shape_of(&prev, &st).reach(prev.entry, prev.length),
                BlockKind::Dwell { .. } => 0.0,
            };
            let b = self.at(k);
            if reach <= b.entry {
                b.entry = reach;
                self.planned = k;
            } else if b.entry >= b.max_entry {
                self.planned = k;
            }
        }
    }
}
