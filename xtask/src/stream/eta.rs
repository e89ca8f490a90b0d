//! Time left, from motion. Every status report is placed on the job's
//! simulated timeline ([`Profile`]): the line the board reports executing
//! (`Ln:`) narrows the search to that line's stretch of the run, and the
//! machine position (`MPos:`) says where in it the board is. A line alone
//! is too coarse a clock: one G0 can be a third of a job. The wall time
//! spent against the simulated time so far (the drift: a slower clock, a
//! `--speed`ed virtual board) is a least-squares slope over those points,
//! and it scales what is left.

use super::timeline::Profile;
use std::collections::VecDeque;

/// Anchors kept for the offset (the slope's running sums hold all of them).
const RECENT: usize = 8;

/// A least-squares line through (simulated s, wall s) points.
#[derive(Default)]
struct Fit {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
}

impl Fit {
    fn add(&mut self, a: f64, s: f64) {
        self.n += 1.0;
        self.sx += s;
        self.sy += a;
        self.sxx += s * s;
        self.sxy += s * a;
    }

    /// Wall seconds per simulated second (None until the points span some
    /// simulated time).
    fn slope(&self) -> Option<f64> {
        let d = self.n * self.sxx - self.sx * self.sx;
        if self.n < 2.0 || d <= 1e-12 * self.n * self.n {
            return None;
        }
        let r = (self.n * self.sxy - self.sx * self.sy) / d;
        (r.is_finite() && (1e-3..1e3).contains(&r)).then_some(r)
    }
}

/// The running estimate.
#[derive(Default)]
pub struct Eta {
    profile: Profile,
    /// (active wall seconds, simulated seconds) of the latest points placed
    /// on the timeline.
    anchors: VecDeque<(f64, f64)>,
    fit: Fit,
    last_line: usize,
    /// Active time of the previous status report.
    last_seen: Option<f64>,
    /// Sum and count of the intervals between status reports: the end is
    /// seen at the first report after it, half an interval late on average.
    gap_sum: f64,
    gaps: f64,
}

impl Eta {
    pub fn new(profile: Profile) -> Eta {
        Eta {
            profile,
            ..Eta::default()
        }
    }

    pub fn simulated_s(&self) -> f64 {
        self.profile.total_s
    }

    /// A status report at `active` seconds (wall time the machine was not
    /// paused) said file line `line` runs (0: none yet), with the machine
    /// at `mpos`.
    pub fn observe(&mut self, active: f64, line: usize, mpos: &[f32]) {
        if let Some(prev) = self.last_seen {
            self.gap_sum += (active - prev).clamp(0.0, 1.0);
            self.gaps += 1.0;
        }
        if line != 0 {
            let after = self.anchors.back().map_or(0.0, |a| a.1);
            if let Some(s) = self.profile.locate(line, mpos, after) {
                self.anchor(active, s);
            } else if line != self.last_line {
                if let Some(s) = self.profile.start(line) {
                    // The line started between the previous report and
                    // this one.
                    let a = self.last_seen.map_or(active, |p| 0.5 * (p + active));
                    self.anchor(a, s);
                }
            }
            self.last_line = line;
        }
        self.last_seen = Some(active);
    }

    fn anchor(&mut self, a: f64, s: f64) {
        if self.anchors.len() == RECENT {
            self.anchors.pop_front();
        }
        self.anchors.push_back((a, s));
        self.fit.add(a, s);
    }

    /// Wall seconds per simulated second, from the points so far.
    pub fn drift(&self) -> Option<f64> {
        self.fit.slope()
    }

    /// Seconds left at `active` (None before the drift is known).
    pub fn remaining(&self, active: f64) -> Option<f64> {
        let r = self.drift()?;
        let p = &self.profile;
        // The offset: the median, not the mean, of the recent anchors'. A
        // report read late (the streamer or the link stalled a few ms)
        // places its anchor late by as much; one such among the recent
        // ones must not move the estimate.
        let mut offsets: Vec<f64> = self.anchors.iter().map(|(a, s)| a - r * s).collect();
        offsets.sort_by(f64::total_cmp);
        let c = match offsets.len() {
            0 => return None,
            n if n % 2 == 1 => offsets[n / 2],
            n => 0.5 * (offsets[n / 2 - 1] + offsets[n / 2]),
        };
        // Where on the timeline the board is now.
        let s_now = ((active - c) / r).clamp(0.0, p.total_s);
        let left = r * (p.total_s - s_now);
        // Never claim more progress than the running line's span allows.
        let floor = p
            .span(self.last_line)
            .map_or(0.0, |(_, hi)| r * (p.total_s - hi));
        let latency = if self.gaps > 0.0 {
            0.5 * self.gap_sum / self.gaps
        } else {
            0.0
        };
        Some(left.max(floor) + latency)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::timeline::tests::profile;

    fn line_at(s: f64) -> usize {
        match s {
            s if s < 1.0 => 1,
            s if s < 2.0 => 2,
            s if s < 3.0 => 3,
            s if s < 4.0 => 5,
            _ => 6,
        }
    }

    #[test]
    fn remaining_follows_the_timeline_at_a_steady_drift() {
        let mut eta = Eta::new(profile());
        assert_eq!(eta.remaining(0.0), None);
        // Twice as slow as simulated, a status report every 0.1 s.
        for i in 0..=60 {
            let a = f64::from(i) * 0.1;
            let s = a / 2.0;
            eta.observe(a, line_at(s), &[s as f32, 0.0, 0.0, 0.0]);
        }
        assert!(
            (eta.drift().unwrap() - 2.0).abs() < 1e-3,
            "{:?}",
            eta.drift()
        );
        // 4 s left, and half a report interval until the end is seen.
        let left = eta.remaining(6.0).unwrap();
        assert!((left - 4.05).abs() < 1e-3, "{left}");
    }

    #[test]
    fn a_report_read_late_does_not_move_the_estimate() {
        let mut eta = Eta::new(profile());
        for i in 0..60 {
            let a = f64::from(i) * 0.1;
            let s = a / 2.0;
            eta.observe(a, line_at(s), &[s as f32, 0.0, 0.0, 0.0]);
        }
        // The report of 6.0 s is read at 6.2 s (the streamer stalled).
        eta.observe(6.2, line_at(3.0), &[3.0, 0.0, 0.0, 0.0]);
        // 3.8 s left at 6.2 s, plus half the mean report interval (about
        // 0.05 s). Averaging the anchors instead would add 0.2 s / 8.
        let left = eta.remaining(6.2).unwrap();
        assert!((left - 3.85).abs() < 0.02, "{left}");
    }

    #[test]
    fn lines_alone_still_give_the_time_left() {
        let mut eta = Eta::new(profile());
        for i in 0..=60 {
            let a = f64::from(i) * 0.1;
            // A position off the simulated path: only lines count.
            eta.observe(a, line_at(a / 2.0), &[9.0, 9.0, 0.0, 0.0]);
        }
        assert!(
            (eta.drift().unwrap() - 2.0).abs() < 0.1,
            "{:?}",
            eta.drift()
        );
        let left = eta.remaining(6.0).unwrap();
        assert!((left - 4.0).abs() < 0.2, "{left}");
    }
}
