//! `cargo xtask bench-motion`: run a job, measure the step trace against
//! the axis limits ([`limits`]) and compare its time with the time-optimal
//! bound of the same path ([`bound`]). All in simulated time, so every
//! figure is the same on every machine and every run.

pub mod bound;
pub mod curvature;
pub mod jerk;
pub mod jobs;
pub mod limits;
pub mod losses;
pub mod replay;

use burin::AXES;

use crate::config::MachineConfig;
use crate::record::{PathEvent, PathKind, PinEvent, Recorder, RunInfo, Summary};
use bound::Bound;
use limits::{LimitMeter, TraceLimits};
use losses::{LineLoss, Locator};

/// One job's figures.
#[derive(Clone, Debug)]
pub struct JobFigures {
    /// burin's time, first step to last, s.
    pub time_s: f64,
    /// Time-optimal bound of the same path, s.
    pub bound_s: f64,
    /// The same with burin's curvature rule (a reference, no bound:
    /// [`Bound::with_curvature_rule`]), s.
    pub curved_ref_s: f64,
    pub limits: TraceLimits,
    pub summary: Summary,
    /// The commanded end of the path, rounded to steps.
    pub bound_end_steps: [i64; AXES],
    /// Time lost against the bound per source line, worst first.
    pub losses: Vec<LineLoss>,
    /// The same meter on the bound's own profile ([`replay`]).
    pub bound_limits: TraceLimits,
    /// The curvature check ([`curvature`]) of the run and of the bound's
    /// profile.
    pub curv: curvature::Curvature,
    pub bound_curv: curvature::Curvature,
    /// Source line of each piece of the path (for [`curvature::Curvature::at`]).
    pub piece_lines: Vec<u32>,
    /// In S-curve mode: the jerk-limited lower bound ([`jerk::jerk_bound`]),
    /// s, and the segments' peak path jerk ([`jerk::JerkMeter`]), mm/s³,
    /// over points this far apart, s. `None` in trapezoid mode.
    pub jerk: Option<JerkFigures>,
}

/// [`JobFigures::jerk`].
#[derive(Clone, Copy, Debug)]
pub struct JerkFigures {
    pub bound_s: f64,
    /// [`jerk::jerk_rest_ref`], s.
    pub rest_ref_s: f64,
    pub peak: f64,
    pub window_s: f64,
}

struct Both {
    info: Option<RunInfo>,
    meter: LimitMeter,
    bound: Locator,
    jerk: Option<jerk::JerkMeter>,
}

impl Recorder for Both {
    fn start(&mut self, info: &RunInfo) {
        self.meter.start(info);
        self.bound.start(info);
        self.info = Some(info.clone());
    }
    fn step_event(&mut self, ev: &PinEvent) {
        self.meter.step_event(ev);
        self.bound.step_event(ev);
    }
    fn commanded(&mut self, line: u32, kind: PathKind, to_mm: [f32; AXES]) {
        self.bound.commanded(line, kind, to_mm);
    }
    fn path(&mut self, ev: &PathEvent) {
        self.bound.path(ev);
    }
    fn velocity(&mut self, tick: u64, mm_per_min: f32) {
        if let Some(j) = self.jerk.as_mut() {
            j.velocity(tick, mm_per_min);
        }
    }
    fn finish(&mut self, summary: &Summary) -> std::io::Result<()> {
        self.meter.finish(summary)
    }
}

/// Runs `source` on `cfg` (streamed through the virtual board, as `cargo
/// xtask sim` does) and measures it.
pub fn run_job(cfg: &MachineConfig, source: &str) -> JobFigures {
    let scurve = cfg.settings.profile == burin::settings::Profile::SCurve;
    let jmax = f64::from(cfg.settings.jerk);
    let mut both = Both {
        info: None,
        meter: LimitMeter::new(cfg.settings.max_step_rate_hz),
        bound: Locator::new(
            Bound::new(cfg.settings, cfg.start_position_mm),
            cfg.settings.axes.map(|a| a.steps_per_mm),
        ),
        jerk: scurve.then(|| {
            let a = cfg.settings.axes.iter().map(|a| f64::from(a.max_accel));
            jerk::JerkMeter::new(cfg.tick_hz, a.fold(0.0, f64::max), jmax)
        }),
    };
    let summary = crate::offline::run_file(cfg, source, &mut both);
    let l = both.meter.out;
    let time_s = match l.first_tick {
        Some(t0) => (l.last_tick - t0) as f64 / f64::from(cfg.tick_hz),
        None => 0.0,
    };
    let end = both.bound.bound().end_mm();
    let spm = cfg.settings.axes.map(|a| f64::from(a.steps_per_mm));
    // The bound's profile once, for its time, the losses and the replay.
    let (prof, commanded) = both.bound.bound().profiles();
    let step_mm = spm.map(|s| 1.0 / s);
    let bound_hits: Vec<Option<f64>> = prof.iter().map(|p| Some(p.end_s)).collect();
    // burin's trace is checked against the commanded lengths (`prof` may
    // be the step-rounded path's profile).
    JobFigures {
        curv: curvature::check(&commanded, &both.bound.hit_s(), step_mm),
        bound_curv: curvature::check(&prof, &bound_hits, step_mm),
        piece_lines: both.bound.lines().to_vec(),
        time_s,
        bound_end_steps: std::array::from_fn(|i| (end[i] * spm[i]).round() as i64),
        bound_s: prof.last().map_or(0.0, |p| p.end_s),
        curved_ref_s: both.bound.bound().with_curvature_rule().time_s(),
        jerk: both.jerk.as_ref().map(|m| JerkFigures {
            bound_s: jerk::jerk_bound(&prof, jmax),
            rest_ref_s: jerk::jerk_rest_ref(&prof, jmax),
            peak: m.peak,
            window_s: m.window_s,
        }),
        losses: both.bound.losses(&prof),
        bound_limits: match &both.info {
            Some(info) => replay::bound_limits(
                &prof,
                cfg.start_position_mm.map(f64::from),
                info,
                cfg.settings.max_step_rate_hz,
            ),
            None => TraceLimits::default(),
        },
        limits: l,
        summary,
    }
}

/// The per-axis limits of `cfg` in the units the figures use: rate mm/s,
/// acceleration mm/s².
pub fn axis_limits(cfg: &MachineConfig) -> ([f64; AXES], [f64; AXES]) {
    let a = &cfg.settings.axes;
    (
        std::array::from_fn(|i| f64::from(a[i].max_rate) / 60.0),
        std::array::from_fn(|i| f64::from(a[i].max_accel)),
    )
}
