//! Shared by the motion tests: a recorder that keeps everything, a machine
//! config built from firmware defaults, and the trace property checks.
#![allow(dead_code)]

use burin::command::Command;
use burin::settings::Settings;
use burin::AXES;
use host_sim::config::{LimitSwitch, MachineConfig, ProbeSurface};
use host_sim::engine::{Input, Sim};
use host_sim::record::{PathKind, PinEvent, Recorder, RunInfo, Summary};

pub const TICK_HZ: u32 = 96_000_000;

/// `machines/grbl_match.toml`: the machine issue 12's bench compares
/// burin and GRBL on.
pub fn grbl_match() -> MachineConfig {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/grbl_match.toml");
    MachineConfig::load(p).unwrap()
}

/// `../shared/bench-motion`'s jobs as (path, text), in name order; none,
/// with a "skipped" line, when it is not there.
pub fn bench_jobs() -> Vec<(String, String)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/bench-motion");
    let Ok(rd) = std::fs::read_dir(&dir) else {
        println!("{}: not found, skipped", dir.display());
        return Vec::new();
    };
    let mut jobs: Vec<(String, String)> = rd
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let ext = p.extension().and_then(|x| x.to_str()).unwrap_or("");
            matches!(ext, "ngc" | "nc" | "gcode")
        })
        .map(|p| {
            (
                p.display().to_string(),
                std::fs::read_to_string(&p).unwrap(),
            )
        })
        .collect();
    jobs.sort();
    assert!(!jobs.is_empty(), "{}: no jobs", dir.display());
    jobs
}

pub fn config() -> MachineConfig {
    MachineConfig {
        tick_hz: TICK_HZ,
        settings: Settings::default(),
        limits: [None; AXES],
        probe: None,
        start_position_mm: [0.0; AXES],
        host: host_sim::config::HostModel::default(),
        interrupts: host_sim::config::Interrupts::default(),
        wiring: None,
        slack_mm: Default::default(),
    }
}

/// A machine with switches at 0 (homing towards positive) and a probe plate
/// at Z = -20 mm.
pub fn config_with_switches() -> MachineConfig {
    let sw = Some(LimitSwitch {
        trip_mm: 0.0,
        hysteresis_mm: 0.05,
    });
    let mut c = config();
    c.limits = burin::pad([sw, sw, sw, None]);
    c.probe = Some(ProbeSurface {
        axis: 2,
        trip_mm: -20.0,
        towards_negative: true,
    });
    c.settings.homing_enable = true;
    c
}

#[derive(Default)]
pub struct Collect {
    pub info: Option<RunInfo>,
    pub events: Vec<PinEvent>,
    pub path: Vec<(u32, PathKind, [f32; AXES])>,
    pub velocity: Vec<(u64, f32)>,
    pub summary: Option<Summary>,
}

impl Recorder for Collect {
    fn start(&mut self, info: &RunInfo) {
        self.info = Some(info.clone());
    }
    fn step_event(&mut self, ev: &PinEvent) {
        self.events.push(*ev);
    }
    fn commanded(&mut self, line: u32, kind: PathKind, to: [f32; AXES]) {
        self.path.push((line, kind, to));
    }
    fn velocity(&mut self, tick: u64, v: f32) {
        self.velocity.push((tick, v));
    }
    fn finish(&mut self, s: &Summary) -> std::io::Result<()> {
        self.summary = Some(s.clone());
        Ok(())
    }
}

/// FNV-1a over the event stream: equal hashes mean equal traces.
pub fn trace_hash(events: &[PinEvent]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |v: u64| {
        for b in v.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x100_0000_01b3);
        }
    };
    for e in events {
        eat(e.tick);
        eat(u64::from(e.dir_mask) << 8 | u64::from(e.step_mask));
        eat(e.dir_changed_tick);
        for p in e.pos {
            eat(p as u64);
        }
    }
    h
}

/// Step times (ticks) and directions per axis.
fn axis_steps(events: &[PinEvent], axis: usize) -> Vec<(u64, i8)> {
    events
        .iter()
        .filter(|e| e.step_mask & (1 << axis) != 0)
        .map(|e| (e.tick, if e.dir_mask & (1 << axis) != 0 { -1 } else { 1 }))
        .collect()
}

