//! The bound's own profile, run through the same meter as the step trace
//! ([`super::limits`]). The bound is a relaxation: it turns corners at
//! the junction-deviation speed and ramps at full acceleration right up to
//! them and away from them, with no hold. Its figures show what a planner
//! as fast as the bound does to the axes over 50 ms windows, and so what
//! a controller that matches it (GRBL 1.1 plans with the same corner rule
//! and the same full ramps) breaks to be that fast.

use burin::AXES;

use super::bound::PieceProfile;
use super::limits::{LimitMeter, TraceLimits};
use crate::record::{PinEvent, Recorder, RunInfo};

/// Sampling step of the replayed profile, s (the meter's grid is 1 ms).
const STEP_S: f64 = 1e-4;

/// The meter's figures for the bound's profile `prof` (`Bound::profile`),
/// starting at `start_mm`, on the machine described by `info`.
pub fn bound_limits(
    prof: &[PieceProfile],
    start_mm: [f64; AXES],
    info: &RunInfo,
    max_step_rate_hz: f32,
) -> TraceLimits {
    let mut meter = LimitMeter::new(max_step_rate_hz);
    meter.start(info);
    let spm: [f64; AXES] = std::array::from_fn(|i| f64::from(info.axes[i].steps_per_mm));
    let tick_hz = f64::from(info.tick_hz);
    let mut from = start_mm;
    let mut t = 0.0;
    let mut k = 0;
    let mut emit = |t: f64, x: &[f64; AXES]| {
        meter.step_event(&PinEvent {
            tick: (t * tick_hz).round() as u64,
            dir_mask: 0,
            step_mask: (1 << AXES) - 1,
            dir_changed_tick: 0,
            pos: std::array::from_fn(|i| (x[i] * spm[i]).round() as i64),
        });
    };
    while k < prof.len() {
        let p = &prof[k];
        let start = p.end_s - p.time_s();
        if t >= p.end_s {
            from = p.end_mm;
            k += 1;
            continue;
        }
        let d = if t < start { 0.0 } else { p.dist_at(t - start) };
        let x: [f64; AXES] = std::array::from_fn(|i| from[i] + p.unit[i] * d);
        emit(t, &x);
        t += STEP_S;
    }
    emit(t, &from);
    meter.flush();
    meter.out
}

#[cfg(test)]
mod tests {
    use crate::bench::{axis_limits, run_job};
    use crate::config::MachineConfig;

    fn machine() -> MachineConfig {
        let mut cfg = MachineConfig::default();
        cfg.settings.axes[2].max_accel = cfg.settings.axes[0].max_accel / 5.0;
        cfg
    }

    #[test]
    fn a_straight_move_replays_at_the_limit() {
        let cfg = machine();
        let f = run_job(&cfg, "G1 X40 F3000\n");
        let (_, amax) = axis_limits(&cfg);
        let x = f.bound_limits.peak_acc[0] / amax[0];
        assert!((0.97..=1.01).contains(&x), "X at {:.3} of its limit", x);
        assert_eq!(f.bound_limits.end_steps, f.limits.end_steps);
    }

    #[test]
    fn z_valleys_at_junction_speed_with_full_ramps_break_the_window_limit() {
        // The bound turns each corner at the junction speed and ramps at
        // full acceleration on both sides: Z's change adds to its ramps.
        let cfg = machine();
        let mut src = String::from("G21 G90 F3000\n");
        for k in 1..=8 {
            let z = if k % 2 == 1 { -1.0 } else { 0.0 };
            src += &format!("G1 X{} Z{z}\n", 4 * k);
        }
        let f = run_job(&cfg, &src);
        let (_, amax) = axis_limits(&cfg);
        assert!(
            f.bound_limits.peak_acc[2] > 1.05 * amax[2],
            "bound's Z at {:.1} mm/s²",
            f.bound_limits.peak_acc[2]
        );
        assert!(f.limits.peak_acc[2] <= 1.05 * amax[2]);
    }
}
