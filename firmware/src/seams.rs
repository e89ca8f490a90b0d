//! The only places the motion core touches hardware. The RTIC binary
//! implements these with registers; host-sim with a virtual clock, a
//! recorder and files. There are four: [`StepPins`] and [`StepTimer`]
//! (driven by `stepper::driver` from the step interrupt), [`Storage`]
//! (settings and offsets; `persist::FlashMap` over an `embedded-storage`
//! `NorFlash` on both) and [`Tx`] (reply bytes). Inputs arrive as values
//! (switch levels, bytes, the millisecond clock) in
//! `controller::Inputs`.

mod config;

pub use config::{StepConfig, StepConfigCell, SPIN_TICKS};

/// Switch inputs as pin levels (before the invert settings).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Switches {
    pub limits: u8,
    pub probe: bool,
}

/// Step, direction and enable outputs. Bit n of each mask is axis n
/// (X, Y, Z, A); masks are logical (bit set: negative direction, or
/// "this axis steps"), implementations apply the `$2`/`$3`/`$4` inverts.
/// Each call is one store (one BSRR write on STM32), so the axes of an
/// event change in the same bus cycle and nothing is read-modified-written.
pub trait StepPins {
    /// A rising edge on the step pins in `step_mask` (not 0), in ONE
    /// store; the direction pins stay as they are. With
    /// [`StepPins::ENDS_PULSES`] the pulse's end is armed first, in the same
    /// interrupt-masked window, so the store can never be late for it. Directions never change
    /// in a step's own event: the stepper gives them an event of their own
    /// ([`StepPins::set_directions`]) and `$200` before the first step.
    fn step_high(&mut self, step_mask: u8);
    /// The direction pins of every axis, in one store (no change when
    /// they already are so); the step pins stay low.
    fn set_directions(&mut self, dir_mask: u8);
    /// Lower all step pins (end of pulse); directions stay.
    fn step_low(&mut self);
    /// Stepper drivers on/off.
    fn set_enabled(&mut self, on: bool);
    /// The hardware ends each pulse by itself, the width after the rise
    /// ([`StepPins::set_pulse_width`], armed by [`StepPins::step_high`]), so
    /// a step costs one interrupt, not two. The F411/F401 boards do (a timer compare triggers a DMA write
    /// of the step-off word to BSRR); QEMU's model has no DMA and lowers
    /// the pins in a second interrupt ([`StepPins::step_low`]).
    const ENDS_PULSES: bool = false;
    /// With [`StepPins::ENDS_PULSES`]: the width of every following pulse,
    /// in step-timer ticks (`$0`). [`StepPins::step_high`] arms the end
    /// before it raises the pins, so a pulse lasts at least this long from
    /// the store whatever interrupts it. Called at each start from rest.
    fn set_pulse_width(&mut self, _ticks: u32) {}
    /// With [`StepPins::ENDS_PULSES`]: the hardware's worst delay, in timer
    /// ticks, beyond the width, from the counter read right after the
    /// rising store to the pins being low (rounding into the pulse timer's
    /// clock, its margin, the DMA's latency). The driver takes the fall
    /// that late for the minimum low time and direction changes.
    fn pulse_end_latency(&self) -> u32 {
        0
    }
    /// With [`StepPins::ENDS_PULSES`]: the pulse-end hardware reports an
    /// error (a DMA transfer error or a stream the chip disabled). Read at
    /// each start from rest; a failure latches
    /// [`crate::chip::HwFault::PulseEndError`].
    fn pulse_end_failed(&self) -> bool {
        false
    }
    /// A new configuration (`$n=`), taken by the step driver while it is
    /// stopped: no pulse is high and the timer is off. Adopt its `$2`/`$3`/
    /// `$4` inverts for every later store and put the idle levels under
    /// them at once: step pins at rest, direction pins at `dir_mask` (the
    /// logical directions as they stand, so the next step never needs a
    /// direction change nobody scheduled). The enable pin keeps its level:
    /// the parse task owns it at rest and writes it under the new `$4`
    /// itself; only the store [`StepPins::set_enabled`] makes changes.
    /// Hardware that ends pulses by itself takes the new step-off level
    /// here too (the width comes at every start:
    /// [`StepPins::set_pulse_width`]).
    fn apply_config(&mut self, _cfg: &StepConfig, _dir_mask: u8) {}
    /// Limit and probe pin levels (before the `$5`/`$6` inverts). The
    /// driver reads them right after each rising edge of a move that
    /// watches a switch (homing, probing) or while hard limits are armed
    /// (a plain move reads nothing), so the stepper
    /// judges a switch with every step so far taken and a trip position
    /// is exact; it is the step interrupt's own read, a closed limit stops
    /// pulses within one event even if its edge interrupt was missed.
    fn switches(&self) -> Switches;
}

