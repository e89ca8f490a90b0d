//! What the machine does when a switch input changes: limits, e-stop and
//! the panel buttons, decided here once for both shells.
//!
//! The board's EXTI interrupts and its heartbeat, and host-sim's timed
//! input levels and virtual heartbeat, only sample levels, mask and unmask
//! lines and keep time; they call [`on_edge`] when an input's line fires
//! and [`heartbeat`] every 10 ms, and do what these return (cut the
//! outputs on an e-stop, re-arm lines). So a limit that closes at rest, an
//! e-stop, a feed-hold or cycle-start button act the same on the board and
//! in host-sim's tests.

use super::{acts_now, Change, Debounce, CYCLE_START, ESTOP, FEED_HOLD, LIMITS};
use crate::realtime::Realtime;
use protocol::Rt;

/// What an input event asks of the shell beyond the machine's state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Acted {
    /// Inputs acted on (the board records them, so the heartbeat does not
    /// act on the same press again when it settles).
    pub inputs: u8,
    /// The e-stop acted: cut spindle, coolant and laser at the pins now,
    /// before the session's reset gets to them.
    pub cut_outputs: bool,
    /// Something the parse task must hear of: wake it.
    pub wake: bool,
}

/// Act on presses: `pressed` are inputs that became active (on their
/// first edge for the instant inputs, once settled for the rest).
/// Realtime commands go to `raise` exactly as if the host had sent them.
///
/// - a limit trips the hard-limit alarm if limits are armed; as in GRBL
///   also at rest: a switch that closes while nothing moves means the
///   machine was pushed or the wiring picks up noise, and either wants the
///   operator (alarm 1, position flagged lost as after any hard limit);
/// - the e-stop stops the pulses at the next step event, latches the
///   e-stop level and resets (as 0x18);
/// - feed hold and cycle start are `!` and `~`.
pub fn act(rt: &Realtime, pressed: u8, raise: &mut impl FnMut(Rt)) -> Acted {
    let mut out = Acted::default();
    let limits = pressed & LIMITS;
    if limits != 0 && rt.limits_armed() {
        rt.hard_limit(limits);
        out.inputs |= limits;
        out.wake = true;
    }
    if pressed & ESTOP != 0 {
        rt.set_estop(true);
        rt.halt_stepper();
        raise(Rt::SoftReset);
        out.inputs |= ESTOP;
        out.cut_outputs = true;
        out.wake = true;
    }
    for (bit, cmd) in [(FEED_HOLD, Rt::FeedHold), (CYCLE_START, Rt::CycleStart)] {
        if pressed & bit != 0 {
            raise(cmd);
            out.inputs |= bit;
            out.wake = true;
        }
    }
    out
}

/// An edge interrupt's decision: of the lines that `fired` (and are masked
/// now), the instant inputs that read `active` act at once. The rest wait
/// for the heartbeat to see them settle.
pub fn on_edge(rt: &Realtime, fired: u8, active: u8, raise: &mut impl FnMut(Rt)) -> Acted {
    act(rt, acts_now(fired, active), raise)
}

/// The heartbeat's input work at `now` (ms): `edges` are the lines whose
/// interrupt fired since the last beat and `seen` those of them it acted
/// on, `active` the levels read now. Settled presses act ([`act`]), late
/// rather than never for an instant input whose interrupt read it open
/// (a bounce); the e-stop's level is latched once it has settled (its
/// interrupt set it already on the first edge). Returns the debounce's
/// change (its `rearm` says which lines to unmask) and what was acted on.
pub fn heartbeat(
    rt: &Realtime,
    deb: &mut Debounce,
    edges: u8,
    seen: u8,
    active: u8,
    now: u32,
    raise: &mut impl FnMut(Rt),
) -> (Change, Acted) {
    let first = deb.edge(edges, active, now);
    let mut change = deb.poll(active, now);
    // Presses the interrupts acted on are not acted on again.
    change.pressed |= first.pressed & !seen;
    let acted = act(rt, change.pressed, raise);
    if deb.masked() & ESTOP == 0 {
        rt.set_estop(deb.stable() & ESTOP != 0);
    }
    (change, acted)
}

