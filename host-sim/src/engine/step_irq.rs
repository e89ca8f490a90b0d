//! The step interrupt (RTIC priority 3) in virtual time: the core's step
//! driver on [`VirtualHw`], entered when its compare target comes due (late
//! by the machine's [`Interrupts`](crate::config::Interrupts) model), and
//! what its pin stores did to the world, the statistics and the recorder.

use burin::stepper::StepEvent;
use burin::AXES;

use super::pins::Wired;
use super::{Edge, Sim};
use crate::record::PinEvent;

impl Sim<'_> {
    /// Prio 3: one step interrupt (a kick, a rise or a fall, see
    /// `burin::stepper::driver`), then what its pin stores did.
    pub(super) fn step_event(&mut self) {
        self.stats.work += 1;
        let underruns = self.rt.underruns();
        let was_running = self.driver.is_running();
        self.hw.enter(self.now);
        let queue = &mut self.queue;
        let mut pop = || queue.dequeue();
        let (hw, world) = (&mut self.hw, &mut self.world);
        if hw.hardware_fall() {
            let mut hw = Wired::<true> { hw, world };
            self.driver
                .on_interrupt(&mut self.stepper, &mut hw, &self.rt, &mut pop);
        } else {
            let mut hw = Wired::<false> { hw, world };
            self.driver
                .on_interrupt(&mut self.stepper, &mut hw, &self.rt, &mut pop);
        }
        if was_running && !self.driver.is_running() && self.rt.underruns() == underruns {
            // Ran dry at a planned stop: a starved planner if the stop was
            // only there because the next line had not arrived or been parsed.
            let running = self.machine.motion.hold() == burin::stepper::prep::Hold::Running
                && !self.rt.hold_requested();
            let waiting = !self.lines.is_empty()
                || (self.device_mode && self.input_pending && !self.task_syncing);
            if running && self.machine.ready() && waiting {
                self.stats.starved += 1;
            }
        }
        self.apply_stores();
        let spm = self.machine.settings().axes.map(|a| a.steps_per_mm);
        self.stats.deviation.check(&self.world.tool_mm(&spm));
        let v = self.stepper.speed_mm_min();
        if v != self.stats.last_speed {
            self.stats.last_speed = v;
            if v <= 0.0 {
                // As the plot's speed panel does (`crate::feed`).
                self.stats.feed.stop();
            }
            self.rec.velocity(self.now, v);
        }
        let done = self.hw.done_at();
        self.next_step = self.hw.target.map(|t| self.masks.unmasked_at(t.max(done)));
    }

    /// The handler's pin stores (the world already moved at each rising
    /// edge): statistics, and the recorder, which sees each rise with the
    /// position the stepper had after that event.
    fn apply_stores(&mut self) {
        let stores = std::mem::take(&mut self.hw.stores);
        // The stepper already counted the event after the last rise: walk
        // back over it and this handler's rises to where the first rise
        // started, then forward again rise by rise (no allocation per event).
        // The motors' position: backlash take-up steps included.
        let mut pos = self.stepper.motor_position(&self.rt);
        unstep(&mut pos, self.driver.pending());
        for e in stores.iter().rev().filter(|e| e.step != 0) {
            move_by(&mut pos, e.dir, e.step, -1);
        }
        for e in &stores {
            if e.dir != self.stats.dir {
                self.stats.dir = e.dir;
                self.stats.dir_changed = e.tick;
            }
            if e.step == 0 {
                if self.stats.step_level != 0 {
                    self.rec.step_fall(e.tick, self.stats.step_level);
                }
                self.stats.step_level = 0;
                continue;
            }
            // Only a rising edge is a step: a pin left high by a pulse
            // that never ended (a failed pulse-end path) moves nothing.
            let rising = e.step & !self.stats.step_level;
            self.stats.step_level = e.step;
            if rising == 0 {
                continue;
            }
            move_by(&mut pos, e.dir, e.step, 1);
            for i in 0..AXES {
                self.stats.steps[i] += u64::from(rising >> i & 1);
            }
            let _ = self.stats.feed.step(e.tick, pos.map(i64::from));
            self.rec.step_event(&PinEvent {
                tick: e.tick,
                dir_mask: e.dir,
                step_mask: e.step,
                dir_changed_tick: self.stats.dir_changed,
                pos: pos.map(i64::from),
            });
        }
        self.hw.stores = stores;
    }

    /// Keep every pin store of the run from now on (see [`Sim::edges`]).
    pub fn record_edges(&mut self) {
        self.hw.log.get_or_insert_with(Vec::new);
    }

    /// Every pin store since [`Sim::record_edges`]: step and direction
    /// levels after it, at its tick.
    pub fn edges(&self) -> &[Edge] {
        self.hw.log.as_deref().unwrap_or(&[])
    }
}

/// Takes an event's steps back out of `pos`.
fn unstep(pos: &mut [i32; AXES], ev: &StepEvent) {
    move_by(pos, ev.dir_mask, ev.step_mask, -1);
}

/// Applies the steps of `step` in directions `dir` to `pos`, `sign` times
/// (1: forward, -1: taken back).
fn move_by(pos: &mut [i32; AXES], dir: u8, step: u8, sign: i32) {
    for (i, p) in pos.iter_mut().enumerate() {
        if step & (1 << i) != 0 {
            *p += sign * if dir & (1 << i) != 0 { -1 } else { 1 };
        }
    }
}
