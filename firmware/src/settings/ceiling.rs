//! The one step-rate ceiling (issue 28). The planner's rate cap
//! ([`crate::planner::interval::floor_ticks`]), the preparer's segment
//! periods and the step driver's spacing of rises all read
//! [`min_period_ticks`], through [`crate::seams::StepConfig::min_period`] or
//! directly, so the planner never plans a step sooner than the driver
//! will make it; `$0` and `$201` values beyond [`ceiling_hz`] are refused
//! (`error:114`).
//!
//! A step after a step needs, rise to rise, the longest of:
//! - the pins: the pulse (`$0`), an allowance for the pulse end's and
//!   the rise's lateness ([`PIN_ALLOWANCE_US`]) and the minimum low time
//!   (`$0`, at least 1 µs: [`crate::seams::StepConfig::min_low_ticks`]);
//! - `$201`'s period;
//! - the CPU: [`STEP_PATH_CYCLES`] of the slower board at most
//!   [`STEP_PATH_SHARE`] of its time ([`CPU_RATE_HZ`]).
use crate::settings::Settings;

/// Cycles one step costs on the F401 at 84 MHz (2 flash wait states) with
/// hard limits on, the whole path: interrupt entry and exit, the TIM5
/// handler, the masked TIM1 pulse-end arming, the switch read. From
/// `cargo xtask bench-target` (`step_path_cycles_1axis_hard_limits_f401`,
/// 305, modelled per executed instruction with every flash line cold),
/// rounded up to the next 10. The slower board's figure holds for both:
/// the library does not know its chip (the F411 at 96 MHz costs 319
/// cycles, 3.3 µs, the F401 3.6 µs). bench-target fails when the step
/// path outgrows it.
pub const STEP_PATH_CYCLES: f32 = 310.0;
/// The slower board's core clock (the F401), Hz.
pub const CPU_HZ: f32 = 84.0e6;
/// The share of the CPU the step interrupt may take at the ceiling: the
/// rest is the preparer's 2 ms segments, the planner, the link and the
/// other interrupts. At 100 % the queue would run dry and motion restart
/// at segment speed without a ramp (issue 28).
pub const STEP_PATH_SHARE: f32 = 0.75;
/// The fastest stepping the CPU sustains, Hz.
pub const CPU_RATE_HZ: f32 = CPU_HZ * STEP_PATH_SHARE / STEP_PATH_CYCLES;
// The default `$201` (200 kHz) must stay valid.
const _: () = assert!(CPU_RATE_HZ >= 200_000.0);
/// What the pins need beyond `$0` and the low time, µs. The driver
/// (`driver::StepDriver`) spaces a step after a step by the pins from the
/// counter read that follows the rising store (so a late interrupt can
/// never shorten the low time) and by the ceiling from the rise's target:
/// at the ceiling it keeps the plan while the pulse end's lateness
/// (`StepPins::pulse_end_latency`: on the boards TIM1's margin and
/// rounding plus the DMA's allowance, 50 step-timer ticks, 0.52 µs at
/// 96 MHz and 0.60 µs at 84 MHz; host-sim's tests model 0.33 µs) plus the interrupt's lateness to that counter read stay
/// within this. 1 µs keeps the default `$0=2`, `$201=200000` valid.
pub const PIN_ALLOWANCE_US: f32 = 1.0;

/// Microseconds in ticks of `tick_hz`, rounded up (0 stays 0).
#[inline]
pub fn ticks(us: f32, tick_hz: u32) -> u32 {
    libm::ceilf(us.max(0.0) * tick_hz as f32 / 1.0e6) as u32
}

/// `$0` in ticks (at least 1).
pub fn pulse_ticks(pulse_us: f32, tick_hz: u32) -> u32 {
    ticks(pulse_us, tick_hz).max(1)
}

/// The minimum low time between two pulses, ticks: `$0`, at least 1 µs.
pub fn min_low_ticks(pulse_us: f32, tick_hz: u32) -> u32 {
    pulse_ticks(pulse_us, tick_hz).max(ticks(1.0, tick_hz).max(1))
}

/// The shortest rise-to-rise time of two steps, ticks: the planner's
/// floor and the driver's spacing alike.
pub fn min_period_ticks(s: &Settings, tick_hz: u32) -> u32 {
    let pins = pulse_ticks(s.step_pulse_us, tick_hz)
        .saturating_add(ticks(PIN_ALLOWANCE_US, tick_hz))
        .saturating_add(min_low_ticks(s.step_pulse_us, tick_hz));
    let hz = crate::num::clamp(s.max_step_rate_hz, 1.0, CPU_RATE_HZ);
    let rate = libm::ceilf(tick_hz as f32 / hz) as u32;
    pins.max(rate).max(1)
}

/// The fastest step rate `$0` allows, Hz (what `$201` may be at most).
pub fn ceiling_hz(pulse_us: f32) -> f32 {
    let pins_us = pulse_us.max(0.0) + PIN_ALLOWANCE_US + pulse_us.max(1.0);
    (1.0e6 / pins_us).min(CPU_RATE_HZ)
}

/// Whether `$0` and `$201` together are within the ceiling.
pub fn settings_fit(s: &Settings) -> bool {
    s.max_step_rate_hz <= ceiling_hz(s.step_pulse_us)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_caps_short_pulses_and_the_pins_long_ones() {
        // 2 µs: the pins allow 1/(2 + 1 + 2 µs) = 200 kHz; the CPU more.
        assert_eq!(ceiling_hz(2.0), CPU_RATE_HZ.min(1.0e6 / 5.0));
        // 5 µs: 1/(5 + 1 + 5 µs) = 90.9 kHz.
        assert!((ceiling_hz(5.0) - 1.0e6 / 11.0).abs() < 1.0);
        // The default settings fit; 450 kHz never does.
        assert!(settings_fit(&Settings::default()));
        let fast = Settings {
            max_step_rate_hz: 450_000.0,
            ..Settings::default()
        };
        assert!(!settings_fit(&fast));
    }

    #[test]
    fn the_tick_period_is_never_shorter_than_the_ceiling() {
        for (pulse, rate) in [
            (2.0, 200_000.0),
            (5.0, 200_000.0),
            (0.5, 1.0e6),
            (10.0, 1.0),
        ] {
            for tick_hz in [1_000_000, 84_000_000, 96_000_000] {
                let s = Settings {
                    step_pulse_us: pulse,
                    max_step_rate_hz: rate,
                    ..Settings::default()
                };
                let p = min_period_ticks(&s, tick_hz);
                let hz = tick_hz as f32 / p as f32;
                assert!(
                    hz <= ceiling_hz(pulse) * 1.0001,
                    "{pulse} µs {rate} Hz {tick_hz}"
                );
                assert!(hz <= rate * 1.0001);
                // The pins: pulse + allowance + low, in ticks.
                let pins = pulse_ticks(pulse, tick_hz)
                    + ticks(PIN_ALLOWANCE_US, tick_hz)
                    + min_low_ticks(pulse, tick_hz);
                assert!(p >= pins);
            }
        }
    }
}
