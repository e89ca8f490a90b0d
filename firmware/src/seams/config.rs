//! The step interrupt's configuration and how a `$n=` reaches it.
//!
//! [`StepConfig`] is what the settings mean to the pins: pulse width,
//! direction setup, enable delay and rate ceiling in timer ticks, and the
//! invert masks. The parse task builds a new one on every `$n=` and
//! publishes it in a [`StepConfigCell`] (inside [`Realtime`]); the step
//! driver takes it only while it is stopped (`stepper::driver`), so no pulse
//! and no timing in flight ever mixes two configurations.
//!
//! Why a sequence lock of atomics and not a mutex: the step interrupt
//! (priority 3) must never wait on the parse task (priority 1). If the
//! interrupt lands while the task is half way through a publish, it sees
//! the odd sequence number, keeps its old configuration and returns; the
//! task kicks the interrupt again once the publish is complete.
//!
//! [`Realtime`]: crate::realtime::Realtime

use core::sync::atomic::{fence, AtomicU32, Ordering};

use crate::settings::ceiling;
use crate::settings::Settings;

/// A target this close (or past) is not left to the compare: the step
/// driver waits for it in a short loop. Covers the compare write's latency
/// (a few timer clocks) so a just-missed match cannot cost a 2^32 wrap.
/// At a 96 MHz count; [`StepConfig::spin_ticks`] scales it to the timer.
pub const SPIN_TICKS: u32 = 8;

/// Pin timing in timer ticks and the invert masks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepConfig {
    pub tick_hz: u32,
    pub pulse_ticks: u32,
    pub dir_setup_ticks: u32,
    /// Shortest time between two step events: the one step-rate ceiling
    /// ([`ceiling::min_period_ticks`]: `$201`, the pins and the
    /// CPU), which the preparer plans with and the driver spaces rises by.
    pub min_period: u32,
    /// Shortest low time between two pulses the step driver guarantees,
    /// however late its interrupt runs: the pulse width (`$0`), and at
    /// least 1 µs (drivers specify low minimums alike; a few need more,
    /// and then `$0` should be raised).
    pub min_low_ticks: u32,
    /// `$207`: from driver enable to the first step edge.
    pub enable_ticks: u32,
    /// How close a target may be for the step interrupt to wait for it
    /// rather than arm the compare: [`SPIN_TICKS`] at 96 MHz,
    /// scaled to the timer's clock (0 below 12 MHz, where the compare
    /// write's latency is a fraction of a tick). A slow counter (a fuzzing
    /// clock of 48 kHz) spun 8 whole ticks per event, 167 µs each.
    pub spin_ticks: u32,
    pub step_invert: u8,
    pub dir_invert: u8,
    pub limit_invert: u8,
    pub probe_invert: bool,
    /// `$4`: the enable pin is active high. The step pins' owner needs it
    /// for the enable store it makes when stepping starts.
    pub enable_invert: bool,
}

impl StepConfig {
    /// All zero: a stand-in until [`StepConfig::new`] (the board's
    /// machine slot before `Machine::rebuild`).
    pub const UNSET: StepConfig = StepConfig {
        tick_hz: 0,
        pulse_ticks: 0,
        dir_setup_ticks: 0,
        min_period: 0,
        min_low_ticks: 0,
        enable_ticks: 0,
        spin_ticks: 0,
        step_invert: 0,
        dir_invert: 0,
        limit_invert: 0,
        probe_invert: false,
        enable_invert: false,
    };

    pub fn new(s: &Settings, tick_hz: u32) -> Self {
        let exact = |us: f32| ceiling::ticks(us, tick_hz);
        StepConfig {
            tick_hz,
            pulse_ticks: ceiling::pulse_ticks(s.step_pulse_us, tick_hz),
            dir_setup_ticks: exact(s.dir_setup_us).max(1),
            min_period: ceiling::min_period_ticks(s, tick_hz),
            min_low_ticks: ceiling::min_low_ticks(s.step_pulse_us, tick_hz),
            enable_ticks: exact(s.enable_delay_us),
            spin_ticks: (SPIN_TICKS as u64 * tick_hz as u64 / 96_000_000).min(SPIN_TICKS as u64)
                as u32,
            step_invert: s.step_invert,
            dir_invert: s.dir_invert,
            limit_invert: s.limit_invert,
            probe_invert: s.probe_invert,
            enable_invert: s.enable_invert,
        }
    }

    fn to_words(self) -> [u32; WORDS] {
        let flags = u32::from(self.step_invert)
            | u32::from(self.dir_invert) << 8
            | u32::from(self.limit_invert) << 16
            | u32::from(self.probe_invert) << 24
            | u32::from(self.enable_invert) << 25;
        [
            self.tick_hz,
            self.pulse_ticks,
            self.dir_setup_ticks,
            self.min_period,
            self.min_low_ticks,
            self.enable_ticks,
            self.spin_ticks,
            flags,
        ]
    }

