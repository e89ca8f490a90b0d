//! The measurements. Each one runs its subject many times between two SysTick
//! reads, so the per-run figure is an average and the tick granularity
//! (about 6 instructions at 168 MHz) vanishes in the division.
use burin::interp::Interpreter;
use burin::planner::{Planner, Speed, Watch};
use burin::realtime::Realtime;
use burin::seams::{StepPins, StepTimer};
use burin::settings::Settings;
use burin::stepper::driver::StepDriver;
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
/// Cortex-M4 exception entry and exit, cycles: 12 to stack eight words
/// and fetch the vector, 12 to unstack (RM: 12 each with zero-wait-state
/// memory; the step handlers use no FPU register, so lazy stacking adds
/// nothing). QEMU's -icount counts neither: they are added here.
const ISR_ENTRY_EXIT: f32 = 12.0 + 12.0;
/// Instructions of the RTIC binding around the driver, per interrupt, that
/// the timed region does not contain: the vector's function (BASEPRI save
/// and restore for a priority-3 task), `StepTask::on_interrupt`'s call,
/// its prologue/epilogue and the `try_send` test of its result.
const BINDING_INSNS: f32 = 14.0;
/// Assumed cycles per instruction of the handler code: QEMU counts
/// instructions, the chip spends cycles. Loads take 2 cycles, taken
/// branches 2-4 (pipeline refill), ALU operations 1; flash at 96 MHz has 3
/// wait states, hidden by the ART accelerator while the handler stays in
/// its 1 KB instruction cache (it is small and runs at every step). 1.3 is
/// an estimate, not a measurement: only DWT.CYCCNT on a board settles it.
const CPI: f32 = 1.3;
/// Peripheral reads per step and their extra cycles: TIM5 CNT at the rise
/// and at the fall (APB1 at 48 MHz behind the bridge: about 5 cycles
/// each), GPIOA IDR at the rise (AHB1: about 2). Stores go through the
/// write buffer and do not stall.
const BUS_CYCLES: f32 = 2.0 * 5.0 + 2.0;
/// Interrupts per step: the rise and the fall.
const IRQS_PER_STEP: f32 = 2.0;
/// The default `$201` (burin's step-rate ceiling), Hz.
const DEFAULT_201_HZ: f32 = 200_000.0;
/// Same size as the firmware's ring (host-sim uses 64 too).
const PLANNER_BLOCKS: usize = 64;
/// Step timer rate the stepper is configured with (TIM5 at 96 MHz).
const TICK_HZ: u32 = 96_000_000;

/// Stand-ins for the step interrupt's registers: GPIOB BSRR and IDR, TIM5
/// CNT, CCR1 and SR. Plain RAM words cost the same instructions as the
/// registers and keep the measurement independent of QEMU's models.
static BSRR: AtomicU32 = AtomicU32::new(0);
static IDR: AtomicU32 = AtomicU32::new(0xFFFF);
static CNT: AtomicU32 = AtomicU32::new(0);
static CCR1: AtomicU32 = AtomicU32::new(0);
static SR: AtomicU32 = AtomicU32::new(0);
static RT: Realtime = Realtime::new();

/// The board's `StepHw` on the stand-ins, store for store: BSRR words from
/// 16-entry tables, one IDR read for the switches, CNT reads, and the
/// compare's flag clear + CCR1 write.
struct BenchHw {
    step_on: [u32; 16],
    dirs: [u32; 16],
    step_off: u32,
}

impl StepPins for BenchHw {
    #[inline(always)]
    fn step_high(&mut self, dir_mask: u8, step_mask: u8) {
        let word =
            self.dirs[usize::from(dir_mask & 0xF)] | self.step_on[usize::from(step_mask & 0xF)];
        BSRR.store(word, Relaxed);
    }
    #[inline(always)]
    fn step_low(&mut self) {
        BSRR.store(self.step_off, Relaxed);
    }
    fn set_enabled(&mut self, _on: bool) {}
    #[inline(always)]
    fn switches(&self) -> Switches {
        let closed = !IDR.load(Relaxed);
        Switches {
            limits: ((closed >> 4) & 0b111) as u8,
            probe: closed & (1 << 3) != 0,
        }
    }
}

impl StepTimer for BenchHw {
    fn tick_hz(&self) -> u32 {
        TICK_HZ
    }
    #[inline(always)]
    fn now(&self) -> u32 {
        CNT.load(Relaxed)
    }
    #[inline(always)]
    fn schedule_at(&mut self, at: u32) {
        SR.store(!2, Relaxed);
        CCR1.store(at, Relaxed);
    }
    fn start(&mut self) {}
    fn stop(&mut self) {}
}

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
        cut: 0.0,
    }
}

