//! Flags and counters shared between the USB interrupt (which catches the
//! realtime bytes `!` `~` `0x18` and the override bytes), the step interrupt
//! and the parse/plan task.
//!
//! Everything is a plain atomic so that no priority ever waits on a lock a
//! lower priority holds. The struct is an instance, not a set of statics, so
//! host-sim can run many machines side by side (tests run in parallel); the
//! firmware keeps one in a `static`.

use core::sync::atomic::{AtomicBool, AtomicI32, AtomicU32, AtomicU8, Ordering::Relaxed};

use crate::seams::StepConfigCell;
use crate::AXES;

// The bits of `Realtime::attention`, which the step event tests against
// its segment's own (`stepper::Running::sense`).
/// Read the switches: the segment watches one (homing, probing).
pub(crate) const SENSE_WATCH: u8 = 1;
/// Read the switches: hard limits (while armed).
pub(crate) const SENSE_HARD: u8 = 2;
/// A new generation the stepper has not looked at yet.
pub(crate) const SENSE_FLUSH: u8 = 4;
/// The segment moves B or C: always set here, so such a segment's every
/// event takes the out-of-line path, and the common one (X-A) tests
/// nothing more than the three reasons above.
pub(crate) const SENSE_EXTRA: u8 = 8;

/// Why the stepper stopped on its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trip {
    None = 0,
    /// A watched homing switch closed (homing seek/locate, G27).
    Homing = 1,
    /// The probe reached the state the G38.x move waits for.
    Probe = 2,
    /// A limit switch closed during normal motion (hard limit).
    HardLimit = 3,
}

/// The shared realtime state. All fields are lock-free atomics.
#[derive(Debug)]
pub struct Realtime {
    /// Feed hold requested (`!`); cleared by cycle start.
    hold: AtomicBool,
    /// Cycle start (`~`) requested and not yet seen by the planner task.
    cycle_start: AtomicBool,
    /// Soft reset (0x18) requested.
    reset: AtomicBool,
    /// The e-stop input is active (set by the board from the pin).
    estop: AtomicBool,
    /// The safety door input reads open (a board with a door switch sets
    /// it; without one, GRBL's default, the door counts as closed and only
    /// 0x84 opens it, for an instant).
    door_open: AtomicBool,
    /// A failed hardware path ([`crate::chip::HwFault`] code, 0: none):
    /// latched until the chip resets.
    hw_fault: AtomicU8,
    feed_override: AtomicU8,
    rapid_override: AtomicU8,
    override_epoch: AtomicU32,
    /// Segment generation: the stepper drops segments from older generations,
    /// which is how the planner task flushes the queue it cannot pop.
    generation: AtomicU32,
    underruns: AtomicU32,
    trip: AtomicU8,
    /// Axes whose switch caused the trip (limit switches) or the probe bit.
    trip_mask: AtomicU8,
    /// Machine position in steps, written by the stepper as it steps: the
    /// tool's, without backlash take-up steps (those go to `takeup`).
    position: [AtomicI32; AXES],
    /// Signed backlash take-up steps the stepper has loaded since power-up
    /// (a take-up segment's whole steps when it starts): the motors stand
    /// at `position + takeup` once it has finished.
    takeup: [AtomicI32; AXES],
    /// Position at the moment of the last trip.
    trip_position: [AtomicI32; AXES],
    /// The stepper has no segment and the timer is stopped.
    stepper_idle: AtomicBool,
    /// The step driver runs (its timer is armed); written only by the
    /// step interrupt. While false the task starts it by pending the
    /// interrupt once segments are queued.
    stepping: AtomicBool,
    /// A new position for the stepper (after homing), taken at its next segment.
    new_position: [AtomicI32; AXES],
    new_position_set: AtomicBool,
    /// Path speed of the segment the stepper runs (f32 bits, mm/min) and
    /// its source line: the status report's `FS:` and `Ln:` (published once
    /// per segment, not per step).
    running_speed: AtomicU32,
    running_line: AtomicU32,
    running_cut: AtomicU32,
    /// What makes the step event leave its plain Bresenham path
    /// ([`SENSE_WATCH`], [`SENSE_HARD`], [`SENSE_FLUSH`]), against the running segment's own reasons:
    /// reading the switches for the segment's watch (always) and for hard
    /// limits (while armed: `$21` on, not homing, not in alarm, decided by
    /// the controller each pass), and a flush (a new generation, until the
    /// stepper has seen it). One byte, so the event tests all three with
    /// one load and one AND; the board's limit interrupts read it too.
    attention: AtomicU8,
    /// The step interrupt's configuration after a `$n=`, taken by the step
    /// driver while it is stopped (`seams::StepConfigCell`).
    step_config: StepConfigCell,
}

