//! `max_tool_deviation_mm`: how far the modelled tool (behind the machine's
//! slack, `World`) strays from the commanded path, checked at every step
//! interrupt against the polyline of commanded path points (arcs and
//! splines arrive as their chords).
//!
//! The path is planned ahead of the tool (up to the planner ring), so the
//! points wait in a queue; the tool is measured against a short window of
//! segments from the one it was nearest last time, and the segments behind
//! that are dropped: the cost per step is a few segment distances.

use std::collections::VecDeque;

use burin::AXES;

/// Segments ahead of the last nearest one that a step is measured against.
const AHEAD: usize = 8;

#[derive(Default)]
pub struct Deviation {
    /// Commanded vertices, mm; segment `k` runs from `pts[k]` to `pts[k+1]`.
    pts: VecDeque<[f64; AXES]>,
    /// The segment the tool was nearest at the last check.
    at: usize,
    pub max_mm: f64,
}

impl Deviation {
    /// A commanded path vertex (a move's start, which repeats the last
    /// end unless a flush or a redefinition moved it, or a piece's end).
    pub fn point(&mut self, p: [f32; AXES]) {
        let p = p.map(f64::from);
        if self.pts.back() != Some(&p) {
            self.pts.push_back(p);
        }
    }

    /// Measures the tool at `tool` (mm) against the window of the path.
    pub fn check(&mut self, tool: &[f64; AXES]) {
        let n = self.pts.len();
        if n == 0 {
            return;
        }
        let mut best = (f64::INFINITY, self.at);
        if n == 1 {
            best.0 = dist2(tool, &self.pts[0]);
        }
        let end = (self.at + AHEAD).min(n.saturating_sub(1));
        for k in self.at..end {
            let d = seg_dist2(tool, &self.pts[k], &self.pts[k + 1]);
            if d < best.0 {
                best = (d, k);
            }
        }
        self.max_mm = self.max_mm.max(best.0.sqrt());
        // Keep one segment behind the nearest: a tool that dwells at a
        // vertex may be measured against the segment before it again.
        let drop = best.1.saturating_sub(1);
        self.pts.drain(..drop);
        self.at = best.1 - drop;
    }
}

fn dist2(a: &[f64; AXES], b: &[f64; AXES]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Squared distance from `p` to the segment `a`-`b`.
fn seg_dist2(p: &[f64; AXES], a: &[f64; AXES], b: &[f64; AXES]) -> f64 {
    let ab: [f64; AXES] = std::array::from_fn(|i| b[i] - a[i]);
    let len2: f64 = ab.iter().map(|v| v * v).sum();
    let t = if len2 > 0.0 {
        let ap: f64 = (0..AXES).map(|i| (p[i] - a[i]) * ab[i]).sum();
        (ap / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q: [f64; AXES] = std::array::from_fn(|i| a[i] + t * ab[i]);
    dist2(p, &q)
}

#[cfg(test)]
mod tests {
    use super::Deviation;

    #[test]
    fn measures_the_distance_to_the_nearest_segment_of_the_window() {
        let mut d = Deviation::default();
        d.point([0.0; burin::AXES]);
        d.point(burin::pad([10.0, 0.0, 0.0, 0.0]));
        d.point(burin::pad([10.0, 10.0, 0.0, 0.0]));
        d.check(&burin::pad([5.0, 0.05, 0.0, 0.0]));
        assert!((d.max_mm - 0.05).abs() < 1e-9, "{}", d.max_mm);
        d.check(&burin::pad([9.9, 5.0, 0.0, 0.0]));
        assert!((d.max_mm - 0.1).abs() < 1e-9, "{}", d.max_mm);
        // Past the corner: the first segment is dropped behind the tool.
        d.check(&burin::pad([10.0, 9.0, 0.0, 0.0]));
        assert!((d.max_mm - 0.1).abs() < 1e-9);
        assert!(d.pts.len() <= 3);
    }
}
