//! The step interrupt's hardware in virtual time: the pins and the timer
//! the core's step driver (`burin::stepper::driver`) drives, as one object.
//!
//! Time inside a handler follows [`IrqTicks`]: the handler's first pin
//! store comes `entry` ticks after it enters; the counter read right after
//! a store sees the store's time, the next read sees the rest of that
//! action done (a rise computes the next event: `rise - entry` ticks; a
//! fall `fall - entry`), which is where the driver re-reads the counter to
//! see whether its next target already passed. A read with nothing done
//! since the previous read (the driver's short wait) costs one tick.
//! Everything is integer ticks: runs are repeatable bit for bit.

use std::cell::Cell;

use burin::seams::{StepPins, StepTimer};
use burin::stepper::Switches;

use super::dma::PulseDma;
use super::World;
use crate::config::IrqTicks;

/// One pin store as the driver made it: levels after it (logical: bit n is
/// axis n, step high, direction negative), at `tick`, with the `$2`/`$3`
/// inverts it was made under ([`Edge::step_pins`], [`Edge::dir_pins`]: the
/// levels on the wires).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    pub tick: u64,
    pub step: u8,
    pub dir: u8,
    pub step_invert: u8,
    pub dir_invert: u8,
}

impl Edge {
    /// Step pin levels (bit set: high).
    pub fn step_pins(&self) -> u8 {
        self.step ^ self.step_invert
    }
    /// Direction pin levels (bit set: high).
    pub fn dir_pins(&self) -> u8 {
        self.dir ^ self.dir_invert
    }
}

/// The timer and the pin levels (see the module docs for its clock).
pub struct VirtualHw {
    t: Cell<u64>,
    /// Counter reads since the last store (2: the store's work is charged).
    reads: Cell<u8>,
    /// Something happened since the last read (no wait-loop tick).
    touched: Cell<bool>,
    work: Cell<u64>,
    /// The armed compare, absolute (None: interrupt disabled).
    pub target: Option<u64>,
    irq: IrqTicks,
    tick_hz: u32,
    step: u8,
    dir: u8,
    /// `$2`/`$3` as the pins were last configured (boot, then
    /// `StepPins::apply_config`).
    step_invert: u8,
    dir_invert: u8,
    enabled: bool,
    /// The pulse-end DMA stream (with hardware pulse ends) and the width
    /// the driver gave it, ticks.
    pub dma: PulseDma,
    width: u64,
    /// This handler's stores, for the engine to apply after it returns.
    pub stores: Vec<Edge>,
    /// Every store of the run, when a caller asked for them.
    pub log: Option<Vec<Edge>>,
}

impl VirtualHw {
    /// `step_invert`/`dir_invert`: `$2`/`$3` at power-up.
    pub fn new(irq: IrqTicks, tick_hz: u32, step_invert: u8, dir_invert: u8) -> Self {
        VirtualHw {
            t: Cell::new(0),
            reads: Cell::new(2),
            touched: Cell::new(true),
            work: Cell::new(0),
            target: None,
            irq,
            tick_hz,
            step: 0,
            dir: 0,
            step_invert,
            dir_invert,
            enabled: false,
            dma: PulseDma::new(irq.pulse_dma.0, irq.pulse_dma.1),
            width: 0,
            stores: Vec::new(),
            log: None,
        }
    }

    /// The handler enters at `at` (its first store is `entry` later).
    pub fn enter(&mut self, at: u64) {
        self.t.set(at + self.irq.entry);
        self.reads.set(2);
        self.touched.set(true);
        self.work.set(0);
        self.stores.clear();
    }

    /// When the handler that ran since [`VirtualHw::enter`] returned.
    pub fn done_at(&self) -> u64 {
        self.t.get() + self.work.get()
    }

    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Pulses end in hardware (the boards), not in a fall interrupt.
    pub fn hardware_fall(&self) -> bool {
        self.irq.pulse_end.is_some()
    }

    /// A store by the handler, now: the pins, and the handler's time.
    fn store(&mut self, step: u8, dir: u8, work: u64) {
        self.record(self.t.get(), step, dir);
        self.reads.set(0);
        self.touched.set(true);
        self.work.set(work);
    }

    /// The hardware's pulse end: a store at a later tick, made without the
    /// CPU (no handler time), if the DMA model's transfer reaches the pins.
    /// It joins this handler's stores; the driver never stores again
    /// before it (the next rise waits for it). A failed transfer leaves
    /// the pins high, as on the chip.
    fn fall_at(&mut self, at: u64) {
        if self.dma.request() {
            self.record(at, 0, self.dir);
        }
    }

