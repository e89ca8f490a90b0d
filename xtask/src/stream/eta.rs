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
/// Shortest pace window, wall seconds: report jitter (0.1 ms at
/// `--speed 20`, a few ms on a real link over its 50 ms reports) is then a
/// small share of it.
const WINDOW_S: f64 = 0.05;
/// Pace windows kept (odd: the median is one of them).
const PACES: usize = 5;

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
    /// Where the current pace window began, and the paces of the latest
    /// closed ones: see [`Eta::drift`].
    window: Option<(f64, f64)>,
    paces: VecDeque<f64>,
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
        match self.window {
            Some((a0, s0)) => {
                let long = WINDOW_S.max(10.0 * self.mean_gap()).max(0.1 * a);
                if a - a0 >= long && s > s0 {
                    if self.paces.len() == PACES {
                        self.paces.pop_front();
                    }
                    self.paces.push_back((a - a0) / (s - s0));
                    self.window = Some((a, s));
                }
            }
            None => self.window = Some((a, s)),
        }
    }

    fn mean_gap(&self) -> f64 {
        if self.gaps > 0.0 {
            self.gap_sum / self.gaps
        } else {
            0.0
        }
    }

    /// Wall seconds per simulated second. A slowdown (the host or the link
    /// stalled, the board waited for lines) is brief, and the pace after it
    /// is the pace before it; a least-squares line through both sides
    /// tilts and misjudges all that is left (a 24 ms stall in a 1.3 s job
    /// put the ETA 5 % high at half way). So once there are enough, the
    /// pace is the median of the latest [`PACES`] windows, each at least
    /// [`WINDOW_S`], ten reports and a tenth of the time so far long (so
    /// report jitter stays a small share of it): one or two slow windows
    /// do not move it, and a lasting change (a feed override) takes over
    /// within three. Before that (the first few tenths of a second, and all
    /// of a job shorter than that) the least-squares slope over every
    /// point.
    pub fn drift(&self) -> Option<f64> {
        if self.paces.len() >= 3 {
            let mut p: Vec<f64> = self.paces.iter().copied().collect();
            p.sort_by(f64::total_cmp);
            let m = p[p.len() / 2];
            if (1e-3..1e3).contains(&m) {
                return Some(m);
            }
        }
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
        let latency = 0.5 * self.mean_gap();
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
    fn a_slowdown_does_not_tilt_the_pace() {
        let mut eta = Eta::new(profile());
        // Twice as slow as simulated, a report every 10 ms; from 3.0 to
        // 3.4 s of wall time the board runs at a third of that pace.
        let s_at = |a: f64| match a {
            a if a < 3.0 => a / 2.0,
            a if a < 3.4 => 1.5 + (a - 3.0) / 6.0,
            a => 1.5 + 0.4 / 6.0 + (a - 3.4) / 2.0,
        };
        for i in 0..=400 {
            let a = f64::from(i) * 0.01;
            let s = s_at(a);
            eta.observe(a, line_at(s), &[s as f32, 0.0, 0.0, 0.0]);
        }
        assert!(
            (eta.drift().unwrap() - 2.0).abs() < 1e-3,
            "{:?}",
            eta.drift()
        );
        // At 4.0 s: 2.0 s left of the 5 s simulated is 6.0 s... less what
        // the slow stretch already covered: 2·(5 − s_at(4.0)), plus half
        // a report interval.
        let want = 2.0 * (5.0 - s_at(4.0)) + 0.005;
        let left = eta.remaining(4.0).unwrap();
        assert!((left - want).abs() < 0.01, "{left} vs {want}");
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