impl Default for Realtime {
    fn default() -> Self {
        Self::new()
    }
}

impl Realtime {
    pub const fn new() -> Self {
        Realtime {
            hold: AtomicBool::new(false),
            cycle_start: AtomicBool::new(false),
            reset: AtomicBool::new(false),
            estop: AtomicBool::new(false),
            door_open: AtomicBool::new(false),
            hw_fault: AtomicU8::new(0),
            feed_override: AtomicU8::new(100),
            rapid_override: AtomicU8::new(100),
            override_epoch: AtomicU32::new(0),
            generation: AtomicU32::new(0),
            underruns: AtomicU32::new(0),
            trip: AtomicU8::new(0),
            trip_mask: AtomicU8::new(0),
            position: [const { AtomicI32::new(0) }; AXES],
            trip_position: [const { AtomicI32::new(0) }; AXES],
            takeup: [const { AtomicI32::new(0) }; AXES],
            stepper_idle: AtomicBool::new(true),
            stepping: AtomicBool::new(false),
            new_position: [const { AtomicI32::new(0) }; AXES],
            new_position_set: AtomicBool::new(false),
            running_speed: AtomicU32::new(0),
            running_line: AtomicU32::new(0),
            running_cut: AtomicU32::new(0),
            attention: AtomicU8::new(SENSE_WATCH | SENSE_EXTRA),
            step_config: StepConfigCell::new(),
        }
    }

    /// `!`: decelerate to a stop along the path.
    pub fn feed_hold(&self) {
        self.hold.store(true, Relaxed);
    }
    /// `~`: resume after a hold (or M0 pause).
    pub fn cycle_start(&self) {
        self.cycle_start.store(true, Relaxed);
    }
    /// 0x18: stop at once and flush everything.
    pub fn request_reset(&self) {
        self.reset.store(true, Relaxed);
    }
    /// The e-stop input's level. While it is active the machine stays in
    /// alarm (it latches there: pressing it raises the alarm, and `$X` and
    /// homing are refused until it is released).
    pub fn set_estop(&self, active: bool) {
        self.estop.store(active, Relaxed);
    }
    pub fn estop(&self) -> bool {
        self.estop.load(Relaxed)
    }
    /// The door switch's level. Its opening edge is the shell's to turn
    /// into [`protocol::Rt::SafetyDoor`], as 0x84; resuming waits for the
    /// level to read closed (`suspend`).
    pub fn set_door_open(&self, open: bool) {
        self.door_open.store(open, Relaxed);
    }
    pub fn door_open(&self) -> bool {
        self.door_open.load(Relaxed)
    }
    /// A hardware path failed (a boot self-check, or the step path's error
    /// flags). Like the e-stop it latches the alarm and refuses `$X` and
    /// homing, but only a reset of the chip clears it: a machine whose
    /// pulses do not reach the drivers must not be unlocked into motion
    /// that only the position counters would make. The first fault stays.
    pub fn set_hw_fault(&self, fault: crate::chip::HwFault) {
        let _ = self
            .hw_fault
            .compare_exchange(0, fault.code(), Relaxed, Relaxed);
    }
    pub fn hw_fault(&self) -> Option<crate::chip::HwFault> {
        crate::chip::HwFault::from_code(self.hw_fault.load(Relaxed))
    }
    pub fn hold_requested(&self) -> bool {
        self.hold.load(Relaxed)
    }
    pub(crate) fn take_cycle_start(&self) -> bool {
        self.cycle_start.swap(false, Relaxed)
    }
    pub(crate) fn clear_hold(&self) {
        self.hold.store(false, Relaxed);
    }
    /// A soft reset was requested and the executor has not done it yet.
    pub fn reset_requested(&self) -> bool {
        self.reset.load(Relaxed)
    }
    pub(crate) fn take_reset(&self) -> bool {
        self.reset.swap(false, Relaxed)
    }