/// Per-step instructions of the step interrupt's two handlers, rise and
/// fall: `StepDriver::on_interrupt` (the rise runs `Stepper::on_event`
/// while the pulse is high) with every register access on [`BenchHw`].
/// Each handler is timed on its own and the figures are averaged over
/// `CHUNKS` x 1000 steps. The harness plays the counter: in each timed
/// region it first sets CNT to the armed CCR1 (one load and one store,
/// counted). Each chunk is two 500-event segments from the spsc queue, the
/// second continuing the first's block, as the preparer emits them (2 ms
/// segments at 250 kHz); a chunk's first rise (the kick from rest) and its
/// stop are not timed. Returns (rise, fall).
fn step_event(clock: &mut Clock, steps: [u32; AXES], dir_mask: u8) -> (f32, f32) {
    const CHUNK: u32 = 1000;
    const CHUNKS: u32 = 20;
    let settings = Settings::default();
    let mut stepper = Stepper::new(StepConfig::new(&settings, TICK_HZ));
    let mut driver = StepDriver::new();
    let mut hw = BenchHw {
        step_on: core::array::from_fn(|m| (m as u32) << 12),
        dirs: core::array::from_fn(|m| ((m as u32) << 4) | ((!m as u32 & 0xF) << 20)),
        step_off: 0xF << 28,
    };
    let mut queue: heapless::spsc::Queue<Segment, 4> = heapless::spsc::Queue::new();
    let (mut tx, mut rx) = queue.split();
    let (mut rise, mut fall, mut rises, mut falls) = (0u32, 0u32, 0u32, 0u32);
    for chunk in 0..=CHUNKS {
        let half = CHUNK / 2;
        let _ = tx.enqueue(segment(steps, half, dir_mask, true));
        let _ = tx.enqueue(segment(steps, half, dir_mask, false));
        let mut pop = || rx.dequeue();
        // The kick: starts, and (target = now) does the first rise, or a
        // direction change whose first step then follows untimed too.
        driver.on_interrupt(&mut stepper, &mut hw, &RT, &mut pop);
        let mut high = BSRR.load(Relaxed) & 0xF000 != 0;
        while !high {
            CNT.store(CCR1.load(Relaxed), Relaxed);
            driver.on_interrupt(&mut stepper, &mut hw, &RT, &mut pop);
            high = BSRR.load(Relaxed) & 0xF000 != 0;
        }
        let mut n = 0;
        while driver.is_running() && n < 2 * CHUNK {
            let ticks = clock.time(|| {
                CNT.store(CCR1.load(Relaxed), Relaxed);
                driver.on_interrupt(&mut stepper, &mut hw, &RT, &mut pop);
            });
            // A fall leaves the step pins low; the slot after the last
            // step (the stop) is no step's cost.
            let was_high = high;
            high = BSRR.load(Relaxed) & 0xF000 != 0;
            if chunk > 0 && driver.is_running() {
                if was_high {
                    fall += ticks.saturating_sub(clock.overhead);
                    falls += 1;
                } else {
                    rise += ticks.saturating_sub(clock.overhead);
                    rises += 1;
                }
            }
            n += 1;
        }
        black_box(stepper.position());
    }
    black_box(BSRR.load(Relaxed) ^ SR.load(Relaxed));
    let per = |t: u32, n: u32| t as f32 / clock.ticks_per_insn / n.max(1) as f32;
    (per(rise, rises), per(fall, falls))
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
    let (rise1, fall1) = step_event(&mut clock, [1000, 0, 0, 0], 0);
    let (rise4, fall4) = step_event(&mut clock, [1000, 750, 500, 250], 0b0101);
    let (one, four) = (rise1 + fall1, rise4 + fall4);
    let line = line(&mut clock);
    let plan = plan_block(&mut clock);
    // Every cycle one step costs: both handlers' instructions and their
    // bindings at the assumed CPI, both interrupts' entry and exit, and the
    // peripheral reads' bus stalls.
    let path_insns = one + IRQS_PER_STEP * BINDING_INSNS;
    let cycles = path_insns * CPI + IRQS_PER_STEP * ISR_ENTRY_EXIT + BUS_CYCLES;
    let rate = TARGET_HZ / cycles;
    let cpu = |hz: f32| cycles * hz / TARGET_HZ * 100.0;
    hprintln!("step_event_insns_1axis {}", libm::roundf(one) as u32);
    hprintln!("step_event_insns_4axis {}", libm::roundf(four) as u32);
    hprintln!("step_rise_insns_1axis {}", libm::roundf(rise1) as u32);
    hprintln!("step_fall_insns_1axis {}", libm::roundf(fall1) as u32);
    hprintln!("step_rise_insns_4axis {}", libm::roundf(rise4) as u32);
    hprintln!("step_fall_insns_4axis {}", libm::roundf(fall4) as u32);
    hprintln!("line_insns {}", libm::roundf(line) as u32);
    hprintln!("plan_block_insns {}", libm::roundf(plan) as u32);
    hprintln!("step_path_insns_1axis {}", libm::roundf(path_insns) as u32);
    hprintln!("step_path_cycles_1axis {}", libm::roundf(cycles) as u32);
    hprintln!("max_step_rate_hz_1axis {}", libm::roundf(rate) as u32);
    hprintln!(
        "cpu_percent_at_100khz {}",
        libm::roundf(cpu(100_000.0)) as u32
    );
    hprintln!(
        "cpu_percent_at_default_201 {}",
        libm::roundf(cpu(DEFAULT_201_HZ)) as u32
    );
    hprintln!(
        "# step_path_cycles_1axis = (step_event_insns_1axis + {} x {} binding insns) x {} CPI (assumed) + {} interrupts x {} cycles entry/exit + {} cycles of peripheral-read stalls; max_step_rate_hz_1axis = 96 MHz / that; cpu_percent_at_* = that x rate / 96 MHz ($201 default {} Hz)",
        IRQS_PER_STEP,
        BINDING_INSNS,
        CPI,
        IRQS_PER_STEP,
        ISR_ENTRY_EXIT,
        BUS_CYCLES,
        DEFAULT_201_HZ
    );
    exit(true)
}