/// Window (in steps) over which rates are measured. Bresenham (and AMASS)
/// place a slower axis's steps on the event grid, so any single step may come
/// up to one event period early or late; over W steps that error is at most
/// two events, i.e. a measured rate up to W/(W-2) of the true one.
pub const RATE_WINDOW: usize = 16;

/// No axis above its max rate. Returns the highest measured ratio rate/max.
pub fn check_max_rate(info: &RunInfo, events: &[PinEvent]) -> f64 {
    let tol = RATE_WINDOW as f64 / (RATE_WINDOW - 2) as f64 * 1.005;
    let mut worst = 0.0f64;
    for (i, ax) in info.axes.iter().enumerate() {
        let st = axis_steps(events, i);
        let max_sps = ax.max_rate_mm_min as f64 / 60.0 * ax.steps_per_mm as f64;
        for w in st.windows(RATE_WINDOW + 1) {
            let dt = (w[RATE_WINDOW].0 - w[0].0) as f64 / info.tick_hz as f64;
            let rate = RATE_WINDOW as f64 / dt;
            let ratio = rate / max_sps;
            worst = worst.max(ratio);
            assert!(
                ratio <= tol,
                "axis {i} at {:.1} steps/s, max {max_sps:.1} (tick {})",
                rate,
                w[0].0
            );
        }
    }
    worst
}

/// Time bins for the acceleration check, seconds.
pub const ACCEL_BIN_S: f64 = 0.025;

/// No axis above its max acceleration, measured from step timestamps.
///
/// Velocity per axis is the step rate inside fixed 25 ms bins (first to last
/// step of the bin, so partial steps do not count); acceleration is the
/// change between adjacent bins over the distance of their centres. The
/// stated tolerance comes from quantisation only: the preparer holds each
/// 2 ms segment at its average speed, a staircase that can add `a·2ms` of
/// speed difference between bins (factor `1 + 2ms/25ms`), and each bin's
/// rate can be off by two event periods of jitter (≤ 125 µs at the AMASS
/// floor), `4·v·p/Δ²`.
///
/// Corners: junction-deviation cornering (like GRBL's) turns at a finite
/// speed, so an axis's velocity steps at the corner by up to
/// `sqrt(8·a·δ)` (the maximum over all corner angles of `v_j·|Δu|` with
/// `v_j² = a·δ·c/(1−c)`). Bin pairs around a sharp corner (`corners`, from
/// [`check_path`]) may exceed the limit by that step spread over one bin.
/// Returns the worst ratio measured/limit.
pub fn check_max_accel(info: &RunInfo, events: &[PinEvent], corners: &[u64], jd_mm: f64) -> f64 {
    check_max_accel_within(info, events, corners, jd_mm, 1.0)
}

