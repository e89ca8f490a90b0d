//! The summary's "max feed", measured on the step trace: path speed over
//! bins of [`BIN_S`] from one step event to the first one a bin later, as
//! the steps actually went out (the speed the preparer asked for can be
//! anything on a block of a step or two: 13,753 mm/min once, on axes that
//! together allow 7,071).
//!
//! Each axis' speed in a bin is held to its rate limit before the axes are
//! combined: the step driver never steps an axis faster than its limit, so
//! anything above it is the bin catching one step more than its share.

use burin::AXES;

/// Bin length, s.
pub const BIN_S: f64 = 0.01;

#[derive(Clone, Debug, Default)]
pub struct FeedMeter {
    bin_ticks: u64,
    /// mm per step, and the rate limits in mm/s.
    mm: [f64; AXES],
    vmax: [f64; AXES],
    start: Option<(u64, [i64; AXES])>,
    tick_hz: f64,
    /// Highest path speed so far, mm/min.
    pub max_mm_min: f64,
}

impl FeedMeter {
    pub fn new(tick_hz: u32, steps_per_mm: [f32; AXES], max_rate_mm_min: [f32; AXES]) -> Self {
        FeedMeter {
            bin_ticks: (BIN_S * f64::from(tick_hz)) as u64,
            mm: steps_per_mm.map(|s| 1.0 / f64::from(s)),
            vmax: max_rate_mm_min.map(|r| f64::from(r) / 60.0),
            start: None,
            tick_hz: f64::from(tick_hz),
            max_mm_min: 0.0,
        }
    }

    /// A step event: the axes stand at `pos` after it.
    pub fn step(&mut self, tick: u64, pos: [i64; AXES]) {
        let Some((t0, p0)) = self.start else {
            self.start = Some((tick, pos));
            return;
        };
        if tick < t0 + self.bin_ticks {
            return;
        }
        let dt = (tick - t0) as f64 / self.tick_hz;
        let v2: f64 = (0..AXES)
            .map(|i| {
                let v = ((pos[i] - p0[i]).abs() as f64 * self.mm[i] / dt).min(self.vmax[i]);
                v * v
            })
            .sum();
        self.max_mm_min = self.max_mm_min.max(v2.sqrt() * 60.0);
        self.start = Some((tick, pos));
    }
}
