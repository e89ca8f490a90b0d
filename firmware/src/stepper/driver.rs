//! The step interrupt: what the board's TIM5 handler and host-sim's virtual
//! timer both run, generic over the [`StepPins`] and [`StepTimer`] seams.
//!
//! One compare channel, one absolute target at a time. Where the hardware
//! ends pulses ([`StepPins::ENDS_PULSES`], the boards' DMA) every action
//! is a rise that also arms the pulse end and schedules the next rise;
//! otherwise (the QEMU build) two alternating actions:
//!
//! - **rise**: one store puts the rising step edges of the pending event
//!   (directions change only in events of their own), the counter is read
//!   right after it, the fall is scheduled at that *actual* rise time +
//!   `$0`, and only then the next event is computed ([`Stepper::on_event`])
//!   while the pulse is high;
//! - **fall**: the step pins go low, the counter is read, and the next rise
//!   is scheduled at its planned time, but never before the fall + the
//!   minimum low time ([`StepConfig::min_low_ticks`]) nor sooner than
//!   `$201`'s period after the last rise ([`StepConfig::min_period`]).
//!
//! Why: with a fixed compare ending every pulse `$0` after each timer
//! update, an interrupt delayed by longer than `$0` (the F411's USB stack
//! masks interrupts for 3-4 µs) could leave a pin high into the next
//! period, and that step had no rising edge: lost. Here a late handler only
//! delays an edge, never skips one: every step gets high ≥ `$0` and low
//! ≥ `min_low_ticks`, and planned times catch up afterwards at no more
//! than `$201`. After each compare write the counter is re-read: a target
//! already past (or within [`SPIN_TICKS`], scaled to the timer) is done at
//! once in the same handler instead of waiting 2^32 ticks for the counter
//! to wrap.
//!
//! Events without steps (direction changes, smoothing events) have no
//! fall: the next rise follows directly, `$200` after a direction change.
//! Starting from rest (the task pends the interrupt while
//! [`Realtime::stepping`] is false) enables the drivers and holds the first
//! edge `$207` back; an idle event from the stepper (underrun, end of
//! motion, halt) stops the timer at its slot, after the last fall.
//!
//! Settings (`$n=`) reach the interrupt only while it is stopped: the parse
//! task publishes a new [`StepConfig`] in [`Realtime::step_config`] and
//! kicks; a stopped driver takes it at that kick (the idle pin levels under
//! new `$2`/`$3` change then), at a start from rest, and at the slot where
//! it stops (which it does then even if more was queued: the task's next
//! kick starts that on the new configuration).

use super::{Segment, StepConfig, StepEvent, Stepper};
use crate::realtime::{Realtime, SENSE_FLUSH};
use crate::seams::{StepPins, StepTimer, SPIN_TICKS};

