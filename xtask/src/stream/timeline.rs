//! The job's timeline, from a run on the virtual board before streaming
//! (`host_sim::offline`, the board's own code, on the settings read from
//! the real board): where the machine is at each virtual instant, and when
//! each file line starts to move. [`super::eta`] places status reports on
//! it.

use burin::AXES;
use host_sim::config::MachineConfig;
use host_sim::offline::{run_file_watched, Progress};
use host_sim::record::{PinEvent, Recorder};

/// How far a reported position may lie from the simulated path and still
/// be placed on it (mm): steps are at most a few hundredths of a mm, and
/// the board runs the same code, so a farther one is another path (a jog,
/// an override changing corners) and only its line is used.
const ON_PATH_MM: f32 = 0.05;

/// Step points kept for the path: one per this much virtual time at most,
/// so a job keeps a few hundred thousand, and a straight line between two
/// is off the real motion by far less than the 2 % the ETA aims at.
const THIN_S: f64 = 0.001;

/// The simulation's step events, thinned: every [`THIN_S`], plus the last
/// step before each longer pause and the very last one, where the motion
/// ends. The rounds of the simulation alone are up to 10 ms apart near the
/// end, and the step timer runs on to the slot after the last step, up to
/// a step interval (several ms at the end of a deceleration) after the
/// board reports Idle.
struct StepPoints {
    thin: u64,
    kept: Vec<(u64, [i64; AXES])>,
    last: Option<(u64, [i64; AXES])>,
}

impl StepPoints {
    fn new(thin: u64) -> StepPoints {
        StepPoints {
            thin: thin.max(1),
            kept: Vec::new(),
            last: None,
        }
    }

    fn finish(mut self) -> Vec<(u64, [i64; AXES])> {
        if let Some(p) = self.last {
            if self.kept.last() != Some(&p) {
                self.kept.push(p);
            }
        }
        self.kept
    }
}

impl Recorder for StepPoints {
    fn step_event(&mut self, ev: &PinEvent) {
        let kept = self.kept.last().map(|p| p.0);
        if let Some(prev) = self.last {
            if ev.tick.saturating_sub(prev.0) > self.thin && kept != Some(prev.0) {
                self.kept.push(prev);
            }
        }
        let now = (ev.tick, ev.pos);
        if self
            .kept
            .last()
            .is_none_or(|p| ev.tick.saturating_sub(p.0) >= self.thin)
        {
            self.kept.push(now);
        }
        self.last = Some(now);
    }
}

