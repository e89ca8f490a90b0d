//! How long the step interrupt takes and when it cannot run, in virtual
//! time: the `[interrupts]` table of a machine file.
//!
//! On the board the step handler enters some cycles after its compare
//! matches (stacking, tail-chaining), stores the pins some cycles later,
//! and cannot enter at all while lower-priority code masks interrupts: the
//! F411's usb-device `poll()` does so for 3-4 µs, about once per USB frame
//! (1 ms). host-sim delays each step interrupt by this model, so a test can
//! check on the recorded pin edges that no step is lost and no pulse is cut
//! short however late the handler runs.

/// Where each mask window sits inside its period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaskPhase {
    /// At this offset from the start of every period, µs.
    Fixed(f32),
    /// At an offset drawn afresh for every period from a PRNG seeded with
    /// this value: irregular, but the same on every run.
    Random(u64),
}

use burin::chip::bus::addr;
use burin::chip::dma::DmaPath;
use burin::chip::Chip;

/// The boards' pulse-end path (`burin::chip::dma::DmaPath::pulse_end`),
/// with the step-off word at a representative SRAM address (the board's
/// is a static the linker places).
pub const BOARD_PULSE_DMA: DmaPath =
    DmaPath::pulse_end(addr::GPIOB + addr::GPIO_BSRR, addr::SRAM + 0x100);

/// Who ends each step pulse (`burin::seams::StepPins::ENDS_PULSES`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PulseEnd {
    /// The timer's second compare and a DMA write, as on the F411 and F401
    /// boards, this many ns after the compare target at most.
    Hardware { latency_ns: u32 },
    /// A second interrupt lowers the pins, as in the QEMU build.
    Interrupt,
}

/// The step interrupt's timing. All zero (the default): handlers take no
/// time and nothing is masked, the ideal timer of earlier host-sim versions;
/// pulses end in hardware, as on the boards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interrupts {
    /// From the compare match (or the end of a mask window) to the
    /// handler's first pin store, ns.
    pub step_entry_ns: u32,
    /// A rise handler from entry to return (pin store, next event
    /// computed), ns. The CPU takes no other step interrupt meanwhile.
    pub step_handler_ns: u32,
    /// A fall handler from entry to return, ns (with [`PulseEnd::Interrupt`]).
    pub step_fall_ns: u32,
    pub pulse_end: PulseEnd,
    /// With [`PulseEnd::Hardware`]: the DMA path that ends pulses and the
    /// chip it runs on (host-sim's DMA model, `engine::PulseDma`, runs it
    /// by `DmaPath::check`): the boards' path by default.
    pub pulse_dma: (DmaPath, Chip),
    /// Length of each interrupt-masked window, µs (0: none).
    pub mask_window_us: f32,
    /// One window per this many µs.
    pub mask_period_us: f32,
    pub mask_phase: MaskPhase,
}

impl Interrupts {
    /// Instant handlers, no masking.
    pub const IDEAL: Interrupts = Interrupts {
        step_entry_ns: 0,
        step_handler_ns: 0,
        step_fall_ns: 0,
        pulse_end: PulseEnd::Hardware { latency_ns: 0 },
        pulse_dma: (BOARD_PULSE_DMA, Chip::F411),
        mask_window_us: 0.0,
        mask_period_us: 1000.0,
        mask_phase: MaskPhase::Random(1),
    };

    /// The model in timer ticks at `tick_hz`.
    pub fn ticks(&self, tick_hz: u32) -> IrqTicks {
        let ns = |v: u32| (u64::from(v) * u64::from(tick_hz)).div_ceil(1_000_000_000);
        let us = |v: f32| (f64::from(v.max(0.0)) * f64::from(tick_hz) / 1e6).round() as u64;
        let period = us(self.mask_period_us).max(1);
        let window = us(self.mask_window_us).min(period);
        let entry = ns(self.step_entry_ns);
        IrqTicks {
            entry,
            rise: ns(self.step_handler_ns).max(entry),
            fall: ns(self.step_fall_ns).max(entry),
            pulse_end: match self.pulse_end {
                PulseEnd::Hardware { latency_ns } => Some(ns(latency_ns)),
                PulseEnd::Interrupt => None,
            },
            pulse_dma: self.pulse_dma,
            masks: Masks {
                window,
                period,
                phase: match self.mask_phase {
                    MaskPhase::Fixed(at) => Phase::Fixed(us(at) % period),
                    MaskPhase::Random(seed) => Phase::Random(seed),
                },
            },
        }
    }
}

impl Default for Interrupts {
    fn default() -> Self {
        Interrupts::IDEAL
    }
}

/// [`Interrupts`] in ticks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IrqTicks {
    pub entry: u64,
    pub rise: u64,
    pub fall: u64,
    /// Hardware pulse end and its latency (None: a fall interrupt).
    pub pulse_end: Option<u64>,
    pub pulse_dma: (DmaPath, Chip),
    pub masks: Masks,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Fixed(u64),
    Random(u64),
}

/// The mask windows: one of `window` ticks in every `period`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Masks {
    window: u64,
    period: u64,
    phase: Phase,
}

/// SplitMix64's finaliser: a stateless hash, so the window of any period
/// is found without replaying the ones before it.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Masks {
    /// Start of the window in period `k`.
    fn start(&self, k: u64) -> u64 {
        let room = self.period - self.window + 1;
        let offset = match self.phase {
            Phase::Fixed(at) => at.min(room - 1),
            Phase::Random(seed) => mix(seed ^ mix(k)) % room,
        };
        k * self.period + offset
    }

    /// When an interrupt raised at `t` can enter: `t`, or the end of the
    /// window masking `t`.
    pub fn unmasked_at(&self, t: u64) -> u64 {
        if self.window == 0 {
            return t;
        }
        let start = self.start(t / self.period);
        if (start..start + self.window).contains(&t) {
            start + self.window
        } else {
            t
        }
    }
}
