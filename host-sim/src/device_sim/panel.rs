//! The virtual board's switch inputs: e-stop, feed hold, cycle start, the
//! probe's status bit and limits that close at rest (the machine pushed),
//! as levels a test sets at a virtual time.
//!
//! This is the board's `inputs.rs` without its registers: an input's edge
//! masks its line and goes to `burin::inputs::on_edge` at once (the EXTI
//! interrupt), and while a line is masked a 10 ms heartbeat on the board's
//! grid (`burin::inputs::heartbeat`) samples the levels, acts on settled
//! presses and unmasks. What an input does is the library's decision, so
//! the tests of these inputs test the board's behaviour.
//!
//! Levels are "active" levels: the `$5`/`$6`/`$14` inverts apply on the
//! board between the pin and these. The world's own limit switches, which
//! the machine reaches by moving, keep reaching the step interrupt through
//! its switch reads (`engine::world`), as the board's step interrupt reads
//! its pins at every event.

use burin::inputs::{self as inp, Debounce};

use super::VirtualDevice;

/// The board's input settle time and heartbeat period, ms
/// (`burin-fw`'s `inputs::SETTLE_MS` and `HEARTBEAT_HZ`).
pub const SETTLE_MS: u32 = 20;
const BEAT_MS: u64 = 10;

/// Input state of the virtual board.
#[derive(Debug)]
pub struct Panel {
    /// Active levels as the test set them.
    levels: u8,
    deb: Debounce,
    /// Lines whose edge fired since the last beat, and those of them that
    /// acted (the board's `EDGES` word).
    edges: u8,
    seen: u8,
    /// The next heartbeat that has work (a masked line), in ticks.
    next_beat: Option<u64>,
}

impl Default for Panel {
    fn default() -> Self {
        Panel {
            levels: 0,
            deb: Debounce::new(SETTLE_MS, 0),
            edges: 0,
            seen: 0,
            next_beat: None,
        }
    }
}

impl Panel {
    /// Debounced inputs as the status report's `Pn:` bits.
    pub fn report_pins(&self) -> u16 {
        inp::report_pins(self.deb.stable())
    }

    fn masked(&self) -> u8 {
        self.deb.masked() | self.edges
    }
}

impl VirtualDevice<'_> {
    /// Set input `bit` (a `burin::inputs` bit: `ESTOP`, `FEED_HOLD`,
    /// `CYCLE_START`, `PROBE`, `LIMIT_X`...) active or not, now. An edge
    /// on an armed line acts as the board's interrupt does; the parse task
    /// runs at once when the library says to wake it.
    pub fn set_input(&mut self, bit: u8, active: bool) {
        let now = self.sim.now();
        let next = self.next_beat_after(now);
        let p = &mut self.panel;
        let before = p.levels;
        p.levels = if active { before | bit } else { before & !bit };
        let fired = (before ^ p.levels) & !p.masked();
        if fired == 0 {
            return;
        }
        p.edges |= fired;
        let acted = inp::on_edge(&self.sim.rt, fired, p.levels, &mut |c| self.flags.raise(c));
        p.seen |= acted.inputs;
        p.next_beat.get_or_insert(next);
        self.obey(acted);
    }

    /// The first heartbeat after `tick`, on the board's 10 ms grid.
    fn next_beat_after(&self, tick: u64) -> u64 {
        let period = (u64::from(self.sim.tick_hz()) * BEAT_MS / 1000).max(1);
        (tick / period + 1) * period
    }

    /// The heartbeat due at or before `tick`, if one is.
    pub(super) fn beat_due(&self, tick: u64) -> Option<u64> {
        self.panel.next_beat.filter(|b| *b <= tick)
    }

    /// The heartbeat's input work at `at` (ticks).
    pub(super) fn beat(&mut self, at: u64) {
        let ms = (at * 1000 / u64::from(self.sim.tick_hz().max(1))) as u32;
        let next = self.next_beat_after(at);
        let p = &mut self.panel;
        let (edges, seen) = (p.edges, p.seen);
        (p.edges, p.seen) = (0, 0);
        let (_, acted) = inp::heartbeat(
            &self.sim.rt,
            &mut p.deb,
            edges,
            seen,
            p.levels,
            ms,
            &mut |c| self.flags.raise(c),
        );
        p.next_beat = (p.masked() != 0).then_some(next);
        self.obey(acted);
    }

    /// What the library asked of the shell after an input event: the
    /// outputs cut (an e-stop), the parse task run now (as the board's
    /// wake-up does).
    fn obey(&mut self, acted: inp::Acted) {
        if acted.cut_outputs {
            self.cut_outputs();
        }
        if acted.wake {
            self.poll();
        }
    }

    /// The e-stop's immediate cut of spindle and coolant at the pins (the
    /// board's `kill_aux`), before the session's reset gets to them.
    fn cut_outputs(&mut self) {
        if let Some(mut pins) = self.pins {
            pins.spindle.enable = false;
            pins.spindle.duty = 0.0;
            pins.flood = false;
            pins.mist = false;
            if self.pins != Some(pins) {
                self.pins = Some(pins);
                self.pin_log.push((self.sim.now(), pins));
            }
        }
    }
}