/// The later of two counter values (wrapping: valid within 2^31 ticks).
#[inline(always)]
fn later(a: u32, b: u32) -> u32 {
    if (b.wrapping_sub(a) as i32) > 0 {
        b
    } else {
        a
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Timer stopped; the next interrupt is a kick.
    Stopped,
    /// Step pins low; the target is the next rise.
    Low,
    /// A pulse is high; the target is its fall.
    High,
}

/// The step interrupt's state. It holds no configuration: timing comes
/// from the stepper's [`StepConfig`], which the driver replaces only while
/// stopped, with what the parse task published after a `$n=`
/// ([`Realtime::step_config`]; see `take_config`).
#[derive(Clone, Debug)]
pub struct StepDriver {
    phase: Phase,
    /// The event the next rise applies (computed during the last pulse).
    pending: StepEvent,
    /// Planned tick of the pending event.
    planned: u32,
    /// Tick the current action is due at (the armed compare).
    target: u32,
    /// Actual tick of the last rising step edge and of the last fall.
    last_rise: u32,
    last_fall: u32,
    /// Direction pins as last written (logical).
    dirs: u8,
    /// Where the hardware ends pulses: ticks from a rise to the latest
    /// moment its pulse is over (`$0` + the hardware's latency), and the
    /// shortest time from a rise's counter read to the next rise that
    /// leaves the minimum low time after the pulse. Set at each start from
    /// rest (the stepper's configuration only changes while stopped).
    fall_after: u32,
    rise_gap: u32,
}

impl Default for StepDriver {
    fn default() -> Self {
        Self::new()
    }
}

/// What one interrupt did, for the task: it should run when a segment was
/// taken (room in the queue) or the driver stopped.
pub type WakeTask = bool;

impl StepDriver {
    pub const fn new() -> Self {
        const IDLE: StepEvent = StepEvent {
            dir_mask: 0,
            step_mask: 0,
            ticks: 0,
        };
        StepDriver {
            phase: Phase::Stopped,
            pending: IDLE,
            planned: 0,
            target: 0,
            last_rise: 0,
            last_fall: 0,
            dirs: 0,
            fall_after: 0,
            rise_gap: 0,
        }
    }

    /// The timer is armed (a kick would do nothing).
    pub fn is_running(&self) -> bool {
        self.phase != Phase::Stopped
    }

    /// The event the next rise applies (its steps are already counted in
    /// the stepper's position).
    pub fn pending(&self) -> &StepEvent {
        &self.pending
    }

    /// The whole step interrupt: a kick from rest, a due rise or fall (and
    /// any that fell due meanwhile), or nothing if it came early. `pop`
    /// takes the next segment.
    ///
    /// The common cases, a due fall or rise whose next action is not due
    /// yet, run straight through inline in the caller's handler; kicks,
    /// stops and late chains go through the general loop.
    #[inline(always)]
    pub fn on_interrupt<H: StepPins + StepTimer>(
        &mut self,
        stepper: &mut Stepper,
        hw: &mut H,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
    ) -> WakeTask {
        let due = (self.target.wrapping_sub(hw.now()) as i32) <= 0;
        if due && self.phase == Phase::Low && self.pending.ticks != 0 {
            self.rise(stepper, hw, rt, pop);
            if (self.target.wrapping_sub(hw.now()) as i32) > SPIN_TICKS as i32 {
                return stepper.take_popped();
            }
        } else if !H::ENDS_PULSES && due && self.phase == Phase::High {
            self.fall(&stepper.cfg, hw);
            // The constant window here (the hot path loads nothing more);
            // a slower timer's closer targets go through `run`'s scaled one.
            if (self.target.wrapping_sub(hw.now()) as i32) > SPIN_TICKS as i32 {
                return false;
            }
        }
        self.run(stepper, hw, rt, pop)
    }

    /// Everything but the plain rise: kicks, spins, stops, the fall
    /// interrupt. `#[cold]` so that the plain rise is the straight path
    /// (a taken branch to a cold flash line costs its wait states).
    #[inline(never)]
    #[cold]
    fn run<H: StepPins + StepTimer>(
        &mut self,
        stepper: &mut Stepper,
        hw: &mut H,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
    ) -> WakeTask {
        if self.phase == Phase::Stopped {
            // A kick: from rest, or only to take a new configuration.
            let fresh = self.take_config(stepper, hw, rt);
            if !self.start(stepper, hw, rt, pop, fresh) {
                stepper.take_popped();
                return true;
            }
        }
        loop {
            let early = self.target.wrapping_sub(hw.now()) as i32;
            if early > stepper.cfg.spin_ticks as i32 {
                if self.phase == Phase::Low && (stepper.is_flushed(rt) || self.reconfigure(rt)) {
                    // A kick after a flush: the pending event is the last
                    // of flushed motion (the stepper already counted its
                    // steps into the position the executor took), so it
                    // runs as soon as the pin timing allows instead of at
                    // its slot, seconds away in a slow move; the stepper's
                    // next event is idle and the timer stops. Likewise the
                    // slot after the last event when a new configuration
                    // waits: the stop that takes it comes as soon as the
                    // last pulse is over.
                    let cfg = &stepper.cfg;
                    let soonest = later(
                        self.last_fall.wrapping_add(cfg.min_low_ticks),
                        self.last_rise.wrapping_add(cfg.min_period),
                    );
                    let soonest = later(soonest, hw.now());
                    if (soonest.wrapping_sub(self.target) as i32) < 0 {
                        self.target = soonest;
                        hw.schedule_at(soonest);
                        continue;
                    }
                }
                // Armed, not due (a kick while running, or a stale match).
                return stepper.take_popped();
            }
            if early > 0 {
                continue;
            }
            match self.phase {
                Phase::High => self.fall(&stepper.cfg, hw),
                _ => {
                    // The slot after the last event stops while a new
                    // configuration waits, even if more was queued
                    // meanwhile: it is taken here, at rest, and the
                    // task's kick starts the rest on it.
                    if self.reconfigure(rt) || !self.rise(stepper, hw, rt, pop) {
                        self.phase = Phase::Stopped;
                        hw.stop();
                        rt.set_stepping(false);
                        self.take_config(stepper, hw, rt);
                        stepper.take_popped();
                        return true;
                    }
                }
            }
        }
    }

    /// [`Stepper::on_event`] off the hot path (start, the slot after the
    /// last event): kept out of line so the rise's own call inlines alone.
    #[inline(never)]
    #[cold]
    fn poll_cold(
        stepper: &mut Stepper,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
        sw: impl FnOnce() -> crate::seams::Switches,
    ) -> StepEvent {
        stepper.on_event(rt, pop, sw)
    }

    /// The pending slot is the one after the last event and a new
    /// configuration waits: the driver stops there to take it.
    fn reconfigure(&self, rt: &Realtime) -> bool {
        self.pending.ticks == 0 && rt.step_config().pending()
    }

    /// Only while stopped: takes the configuration the parse task
    /// published since the last one taken (`$n=`), for the stepper (timing,
    /// `$5`/`$6` for its switch reads) and the pins (`$2`/`$3`/`$4`, idle
    /// levels at once). True when there was one.
    fn take_config<H: StepPins>(&self, stepper: &mut Stepper, hw: &mut H, rt: &Realtime) -> bool {
        debug_assert!(
            self.phase == Phase::Stopped,
            "a new configuration while running"
        );
        let Some(cfg) = rt.step_config().take() else {
            return false;
        };
        stepper.cfg = cfg;
        // Pulse-end hardware takes its step-off level in there (its width
        // at every start: `StepPins::set_pulse_width`).
        hw.apply_config(&stepper.cfg, self.dirs);
        true
    }

    /// From rest: the first event, drivers on, its rise `$207` from now.
    /// `fresh`: a new configuration was just taken, so the pins' idle
    /// levels moved this instant; the first edge also waits `$200` and the
    /// minimum low time after that. False when there is nothing to run
    /// (the queue held only flushed segments, or a halt holds).
    fn start<H: StepPins + StepTimer>(
        &mut self,
        stepper: &mut Stepper,
        hw: &mut H,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
        fresh: bool,
    ) -> bool {
        let ev = Self::poll_cold(stepper, rt, pop, || hw.switches());
        if ev.ticks == 0 {
            return false;
        }
        // The pulse-end hardware's own error flags, once per start: a
        // broken path latches the alarm instead of a run of pulses that
        // never end (the boards; host-sim's DMA model alike). The event
        // taken is dropped unpulsed; the alarm's flush drops the rest at
        // the next kick.
        if H::ENDS_PULSES && hw.pulse_end_failed() {
            rt.set_hw_fault(crate::chip::HwFault::PulseEndError);
            stepper.take_back(rt, &ev);
            return false;
        }
        rt.set_stepping(true);
        hw.set_pulse_width(stepper.cfg.pulse_ticks);
        hw.set_enabled(true);
        hw.start();
        let now = hw.now();
        let cfg = &stepper.cfg;
        self.pending = ev;
        let hold = if fresh {
            cfg.enable_ticks
                .max(cfg.dir_setup_ticks)
                .max(cfg.min_low_ticks)
        } else {
            cfg.enable_ticks
        };
        self.planned = now.wrapping_add(hold);
        // Long low and long since the last rise: no bound applies.
        self.last_fall = now.wrapping_sub(cfg.min_low_ticks);
        self.last_rise = now.wrapping_sub(cfg.min_period);
        self.fall_after = cfg.pulse_ticks.saturating_add(hw.pulse_end_latency());
        self.rise_gap = self.fall_after.saturating_add(cfg.min_low_ticks);
        self.phase = Phase::Low;
        self.target = self.planned;
        hw.schedule_at(self.target);
        true
    }

    /// Applies the pending event and computes the next one. False: the
    /// stepper is idle at this slot, stop.
    #[inline(always)]
    fn rise<H: StepPins + StepTimer>(
        &mut self,
        stepper: &mut Stepper,
        hw: &mut H,
        rt: &Realtime,
        pop: &mut impl FnMut() -> Option<Segment>,
    ) -> bool {
        let mut ev = self.pending;
        if ev.step_mask != 0 && rt.attention() & SENSE_FLUSH != 0 && rt.halting() {
            // A hard limit or the e-stop halted the stepper after this
            // step was computed: it never leaves, so no pulse follows the
            // trip. Its count stays: the executor may already have taken
            // the position (a reset's flush), and both halts declare the
            // position lost, so one step of difference is what the alarm
            // already says, where the old order drove it into the switch.
            ev = Self::poll_cold(stepper, rt, pop, || hw.switches());
            self.pending = ev;
            if ev.ticks == 0 {
                return false;
            }
        }
        if ev.ticks == 0 {
            // The slot after the last event: go on if more was queued
            // meanwhile, else stop.
            ev = Self::poll_cold(stepper, rt, pop, || hw.switches());
            if ev.ticks == 0 {
                return false;
            }
        }
        let cfg = &stepper.cfg;
        let mut next = self.planned.wrapping_add(ev.ticks);
        let steps = ev.step_mask != 0;
        let now;
        if steps {
            // Directions change only in an event of their own (the
            // stepper's direction event before a block's first step), never
            // with a step: a step and its direction in one store would have
            // no setup time. So a step's store is the step pins alone.
            debug_assert!(ev.dir_mask == self.dirs, "direction changed with a step");
            hw.step_high(ev.step_mask);
            now = hw.now();
            self.last_rise = now;
            if H::ENDS_PULSES {
                // The hardware ends the pulse `$0` after the store at the
                // soonest (`step_high` armed it first), and by
                // `fall_after` after `now`, read after the store, at the
                // latest.
                self.last_fall = now.wrapping_add(self.fall_after);
            } else {
                self.phase = Phase::High;
                self.target = now.wrapping_add(cfg.pulse_ticks);
                hw.schedule_at(self.target);
            }
        } else {
            hw.set_directions(ev.dir_mask);
            now = hw.now();
            if ev.dir_mask != self.dirs {
                self.dirs = ev.dir_mask;
                next = later(next, now.wrapping_add(cfg.dir_setup_ticks));
            }
        }
        self.planned = next;
        // One call site, so the inlined stepper exists once here.
        let ev = stepper.on_event(rt, pop, || hw.switches());
        // Field by field: a whole-struct store packs the padding too.
        self.pending.ticks = ev.ticks;
        self.pending.dir_mask = ev.dir_mask;
        self.pending.step_mask = ev.step_mask;
        if H::ENDS_PULSES && steps {
            // What the fall handler does in the two-interrupt scheme; a
            // step after a step is `rise_gap` after this rise's counter
            // read (the pins) and the one ceiling after this rise's target
            // (`min_period`, which the plan also keeps: measured from the
            // late counter read it made every step late by the interrupt's
            // latency, and the driver fell behind the plan at the ceiling).
            self.target = if self.pending.step_mask != 0 {
                let pins = later(self.planned, now.wrapping_add(self.rise_gap));
                later(pins, self.target.wrapping_add(stepper.cfg.min_period))
            } else {
                self.rise_target::<H>(&stepper.cfg)
            };
            hw.schedule_at(self.target);
        } else if !steps {
            // A wait or dwell steps nothing, and may last longer than the
            // 2^31 ticks the wrapping comparisons in `later` can tell
            // apart: a bound older than itself no longer binds, so keep it
            // just within reach. (A 28 s dwell left them stale; the next
            // rise then read as 16 s in the future, waited for the counter
            // to wrap and caught up at the `$201` floor: a fuzz finding.)
            let cfg = &stepper.cfg;
            if now.wrapping_sub(self.last_rise) > cfg.min_period {
                self.last_rise = now.wrapping_sub(cfg.min_period);
            }
            if now.wrapping_sub(self.last_fall) > cfg.min_low_ticks {
                self.last_fall = now.wrapping_sub(cfg.min_low_ticks);
            }
            self.phase = Phase::Low;
            self.target = self.rise_target::<H>(&stepper.cfg);
            hw.schedule_at(self.target);
        }
        true
    }

    /// Ends the pulse and schedules the next rise.
    #[inline(always)]
    fn fall<H: StepPins + StepTimer>(&mut self, cfg: &StepConfig, hw: &mut H) {
        hw.step_low();
        self.last_fall = hw.now();
        self.phase = Phase::Low;
        self.target = self.rise_target::<H>(cfg);
        hw.schedule_at(self.target);
    }

    /// The planned time of the pending event, held back by the minimum low
    /// time and `$201` when it steps. When the hardware ends pulses, an
    /// event without steps (a direction change, a wait) still waits for
    /// the last pulse's end: direction pins never change while a step pin
    /// is high, as with the fall handler first.
    #[inline(always)]
    fn rise_target<H: StepPins>(&self, cfg: &StepConfig) -> u32 {
        if self.pending.step_mask == 0 {
            if self.pending.dir_mask != self.dirs {
                // Direction pins change no sooner than the minimum low
                // time after the last pulse's end: drivers that latch the
                // direction at the falling edge need it held there.
                let settled = self.last_fall.wrapping_add(cfg.min_low_ticks);
                return later(self.planned, settled);
            }
            if H::ENDS_PULSES {
                return later(self.planned, self.last_fall);
            }
            return self.planned;
        }
        let low = self.last_fall.wrapping_add(cfg.min_low_ticks);
        let rate = self.last_rise.wrapping_add(cfg.min_period);
        later(later(self.planned, low), rate)
    }
}

#[cfg(test)]
mod tests;
