//! Step interrupt latency: the core's step driver under interrupt-masked
//! windows of 0 to 10 µs at step rates up to `$201`, checked on the pin
//! edges host-sim records. No step may be lost (rising edges per axis ==
//! the stepper's count == the commanded steps), every pulse stays high for
//! `$0` and low for the driver's stated minimum, and `$200` holds before
//! every rise after a direction change.
//!
//! The same windows are run through a model of the step timer burin used
//! before (the update interrupt raises the pins, a compare fixed at `$0`
//! after each update lowers them) to show what the test guards against:
//! there a window longer than the pulse loses steps.
//!
//! `cargo test -p host-sim --test sim step_latency -- --nocapture` prints the
//! sweep.

use crate::common;
use burin::command::{Command, Feed};
use burin::stepper::StepConfig;
use burin::AXES;
use common::*;
use host_sim::config::{Interrupts, MachineConfig, MaskPhase, Masks, PulseEnd};
use host_sim::engine::{Edge, Sim};
use host_sim::record::Discard;

/// Mask windows swept, µs.
const WINDOWS_US: [f32; 8] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 7.0, 10.0];
/// X step rates swept, Hz (200 kHz is the default `$201`).
const RATES_HZ: [f32; 3] = [50_000.0, 120_000.0, 200_000.0];
/// X steps per move (Y makes half): out and back.
const STEPS: i64 = 2000;

/// An F411-like handler model (96 MHz): about 24 cycles to the first pin
/// store, the rise handler with the next event computed, a short fall
/// handler; windows every 100 µs (ten times the USB frame rate, so every
/// run meets many of them) at a new random offset each time.
fn irq(window_us: f32, pulse_end: PulseEnd) -> Interrupts {
    Interrupts {
        step_entry_ns: 250,
        step_handler_ns: 1600,
        step_fall_ns: 600,
        pulse_end,
        mask_window_us: window_us,
        mask_period_us: 100.0,
        mask_phase: MaskPhase::Random(7),
        ..Interrupts::default()
    }
}

fn machine(rate_hz: f32, window_us: f32, pulse_end: PulseEnd) -> MachineConfig {
    let mut cfg = config();
    let s = &mut cfg.settings;
    s.max_step_rate_hz = 200_000.0;
    for a in &mut s.axes[..2] {
        a.steps_per_mm = 80.0;
        a.max_rate = rate_hz / 80.0 * 60.0;
        a.max_accel = 1.0e6;
    }
    cfg.interrupts = irq(window_us, pulse_end);
    cfg
}

/// Rising edges per axis, and the shortest high time, low time and
/// direction setup seen, in ticks (u64::MAX: none seen).
#[derive(Debug, Default)]
struct Train {
    rises: [i64; AXES],
    min_high: u64,
    min_low: u64,
    min_setup: u64,
}

fn analyse(edges: &[Edge]) -> Train {
    let mut t = Train {
        min_high: u64::MAX,
        min_low: u64::MAX,
        min_setup: u64::MAX,
        ..Train::default()
    };
    let (mut step, mut dir) = (0u8, 0u8);
    let mut rose = [0u64; AXES];
    let mut fell: [Option<u64>; AXES] = [None; AXES];
    let mut dir_at: [Option<u64>; AXES] = [None; AXES];
    for e in edges {
        for i in 0..AXES {
            let bit = 1 << i;
            if (e.dir ^ dir) & bit != 0 {
                dir_at[i] = Some(e.tick);
            }
            match (step & bit != 0, e.step & bit != 0) {
                (false, true) => {
                    t.rises[i] += 1;
                    rose[i] = e.tick;
                    if let Some(f) = fell[i] {
                        t.min_low = t.min_low.min(e.tick - f);
                    }
                    if let Some(d) = dir_at[i].take() {
                        t.min_setup = t.min_setup.min(e.tick - d);
                    }
                }
                (true, false) => {
                    t.min_high = t.min_high.min(e.tick - rose[i]);
                    fell[i] = Some(e.tick);
                }
                _ => {}
            }
        }
        (step, dir) = (e.step, e.dir);
    }
    t
}

fn feed(rate_hz: f32) -> Feed {
    // Path speed for X at `rate_hz` on a (2, 1) diagonal.
    let x_mm_min = rate_hz / 80.0 * 60.0;
    Feed::PerMin(x_mm_min * (1.25f32).sqrt())
}

