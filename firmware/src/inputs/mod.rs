//! Switch inputs: polarity and debounce, as plain logic so host tests can
//! drive it with made-up levels and times.
//!
//! The firmware splits the work over two priorities. An edge interrupt
//! (EXTI) masks its line at once, so a bouncing contact costs one interrupt
//! and not hundreds, and acts on the first edge of the inputs in
//! [`INSTANT`] (see [`acts_now`]): a limit or the e-stop must not wait for a
//! debounce delay. A periodic task then owns a [`Debounce`]: it hears about
//! the edges, samples the levels, and says when an input has settled (its
//! new level, and whether its line may be unmasked again).
//!
//! Bits, the same in every mask here: 0-2 X/Y/Z limit, 3 probe, 4 feed hold,
//! 5 cycle start, 6 reset/e-stop. A set bit means "active" (switch closed
//! after the `$5`/`$6` inverts), never a raw pin level. The limits are the
//! boards' switch inputs, not the axis count ([`LIMIT_INPUTS`]): axis `i`'s
//! limit is bit `i` here as in the stepper's `Switches` and the report.

mod panel;
pub use panel::{act, heartbeat, on_edge, Acted};

/// Axes with a limit switch input: the first three (X, Y, Z), as the
/// boards wire them; a rotary axis (A, B, C) has none.
pub const LIMIT_INPUTS: usize = 3;
const _: () = assert!(LIMIT_INPUTS <= crate::AXES);

pub const LIMIT_X: u8 = 1 << 0;
pub const LIMIT_Y: u8 = 1 << 1;
pub const LIMIT_Z: u8 = 1 << 2;
pub const LIMITS: u8 = (1 << LIMIT_INPUTS) - 1;
pub const PROBE: u8 = 1 << 3;
pub const FEED_HOLD: u8 = 1 << 4;
pub const CYCLE_START: u8 = 1 << 5;
pub const ESTOP: u8 = 1 << 6;
pub const ALL: u8 = 0x7F;

/// Inputs that act on their first edge, with no delay: a limit or the
/// e-stop that waited for a contact to stop bouncing would let the machine
/// drive on for that long, and a feed hold must act within a millisecond
/// (a hold on a glitch only pauses the job; the operator resumes it). They
/// re-arm only after a settled *release*, so a switch held closed raises
/// one event, not one per bounce. (The probe is here for its status bit;
/// probing itself is timed by the step interrupt, which reads the pin at
/// every step event.)
pub const INSTANT: u8 = LIMITS | PROBE | FEED_HOLD | ESTOP;

/// Cycle start acts only once its new level has held for the settle time:
/// a glitch on a long cable must not resume a job.
pub const BUTTONS: u8 = CYCLE_START;

/// The inverts that apply to the inputs, from the settings: `$5` limits,
/// `$6` probe and `$14` control inputs (bit 0 e-stop, 1 feed hold, 2 cycle
/// start), which GRBL defines on the switch, not on the pin.
pub fn invert_mask(limit_invert: u8, probe_invert: bool, control_invert: u8) -> u8 {
    let control = [(1, ESTOP), (2, FEED_HOLD), (4, CYCLE_START)]
        .iter()
        .filter(|(bit, _)| control_invert & bit != 0)
        .fold(0, |acc, (_, input)| acc | input);
    (limit_invert & LIMITS) | if probe_invert { PROBE } else { 0 } | control
}

/// Active levels from the closed-to-ground levels (`closed`, bit set = pin
/// pulled low) and an [`invert_mask`].
pub fn active(closed: u8, invert: u8) -> u8 {
    (closed ^ invert) & ALL
}

/// What an edge interrupt acts on at once: the instant inputs among the
/// lines that fired which are active now (an opening edge does nothing).
pub fn acts_now(fired: u8, active: u8) -> u8 {
    fired & active & INSTANT
}

/// Active inputs as the status report's `Pn:` bits.
pub fn report_pins(active: u8) -> u16 {
    use protocol::msg::pins;
    const MAP: [(u8, u16); 4] = [
        (PROBE, pins::PROBE),
        (FEED_HOLD, pins::HOLD),
        (CYCLE_START, pins::START),
        (ESTOP, pins::RESET),
    ];
    let limits = (0..LIMIT_INPUTS)
        .filter(|i| active & (1 << i) != 0)
        .fold(0, |acc, i| acc | pins::limit(i));
    MAP.iter()
        .filter(|(bit, _)| active & bit != 0)
        .fold(limits, |acc, (_, pin)| acc | pin)
}

/// What one call to [`Debounce`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Change {
    /// Inputs whose debounced level became active.
    pub pressed: u8,
    /// Inputs whose debounced level became inactive.
    pub released: u8,
    /// Inputs whose edge line may be unmasked again.
    pub rearm: u8,
}