    /// Feed override in percent, clamped to 10–200.
    pub fn set_feed_override(&self, percent: u16) {
        let p = percent.clamp(10, 200) as u8;
        if self.feed_override.swap(p, Relaxed) != p {
            self.override_epoch.fetch_add(1, Relaxed);
        }
    }
    /// Rapid override: 25, 50 or 100 percent (other values snap down to one of them).
    pub fn set_rapid_override(&self, percent: u16) {
        let p = match percent {
            0..=37 => 25,
            38..=74 => 50,
            _ => 100,
        };
        if self.rapid_override.swap(p, Relaxed) != p {
            self.override_epoch.fetch_add(1, Relaxed);
        }
    }
    pub fn feed_override(&self) -> u8 {
        self.feed_override.load(Relaxed)
    }
    pub fn rapid_override(&self) -> u8 {
        self.rapid_override.load(Relaxed)
    }
    /// Changes whenever an override changes, so the planner knows to replan.
    pub fn override_epoch(&self) -> u32 {
        self.override_epoch.load(Relaxed)
    }

    pub fn generation(&self) -> u32 {
        self.generation.load(Relaxed)
    }
    /// A new generation, and the step event told to look (after the
    /// increment: a stepper that clears the flag in between already sees
    /// the new generation).
    pub(crate) fn bump_generation(&self) -> u32 {
        let g = self.generation.fetch_add(1, Relaxed).wrapping_add(1);
        self.attention.fetch_or(SENSE_FLUSH, Relaxed);
        g
    }
    /// The stepper looked at the generation: clears the flush flag
    /// *before* it compares, so a bump after the clear raises it again.
    pub(crate) fn take_flush(&self) -> bool {
        self.attention.fetch_and(!SENSE_FLUSH, Relaxed) & SENSE_FLUSH != 0
    }

    /// Times the stepper ran dry while motion was still going (the planner
    /// task did not keep up). Never reset except by power-up.
    pub fn underruns(&self) -> u32 {
        self.underruns.load(Relaxed)
    }
    pub(crate) fn count_underrun(&self) {
        self.underruns.fetch_add(1, Relaxed);
    }

    pub fn trip(&self) -> Trip {
        match self.trip.load(Relaxed) {
            1 => Trip::Homing,
            2 => Trip::Probe,
            3 => Trip::HardLimit,
            _ => Trip::None,
        }
    }
    pub fn trip_mask(&self) -> u8 {
        self.trip_mask.load(Relaxed)
    }
    pub fn trip_position(&self) -> [i32; AXES] {
        core::array::from_fn(|i| self.trip_position[i].load(Relaxed))
    }
    pub(crate) fn set_trip(&self, trip: Trip, mask: u8, pos: &[i32; AXES]) {
        for (a, p) in self.trip_position.iter().zip(pos) {
            a.store(*p, Relaxed);
        }
        self.trip_mask.store(mask, Relaxed);
        self.trip.store(trip as u8, Relaxed);
    }
    /// A limit-switch interrupt saw a limit close during motion. It records
    /// the same trip the stepper would at its next event (unless a trip is
    /// already there) and makes the queued segments stale, so the stepper
    /// stops at its next event whatever the pin reads by then (a bouncing
    /// switch may read open again). The planner task raises the alarm and
    /// flushes as for the stepper's own trip.
    pub fn hard_limit(&self, mask: u8) {
        if self.trip() == Trip::None {
            self.set_trip(Trip::HardLimit, mask, &self.position());
        }
        self.halt_stepper();
    }
    /// Stops the stepper at its next event (e-stop, hard limit): the
    /// running segment and everything queued become an old generation.
    /// Only the planner task's flush (reset or alarm) makes the machine
    /// consistent again; this only stops the pulses early.
    pub fn halt_stepper(&self) {
        self.bump_generation();
    }
    /// The stepper must stop without one more pulse: a hard-limit trip or
    /// the e-stop (a plain flush lets the pulse already computed run, the
    /// executor having counted it).
    pub(crate) fn halting(&self) -> bool {
        self.trip() == Trip::HardLimit || self.estop()
    }
    pub(crate) fn clear_trip(&self) {
        self.trip.store(0, Relaxed);
        self.trip_mask.store(0, Relaxed);
    }

