//! The driver on a toy timer: the interrupt enters at each target, late by
//! a chosen amount, and every store is logged with its time.
use super::*;
use crate::planner::Watch;
use crate::seams::Switches;
use crate::settings::Settings;

/// The clock advances one tick per counter read, so the driver's short
/// wait for a near target ends. `HW`: the hardware ends pulses (logged as
/// a fall at the tick asked for, when it is asked).
struct Toy<const HW: bool> {
    t: core::cell::Cell<u64>,
    target: Option<u64>,
    log: [(u64, u8, u8); 64],
    n: usize,
    enabled: bool,
    /// Interrupts entered (the kick included).
    irqs: usize,
    /// Direction pins as last set.
    dir: u8,
    /// The pulse width the driver gave (`HW`).
    width: u64,
    /// The last configuration the driver handed over, with its directions.
    applied: Option<(StepConfig, u8)>,
}

impl<const HW: bool> Toy<HW> {
    fn new() -> Self {
        Toy {
            t: core::cell::Cell::new(1000),
            target: None,
            log: [(0, 0, 0); 64],
            n: 0,
            enabled: false,
            irqs: 0,
            dir: 0,
            width: 0,
            applied: None,
        }
    }
    fn push(&mut self, step: u8, dir: u8) {
        self.push_at(self.t.get(), step, dir);
    }
    fn push_at(&mut self, tick: u64, step: u8, dir: u8) {
        if self.n < self.log.len() {
            self.log[self.n] = (tick, step, dir);
            self.n += 1;
        }
    }
}

impl<const HW: bool> StepPins for Toy<HW> {
    const ENDS_PULSES: bool = HW;
    fn set_pulse_width(&mut self, ticks: u32) {
        self.width = u64::from(ticks);
    }
    /// With `HW`, the end is logged with the rise, at the width asked for.
    fn step_high(&mut self, step_mask: u8) {
        self.push(step_mask, self.dir);
        if HW {
            self.push_at(self.t.get() + self.width, 0, 0xFF);
        }
    }
    fn set_directions(&mut self, dir_mask: u8) {
        self.dir = dir_mask;
        self.push(0, dir_mask);
    }
    fn step_low(&mut self) {
        self.push(0, 0xFF);
    }
    fn set_enabled(&mut self, on: bool) {
        self.enabled = on;
    }
    fn apply_config(&mut self, cfg: &StepConfig, dir_mask: u8) {
        self.applied = Some((*cfg, dir_mask));
    }
    fn switches(&self) -> Switches {
        Switches::default()
    }
}

impl<const HW: bool> StepTimer for Toy<HW> {
    fn tick_hz(&self) -> u32 {
        1_000_000 * US as u32
    }
    fn now(&self) -> u32 {
        let t = self.t.get();
        self.t.set(t + 1);
        t as u32
    }
    fn schedule_at(&mut self, at: u32) {
        let t = self.t.get();
        let ahead = at.wrapping_sub(t as u32);
        self.target = Some(t + u64::from(ahead));
    }
    fn start(&mut self) {}
    fn stop(&mut self) {
        self.target = None;
    }
}

/// Ticks per µs of the toy timer.
const US: u64 = 100;

fn segment(steps: u32, dir: u8, new_block: bool) -> Segment {
    let mut s = [0; crate::AXES];
    s[0] = steps;
    Segment {
        events: steps,
        period: 10 * US as u32,
        amass: 0,
        new_block,
        steps: s,
        count: steps,
        dir_mask: dir,
        watch: Watch::default(),
        end_of_motion: true,
        generation: 0,
        speed_mm_min: 1.0,
        line: 1,
        cut: 0.0,
        takeup: false,
    }
}

/// Runs to a stop; every interrupt enters `late` ticks after its target.
fn run<const HW: bool>(late: u64, segments: &[Segment]) -> Toy<HW> {
    let (hw, pos) = run_to(late, segments);
    assert_eq!(pos, -3);
    hw
}

/// As [`run`], with X's final position.
fn run_to<const HW: bool>(late: u64, segments: &[Segment]) -> (Toy<HW>, i32) {
    let rt = Realtime::new();
    let s = Settings {
        step_pulse_us: 2.0,
        dir_setup_us: 3.0,
        enable_delay_us: 5.0,
        max_step_rate_hz: 200_000.0,
        ..Settings::default()
    };
    let mut stepper = Stepper::new(StepConfig::new(&s, 1_000_000 * US as u32));
    let mut d = StepDriver::new();
    let mut hw = Toy::new();
    let mut q = segments.iter().copied();
    let mut pop = || q.next();
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    hw.irqs += 1;
    assert!(rt.stepping() && hw.enabled);
    for _ in 0..200 {
        let Some(t) = hw.target else { break };
        hw.t.set(hw.t.get().max(t + late));
        d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
        hw.irqs += 1;
    }
    assert!(!rt.stepping() && !d.is_running());
    (hw, stepper.position()[0])
}