/// Debounce state of every input, owned by one periodic task.
///
/// Times are milliseconds from any wrapping clock; only differences count.
#[derive(Clone, Debug)]
pub struct Debounce {
    settle_ms: u32,
    /// Debounced levels.
    stable: u8,
    /// Inputs whose line is masked, waiting to settle.
    masked: u8,
    /// Level at the last sample, per input.
    last: u8,
    /// When each masked input's level last changed.
    since: [u32; 7],
}

impl Debounce {
    /// `active` is the level at start-up: it counts as settled, so a switch
    /// already closed at power-up is not an event (GRBL does the same).
    pub fn new(settle_ms: u32, active: u8) -> Self {
        Debounce {
            settle_ms,
            stable: active & ALL,
            masked: 0,
            last: active & ALL,
            since: [0; 7],
        }
    }

    /// Debounced levels.
    pub fn stable(&self) -> u8 {
        self.stable
    }

    /// Inputs whose line is masked (waiting for [`poll`](Self::poll)).
    pub fn masked(&self) -> u8 {
        self.masked
    }

    /// The lines in `fired` had an edge and are masked now; `active` are the
    /// levels read now. Instant inputs that are active are reported pressed
    /// at once (the interrupt has acted on them already).
    pub fn edge(&mut self, fired: u8, active: u8, now: u32) -> Change {
        let fired = fired & ALL;
        self.masked |= fired;
        for i in bits(fired) {
            self.since[i] = now;
        }
        self.last = (self.last & !fired) | (active & fired);
        let pressed = acts_now(fired, active) & !self.stable;
        self.stable |= pressed;
        Change {
            pressed,
            ..Change::default()
        }
    }

    /// Periodic re-check of the masked inputs with the levels read now. An
    /// input settles when its level has not changed for the settle time;
    /// then its debounced level follows and its line is re-armed, except an
    /// instant input that is still active: it stays masked until released.
    pub fn poll(&mut self, active: u8, now: u32) -> Change {
        let mut out = Change::default();
        let moved = (active ^ self.last) & self.masked;
        for i in bits(moved) {
            self.since[i] = now;
        }
        self.last = active & ALL;
        for i in bits(self.masked) {
            if now.wrapping_sub(self.since[i]) < self.settle_ms {
                continue;
            }
            let bit = 1u8 << i;
            let level = active & bit;
            if level != self.stable & bit {
                if level != 0 {
                    out.pressed |= bit;
                } else {
                    out.released |= bit;
                }
                self.stable ^= bit;
            }
            if bit & INSTANT == 0 || level == 0 {
                self.masked &= !bit;
                out.rearm |= bit;
            }
        }
        out
    }
}

