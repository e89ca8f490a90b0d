//! The measurements. Each one runs its subject many times between two SysTick
//! reads, so the per-run figure is an average and the tick granularity
//! (about 6 instructions at 168 MHz) vanishes in the division.
use burin::interp::Interpreter;
use burin::planner::{Planner, Speed, Watch};
use burin::realtime::Realtime;
use burin::settings::Settings;
use burin::stepper::{Segment, StepConfig, Stepper, Switches};
use burin::AXES;
use core::hint::black_box;
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_semihosting::{debug, hprintln};
// Links the PAC's interrupt vectors, which cortex-m-rt's `device` feature
// (enabled by the HAL) expects in every binary of this package.
use stm32f4xx_hal as _;

/// Core clock the step rate is quoted for (the F411 at 96 MHz).
const TARGET_HZ: f32 = 96.0e6;
/// Cortex-M4 exception entry and exit (stacking/unstacking, no FPU context,
/// zero-wait-state flash: ART accelerator hit), cycles.
const ISR_ENTRY_EXIT: f32 = 12.0 + 12.0;
/// Assumed cycles per instruction of the straight-line ISR code.
const CPI: f32 = 1.0;
/// Same size as the firmware's ring (host-sim uses 64 too).
const PLANNER_BLOCKS: usize = 64;
/// Step timer rate the stepper is configured with (TIM5 at 96 MHz).
const TICK_HZ: u32 = 96_000_000;

/// Stand-ins for GPIOB BSRR and TIM5 ARR: the ISR's two register stores.
/// Plain RAM words cost the same instructions as the registers and keep the
/// measurement independent of QEMU's GPIO stub.
static BSRR: AtomicU32 = AtomicU32::new(0);
static ARR: AtomicU32 = AtomicU32::new(0);
static RT: Realtime = Realtime::new();

struct Clock {
    /// Owned so nothing else reconfigures SysTick while it is the clock.
    _syst: SYST,
    /// Ticks of an empty measurement (the two reads themselves).
    overhead: u32,
    /// SysTick ticks per executed instruction, from the calibration loop.
    ticks_per_insn: f32,
}

impl Clock {
    fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        let mut c = Clock {
            _syst: syst,
            overhead: 0,
            ticks_per_insn: 1.0,
        };
        c.overhead = (0..8).map(|_| c.time(|| ())).min().unwrap_or(0);
        const N: u32 = 1_000_000;
        let ticks = c.time(|| count_down(N)).saturating_sub(c.overhead);
        c.ticks_per_insn = ticks as f32 / (2 * N) as f32;
        c
    }

    /// SysTick ticks spent in `f` (SysTick counts down, 24 bits: keep each
    /// timed region under 16.7 M ticks, about 100 M instructions).
    #[inline(never)]
    fn time(&mut self, f: impl FnOnce()) -> u32 {
        let a = SYST::get_current();
        f();
        let b = SYST::get_current();
        a.wrapping_sub(b) & 0x00FF_FFFF
    }

    /// Instructions per repetition of a region that ran `reps` times.
    fn insns(&self, ticks: u32, reps: u32) -> f32 {
        ticks.saturating_sub(self.overhead) as f32 / self.ticks_per_insn / reps as f32
    }
}

/// Executes exactly `2 * n` instructions (n >= 1): a `subs`/`bne` loop
/// written in assembly so that no compiler or crate version can change it.
#[inline(always)]
fn count_down(n: u32) {
    // SAFETY: the loop only decrements the one register given to it and
    // branches back to itself; it touches no memory, stack or flags the
    // compiler relies on (`nomem, nostack`; flags are clobbered by default).
    unsafe {
        core::arch::asm!(
            ".p2align 2",
            "2:",
            "subs {0}, #1",
            "bne 2b",
            inout(reg) n.max(1) => _,
            options(nomem, nostack),
        );
    }
}

/// A block of `events` events with the given per-axis steps (already scaled
/// to the event count: no smoothing, amass 0).
fn segment(steps: [u32; AXES], events: u32, dir_mask: u8, new_block: bool) -> Segment {
    Segment {
        events,
        period: 192,
        amass: 0,
        new_block,
        steps,
        count: steps.iter().copied().max().unwrap_or(1),
        dir_mask,
        watch: Watch::default(),
        end_of_motion: false,
        generation: 0,
        speed_mm_min: 6000.0,
        line: 1,
    }
}

/// Per-event instructions of `Stepper::on_event` plus the ISR's two stores
/// (BSRR word from a 16-entry table, next period into ARR), averaged over
/// `CHUNKS` x 1000 events. Each chunk is two 500-event segments from the
/// spsc queue, the second continuing the first's block, as the preparer
/// emits them (2 ms segments at 250 kHz).
fn step_event(clock: &mut Clock, steps: [u32; AXES], dir_mask: u8) -> f32 {
    const CHUNK: u32 = 1000;
    const CHUNKS: u32 = 20;
    let settings = Settings::default();
    let mut stepper = Stepper::new(StepConfig::new(&settings, TICK_HZ));
    let table: [u32; 16] = core::array::from_fn(|m| (m as u32) << 12);
    let mut queue: heapless::spsc::Queue<Segment, 4> = heapless::spsc::Queue::new();
    let (mut tx, mut rx) = queue.split();
    let mut total = 0u32;
    let sw = Switches::default();
    for chunk in 0..=CHUNKS {
        let half = CHUNK / 2;
        let _ = tx.enqueue(segment(steps, half, dir_mask, true));
        let _ = tx.enqueue(segment(steps, half, dir_mask, false));
        let mut pop = || rx.dequeue();
        let ticks = clock.time(|| {
            for _ in 0..CHUNK {
                let ev = stepper.on_event(&RT, &mut pop, sw);
                BSRR.store(table[usize::from(ev.step_pins & 0xF)], Relaxed);
                ARR.store(ev.ticks, Relaxed);
            }
        });
        // Chunk 0 warms up (its first event is a direction setup).
        if chunk > 0 {
            total += ticks;
        }
        black_box(stepper.position());
    }
    // Read the stand-in registers back: a static that is only ever written
    // is removed by the optimizer, stores and all.
    black_box(BSRR.load(Relaxed) ^ ARR.load(Relaxed));
    // The per-chunk overhead is subtracted once per chunk.
    let overhead = clock.overhead * (CHUNKS - 1);
    clock.insns(total.saturating_sub(overhead), CHUNKS * CHUNK)
}