/// The simulated run.
#[derive(Default)]
pub struct Profile {
    /// Virtual seconds from the first motion at which file line `i + 1`
    /// first ran (NaN: it never moves the machine).
    starts: Vec<f64>,
    /// Where on the timeline each line may be: see [`Profile::span`].
    spans: Vec<(f64, f64)>,
    /// (virtual seconds, machine position in mm) after every round of the
    /// simulation from the first motion to the last.
    path: Vec<(f64, [f32; AXES])>,
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
        let spm = cfg.settings.axes.map(|a| a.steps_per_mm);
        let mut first: Vec<Option<u64>> = vec![None; lines + 1];
        let (mut t0, mut t_run) = (None::<u64>, 0u64);
        let mut rounds: Vec<(u64, [i64; AXES])> = Vec::new();
        let mut watch = |p: Progress| {
            if p.line != 0 {
                let slot = &mut first[(p.line as usize).min(lines)];
                slot.get_or_insert(p.tick);
                t0.get_or_insert(p.tick);
            }
            if p.running {
                t_run = p.tick;
            }
            if t0.is_some() {
                rounds.push((p.tick, p.steps.map(i64::from)));
            }
        };
        let mut steps = StepPoints::new((THIN_S * hz) as u64);
        run_file_watched(&cfg, source, &mut steps, &mut watch);
        let steps = steps.finish();
        let t0 = t0.unwrap_or(0);
        // The board says Idle from the last step on (a trailing dwell ends
        // later, seen to a round).
        let t_end = steps.last().map_or(0, |p| p.0).max(t_run);
        let secs = |t: u64| t.saturating_sub(t0) as f64 / hz;
        let starts = first[1..]
            .iter()
            .map(|t| t.map_or(f64::NAN, secs))
            .collect();
        // Both lists are in time order; merged, rounds keep standstills
        // visible (equal neighbours) and steps keep motion exact.
        let mut path: Vec<(u64, [i64; AXES])> = rounds;
        path.extend(steps.into_iter().filter(|p| p.0 >= t0));
        path.sort_by_key(|p| p.0);
        let path = path
            .into_iter()
            .filter(|&(t, _)| t <= t_end)
            .map(|(t, p)| (secs(t), std::array::from_fn(|i| p[i] as f32 / spm[i])))
            .collect();
        Profile::new(starts, path, secs(t_end))
    }

    pub fn new(starts: Vec<f64>, path: Vec<(f64, [f32; AXES])>, total_s: f64) -> Profile {
        let mut spans = vec![(f64::NAN, total_s); starts.len()];
        let mut last = f64::NAN;
        for (span, &s) in spans.iter_mut().zip(&starts) {
            if !s.is_nan() {
                last = s;
            }
            span.0 = last;
        }
        // Backwards: the start of the first seen line after this one, and
        // the end of the span of the first seen line from this one.
        let (mut next, mut end) = (total_s, total_s);
        for (span, &s) in spans.iter_mut().zip(&starts).rev() {
            if !s.is_nan() {
                end = next;
                next = s;
            }
            span.1 = end;
        }
        Profile {
            starts,
            spans,
            path,
            total_s,
        }
    }

    /// When file line `line` starts, in simulated seconds.
    pub fn start(&self, line: usize) -> Option<f64> {
        let s = *self.starts.get(line.checked_sub(1)?)?;
        (!s.is_nan()).then_some(s)
    }

    /// The stretch of the run (simulated seconds) in which file line `line`
    /// moves the machine: from the start of the last line up to it that was
    /// seen running, to the start of the next line seen after the first one
    /// from it that was. Wider than the line on purpose: the planner merges
    /// collinear lines into one block, reported under one of their numbers,
    /// and how many it merges depends on how fast lines arrive, so a board
    /// may report a line this run never reported; a line shorter than one
    /// round of the simulation is never seen either.
    pub fn span(&self, line: usize) -> Option<(f64, f64)> {
        let (lo, hi) = *self.spans.get(line.checked_sub(1)?)?;
        (!lo.is_nan()).then_some((lo, hi))
    }

    /// The simulated instant, not before `after`, at which the machine,
    /// running file line `line`, was at `mpos`: the first point of the path
    /// near enough to it within the line's [span](Profile::span). The first,
    /// because one line may pass a point twice (a canned cycle's plunge and
    /// retract); time only runs forward, so the earliest pass that fits is
    /// the one, at its nearest. None while the machine stands still (a
    /// dwell, a spindle wait: every instant of it fits).
    pub fn locate(&self, line: usize, mpos: &[f32], after: f64) -> Option<f64> {
        let (lo, hi) = self.span(line)?;
        let lo = lo.max(after);
        let i0 = self.path.partition_point(|p| p.0 < lo).saturating_sub(1);
        let i1 = (self.path.partition_point(|p| p.0 <= hi) + 1).min(self.path.len());
        let path = self.path.get(i0..i1)?;
        let still = |k: usize| {
            path.get(k)
                .zip(path.get(k + 1))
                .is_some_and(|(a, b)| a.1 == b.1)
        };
        // The axes the report gives (`$208` may name fewer than the build
        // drives): the others cannot place it.
        let n = AXES.min(mpos.len());
        // (offset, instant, whether the machine stood still there)
        let mut best: Option<(f32, f64, bool)> = None;
        for k in 0..path.len().saturating_sub(1) {
            let ((ta, a), (tb, b)) = (path[k], path[k + 1]);
            let d: [f32; AXES] = std::array::from_fn(|i| b[i] - a[i]);
            let len2: f32 = d[..n].iter().map(|x| x * x).sum();
            if len2 == 0.0 {
                continue;
            }
            let along: f32 = (0..n).map(|i| (mpos[i] - a[i]) * d[i]).sum();
            let u = (along / len2).clamp(0.0, 1.0);
            let off: f32 = (0..n)
                .map(|i| (a[i] + u * d[i] - mpos[i]).powi(2))
                .sum::<f32>()
                .sqrt();
            let s = ta + f64::from(u) * (tb - ta);
            let fits = off <= ON_PATH_MM && s >= after;
            // An end of a move next to a standstill: any instant of the
            // standstill fits as well.
            let stood = (u == 0.0 && k > 0 && still(k - 1)) || (u == 1.0 && still(k + 1));
            match best {
                // Still closing in on the point.
                Some((o, ..)) if fits && off < o => best = Some((off, s, stood)),
                // Moving away again: the nearest pass is found.
                Some(_) => break,
                None if fits => best = Some((off, s, stood)),
                None => {}
            }
        }
        best.and_then(|(_, s, stood)| (!stood).then_some(s))
    }
}

#[cfg(test)]
pub mod tests {
    use super::*;

    /// A run of `total_s` seconds sampled every 0.1 s, the machine at
    /// `at(t)`.
    fn sampled(starts: Vec<f64>, total_s: f64, at: impl Fn(f32) -> [f32; AXES]) -> Profile {
        let rounds = (total_s * 10.0).round() as i32;
        let path = (0..=rounds)
            .map(|i| {
                let t = f64::from(i) * 0.1;
                (t, at(t as f32))
            })
            .collect();
        Profile::new(starts, path, total_s)
    }