/// [`check_max_accel`] with its tolerance widened by `slack` (1.0: none),
/// for a job with a violation already known and tracked elsewhere.
pub fn check_max_accel_within(
    info: &RunInfo,
    events: &[PinEvent],
    corners: &[u64],
    jd_mm: f64,
    slack: f64,
) -> f64 {
    let mut worst = 0.0f64;
    let hz = info.tick_hz as f64;
    for (i, ax) in info.axes.iter().enumerate() {
        let st = axis_steps(events, i);
        if st.len() < 4 {
            continue;
        }
        let spm = ax.steps_per_mm as f64;
        let bin = (ACCEL_BIN_S * hz) as u64;
        // (centre time s, velocity mm/s)
        let mut pts: Vec<(f64, f64, bool)> = Vec::new();
        let mut k = 0;
        while k < st.len() {
            let b = st[k].0 / bin;
            let mut j = k;
            while j + 1 < st.len() && st[j + 1].0 / bin == b && st[j + 1].1 == st[k].1 {
                j += 1;
            }
            // A bin is only trusted when it is full of motion on both sides.
            if j > k + 2 {
                let dt = (st[j].0 - st[k].0) as f64 / hz;
                let v = (j - k) as f64 / dt / spm * st[k].1 as f64;
                let centre = (st[j].0 + st[k].0) as f64 / 2.0 / hz;
                let full = dt > ACCEL_BIN_S * 0.8;
                pts.push((centre, v, full));
            }
            k = j + 1;
        }
        let a_max = ax.max_accel_mm_s2 as f64;
        for w in pts.windows(2) {
            let ((t0, v0, f0), (t1, v1, f1)) = (w[0], w[1]);
            if !(f0 && f1) || t1 - t0 > 1.5 * ACCEL_BIN_S {
                continue;
            }
            let a = (v1 - v0).abs() / (t1 - t0);
            let v = v0.abs().max(v1.abs());
            let mut tol = a_max * (1.0 + 0.002 / ACCEL_BIN_S)
                + 4.0 * v * 125e-6 / (ACCEL_BIN_S * ACCEL_BIN_S);
            // `check_path` registers a corner when the stepped path leaves
            // the previous piece's one-step tolerance, which on a steep
            // turn (an arc's end into a near-reversal of Z) comes a few ms
            // after the vertex: look one more bin ahead for it.
            let (lo, hi) = (
                ((t0 - ACCEL_BIN_S) * hz) as u64,
                ((t1 + 2.0 * ACCEL_BIN_S) * hz) as u64,
            );
            let i0 = corners.partition_point(|&c| c < lo);
            if corners.get(i0).is_some_and(|&c| c <= hi) {
                tol += (8.0 * a_max * jd_mm).sqrt() / ACCEL_BIN_S;
            }
            worst = worst.max(a / a_max);
            assert!(
                a <= tol * slack,
                "axis {i} accel {a:.1} mm/s² > {tol:.1} at t={t0:.4}s (v {v0:.2} -> {v1:.2}); nearest corners {:?}",
                corners.get(i0.saturating_sub(1)..(i0 + 1).min(corners.len())).map(|c| c.iter().map(|&c| c as f64 / hz - t0).collect::<Vec<_>>())
            );
        }
    }
    worst
}

/// Step pulses never overlap and direction changes respect setup time.
pub fn check_pin_timing(info: &RunInfo, events: &[PinEvent]) {
    let mut last_step = [None::<u64>; AXES];
    let mut last_dir = [0u8; AXES];
    for e in events {
        for i in 0..AXES {
            if e.step_mask & (1 << i) == 0 {
                continue;
            }
            let d = e.dir_mask >> i & 1;
            if let Some(t) = last_step[i] {
                assert!(
                    e.tick - t > u64::from(info.pulse_ticks),
                    "axis {i}: pulses {t} and {} overlap",
                    e.tick
                );
                if d != last_dir[i] {
                    assert!(
                        e.dir_changed_tick > t,
                        "axis {i}: direction flipped without a recorded change"
                    );
                    assert!(
                        e.dir_changed_tick >= t + u64::from(info.pulse_ticks),
                        "dir changed during a pulse at {}",
                        e.tick
                    );
                }
            }
            // This axis's direction pin changed before this step (pins start
            // out positive): the step must wait the setup time.
            let changed = match last_step[i] {
                None => d == 1,
                Some(_) => d != last_dir[i],
            };
            if changed {
                let setup = e.tick.saturating_sub(e.dir_changed_tick);
                assert!(
                    setup >= u64::from(info.dir_setup_ticks),
                    "axis {i}: direction set {setup} ticks before the step at {}",
                    e.tick
                );
            }
            last_step[i] = Some(e.tick);
            last_dir[i] = d;
        }
    }
}

