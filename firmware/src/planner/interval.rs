//! Single step intervals within each axis' rate limit.
//!
//! A block is stepped as one Bresenham run: the dominant axis steps on
//! every event, a minor axis with `s` of the block's `C` events steps
//! `floor(C/s)` or `ceil(C/s)` events apart. At the axis limit's *average*
//! rate the short intervals are therefore faster than the limit, by up to
//! 2:1 on a move whose ratio is just under 2. Smoothing (AMASS) divides
//! each dominant step into `2^a` events, which spaces the minor steps more
//! evenly; the preparer holds the event period at [`floor_ticks`]
//! (`stepper::prep::rate`). So that this floor never has to cut the speed
//! suddenly (a 2:1 diagonal at 8 kHz lost 20 % of its speed in one step,
//! over twice its axis' acceleration, where smoothing switched off), the
//! planner caps each block at [`speed_cap`]: the fastest speed up to which
//! the level the preparer picks keeps every interval legal.

use crate::settings::Settings;
use crate::AXES;

/// Highest smoothing level: the run may step at up to 2^3 events per
/// dominant step (re-exported as `stepper::MAX_AMASS`).
pub const MAX_AMASS: u8 = 3;
/// Smoothing runs at most this event rate (Hz): level `a` is used while
/// `2^a` events per dominant step stay at or below it ([`level`]).
pub const AMASS_FINE_HZ: f32 = 16_000.0;

/// The smoothing level the preparer runs a segment at: the finest whose
/// event rate, `2^a` events per dominant step of `dominant` ticks, stays
/// within [`AMASS_FINE_HZ`]; 0 without minor axes. [`speed_cap`] plans
/// with this same rule.
pub fn level(dominant: f32, tick_hz: u32, minor: bool) -> u8 {
    let mut a = 0u8;
    if minor {
        let fine = tick_hz as f32 / AMASS_FINE_HZ;
        while a < MAX_AMASS && dominant / (2u32 << a) as f32 >= fine {
            a += 1;
        }
    }
    a
}

/// Shortest event period (ticks) at which no axis of a block with these
/// `steps` (dominant `count`) steps faster than its limit, with `2^amass`
/// events per dominant step.
pub fn floor_ticks(s: &Settings, tick_hz: u32, steps: &[u32; AXES], count: u32, amass: u8) -> u32 {
    // The one ceiling (`$201`, the pins, the CPU), as the driver spaces rises.
    let ceiling = crate::settings::ceiling::min_period_ticks(s, tick_hz) as f32;
    let tick_hz = tick_hz as f32;
    let events = (count as u64) << amass;
    let mut floor = 0u32;
    for (i, &n) in steps.iter().enumerate() {
        if n == 0 {
            continue;
        }
        let ax = &s.axes[i];
        let hz = ax.max_rate / 60.0 * ax.steps_per_mm;
        if !(hz.is_finite() && hz > 0.0) {
            continue;
        }
        let limit = libm::ceilf(tick_hz / hz).max(ceiling);
        // A u32 division where the events fit (always, but for blocks
        // of more than 2^29 steps): the u64 one is a library call.
        let k = match u32::try_from(events) {
            Ok(e) => (e / n).max(1) as f32,
            Err(_) => (events / n as u64).max(1) as f32,
        };
        let p = libm::ceilf(limit / k);
        if p.is_finite() && p > floor as f32 {
            floor = p.min(crate::seams::MAX_PERIOD as f32) as u32;
        }
    }
    floor
}

/// Fastest path speed (mm/s) up to which the preparer's smoothing level
/// ([`level`], chosen by rate alone) keeps the event period at or above [`floor_ticks`]
/// all the way from rest, so the floor never has to cut in.
///
/// In dominant-step periods `D` (ticks), [`level`] picks `a` for
/// `fine·2^a <= D < fine·2^(a+1)` (level 0 everything faster, the top level
/// everything slower) and is legal from `L_a = floor_ticks(a)·2^a` up.
/// Walking from slow to fast, the first level whose legal bound falls
/// inside its range caps `D` there; one wholly illegal caps at the slower
/// level's edge (1 % inside it, so rounding cannot tip the level).
pub fn speed_cap(s: &Settings, tick_hz: u32, steps: &[u32; AXES], count: u32, length: f32) -> f32 {
    if count == 0 || tick_hz == 0 {
        return f32::INFINITY;
    }
    let fine = tick_hz as f32 / AMASS_FINE_HZ;
    let minor = steps.iter().any(|&n| n != 0 && n != count);
    let top = if minor { MAX_AMASS } else { 0 };
    let mut cap = 0.0f32;
    for a in (0..=top).rev() {
        let legal = floor_ticks(s, tick_hz, steps, count, a) as f32 * (1u32 << a) as f32;
        let lo = if a == 0 {
            0.0
        } else {
            fine * (1u32 << a) as f32
        };
        let hi = if a == top {
            f32::INFINITY
        } else {
            fine * (2u32 << a) as f32
        };
        if legal >= hi {
            cap = hi * 1.01;
            break;
        }
        if legal > lo {
            cap = legal;
            break;
        }
    }
    if !(cap.is_finite() && cap > 0.0) {
        return f32::INFINITY;
    }
    tick_hz as f32 / cap * length / count as f32
}