/// Three steps, however late each interrupt: the direction first (no
/// step), then rise/fall pairs (a fall logged by `step_low` or, with `HW`,
/// by `step_high` at the width given, both as (0, 0xFF)), each with its widths.
fn check_train<const HW: bool>() {
    let segs = [segment(3, 1, true)];
    for late in [0, 1, 3, 7, 15].map(|us| us * US) {
        let hw = run::<HW>(late, &segs);
        let log = &hw.log[..hw.n];
        assert_eq!(hw.n, 7, "late {late}: {log:?}");
        assert_eq!((log[0].1, log[0].2), (0, 1), "late {late}: {log:?}");
        // `$207` from start (t = 1000) to the direction store, `$200` after it.
        assert!(log[0].0 >= 1000 + 5 * US);
        assert!(log[1].0 >= log[0].0 + 3 * US, "late {late}: {log:?}");
        for i in 0..3 {
            let (rise, fall) = (log[1 + 2 * i], log[2 + 2 * i]);
            assert_eq!((rise.1, fall.1, fall.2), (1, 0, 0xFF), "{log:?}");
            assert!(fall.0 >= rise.0 + 2 * US, "high time, late {late}: {log:?}");
            if i > 0 {
                let (last_rise, last_fall) = (log[2 * i - 1], log[2 * i]);
                assert!(rise.0 >= last_fall.0 + 2 * US, "low time, late {late}");
                assert!(rise.0 >= last_rise.0 + 5 * US, "$201, late {late}");
            }
        }
    }
}

#[test]
fn pulses_keep_their_widths_however_late() {
    check_train::<false>();
}

#[test]
fn hardware_pulse_ends_take_one_interrupt_per_step() {
    // The same train as with fall interrupts, each fall `$0` after its
    // rise was read. On time, three interrupts fewer for the three steps
    // (kick, direction, three rises, stop: 6 against 9); late, the fall
    // scheme chains some falls and rises in one handler, and never needs
    // fewer than the hardware end.
    check_train::<true>();
    let segs = [segment(3, 1, true)];
    for late in [0, 1, 3, 7, 15].map(|us| us * US) {
        let (dma, irq) = (run::<true>(late, &segs), run::<false>(late, &segs));
        if late == 0 {
            assert_eq!((dma.irqs, irq.irqs), (6, 9));
        }
        assert!(
            dma.irqs <= irq.irqs,
            "late {late}: {} > {}",
            dma.irqs,
            irq.irqs
        );
    }
}

#[test]
fn a_direction_change_waits_for_the_hardware_pulse_end() {
    // Back and forth at the `$201` period: the reversal's direction store
    // (an event without steps) is due while the last pulse is still high.
    let mut segs = [segment(3, 1, true), segment(3, 0, true)];
    for s in &mut segs {
        s.period = 3 * US as u32;
    }
    let (hw, pos) = run_to::<true>(0, &segs);
    assert_eq!(pos, 0);
    let log = &hw.log[..hw.n];
    let mut fall_at = 0;
    for w in log {
        if w.2 == 0xFF {
            fall_at = w.0;
        } else {
            assert!(w.0 >= fall_at, "a store before the pulse ended: {log:?}");
        }
    }
    let turn = log.iter().position(|w| w.2 == 0 && w.1 == 0);
    assert!(turn.is_some(), "no direction store: {log:?}");
}

/// Drivers that latch the direction at the falling step edge need it to
/// hold there: a reversal's direction store comes no sooner than the
/// minimum low time (`$0`, at least 1 µs) after the last pulse's end, with
/// the hardware's pulse end and with the fall interrupt alike.
fn reversal_waits_a_low_time<const HW: bool>() {
    let mut segs = [segment(3, 1, true), segment(3, 0, true)];
    for s in &mut segs {
        s.period = 3 * US as u32;
    }
    let (hw, pos) = run_to::<HW>(0, &segs);
    assert_eq!(pos, 0);
    let log = &hw.log[..hw.n];
    let min_low = 2 * US; // `$0` = 2 µs in `run_to`
    let mut fall_at = None;
    let mut dir = 1;
    for w in log {
        if w.1 == 0 && w.2 == 0xFF {
            fall_at = Some(w.0);
        } else if w.1 == 0 && w.2 != dir {
            dir = w.2;
            if let Some(f) = fall_at {
                assert!(
                    w.0 >= f + min_low,
                    "direction {} ticks after a fall: {log:?}",
                    w.0 - f
                );
            }
        }
    }
    assert_eq!(dir, 0, "no reversal: {log:?}");
}