    /// New pin levels at `tick`, into this handler's stores and the log.
    fn record(&mut self, tick: u64, step: u8, dir: u8) {
        self.step = step;
        self.dir = dir;
        let e = Edge {
            tick,
            step,
            dir,
            step_invert: self.step_invert,
            dir_invert: self.dir_invert,
        };
        self.stores.push(e);
        if let Some(log) = &mut self.log {
            log.push(e);
        }
    }

    /// The absolute tick of the counter value `at`: the next time the
    /// 32-bit counter reads it (a value behind it waits for the wrap, as
    /// on TIM5).
    fn ahead(&self, at: u32) -> u64 {
        let t = self.t.get();
        t + u64::from(at.wrapping_sub(t as u32))
    }
}

/// The hardware and the machine it moves, for one handler: the carriage
/// moves at each rising edge, so the switches the driver reads right after
/// it already see that step. `HW_FALL`: pulses end in hardware
/// ([`crate::config::PulseEnd`]).
pub struct Wired<'a, const HW_FALL: bool> {
    pub hw: &'a mut VirtualHw,
    pub world: &'a mut World,
}

impl<const HW_FALL: bool> StepPins for Wired<'_, HW_FALL> {
    const ENDS_PULSES: bool = HW_FALL;
    fn set_pulse_width(&mut self, ticks: u32) {
        self.hw.width = u64::from(ticks);
    }
    fn pulse_end_latency(&self) -> u32 {
        self.hw.irq.pulse_end.unwrap_or(0) as u32
    }
    fn pulse_end_failed(&self) -> bool {
        self.hw.dma.flags().failed()
    }
    /// A driver counts a step at a rising edge only: a pin still high from
    /// a pulse that never ended moves nothing.
    fn step_high(&mut self, step_mask: u8) {
        let hw = &mut *self.hw;
        let work = hw.irq.rise - hw.irq.entry;
        let (dir, rising) = (hw.dir, step_mask & !hw.step);
        let at = hw.t.get();
        hw.store(hw.step | step_mask, dir, work);
        self.world.step(rising, dir ^ hw.dir_invert);
        if HW_FALL {
            let end = at + hw.width + hw.irq.pulse_end.unwrap_or(0);
            hw.fall_at(end);
        }
    }
    /// BSRR's direction word leaves the step pins as they are.
    fn set_directions(&mut self, dir_mask: u8) {
        let hw = &mut *self.hw;
        let work = hw.irq.rise - hw.irq.entry;
        hw.store(hw.step, dir_mask, work);
    }
    fn step_low(&mut self) {
        let hw = &mut *self.hw;
        let work = hw.irq.fall - hw.irq.entry;
        hw.store(0, hw.dir, work);
    }
    fn set_enabled(&mut self, on: bool) {
        self.hw.enabled = on;
    }
    /// The new inverts, and the idle levels under them in one store (as
    /// the board's BSRR word), made at once by the handler.
    fn apply_config(&mut self, cfg: &burin::stepper::StepConfig, dir_mask: u8) {
        let hw = &mut *self.hw;
        hw.step_invert = cfg.step_invert;
        hw.dir_invert = cfg.dir_invert;
        let work = hw.irq.fall - hw.irq.entry;
        hw.store(0, dir_mask, work);
    }
    fn switches(&self) -> Switches {
        self.world.switches()
    }
}

impl<const HW_FALL: bool> StepTimer for Wired<'_, HW_FALL> {
    fn tick_hz(&self) -> u32 {
        self.hw.tick_hz()
    }
    fn now(&self) -> u32 {
        self.hw.now()
    }
    fn schedule_at(&mut self, at: u32) {
        self.hw.schedule_at(at);
    }
    fn start(&mut self) {
        self.hw.start();
    }
    fn stop(&mut self) {
        self.hw.stop();
    }
}

impl StepTimer for VirtualHw {
    fn tick_hz(&self) -> u32 {
        self.tick_hz
    }
    fn now(&self) -> u32 {
        let mut t = self.t.get();
        if self.reads.get() == 1 {
            t += self.work.replace(0);
        }
        if !self.touched.replace(false) {
            t += 1;
        }
        self.reads.set(self.reads.get().saturating_add(1));
        self.t.set(t);
        t as u32
    }
    fn schedule_at(&mut self, at: u32) {
        self.target = Some(self.ahead(at));
        self.touched.set(true);
    }
    fn start(&mut self) {
        self.touched.set(true);
    }
    fn stop(&mut self) {
        self.target = None;
    }
}