/// Indices of the set bits of `mask` (inputs 0..7).
fn bits(mask: u8) -> impl Iterator<Item = usize> {
    (0..7).filter(move |i| mask & (1 << i) != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SETTLE: u32 = 20;

    #[test]
    fn inverts_apply_to_their_own_inputs() {
        let act =
            |closed, limits, probe, control| active(closed, invert_mask(limits, probe, control));
        assert_eq!(act(0, 0, false, 0), 0);
        assert_eq!(act(LIMIT_Y, 0, false, 0), LIMIT_Y);
        // $5 = 0b101: X and Z read inverted, Y not.
        assert_eq!(act(0, 0b101, false, 0), LIMIT_X | LIMIT_Z);
        assert_eq!(act(PROBE | FEED_HOLD, 0, true, 0), FEED_HOLD);
        // Bits above the limits in $5 do not touch the buttons.
        assert_eq!(act(0, 0xF8, false, 0), 0);
        // $14 bit 0: a normally-closed e-stop is active when its pin opens
        // (a cut wire stops the machine); the rest are not touched.
        assert_eq!(act(ESTOP, 0, false, 1), 0);
        assert_eq!(act(0, 0, false, 1), ESTOP);
        assert_eq!(act(0, 0, false, 0b110), FEED_HOLD | CYCLE_START);
        assert_eq!(act(0, 0, false, 0xF8), 0);
    }

    #[test]
    fn limit_acts_on_the_first_edge() {
        let mut d = Debounce::new(SETTLE, 0);
        assert_eq!(acts_now(LIMIT_X, LIMIT_X), LIMIT_X);
        let c = d.edge(LIMIT_X, LIMIT_X, 100);
        assert_eq!(c.pressed, LIMIT_X, "no debounce delay for a limit");
        assert_eq!(d.masked(), LIMIT_X);
        // An opening edge of a limit does nothing by itself.
        assert_eq!(acts_now(LIMIT_X, 0), 0);
    }

    #[test]
    fn held_limit_stays_masked_until_a_settled_release() {
        let mut d = Debounce::new(SETTLE, 0);
        d.edge(LIMIT_Z, LIMIT_Z, 0);
        // Closed and steady for long: still masked, nothing new.
        assert_eq!(d.poll(LIMIT_Z, 50), Change::default());
        assert_eq!(d.masked(), LIMIT_Z);
        // Released, bouncing: not yet.
        assert_eq!(d.poll(0, 60).rearm, 0);
        assert_eq!(d.poll(LIMIT_Z, 65).rearm, 0);
        assert_eq!(d.poll(0, 70).rearm, 0);
        assert_eq!(
            d.poll(0, 85).rearm,
            0,
            "15 ms open is below the settle time"
        );
        let c = d.poll(0, 90);
        assert_eq!(c.released, LIMIT_Z);
        assert_eq!(c.rearm, LIMIT_Z);
        assert_eq!(d.masked(), 0);
        assert_eq!(d.stable(), 0);
    }

    #[test]
    fn button_needs_a_settled_press() {
        let mut d = Debounce::new(SETTLE, 0);
        let c = d.edge(CYCLE_START, CYCLE_START, 1000);
        assert_eq!(c.pressed, 0, "cycle start never acts on the edge");
        assert_eq!(d.poll(CYCLE_START, 1010), Change::default());
        let c = d.poll(CYCLE_START, 1020);
        assert_eq!(c.pressed, CYCLE_START);
        assert_eq!(c.rearm, CYCLE_START, "a button re-arms while held");
        // Held on: no second press.
        assert_eq!(d.poll(CYCLE_START, 1100), Change::default());
    }

    #[test]
    fn feed_hold_acts_on_the_first_edge_once() {
        let mut d = Debounce::new(SETTLE, 0);
        assert_eq!(acts_now(FEED_HOLD, FEED_HOLD), FEED_HOLD);
        let c = d.edge(FEED_HOLD, FEED_HOLD, 1000);
        assert_eq!(c.pressed, FEED_HOLD, "no settle delay for a hold");
        // Bouncing and held: no second press, masked until released.
        assert_eq!(d.poll(0, 1002).pressed, 0);
        assert_eq!(d.poll(FEED_HOLD, 1004).pressed, 0);
        assert_eq!(d.poll(FEED_HOLD, 1100), Change::default());
        assert_eq!(d.masked(), FEED_HOLD);
        let c = d.poll(0, 1200);
        assert_eq!(d.poll(0, 1220).rearm | c.rearm, FEED_HOLD);
    }

    #[test]
    fn button_glitch_is_ignored() {
        let mut d = Debounce::new(SETTLE, 0);
        d.edge(CYCLE_START, CYCLE_START, 0);
        // Back open at the first re-check, and it stays open.
        assert_eq!(d.poll(0, 10).pressed, 0);
        let c = d.poll(0, 30);
        assert_eq!((c.pressed, c.released), (0, 0));
        assert_eq!(c.rearm, CYCLE_START);
        assert_eq!(d.stable(), 0);
    }

    #[test]
    fn bouncing_restarts_the_settle_time() {
        let mut d = Debounce::new(SETTLE, 0);
        d.edge(CYCLE_START, CYCLE_START, 0);
        d.poll(0, 10);
        d.poll(CYCLE_START, 18);
        // 18 + 20 > 30: not settled yet though the first edge was 30 ms ago.
        assert_eq!(d.poll(CYCLE_START, 30).pressed, 0);
        assert_eq!(d.poll(CYCLE_START, 38).pressed, CYCLE_START);
    }

    #[test]
    fn clock_wrap_does_not_stall() {
        let mut d = Debounce::new(SETTLE, 0);
        d.edge(CYCLE_START, CYCLE_START, u32::MAX - 5);
        assert_eq!(d.poll(CYCLE_START, 14).pressed, CYCLE_START);
    }

    #[test]
    fn closed_at_power_up_is_no_event() {
        let mut d = Debounce::new(SETTLE, LIMIT_X);
        assert_eq!(d.stable(), LIMIT_X);
        assert_eq!(d.poll(LIMIT_X, 100), Change::default());
        // Its release (an edge) settles as a release.
        d.edge(LIMIT_X, 0, 200);
        assert_eq!(d.poll(0, 220).released, LIMIT_X);
    }

    #[test]
    fn unrelated_inputs_are_untouched() {
        let mut d = Debounce::new(SETTLE, 0);
        d.edge(LIMIT_X, LIMIT_X, 0);
        // Cycle start reads closed but had no edge: not masked, not reported.
        let c = d.poll(LIMIT_X | CYCLE_START, 100);
        assert_eq!(c, Change::default());
        assert_eq!(d.masked(), LIMIT_X);
    }

    #[test]
    fn report_pins_map_to_grbl_letters() {
        use protocol::msg::pins;
        assert_eq!(report_pins(0), 0);
        assert_eq!(
            report_pins(LIMIT_X | PROBE | ESTOP),
            pins::LIMIT_X | pins::PROBE | pins::RESET
        );
        assert_eq!(
            report_pins(FEED_HOLD | CYCLE_START),
            pins::HOLD | pins::START
        );
    }
}