#[test]
fn no_step_lost_and_no_pulse_cut_short_under_masked_windows() {
    let mm = STEPS as f32 / 80.0;
    // The boards' DMA pulse end (with the latency the board's driver
    // allows for) and QEMU's fall interrupt.
    let ends = [PulseEnd::Hardware { latency_ns: 333 }, PulseEnd::Interrupt];
    for (end, rate, w) in ends
        .into_iter()
        .flat_map(|e| RATES_HZ.into_iter().map(move |r| (e, r)))
        .flat_map(|(e, r)| WINDOWS_US.into_iter().map(move |w| (e, r, w)))
    {
        {
            let cfg = machine(rate, w, end);
            let sc = StepConfig::new(&cfg.settings, cfg.tick_hz);
            let mut rec = Discard;
            let mut sim = Sim::new(&cfg, &mut rec);
            sim.record_edges();
            let out = burin::pad([mm, mm / 2.0]);
            let back = [0.0; AXES];
            for (line, end) in [(1, out), (2, back)] {
                sim.push_command(
                    line,
                    Command::Line {
                        end,
                        feed: feed(rate),
                    },
                );
            }
            sim.run();
            let s = sim.summary(2, [0.0; AXES]);
            assert!(s.errors.is_empty(), "{rate} Hz, {w} µs: {:?}", s.errors);
            let t = analyse(sim.edges());
            let label = format!("{end:?} {rate} Hz, {w} µs window: {t:?}");
            let want = burin::pad([2 * STEPS, STEPS]);
            assert_eq!(t.rises, want, "rising edges, {label}");
            assert_eq!(s.steps.map(|n| n as i64), want, "stepper steps, {label}");
            assert_eq!(s.final_position_steps, [0; AXES], "{label}");
            assert!(
                t.min_high >= u64::from(sc.pulse_ticks),
                "high < $0, {label}"
            );
            assert!(t.min_low >= u64::from(sc.min_low_ticks), "low, {label}");
            assert!(
                t.min_setup >= u64::from(sc.dir_setup_ticks),
                "$200, {label}"
            );
            let us = |ticks: u64| ticks as f64 * 1e6 / f64::from(cfg.tick_hz);
            println!(
                "{end:?} {:>6} Hz window {w:>4} µs: rises {:?}, high >= {:.2} µs, low >= {:.2} µs, setup >= {:.2} µs, job {:.3} ms",
                rate,
                &t.rises[..2],
                us(t.min_high),
                us(t.min_low),
                us(t.min_setup),
                s.job_time_s * 1e3
            );
        }
    }
}

/// burin's previous step timer on the same windows: TIM5 restarts at every
/// update (a constant period here, preloaded, so updates are exactly on
/// time), the update interrupt raises the pins, CC1 at a fixed `$0` after
/// each update lowers them, both flags are served by one handler (low
/// first, as the old `StepDriver::on_interrupt` did). Returns the edges of
/// `n` steps on one axis.
fn old_scheme(n: u64, period: u64, pulse: u64, cfg: &MachineConfig) -> Vec<Edge> {
    let irq = cfg.interrupts.ticks(cfg.tick_hz);
    let masks: Masks = irq.masks;
    let start = 1000;
    let update = |k: u64| start + k * period;
    let (mut k_up, mut k_cc) = (0u64, 0u64);
    let mut free = 0u64;
    let mut edges = Vec::new();
    while k_cc < n {
        // The earliest flag not served yet (a period's CC1 follows its update).
        let f = if k_up < n && k_up <= k_cc {
            update(k_up)
        } else {
            update(k_cc) + pulse
        };
        let enter = masks.unmasked_at(f.max(free));
        // Every flag raised by the time the handler reads SR; a flag raised
        // twice meanwhile is served once.
        let mut up = false;
        while k_up < n && update(k_up) <= enter {
            k_up += 1;
            up = true;
        }
        let mut cc = false;
        while k_cc < k_up && update(k_cc) + pulse <= enter {
            k_cc += 1;
            cc = true;
        }
        let store = enter + irq.entry;
        if cc {
            edges.push(Edge {
                tick: store,
                step: 0,
                dir: 0,
                step_invert: 0,
                dir_invert: 0,
            });
        }
        if up {
            // The event's BSRR store follows the pulse end's in one handler.
            edges.push(Edge {
                tick: store + u64::from(cc),
                step: 1,
                dir: 0,
                step_invert: 0,
                dir_invert: 0,
            });
        }
        free = enter + if up { irq.rise } else { irq.fall };
    }
    edges
}

#[test]
fn the_previous_step_timer_loses_steps_in_the_same_windows() {
    let mut lost_at_4us = 0;
    for w in WINDOWS_US {
        let cfg = machine(200_000.0, w, PulseEnd::Interrupt);
        let sc = StepConfig::new(&cfg.settings, cfg.tick_hz);
        let n = 20_000;
        let (period, pulse) = (u64::from(sc.min_period), u64::from(sc.pulse_ticks));
        let t = analyse(&old_scheme(n, period, pulse, &cfg));
        // A "pulse" whose low time before it is shorter than the driver's
        // minimum merges with the one before: count those as lost too.
        let lost = n as i64 - t.rises[0];
        let short_low = t.min_low < u64::from(sc.min_low_ticks);
        let short_high = t.min_high < pulse;
        println!(
            "old 200000 Hz window {w:>4} µs: {lost} of {n} steps without a rising edge, min high {} ticks, min low {} ticks ($0 = {pulse})",
            t.min_high, t.min_low
        );
        if w == 0.0 {
            assert!(lost == 0 && !short_low && !short_high, "{t:?}");
        } else {
            // Any window cuts a pulse short there.
            assert!(short_high, "window {w} µs: {t:?}");
        }
        if w == 4.0 {
            lost_at_4us = lost;
            assert!(short_low, "{t:?}");
        }
    }
    // The F411's USB poll (4 µs) loses steps outright.
    assert!(lost_at_4us > 0);
}
