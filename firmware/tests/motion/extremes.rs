//! Bounded work at the extremes: feeds from 1e-6 to 1e6 mm/min, lengths from
//! 1e-6 to 1e4 mm, 1 to 10 000 steps/mm. Every job either runs its exact
//! step count or is refused with a typed error; no `Machine::poll` call
//! may do unbounded work (the preparer's walk counter says how much it did).
//!
//! A watchdog thread turns a hang (the old behaviour of `G1 X-1 F0.0001`)
//! into a test failure instead of a test run that never ends.

use std::sync::mpsc;
use std::time::Duration;

use burin::command::{Command, Feed};
use burin::executor::{Machine, MachineError};
use burin::realtime::Realtime;
use burin::settings::Settings;
use burin::stepper::prep::MAX_WALKS_PER_SEGMENT;
use burin::stepper::{Segment, Stepper, Switches};
use heapless::spsc::Queue;
use proptest::prelude::*;

const TICK_HZ: u32 = 96_000_000;
const SLOTS: usize = 16;
/// Segments one poll may push: the queue never holds more than its slots.
const MAX_SEGMENTS_PER_POLL: u32 = SLOTS as u32;
/// Past this many events a job's remaining segments are counted instead of
/// stepped (a 1e4 mm move at 1e4 steps/mm is 1e8 events; the stepper's
/// part is the same for all of them).
const STEP_THROUGH: u64 = 1_000_000;

#[derive(Debug)]
enum Outcome {
    Done { steps: i64 },
    Refused(MachineError),
}

/// Runs one move: submit, then poll and drain the segment queue through
/// the stepper until everything is idle. Panics if a poll did more walk
/// iterations than its bound or the job needs more than `MAX_EVENTS`.
fn run_move(settings: Settings, dx: f32, feed: f32) -> Outcome {
    let rt = Realtime::new();
    let mut m = Machine::<16>::new(settings, TICK_HZ);
    let mut st = Stepper::new(m.step_config());
    let mut q: Queue<Segment, SLOTS> = Queue::new();
    let cmd = Command::Line {
        end: burin::pad([dx, 0.0, 0.0, 0.0]),
        feed: Feed::PerMin(feed),
    };
    let mut late = None;
    if let Err(e) = m.submit(&rt, &cmd, 1, &mut |_| {}) {
        return Outcome::Refused(e);
    }
    let mut events = 0u64;
    let mut counted = 0i64;
    let sign = if dx < 0.0 { -1 } else { 1 };
    loop {
        let before = m.motion.prep().walks();
        m.poll(&rt, &mut q, Switches::default(), &mut |n| {
            if let burin::executor::Note::Error { error, .. } = n {
                late = Some(error);
            }
        });
        let walked = m.motion.prep().walks().wrapping_sub(before);
        assert!(
            walked <= MAX_SEGMENTS_PER_POLL * MAX_WALKS_PER_SEGMENT,
            "one poll walked {walked} times"
        );
        if let Some(e) = late {
            return Outcome::Refused(e);
        }
        if q.is_empty() && m.motion.planner().is_empty() && m.motion.prep().is_idle() {
            break;
        }
        // The step interrupt drains what the task prepared.
        while !q.is_empty() {
            if events >= STEP_THROUGH && st.is_idle() {
                if let Some(s) = q.dequeue() {
                    if s.steps[0] != 0 {
                        counted += i64::from(s.events >> s.amass);
                    }
                }
                continue;
            }
            st.on_event(&rt, &mut || q.dequeue(), Switches::default);
            events += 1;
        }
    }
    // Let the stepper finish the last segment.
    while st
        .on_event(&rt, &mut || q.dequeue(), Switches::default)
        .ticks
        != 0
    {
        events += 1;
    }
    let steps = i64::from(rt.position()[0]) + sign * counted;
    // Steps, plus at most one wait per 20 s step interval and smoothing
    // (single-axis moves do not smooth): bounded by the job itself.
    assert!(
        events <= 3 * steps.unsigned_abs() + 64,
        "{events} events for {steps} steps"
    );
    Outcome::Done { steps }
}

/// Runs `f` on a thread; a hang becomes a failure after `secs`.
fn within<T: Send + 'static>(secs: u64, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    let h = std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    match rx.recv_timeout(Duration::from_secs(secs)) {
        Ok(v) => v,
        Err(mpsc::RecvTimeoutError::Disconnected) => match h.join() {
            Err(p) => std::panic::resume_unwind(p),
            Ok(()) => unreachable!("the thread sends before it ends"),
        },
        Err(mpsc::RecvTimeoutError::Timeout) => {
            panic!("no answer within {secs} s: the preparer loops")
        }
    }
}

