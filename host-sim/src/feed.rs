//! The summary's "max feed" and the plot's speed panel, measured on the
//! step trace: path speed over
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

    /// Motion stopped: the next bin starts at the next step, not across
    /// the standstill.
    pub fn stop(&mut self) {
        self.start = None;
    }

    /// A step event: the axes stand at `pos` after it. Returns the path
    /// speed (mm/min) of the bin this event closes, if it closes one.
    pub fn step(&mut self, tick: u64, pos: [i64; AXES]) -> Option<f64> {
        let Some((t0, p0)) = self.start else {
            self.start = Some((tick, pos));
            return None;
        };
        if tick < t0 + self.bin_ticks {
            return None;
        }
        let dt = (tick - t0) as f64 / self.tick_hz;
        let v2: f64 = (0..AXES)
            .map(|i| {
                let v = ((pos[i] - p0[i]).abs() as f64 * self.mm[i] / dt).min(self.vmax[i]);
                v * v
            })
            .sum();
        let v = v2.sqrt() * 60.0;
        self.max_mm_min = self.max_mm_min.max(v);
        self.start = Some((tick, pos));
        Some(v)
    }
}