#[test]
fn a_reversal_waits_a_low_time_after_the_pulse_end() {
    reversal_waits_a_low_time::<true>();
    reversal_waits_a_low_time::<false>();
}

/// A hard limit (or the e-stop) that trips between an event's computation
/// and its rise: that step never leaves.
#[test]
fn no_pulse_after_a_hard_limit_halt() {
    let rt = Realtime::new();
    let s = Settings::default();
    let mut stepper = Stepper::new(StepConfig::new(&s, 1_000_000 * US as u32));
    let mut d = StepDriver::new();
    let mut hw = Toy::<true>::new();
    let segs = [segment(10, 0, true)];
    let mut q = segs.iter().copied();
    let mut pop = || q.next();
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    let rises = |hw: &Toy<true>| hw.log[..hw.n].iter().filter(|w| w.1 != 0).count();
    // Run to the third rise: the fourth step is computed and pending.
    while rises(&hw) < 3 {
        let t = hw.target.expect("running");
        hw.t.set(hw.t.get().max(t));
        d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    }
    assert_eq!(stepper.position()[0], 4, "the pending step is counted");
    rt.hard_limit(1);
    for _ in 0..10 {
        let Some(t) = hw.target else { break };
        hw.t.set(hw.t.get().max(t));
        d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    }
    assert_eq!(
        rises(&hw),
        3,
        "a pulse after the trip: {:?}",
        &hw.log[..hw.n]
    );
    // The count the executor may already have read stays.
    assert_eq!(stepper.position()[0], 4);
    assert!(!d.is_running());
}

/// Interrupts at each target until the driver stops; `before` runs ahead
/// of every one (a publish mid-move).
fn drive<const HW: bool>(
    d: &mut StepDriver,
    stepper: &mut Stepper,
    hw: &mut Toy<HW>,
    rt: &Realtime,
    pop: &mut impl FnMut() -> Option<Segment>,
    before: &mut impl FnMut(usize),
) {
    for i in 0..200 {
        let Some(t) = hw.target else { break };
        hw.t.set(hw.t.get().max(t));
        before(i);
        d.on_interrupt(stepper, hw, rt, pop);
    }
    assert!(!d.is_running());
}

#[test]
fn a_new_configuration_is_taken_at_rest_only() {
    let tick_hz = 1_000_000 * US as u32;
    let rt = Realtime::new();
    let base = Settings {
        step_pulse_us: 2.0,
        max_step_rate_hz: 50_000.0,
        ..Settings::default()
    };
    let wide = Settings {
        step_pulse_us: 7.0,
        step_invert: 0b1,
        dir_invert: 0b1,
        ..base
    };
    let wider = Settings {
        step_pulse_us: 9.0,
        ..wide
    };
    let mut stepper = Stepper::new(StepConfig::new(&base, tick_hz));
    let mut d = StepDriver::new();
    let mut hw = Toy::<true>::new();
    // A kick at rest with nothing queued only takes the configuration: the
    // pins get it (idle levels) with the directions as they stand.
    rt.step_config().publish(&StepConfig::new(&wide, tick_hz));
    assert!(d.on_interrupt(&mut stepper, &mut hw, &rt, &mut || None));
    assert_eq!(hw.applied, Some((StepConfig::new(&wide, tick_hz), 0)));
    assert_eq!(stepper.cfg, StepConfig::new(&wide, tick_hz));
    assert!(!rt.step_config().pending() && !d.is_running());
    // A move on it; `$0` raised again half way is not taken mid-move.
    let segs = [segment(3, 1, true)];
    let mut q = segs.iter().copied();
    let mut pop = || q.next();
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    let mut publish = |i: usize| {
        if i == 2 {
            rt.step_config().publish(&StepConfig::new(&wider, tick_hz));
        }
    };
    drive(&mut d, &mut stepper, &mut hw, &rt, &mut pop, &mut publish);
    let log = &hw.log[..hw.n];
    let rises: Vec<_> = log.iter().filter(|e| e.1 != 0).collect();
    let falls: Vec<_> = log.iter().filter(|e| e.2 == 0xFF).collect();
    assert_eq!((rises.len(), falls.len()), (3, 3), "{log:?}");
    for (r, f) in rises.iter().zip(&falls) {
        let high = f.0 - r.0;
        assert!((7 * US..8 * US).contains(&high), "7 µs, not 9: {log:?}");
    }
    // Taken at the stop, with X's direction (negative) as it stands.
    assert_eq!(hw.applied, Some((StepConfig::new(&wider, tick_hz), 1)));
    assert_eq!(stepper.cfg.pulse_ticks, 9 * US as u32);
}