fn settings_with(steps_per_mm: f32) -> Settings {
    let mut s = Settings::default();
    s.axes[0].steps_per_mm = steps_per_mm;
    // Keep the axis's max rate within `$201` at every steps/mm tried.
    s.axes[0].max_rate = s.axes[0]
        .max_rate
        .min(0.99 * s.max_step_rate_hz * 60.0 / steps_per_mm);
    s
}

fn check(steps_per_mm: f32, dx: f32, feed: f32) {
    let s = settings_with(steps_per_mm);
    let want = libm::roundf(dx * steps_per_mm) as i64;
    match within(20, move || run_move(s, dx, feed)) {
        Outcome::Done { steps } => {
            assert_eq!(steps, want, "{steps_per_mm} steps/mm {dx} mm F{feed}")
        }
        Outcome::Refused(e) => assert_eq!(
            e,
            MachineError::FeedTooSlow,
            "{steps_per_mm} steps/mm {dx} mm F{feed}"
        ),
    }
}

#[test]
fn issue_feed_0_0001_on_default_machine_is_refused() {
    // 7 500 s per step: beyond the driver's 11.2 s (`seams::MAX_PERIOD`).
    check(80.0, -1.0, 0.0001);
    let r = within(20, || run_move(Settings::default(), -1.0, 0.0001));
    assert!(
        matches!(r, Outcome::Refused(MachineError::FeedTooSlow)),
        "{r:?}"
    );
}

#[test]
fn fuzzer_feed_0_0008_on_10_steps_per_mm_is_refused() {
    let r = within(20, || run_move(settings_with(10.0), -1.0, 0.0008));
    assert!(
        matches!(r, Outcome::Refused(MachineError::FeedTooSlow)),
        "{r:?}"
    );
}

/// Ticks from the first to the last step of a move at `feed`, run
/// through the stepper at feed override `pct`.
fn step_span(s: Settings, dx: f32, feed: f32, pct: u16) -> (i32, u64) {
    let rt = Realtime::new();
    rt.set_feed_override(pct);
    let mut m = Machine::<16>::new(s, TICK_HZ);
    let mut st = Stepper::new(m.step_config());
    let mut q: Queue<Segment, SLOTS> = Queue::new();
    let cmd = Command::Line {
        end: burin::pad([dx, 0.0, 0.0, 0.0]),
        feed: Feed::PerMin(feed),
    };
    m.submit(&rt, &cmd, 1, &mut |_| {}).expect("accepted");
    let (mut now, mut first, mut last) = (0u64, None, 0u64);
    for _ in 0..10_000 {
        m.poll(&rt, &mut q, Switches::default(), &mut |_| {});
        if q.is_empty()
            && m.motion.planner().is_empty()
            && m.motion.prep().is_idle()
            && st.is_idle()
        {
            break;
        }
        let ev = st.on_event(&rt, &mut || q.dequeue(), Switches::default);
        if ev.step_mask != 0 {
            first.get_or_insert(now);
            last = now;
        }
        now += u64::from(ev.ticks);
    }
    (rt.position()[0], last - first.unwrap_or(0))
}

#[test]
fn slowest_accepted_feed_is_split_into_waits_and_keeps_time() {
    // 1 step/mm at F6: a step every 10 s, inside the driver's 11.2 s
    // (`seams::MAX_PERIOD`): each step comes after a wait.
    let (pos, span) = within(20, || step_span(settings_with(1.0), 4.0, 6.0, 100));
    assert_eq!(pos, 4);
    let want = 3.0 * 10.0 * TICK_HZ as f64;
    assert!(
        (span as f64 - want).abs() < 0.02 * want,
        "3 step intervals took {} s, want 30 s",
        span as f64 / TICK_HZ as f64
    );
}

#[test]
fn feed_override_never_takes_a_move_below_the_timer_floor() {
    // Accepted at 100 % (10 s per step); at 10 % it would be 100 s per step,
    // so it runs at the floor (11.2 s) instead of failing halfway.
    let (pos, span) = within(20, || step_span(settings_with(1.0), 3.0, 6.0, 10));
    assert_eq!(pos, 3);
    let floor = 2.0 * burin::seams::MAX_PERIOD as f64;
    assert!(
        (span as f64 - floor).abs() < 0.02 * floor,
        "2 step intervals took {} s, want 22.4 s",
        span as f64 / TICK_HZ as f64
    );
}

/// Log-uniform over `[lo, hi]`.
fn log_range(lo: f64, hi: f64) -> impl Strategy<Value = f32> {
    (lo.ln()..hi.ln()).prop_map(|l| l.exp() as f32)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn extremes_finish_or_are_refused(
        feed in log_range(1e-6, 1e6),
        len in log_range(1e-6, 1e4),
        spm in log_range(1.0, 1e4),
        neg in any::<bool>(),
    ) {
        let dx = if neg { -len } else { len };
        check(spm, dx, feed);
    }
}