    /// Five lines moving X from 0 to 5 mm at 1 mm/s; line 4 is a dwell.
    pub fn profile() -> Profile {
        sampled(vec![0.0, 1.0, 2.0, f64::NAN, 3.0, 4.0], 5.0, |t| {
            burin::pad([t, 0.0, 0.0, 0.0])
        })
    }

    #[test]
    fn step_points_thin_but_keep_pauses_and_the_end() {
        let mut sp = StepPoints::new(100);
        let ev = |tick: u64, x: i64| PinEvent {
            tick,
            dir_mask: 0,
            step_mask: 1,
            dir_changed_tick: 0,
            pos: burin::pad([x, 0, 0, 0]),
        };
        // Steps every 30 ticks up to 300, a pause, then two more.
        for k in 0..=10 {
            sp.step_event(&ev(30 * k, k as i64));
        }
        sp.step_event(&ev(1000, 11));
        sp.step_event(&ev(1030, 12));
        let kept: Vec<u64> = sp.finish().iter().map(|p| p.0).collect();
        // One per 100 ticks; 300 (the step before the pause); 1000 (after
        // it); 1030 (the last).
        assert_eq!(kept, [0, 120, 240, 300, 1000, 1030]);
    }

    #[test]
    fn a_simulated_job_ends_at_its_last_step() {
        let p = Profile::simulate("G1 X10 F600\nG1 X0\n", &[]);
        let (end_s, end) = *p.path.last().unwrap();
        assert_eq!(end_s, p.total_s);
        assert_eq!(end[0], 0.0);
        // The end is where the final position is first reached: the step
        // timer's run to the slot after the last step (the board already
        // says Idle) is not part of the job.
        let moving = p.path.iter().rposition(|q| q.1 != end).unwrap();
        assert_eq!(p.path[moving + 1].0, p.total_s);
        assert!(p.total_s > 2.0, "{}", p.total_s);
    }

    /// A report of X Y Z only (`$208=3`) on a path that also turns A: placed
    /// on the axes it names (it indexed past the report before).
    #[test]
    fn a_report_naming_fewer_axes_is_placed_on_those() {
        let p = profile();
        let s = p.locate(3, &[2.25, 0.0, 0.0], 0.0).unwrap();
        assert!((s - 2.25).abs() < 1e-6, "{s}");
        assert_eq!(p.locate(3, &[2.25, 1.0, 0.0], 0.0), None);
    }

    #[test]
    fn a_position_is_placed_within_its_line() {
        let p = profile();
        let s = p.locate(3, &[2.25, 0.0, 0.0, 0.0], 0.0).unwrap();
        assert!((s - 2.25).abs() < 1e-6, "{s}");
        // The same point, reported for a line that ran elsewhere.
        assert_eq!(p.locate(6, &[2.25, 0.0, 0.0, 0.0], 0.0), None);
        // Off the path.
        assert_eq!(p.locate(3, &[2.25, 1.0, 0.0, 0.0], 0.0), None);
        // Already past it.
        assert_eq!(p.locate(3, &[2.25, 0.0, 0.0, 0.0], 2.5), None);
    }

    #[test]
    fn a_line_never_seen_running_is_looked_for_around_its_neighbours() {
        let p = profile();
        assert_eq!(p.span(3), Some((2.0, 3.0)));
        // Line 4 never ran on its own (merged into line 5's block, say).
        assert_eq!(p.span(4), Some((2.0, 4.0)));
        let s = p.locate(4, &[3.5, 0.0, 0.0, 0.0], 0.0).unwrap();
        assert!((s - 3.5).abs() < 1e-6, "{s}");
    }

    #[test]
    fn a_standstill_is_not_placed() {
        // Line 1 dwells 1 s at X0, then moves X to 1 mm at 1 mm/s.
        let p = sampled(vec![0.0], 2.0, |t| {
            burin::pad([(t - 1.0).max(0.0), 0.0, 0.0, 0.0])
        });
        assert_eq!(p.locate(1, &[0.0; burin::AXES], 0.0), None);
        let s = p.locate(1, &[0.01, 0.0, 0.0, 0.0], 0.0).unwrap();
        assert!((s - 1.01).abs() < 1e-6, "{s}");
    }

    #[test]
    fn a_point_passed_twice_in_one_line_is_placed_in_order() {
        // Line 1 plunges Z to -1 mm and retracts it, 1 mm/s.
        let p = sampled(vec![0.0], 2.0, |t| {
            burin::pad([0.0, 0.0, -(1.0 - (t - 1.0).abs()), 0.0])
        });
        let z = [0.0, 0.0, -0.5, 0.0];
        let down = p.locate(1, &z, 0.0).unwrap();
        assert!((down - 0.5).abs() < 1e-6, "{down}");
        let up = p.locate(1, &z, 1.2).unwrap();
        assert!((up - 1.5).abs() < 1e-6, "{up}");
    }
}