#[cfg(test)]
mod tests {
    use super::super::{LIMIT_X, PROBE};
    use super::*;

    fn raised(f: impl FnOnce(&mut dyn FnMut(Rt))) -> heapless::Vec<Rt, 4> {
        let mut v = heapless::Vec::new();
        f(&mut |c| {
            let _ = v.push(c);
        });
        v
    }

    #[test]
    fn a_limit_trips_only_while_armed() {
        let rt = Realtime::new();
        let a = act(&rt, LIMIT_X, &mut |_| {});
        assert_eq!(a, Acted::default());
        assert_eq!(rt.trip(), crate::realtime::Trip::None);
        rt.set_limits_armed(true);
        let a = act(&rt, LIMIT_X, &mut |_| {});
        assert_eq!(a.inputs, LIMIT_X);
        assert!(a.wake && !a.cut_outputs);
        assert_eq!(rt.trip(), crate::realtime::Trip::HardLimit);
        assert_eq!(rt.trip_mask(), LIMIT_X);
    }

    #[test]
    fn the_estop_latches_resets_and_cuts_the_outputs() {
        let rt = Realtime::new();
        let mut a = Acted::default();
        let cmds = raised(|r| a = act(&rt, ESTOP, &mut |c| r(c)));
        assert!(rt.estop());
        assert!(a.cut_outputs && a.wake);
        assert_eq!(cmds.as_slice(), &[Rt::SoftReset]);
    }

    #[test]
    fn buttons_are_the_hosts_realtime_commands() {
        let rt = Realtime::new();
        let cmds = raised(|r| {
            act(&rt, FEED_HOLD | CYCLE_START | PROBE, &mut |c| r(c));
        });
        assert_eq!(cmds.as_slice(), &[Rt::FeedHold, Rt::CycleStart]);
    }

    #[test]
    fn cycle_start_acts_only_once_settled_and_the_estop_level_follows() {
        let rt = Realtime::new();
        let mut deb = Debounce::new(20, 0);
        // The edge itself does nothing for cycle start (not instant).
        let a = on_edge(&rt, CYCLE_START, CYCLE_START, &mut |_| {
            panic!("acted on an edge")
        });
        assert_eq!(a, Acted::default());
        let mut cmds = heapless::Vec::<Rt, 4>::new();
        let (_, a) = heartbeat(&rt, &mut deb, CYCLE_START, 0, CYCLE_START, 0, &mut |c| {
            let _ = cmds.push(c);
        });
        assert_eq!(a.inputs, 0, "not settled yet");
        let (ch, a) = heartbeat(&rt, &mut deb, 0, 0, CYCLE_START, 20, &mut |c| {
            let _ = cmds.push(c);
        });
        assert_eq!(a.inputs, CYCLE_START);
        assert_eq!(ch.rearm, CYCLE_START);
        assert_eq!(cmds.as_slice(), &[Rt::CycleStart]);
        // An e-stop its interrupt acted on: not again at the heartbeat, and
        // its level released once it settles open.
        let a = on_edge(&rt, ESTOP, ESTOP, &mut |_| {});
        assert!(a.cut_outputs && rt.estop());
        let (_, a) = heartbeat(&rt, &mut deb, ESTOP, ESTOP, ESTOP, 30, &mut |_| {
            panic!("acted twice")
        });
        assert_eq!(a.inputs, 0);
        heartbeat(&rt, &mut deb, 0, 0, 0, 40, &mut |_| {});
        assert!(rt.estop(), "released, not settled yet");
        heartbeat(&rt, &mut deb, 0, 0, 0, 60, &mut |_| {});
        assert!(!rt.estop());
    }
}