/// Every stepped position lies within one step per axis (plus `extra_mm`)
/// of the commanded polyline. Returns the worst distance in mm.
/// Also returns the ticks at which the stepped path passes a corner of the
/// commanded path (any vertex that is not inside one arc or spline).
pub fn check_path(
    info: &RunInfo,
    start: [f32; AXES],
    path: &[(u32, PathKind, [f32; AXES])],
    events: &[PinEvent],
    extra_mm: f64,
) -> (f64, Vec<u64>) {
    let spm: Vec<f64> = info.axes.iter().map(|a| a.steps_per_mm as f64).collect();
    // One step on every axis that moves in this trace or on the commanded
    // path (an axis commanded less than half a step never steps: a line
    // of 67.86 mm in X that rises 0.0039 mm in Y, on 80 steps/mm, ends
    // 0.0039 mm off its stepped path).
    let commanded = path.iter().fold(0u8, |m, p| {
        (0..AXES).fold(m, |m, i| if p.2[i] != start[i] { m | 1 << i } else { m })
    });
    let moved = events.iter().fold(commanded, |m, e| m | e.step_mask);
    let step_diag: f64 = spm
        .iter()
        .enumerate()
        .filter(|(i, _)| moved & (1 << i) != 0)
        .map(|(_, s)| 1.0 / (s * s))
        .sum::<f64>()
        .sqrt();
    let mut verts: Vec<[f64; AXES]> = vec![start.map(|v| v as f64)];
    verts.extend(path.iter().map(|p| p.2.map(|v| v as f64)));
    let mut seg = 0usize;
    let mut worst = 0.0f64;
    let mut corners = Vec::new();
    // Vertex k joins pieces k-1 and k. Every vertex is a junction-deviation
    // corner except those inside one arc or spline (its chords).
    let sharp = |k: usize| -> bool {
        if k == 0 || k >= path.len() {
            return false;
        }
        let (a, b) = (&path[k - 1], &path[k]);
        let curve = |m: PathKind| matches!(m, PathKind::Arc | PathKind::Spline);
        !(curve(a.1) && curve(b.1) && a.0 == b.0)
    };
    let dist = |p: &[f64; AXES], a: &[f64; AXES], b: &[f64; AXES]| {
        let mut ab = [0.0; AXES];
        let mut ap = [0.0; AXES];
        for i in 0..AXES {
            ab[i] = b[i] - a[i];
            ap[i] = p[i] - a[i];
        }
        let l2: f64 = ab.iter().map(|v| v * v).sum();
        let t = if l2 > 0.0 {
            (ap.iter().zip(&ab).map(|(x, y)| x * y).sum::<f64>() / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (0..AXES)
            .map(|i| (ap[i] - t * ab[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    for e in events {
        let p: [f64; AXES] = std::array::from_fn(|i| e.pos[i] as f64 / spm[i]);
        let mut best = f64::INFINITY;
        let mut best_seg = seg;
        let end = (seg + 64).min(verts.len().saturating_sub(1));
        // Paths may cross or retrace themselves: take the earliest piece
        // (from the current one on) that is within tolerance.
        for s in seg..end {
            let d = dist(&p, &verts[s], &verts[s + 1]);
            if d < best - 1e-12 {
                best = d;
                best_seg = s;
            }
            if d <= step_diag + extra_mm {
                break;
            }
        }
        for s in best_seg..end {
            best = best.min(dist(&p, &verts[s], &verts[s + 1]));
        }
        if best.is_finite() {
            for k in seg + 1..=best_seg {
                if sharp(k) {
                    corners.push(e.tick);
                }
            }
            seg = best_seg;
            worst = worst.max(best);
            assert!(
                best <= step_diag + extra_mm + 1e-6,
                "stepped point {p:?} is {best:.5} mm off the path (tick {})",
                e.tick
            );
        }
    }
    (worst, corners)
}

/// Final position in steps equals the commanded end rounded to steps.
pub fn expected_steps(info: &RunInfo, mm: [f32; AXES]) -> [i64; AXES] {
    std::array::from_fn(|i| (mm[i] * info.axes[i].steps_per_mm).round() as i64)
}

/// The last stop of `axis` in the trace decelerates within its limit.
///
/// A body that ends at rest after decelerating at most at `a` covers at
/// most `a·t²/2` in the last `t` before it stops. For every step `k` of the
/// final `window` steps this compares the distance from `k` to the last
/// step with that bound. Quantisation: the continuous ramp ends somewhere
/// inside the step after the last one, which it may take up to
/// `t_q = sqrt(2·step/a)` to reach, so `t` counts from `t_q` after the last
/// step; the preparer's 2 ms staircase adds the factor `1 + 2ms/25ms` (as in
/// [`check_max_accel`]) and position quantisation 2 steps. An instant stop
/// from `v` fails as soon as `v·t > a·(t+t_q)²/2·1.08 + 2 steps`.
/// Returns the worst ratio distance/bound.
pub fn check_stop_decel(info: &RunInfo, events: &[PinEvent], axis: usize, window: usize) -> f64 {
    let st = axis_steps(events, axis);
    let Some(&(t_end, _)) = st.last() else {
        return 0.0;
    };
    let ax = &info.axes[axis];
    let spm = ax.steps_per_mm as f64;
    let a = ax.max_accel_mm_s2 as f64;
    let hz = info.tick_hz as f64;
    let tq = (2.0 / spm / a).sqrt();
    let mut worst = 0.0f64;
    for (n, (t, _)) in st.iter().rev().enumerate().take(window).skip(1) {
        let dt = (t_end - t) as f64 / hz + tq;
        let d = n as f64 / spm;
        let bound = a * dt * dt / 2.0 * (1.0 + 0.002 / ACCEL_BIN_S) + 2.0 / spm;
        worst = worst.max(d / bound);
        assert!(
            d <= bound,
            "axis {axis}: {d:.4} mm in the last {dt:.5} s before the stop, at most {bound:.4} mm decelerating at {a} mm/s²"
        );
    }
    worst
}

/// A job of Commands with realtime inputs at given seconds.
pub struct Run {
    pub rec: Collect,
    pub summary: host_sim::record::Summary,
}

pub fn run(cfg: &MachineConfig, cmds: &[Command], inputs: &[(f64, Input)]) -> Run {
    let mut rec = Collect::default();
    let mut sim = Sim::new(cfg, &mut rec);
    for (i, c) in cmds.iter().enumerate() {
        sim.push_command(i as u32 + 1, c.clone());
    }
    for (t, inp) in inputs {
        sim.input_at((t * cfg.tick_hz as f64) as u64, *inp);
    }
    sim.run();
    let summary = sim.summary(cmds.len() as u32, [0.0; burin::AXES]);
    drop(sim);
    Run { rec, summary }
}

pub fn last_end(cmds: &[Command]) -> [f32; burin::AXES] {
    cmds.iter()
        .rev()
        .find_map(|c| c.end().copied())
        .unwrap_or([0.0; burin::AXES])
}

pub fn check_all(cfg: &MachineConfig, r: &Run, cmds: &[Command], label: &str) {
    let info = r.rec.info.as_ref().unwrap();
    assert!(
        r.summary.errors.is_empty(),
        "{label}: {:?}",
        r.summary.errors
    );
    assert_eq!(
        r.summary.final_position_steps,
        expected_steps(info, last_end(cmds)),
        "{label}"
    );
    let rate = check_max_rate(info, &r.rec.events);
    let (dev, corners) = check_path(info, cfg.start_position_mm, &r.rec.path, &r.rec.events, 0.0);
    let acc = check_max_accel(
        info,
        &r.rec.events,
        &corners,
        cfg.settings.junction_deviation as f64,
    );
    check_pin_timing(info, &r.rec.events);
    println!(
        "{label}: {} step events, {:.3} s, worst rate {:.3}, worst accel {:.3}, worst path dev {:.4} mm, underruns {}",
        r.rec.events.len(),
        r.summary.job_time_s,
        rate,
        acc,
        dev,
        r.summary.planner_underruns
    );
    assert_eq!(r.summary.planner_underruns, 0, "{label}");
}

/// Jerk of the X axis from its step times: velocity from the first to the
/// last step inside 25 ms bins, acceleration and jerk as differences of
/// neighbouring bins. Quantisation noise is a few hundred mm/s³ here.
pub fn max_jerk_x(r: &Run, hz: f64) -> f64 {
    let t: Vec<f64> = r
        .rec
        .events
        .iter()
        .filter(|e| e.step_mask & 1 != 0)
        .map(|e| e.tick as f64 / hz)
        .collect();
    let bin = 0.025;
    let mut v: Vec<(f64, f64)> = Vec::new();
    let mut k = 0;
    while k < t.len() {
        let b = (t[k] / bin) as u64;
        let mut j = k;
        while j + 1 < t.len() && (t[j + 1] / bin) as u64 == b {
            j += 1;
        }
        if j > k + 2 && t[j] - t[k] > 0.8 * bin {
            v.push(((t[j] + t[k]) / 2.0, (j - k) as f64 / (t[j] - t[k]) / 80.0));
        }
        k = j + 1;
    }
    let a: Vec<(f64, f64)> = v
        .windows(2)
        .map(|w| {
            (
                (w[0].0 + w[1].0) / 2.0,
                (w[1].1 - w[0].1) / (w[1].0 - w[0].0),
            )
        })
        .collect();
    a.windows(2)
        .map(|w| ((w[1].1 - w[0].1) / (w[1].0 - w[0].0)).abs())
        .fold(0.0, f64::max)
}