    /// Machine position in steps as the stepper last wrote it.
    pub fn position(&self) -> [i32; AXES] {
        core::array::from_fn(|i| self.position[i].load(Relaxed))
    }
    pub(crate) fn store_position(&self, axis: usize, steps: i32) {
        if let Some(a) = self.position.get(axis) {
            a.store(steps, Relaxed);
        }
    }
    /// Backlash take-up steps loaded so far, per axis (see `takeup`):
    /// at rest, the motors' position is [`Self::position`] plus this.
    pub fn takeup(&self) -> [i32; AXES] {
        core::array::from_fn(|i| self.takeup[i].load(Relaxed))
    }
    pub(crate) fn add_takeup(&self, axis: usize, steps: i32) {
        if let Some(a) = self.takeup.get(axis) {
            a.store(a.load(Relaxed).wrapping_add(steps), Relaxed);
        }
    }
    pub fn stepper_idle(&self) -> bool {
        self.stepper_idle.load(Relaxed)
    }
    /// Nothing moves: the stepper is stopped, or runs a segment that
    /// steps nothing at speed 0 (a dwell). A hold is complete (`Hold:0`)
    /// and a reset loses no position from here, as in GRBL.
    pub fn at_rest(&self) -> bool {
        self.stepper_idle() || self.running().0 == 0.0
    }
    pub(crate) fn set_stepper_idle(&self, idle: bool) {
        self.stepper_idle.store(idle, Relaxed);
    }
    /// The step driver is running: no kick needed (see `stepper::driver`).
    pub fn stepping(&self) -> bool {
        self.stepping.load(core::sync::atomic::Ordering::Acquire)
    }
    pub(crate) fn set_stepping(&self, on: bool) {
        self.stepping
            .store(on, core::sync::atomic::Ordering::Release);
    }

    /// Redefine the machine position (homing). Only while the stepper is idle;
    /// it adopts the value before its next step.
    pub(crate) fn redefine_position(&self, pos: &[i32; AXES]) {
        for (i, p) in pos.iter().enumerate() {
            self.new_position[i].store(*p, Relaxed);
            self.position[i].store(*p, Relaxed);
        }
        self.new_position_set.store(true, Relaxed);
    }
    /// Speed (mm/min) and source line of the running segment; (0, 0)
    /// while the stepper is idle.
    pub fn running(&self) -> (f32, u32) {
        (
            f32::from_bits(self.running_speed.load(Relaxed)),
            self.running_line.load(Relaxed),
        )
    }
    pub(crate) fn set_running(&self, speed_mm_min: f32, line: u32, cut: f32) {
        self.running_speed.store(speed_mm_min.to_bits(), Relaxed);
        self.running_line.store(line, Relaxed);
        self.running_cut.store(cut.to_bits(), Relaxed);
    }
    /// The running segment's `Segment::cut` (0 while idle): laser mode
    /// fires only while it is above 0.
    pub fn running_cut(&self) -> f32 {
        f32::from_bits(self.running_cut.load(Relaxed))
    }
    /// Whether a closed limit switch trips now (see the field).
    pub fn limits_armed(&self) -> bool {
        self.attention() & SENSE_HARD != 0
    }
    /// Read-modify-write, not a store: the flush flag shares the byte.
    pub fn set_limits_armed(&self, armed: bool) {
        if armed != self.limits_armed() {
            if armed {
                self.attention.fetch_or(SENSE_HARD, Relaxed);
            } else {
                self.attention.fetch_and(!SENSE_HARD, Relaxed);
            }
        }
    }
    /// The reasons that take the step event off its plain path now (see
    /// the field).
    #[inline(always)]
    pub(crate) fn attention(&self) -> u8 {
        self.attention.load(Relaxed)
    }

    /// Tests: the flush flag raised without a new generation (a stale one).
    #[cfg(test)]
    pub(crate) fn raise_stale_flush(&self) {
        self.attention.fetch_or(SENSE_FLUSH, Relaxed);
    }

    /// Where the parse task publishes a new step configuration and the
    /// step driver takes it.
    pub fn step_config(&self) -> &StepConfigCell {
        &self.step_config
    }

    pub(crate) fn take_new_position(&self) -> Option<[i32; AXES]> {
        if self.new_position_set.swap(false, Relaxed) {
            Some(core::array::from_fn(|i| self.new_position[i].load(Relaxed)))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hard_limit_keeps_an_earlier_trip() {
        let rt = Realtime::new();
        rt.set_trip(Trip::Probe, 0, &[5; AXES]);
        let g = rt.generation();
        rt.hard_limit(0b100);
        assert_eq!(rt.trip(), Trip::Probe);
        assert_eq!(rt.trip_position(), [5; AXES]);
        assert_ne!(rt.generation(), g, "the stepper still stops");
    }
}