/// One typical line through the lexer and the interpreter, commands out.
fn line(clock: &mut Clock) -> f32 {
    const REPS: u32 = 200;
    let text: &[u8] = b"G1 X10.5 Y-3.25 F1200";
    let mut interp = Interpreter::new();
    let mut n = 0u32;
    let mut ok = true;
    // Warm-up: the first line also switches the modal motion to G1.
    let _ = interp.execute_line(text, &mut |c| {
        black_box(&c);
    });
    let ticks = clock.time(|| {
        for _ in 0..REPS {
            ok &= interp
                .execute_line(black_box(text), &mut |c| {
                    black_box(&c);
                    n += 1;
                })
                .is_ok();
        }
    });
    if !ok || n != REPS {
        hprintln!("# line: {} commands from {} lines, ok={}", n, REPS, ok);
    }
    clock.insns(ticks, REPS)
}

/// One 0.1 mm block at 10,000 mm/min (the goal's scenario), converted to
/// steps and pushed into a full 64-block ring, look-ahead included. The path
/// is a 10 mm-radius polygon, so every junction is a shallow corner and no
/// block reaches full speed within the ring: the backward pass has real work.
fn plan_block(clock: &mut Clock) -> f32 {
    const REPS: u32 = 256;
    let mut planner: Planner<PLANNER_BLOCKS> = Planner::new(Settings::default());
    let speed = Speed::Feed(10_000.0 / 60.0);
    let step = 0.01f32; // 0.1 mm chord on a 10 mm radius
    let point = |k: u32| {
        let a = step * k as f32;
        [10.0 * libm::cosf(a), 10.0 * libm::sinf(a), 0.0, 0.0]
    };
    let mut k = 0u32;
    let push = |planner: &mut Planner<PLANNER_BLOCKS>, k: &mut u32| {
        if planner.is_full() {
            planner.pop();
        }
        *k += 1;
        let end = point(*k);
        match planner.to_steps(&end) {
            Ok(t) => planner.push_line(t, speed, Watch::default(), *k).is_ok(),
            Err(_) => false,
        }
    };
    // Fill the ring and run it to steady state (start point first).
    let _ = planner
        .to_steps(&point(0))
        .map(|t| planner.push_line(t, Speed::Rapid, Watch::default(), 0));
    for _ in 0..2 * PLANNER_BLOCKS {
        push(&mut planner, &mut k);
    }
    // Precompute outside the timed region what is not planning: the points.
    let mut ok = true;
    let mut total = 0u32;
    for _ in 0..REPS {
        let ticks = clock.time(|| ok &= push(&mut planner, &mut k));
        total += ticks;
    }
    if !ok {
        hprintln!("# plan: a push failed");
    }
    // `point()` (sin/cos) runs inside the region; measure it alone and remove it.
    let mut trig = 0u32;
    for i in 0..REPS {
        trig += clock.time(|| {
            black_box(point(black_box(i)));
        });
    }
    let per = clock.insns(total, REPS) - clock.insns(trig, REPS);
    black_box(planner.len());
    per
}

/// Ends QEMU with a status; `debug::exit` only returns without a debugger.
pub fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

pub fn run() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        hprintln!("# core peripherals already taken");
        exit(false)
    };
    let mut clock = Clock::new(cp.SYST);
    hprintln!(
        "# SysTick ticks per instruction: {} (expected 0.168: 168 MHz core clock, 1 ns per instruction)",
        clock.ticks_per_insn
    );
    if !(0.16..0.176).contains(&clock.ticks_per_insn) {
        hprintln!("# WARNING: not 0.168; is QEMU running with -icount shift=0?");
    }
    let one = step_event(&mut clock, [1000, 0, 0, 0], 0);
    let four = step_event(&mut clock, [1000, 750, 500, 250], 0b0101);
    let line = line(&mut clock);
    let plan = plan_block(&mut clock);
    let cycles = one * CPI + ISR_ENTRY_EXIT;
    let rate = TARGET_HZ / cycles;
    hprintln!("step_event_insns_1axis {}", libm::roundf(one) as u32);
    hprintln!("step_event_insns_4axis {}", libm::roundf(four) as u32);
    hprintln!("line_insns {}", libm::roundf(line) as u32);
    hprintln!("plan_block_insns {}", libm::roundf(plan) as u32);
    hprintln!("max_step_rate_hz_1axis {}", libm::roundf(rate) as u32);
    hprintln!(
        "# max_step_rate_hz_1axis = 96 MHz / (step_event_insns_1axis x {} CPI + {} cycles ISR entry/exit)",
        CPI,
        ISR_ENTRY_EXIT
    );
    exit(true)
}