#[test]
fn a_configuration_waiting_at_the_last_slot_stops_the_driver_there() {
    // The task published after the stepper went idle but before the
    // driver's slot after the last event; a move queued meanwhile starts
    // from rest on the new configuration (the task's kick), not on the old.
    let tick_hz = 1_000_000 * US as u32;
    let rt = Realtime::new();
    let base = Settings {
        step_pulse_us: 2.0,
        ..Settings::default()
    };
    let wide = Settings {
        step_pulse_us: 7.0,
        ..base
    };
    let mut stepper = Stepper::new(StepConfig::new(&base, tick_hz));
    let mut d = StepDriver::new();
    let mut hw = Toy::<true>::new();
    let segs = [segment(1, 0, true), segment(1, 0, true)];
    let mut q = segs.iter().copied();
    let mut n = 0;
    // The first segment alone, then the second appears with the config.
    let mut pop = || {
        n += 1;
        if n == 2 {
            return None;
        }
        q.next()
    };
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    let mut first = true;
    for _ in 0..20 {
        let Some(t) = hw.target else { break };
        hw.t.set(hw.t.get().max(t));
        if first && d.pending().ticks == 0 {
            first = false;
            rt.step_config().publish(&StepConfig::new(&wide, tick_hz));
        }
        d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    }
    assert!(!first, "never reached the slot after the last event");
    assert!(!d.is_running() && !rt.stepping(), "stopped for the config");
    assert_eq!(stepper.cfg.pulse_ticks, 7 * US as u32);
    assert_eq!(hw.log[..hw.n].iter().filter(|e| e.1 != 0).count(), 1);
    // The kick: the queued step on the new width, `$0`+ after the start.
    let t0 = hw.t.get();
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    drive(&mut d, &mut stepper, &mut hw, &rt, &mut pop, &mut |_| {});
    let log = &hw.log[..hw.n];
    let rise = log.iter().rposition(|e| e.1 != 0);
    let rise = rise.map(|i| log[i]);
    let fall = log.last().copied();
    assert!(rise.is_some_and(|r| r.0 >= t0), "{log:?}");
    let high = rise.zip(fall).map(|(r, f)| f.0 - r.0);
    assert!(
        high.is_some_and(|h| (7 * US..8 * US).contains(&h)),
        "{log:?}"
    );
}

#[test]
fn a_kick_after_a_slow_last_step_takes_the_configuration_without_waiting() {
    // One step 10 ms long: the slot after it is 10 ms away when `$0=` is
    // published; the task's kick stops the driver as soon as the pulse is
    // over and the configuration is taken then.
    let tick_hz = 1_000_000 * US as u32;
    let rt = Realtime::new();
    let base = Settings::default();
    let wide = Settings {
        step_pulse_us: 7.0,
        ..base
    };
    let mut stepper = Stepper::new(StepConfig::new(&base, tick_hz));
    let mut d = StepDriver::new();
    let mut hw = Toy::<true>::new();
    let mut seg = segment(1, 0, true);
    seg.period = 10_000 * US as u32;
    let mut q = [seg].into_iter();
    let mut pop = || q.next();
    // The kick from rest makes the step at once (`$207` = 0).
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    let rise = hw.log[..hw.n].iter().find(|e| e.1 != 0).map_or(0, |e| e.0);
    assert!(rise > 0 && d.pending().ticks == 0 && d.is_running());
    assert!(hw.target.is_some_and(|t| t >= rise + 10_000 * US - 10));
    rt.step_config().publish(&StepConfig::new(&wide, tick_hz));
    // The kick moves the stop to the end of the pulse's timing...
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    let stop = hw.target.unwrap_or(u64::MAX);
    assert!(
        stop < rise + 100 * US,
        "the stop waits for the slot: {stop}"
    );
    // ...where it stops and takes it.
    hw.t.set(stop);
    d.on_interrupt(&mut stepper, &mut hw, &rt, &mut pop);
    assert!(!d.is_running() && !rt.stepping());
    assert_eq!(stepper.cfg.pulse_ticks, 7 * US as u32);
    assert!(hw.applied.is_some());
}