    fn from_words(w: [u32; WORDS]) -> Self {
        let f = w[7];
        StepConfig {
            tick_hz: w[0],
            pulse_ticks: w[1],
            dir_setup_ticks: w[2],
            min_period: w[3],
            min_low_ticks: w[4],
            enable_ticks: w[5],
            spin_ticks: w[6],
            step_invert: f as u8,
            dir_invert: (f >> 8) as u8,
            limit_invert: (f >> 16) as u8,
            probe_invert: f & (1 << 24) != 0,
            enable_invert: f & (1 << 25) != 0,
        }
    }
}

/// [`StepConfig`] as words.
const WORDS: usize = 8;

/// The newest [`StepConfig`] the parse task published, for the step
/// interrupt: one writer (the parse task), one reader (the step driver),
/// lock-free both ways (see the module docs).
#[derive(Debug)]
pub struct StepConfigCell {
    /// Even: `words` are complete; odd: a publish is under way. 0: nothing
    /// published yet (the stepper runs on the configuration it was built with).
    seq: AtomicU32,
    /// The `seq` of the configuration the driver took last.
    taken: AtomicU32,
    words: [AtomicU32; WORDS],
}

impl Default for StepConfigCell {
    fn default() -> Self {
        Self::new()
    }
}

impl StepConfigCell {
    pub const fn new() -> Self {
        StepConfigCell {
            seq: AtomicU32::new(0),
            taken: AtomicU32::new(0),
            words: [const { AtomicU32::new(0) }; WORDS],
        }
    }

    /// Parse task: `cfg` replaces what the step driver runs on, from its
    /// next stop on. The caller then makes the interrupt look
    /// ([`StepConfigCell::pending`] says when).
    pub fn publish(&self, cfg: &StepConfig) {
        let s = self.seq.load(Ordering::Relaxed);
        self.seq.store(s.wrapping_add(1) | 1, Ordering::Relaxed);
        fence(Ordering::Release);
        for (w, v) in self.words.iter().zip(cfg.to_words()) {
            w.store(v, Ordering::Relaxed);
        }
        // Never 0 again after the first publish ("nothing published").
        let done = s.wrapping_add(2) & !1;
        self.seq
            .store(if done == 0 { 2 } else { done }, Ordering::Release);
    }

    /// A complete configuration waits that the driver has not taken yet.
    pub fn pending(&self) -> bool {
        let s = self.seq.load(Ordering::Acquire);
        s & 1 == 0 && s != self.taken.load(Ordering::Relaxed)
    }

    /// Step driver, while stopped: the newest configuration if it has not
    /// taken it yet. `None` as well while a publish is under way (this
    /// interrupt preempted it: the publisher kicks again when it is done).
    pub(crate) fn take(&self) -> Option<StepConfig> {
        let s = self.seq.load(Ordering::Acquire);
        if s & 1 != 0 || s == self.taken.load(Ordering::Relaxed) {
            return None;
        }
        let words = core::array::from_fn(|i| self.words[i].load(Ordering::Relaxed));
        fence(Ordering::Acquire);
        if self.seq.load(Ordering::Relaxed) != s {
            return None;
        }
        self.taken.store(s, Ordering::Relaxed);
        Some(StepConfig::from_words(words))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn odd() -> StepConfig {
        let s = Settings {
            step_pulse_us: 7.5,
            dir_setup_us: 3.0,
            enable_delay_us: 11.0,
            max_step_rate_hz: 30_000.0,
            step_invert: 0b1010,
            dir_invert: 0b0101,
            limit_invert: 0b0111,
            probe_invert: true,
            enable_invert: true,
            ..Settings::default()
        };
        StepConfig::new(&s, 96_000_000)
    }

    #[test]
    fn a_published_config_is_taken_once_and_whole() {
        let cell = StepConfigCell::new();
        assert!(!cell.pending());
        assert_eq!(cell.take(), None, "nothing published yet");
        let cfg = odd();
        cell.publish(&cfg);
        assert!(cell.pending());
        assert_eq!(cell.take(), Some(cfg));
        assert!(!cell.pending());
        assert_eq!(cell.take(), None, "taken already");
        let plain = StepConfig::new(&Settings::default(), 96_000_000);
        cell.publish(&plain);
        cell.publish(&cfg);
        assert_eq!(cell.take(), Some(cfg), "the newest wins");
    }

    #[test]
    fn a_publish_under_way_is_not_taken() {
        let cell = StepConfigCell::new();
        let cfg = odd();
        cell.publish(&cfg);
        // The interrupt lands after the writer's first store: odd sequence.
        cell.seq.fetch_add(1, Ordering::Relaxed);
        cell.words[1].store(1, Ordering::Relaxed);
        assert!(!cell.pending());
        assert_eq!(cell.take(), None, "half a configuration");
        // The writer finishes; the kick that follows takes it.
        cell.publish(&cfg);
        assert_eq!(cell.take(), Some(cfg));
    }

    #[test]
    fn the_sequence_never_reads_as_nothing_published_again() {
        let cell = StepConfigCell::new();
        cell.seq.store(u32::MAX - 1, Ordering::Relaxed);
        cell.taken.store(u32::MAX - 1, Ordering::Relaxed);
        cell.publish(&odd());
        assert!(cell.pending(), "wrapped to 0 and read as taken");
        assert_eq!(cell.take(), Some(odd()));
    }
}