/// The step timer: a free-running 32-bit tick counter with one compare that
/// raises the step interrupt. Targets are absolute counter values, so a late
/// interrupt delays the next edge instead of shifting every later one, and
/// the driver can tell "already past" from "not yet" (wrapping difference).
pub trait StepTimer {
    /// Tick rate in Hz (96 MHz TIM5 on the F411; whatever host-sim chooses).
    fn tick_hz(&self) -> u32;
    /// The counter now (wraps at 2^32; compare with `wrapping_sub`).
    fn now(&self) -> u32;
    /// Raise the step interrupt when the counter reaches `at`, replacing the
    /// previous target; a match of the previous target that is still
    /// pending is dropped. A target already past fires only after the
    /// counter wraps, so the caller re-reads [`StepTimer::now`] afterwards.
    fn schedule_at(&mut self, at: u32);
    /// Counting, with the compare interrupt enabled.
    fn start(&mut self);
    /// No more interrupts (idle, hold complete, alarm).
    fn stop(&mut self);
}

/// Persistent records: a small key/value store (a record log
/// in flash on the MCU, RAM on QEMU and in host-sim; see `persist`). It is
/// blocking on purpose: a flash write stalls the CPU anyway (code runs from
/// flash), so the device calls it only while no motion runs.
pub trait Storage {
    type Error: core::fmt::Debug;
    /// Read the newest record for `key` into `buf`, returning its length,
    /// or `None` when there is none (a torn last write leaves the one before).
    fn load(&mut self, key: u16, buf: &mut [u8]) -> Result<Option<usize>, Self::Error>;
    /// Write the record for `key`; it replaces the previous one only once
    /// it is complete.
    fn store(&mut self, key: u16, data: &[u8]) -> Result<(), Self::Error>;
}

/// No storage: nothing is ever found, writes vanish. Devices built with
/// `Device::new` (tests, tools) use it.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStorage;

impl Storage for NoStorage {
    type Error = core::convert::Infallible;
    fn load(&mut self, _key: u16, _buf: &mut [u8]) -> Result<Option<usize>, Self::Error> {
        Ok(None)
    }
    fn store(&mut self, _key: u16, _data: &[u8]) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Reply bytes towards the host: the TX ring the USB (or USART)
/// interrupt drains on the board, a buffer host-sim hands to its pty or
/// pipe. It must take every byte: the session writes whole replies only,
/// and runs only while [`Tx::room`] holds its longest burst.
pub trait Tx {
    fn send(&mut self, bytes: &[u8]);
    /// Bytes it can take now (a ring's free space; unbounded sinks say so).
    fn room(&self) -> usize {
        usize::MAX
    }
}

impl<T: Tx + ?Sized> Tx for &mut T {
    fn send(&mut self, bytes: &[u8]) {
        (**self).send(bytes)
    }
    fn room(&self) -> usize {
        (**self).room()
    }
}

/// Longest interval between two step events, ticks (11.2 s at 96 MHz).
/// The step driver compares counter times with `wrapping_sub(..) as i32`,
/// which is only right for differences under 2^31 ticks: a step period
/// between 2^31 and the 32-bit timer's full range (a diagonal `G1 X0 Y0
/// F0.4` on the fuzz machine, 42 s per step) read as "already past" and
/// the steps went out at the `$201` floor (fuzz finding, `executor`
/// target). Half that range leaves a margin for interrupt lateness.
pub const MAX_PERIOD: u32 = 1 << 30;
