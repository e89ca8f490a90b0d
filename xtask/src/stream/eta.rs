//! Time left, from motion. Before streaming, the job runs on the virtual
//! board (`host_sim::offline`, the board's own code) with the settings read
//! from the real one; that gives the virtual time at which each file line
//! starts to move. While streaming, the line the board reports executing
//! (`Ln:`) says where on that timeline the job is, and the wall time spent
//! against the simulated time so far (the drift: a loaded link, a slower
//! clock, a `--speed`ed virtual board) scales what is left.

use host_sim::config::MachineConfig;
use host_sim::offline::{run_file_watched, Progress};
use host_sim::record::Discard;

/// The simulated run: when each file line starts moving.
pub struct Profile {
    /// Virtual seconds from the first motion at which file line `i + 1`
    /// first ran (NaN: it never moves the machine).
    starts: Vec<f64>,
    /// Virtual seconds from the first motion to the last.
    pub total_s: f64,
}

impl Profile {
    /// Simulate `source` on the default virtual machine with `settings`
    /// (the board's `$n` values) applied.
    pub fn simulate(source: &str, settings: &[(u16, f32)]) -> Profile {
        let mut cfg = MachineConfig::default();
        for &(n, v) in settings {
            // A setting the host model does not know stays at its default.
            let _ = cfg.settings.set(n, v);
        }
        let lines = source.lines().count();
        let hz = f64::from(cfg.tick_hz);
        let mut first: Vec<Option<u64>> = vec![None; lines + 1];
        let (mut t0, mut t_end) = (None::<u64>, 0u64);
        let mut watch = |p: Progress| {
            if p.line != 0 {
                let slot = &mut first[(p.line as usize).min(lines)];
                slot.get_or_insert(p.tick);
                t0.get_or_insert(p.tick);
            }
            if p.stepping {
                t_end = p.tick;
            }
        };
        run_file_watched(&cfg, source, &mut Discard, &mut watch);
        let t0 = t0.unwrap_or(0);
        let starts = first[1..]
            .iter()
            .map(|t| t.map_or(f64::NAN, |t| t.saturating_sub(t0) as f64 / hz))
            .collect();
        Profile {
            starts,
            total_s: t_end.saturating_sub(t0) as f64 / hz,
        }
    }

    /// When file line `line` starts, in simulated seconds.
    fn start(&self, line: usize) -> Option<f64> {
        let s = *self.starts.get(line.checked_sub(1)?)?;
        (!s.is_nan()).then_some(s)
    }
}

/// Anchors kept for the offset (the slope uses all of them).
const RECENT: usize = 8;

/// The running estimate.
pub struct Eta {
    profile: Profile,
    /// The end is seen at the first status report after it: half a
    /// report interval on average.
    latency_s: f64,
    /// (active wall seconds, simulated seconds) where a line was first seen.
    anchors: Vec<(f64, f64)>,
    last_line: usize,
    /// Active time of the previous status report.
    last_seen: f64,
    // Running sums for the least-squares slope.
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
}

impl Eta {
    pub fn new(profile: Profile, latency_s: f64) -> Eta {
        Eta {
            profile,
            latency_s,
            anchors: Vec::new(),
            last_line: 0,
            last_seen: 0.0,
            n: 0.0,
            sx: 0.0,
            sy: 0.0,
            sxx: 0.0,
            sxy: 0.0,
        }
    }

    pub fn simulated_s(&self) -> f64 {
        self.profile.total_s
    }

    /// A status report at `active` seconds (wall time the machine was not
    /// paused) said file line `line` runs (0: none yet).
    pub fn observe(&mut self, active: f64, line: usize) {
        if line != 0 && line != self.last_line {
            if let Some(s) = self.profile.start(line) {
                // The line started between the previous report and this one.
                let a = if self.anchors.is_empty() {
                    active
                } else {
                    0.5 * (self.last_seen + active)
                };
                self.anchors.push((a, s));
                self.n += 1.0;
                self.sx += s;
                self.sy += a;
                self.sxx += s * s;
                self.sxy += s * a;
            }
            self.last_line = line;
        }
        self.last_seen = active;
    }

    /// Wall seconds per simulated second, from the lines seen so far
    /// (1 until the job has moved for a while).
    pub fn drift(&self) -> f64 {
        let d = self.n * self.sxx - self.sx * self.sx;
        if self.n < 2.0 || d <= 0.0 {
            return 1.0;
        }
        let r = (self.n * self.sxy - self.sx * self.sy) / d;
        if r.is_finite() && (1e-3..1e3).contains(&r) {
            r
        } else {
            1.0
        }
    }

    /// Seconds left at `active` (None before the first motion).
    pub fn remaining(&self, active: f64) -> Option<f64> {
        self.anchors.last()?;
        let r = self.drift();
        let recent = &self.anchors[self.anchors.len().saturating_sub(RECENT)..];
        let c = recent.iter().map(|(a, s)| a - r * s).sum::<f64>() / recent.len() as f64;
        let end = c + r * self.profile.total_s;
        // Never claim more progress than the next line's start allows.
        let floor = self
            .next_start(self.last_line)
            .map_or(0.0, |n| r * (self.profile.total_s - n));
        Some((end - active).max(floor).max(0.0) + self.latency_s)
    }

    fn next_start(&self, line: usize) -> Option<f64> {
        (line + 1..=self.profile.starts.len()).find_map(|l| self.profile.start(l))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remaining_follows_the_timeline_at_a_steady_drift() {
        let profile = Profile {
            starts: vec![0.0, 1.0, 2.0, f64::NAN, 3.0, 4.0],
            total_s: 5.0,
        };
        let mut eta = Eta::new(profile, 0.0);
        assert_eq!(eta.remaining(0.0), None);
        // Twice as slow as simulated, a status report every 0.1 s.
        let line_at = |s: f64| match s {
            s if s < 1.0 => 1,
            s if s < 2.0 => 2,
            s if s < 3.0 => 3,
            s if s < 4.0 => 5,
            _ => 6,
        };
        for i in 0..=60 {
            let a = f64::from(i) * 0.1;
            eta.observe(a, line_at(a / 2.0));
        }
        assert!((eta.drift() - 2.0).abs() < 0.1, "{}", eta.drift());
        let left = eta.remaining(6.0).unwrap();
        assert!((left - 4.0).abs() < 0.2, "{left}");
    }
}
