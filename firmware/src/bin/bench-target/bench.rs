//! The measurements. Each one runs its subject many times between two SysTick
//! reads, so the per-run figure is an average and the tick granularity
//! (about 6 instructions at 168 MHz) vanishes in the division. The step
//! handler also runs in a trace run ([`trace_run`]) whose executed
//! instructions the xtask charges by Cortex-M4 timings.
use burin::controller::PLANNER_BLOCKS;
use burin::interp::Interpreter;
use burin::planner::{Curve, Planner, Speed, Watch};
use burin::realtime::Realtime;
use burin::seams::{StepPins, StepTimer};
use burin::settings::{Profile, Settings};
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

/// Step timer rate the stepper is configured with (TIM5 at 96 MHz).
const TICK_HZ: u32 = 96_000_000;

/// Stand-ins for the step interrupt's registers, at fixed addresses as the
/// registers are: TIM5's SR, CNT, CCR1 and CCR2 at their offsets in one
/// block (APB1 on the chip), a GPIO port's IDR and BSRR (AHB1), and TIM1's
/// CNT, ARR and CCR2 (APB2: the pulse end's compare, whose match requests
/// DMA2 to write the step-off word). The board reaches TIM5 from one base
/// address in a register and the port's BSRR through the address the
/// step port holds ([`BenchHw::bsrr`]); so do these, so the timed code is
/// the board's instruction for instruction. Plain RAM words, not QEMU's
/// peripheral models: a load or store costs the same instructions, and
/// the harness plays the counter. The window is the top 4 KiB of the
/// machine's RAM, which `memory-f405.x` keeps out of the linker's RAM;
/// `cargo xtask bench-target`'s cycle model (xtask/src/bench_target/)
/// charges an access to each block as one to its bus, by these addresses.
mod regs {
    use core::sync::atomic::AtomicU32;

    const TIM: usize = 0x2001_F000;
    const GPIO: usize = 0x2001_F400;
    const TIM1: usize = 0x2001_F800;
    /// Non-zero: the trace run (QEMU's loader device writes it before
    /// reset; see [`super::trace_run`]).
    const TRACE: usize = 0x2001_FFFC;

    #[inline(always)]
    fn at(addr: usize) -> &'static AtomicU32 {
        // SAFETY: register level (stand-ins): `addr` is a word-aligned
        // address inside the 4 KiB of RAM that memory-f405.x reserves for
        // these registers; nothing else (no static, no stack) lives there,
        // and every access goes through this atomic view.
        unsafe { &*(addr as *const AtomicU32) }
    }
    pub fn sr() -> &'static AtomicU32 {
        at(TIM + 0x10)
    }
    pub fn cnt() -> &'static AtomicU32 {
        at(TIM + 0x24)
    }
    pub fn ccr1() -> &'static AtomicU32 {
        at(TIM + 0x34)
    }
    pub fn ccr2() -> &'static AtomicU32 {
        at(TIM + 0x38)
    }
    pub fn idr() -> &'static AtomicU32 {
        at(GPIO + 0x10)
    }
    pub fn bsrr() -> &'static AtomicU32 {
        at(GPIO + 0x18)
    }
    pub fn tim1_cnt() -> &'static AtomicU32 {
        at(TIM1 + 0x24)
    }
    pub fn tim1_arr() -> &'static AtomicU32 {
        at(TIM1 + 0x2C)
    }
    pub fn tim1_ccr2() -> &'static AtomicU32 {
        at(TIM1 + 0x38)
    }
    pub fn trace() -> &'static AtomicU32 {
        at(TRACE)
    }
}
static RT: Realtime = Realtime::new();
/// The stand-in port's step-off word (all four step pins low).
const STEP_OFF: u32 = 0xF << 28;
/// Peripheral reads of a counting run (never touched by a timed one).
static CNT_READS: AtomicU32 = AtomicU32::new(0);
static IDR_READS: AtomicU32 = AtomicU32::new(0);

/// The board's `StepHw` on the stand-ins, store for store: BSRR words from
/// 16-entry tables, one IDR read for the switches, CNT reads, and the
/// compare's flag clear + CCR1 write. `HW`: pulses end by DMA2 on a TIM1
/// compare (the F411 and F401 boards, issue 28: DMA1, which TIM5's
/// requests reach, cannot write GPIO); else by a fall interrupt (the QEMU
/// build). `COUNT`: count the peripheral reads instead of timing (the
/// counting code is not in the timed build).
struct BenchHw<const HW: bool, const COUNT: bool> {
    /// The port's BSRR, as `StepPort` holds its address.
    bsrr: &'static AtomicU32,
    step_on: [u32; 16],
    dirs: [u32; 16],
    step_off: u32,
    /// The pulse width in TIM1 ticks plus the margin (precomputed).
    w1: u32,
    /// TIM1's ARR as `PulseEnd` caches it (the 1 kHz PWM at 48 MHz).
    arr1: u32,
}

impl<const HW: bool, const COUNT: bool> StepPins for BenchHw<HW, COUNT> {
    const ENDS_PULSES: bool = HW;
    fn pulse_end_latency(&self) -> u32 {
        32
    }
    /// With `HW` the boards' rise: interrupts masked (an EXTI handler can
    /// no longer land between the counter read and the stores), TIM1's
    /// counter read, the pulse end computed modulo its period (kept in
    /// RAM, as `PulseEnd` keeps TIM1's ARR), CCR2 written, then the rising
    /// BSRR store.
    #[inline(always)]
    fn step_high(&mut self, step_mask: u8) {
        let on = self.step_on[usize::from(step_mask & 0xF)];
        if HW {
            // Everything from RAM first, as the board's `StepHw::step_high`:
            // inside the masked window only the registers.
            let (bsrr, w1, arr) = (self.bsrr, self.w1, self.arr1);
            cortex_m::interrupt::disable();
            let c = regs::tim1_cnt().load(Relaxed);
            let mut e = c.wrapping_add(w1);
            if e > arr {
                e -= arr + 1;
            }
            regs::tim1_ccr2().store(e, Relaxed);
            bsrr.store(on, Relaxed);
            // SAFETY: register level (PRIMASK): the step handler runs with
            // interrupts enabled, so this restores the state it found.
            unsafe { cortex_m::interrupt::enable() };
        } else {
            self.bsrr.store(on, Relaxed);
        }
    }
    #[inline(always)]
    fn set_directions(&mut self, dir_mask: u8) {
        self.bsrr
            .store(self.dirs[usize::from(dir_mask & 0xF)], Relaxed);
    }
    #[inline(always)]
    fn step_low(&mut self) {
        self.bsrr.store(self.step_off, Relaxed);
    }
    fn set_enabled(&mut self, _on: bool) {}
    #[inline(always)]
    fn switches(&self) -> Switches {
        if COUNT {
            IDR_READS.fetch_add(1, Relaxed);
        }
        let closed = !regs::idr().load(Relaxed);
        Switches {
            limits: ((closed >> 4) & 0b111) as u8,
            probe: closed & (1 << 3) != 0,
        }
    }
}

impl<const HW: bool, const COUNT: bool> StepTimer for BenchHw<HW, COUNT> {
    fn tick_hz(&self) -> u32 {
        TICK_HZ
    }
    #[inline(always)]
    fn now(&self) -> u32 {
        if COUNT {
            CNT_READS.fetch_add(1, Relaxed);
        }
        regs::cnt().load(Relaxed)
    }
    #[inline(always)]
    fn schedule_at(&mut self, at: u32) {
        regs::sr().store(!2, Relaxed);
        regs::ccr1().store(at, Relaxed);
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
        c
    }

    /// Ticks per instruction, from 2 M instructions of a known loop (not
    /// in the trace run, whose log would hold them all).
    fn calibrate(&mut self) {
        const N: u32 = 1_000_000;
        let ticks = self.time(|| count_down(N)).saturating_sub(self.overhead);
        self.ticks_per_insn = ticks as f32 / (2 * N) as f32;
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
        takeup: false,
    }
}

/// How [`step_event`] runs: `chunks` timed chunks of `chunk` steps after
/// an untimed one, hard limits armed or not, and with `trace` the trace
/// run's markers around each timed handler.
#[derive(Clone, Copy)]
struct Run {
    chunk: u32,
    chunks: u32,
    hard_limits: bool,
    trace: Option<u32>,
}

impl Run {
    /// The timing run: 20 chunks of 1000 steps.
    const fn timed(hard_limits: bool) -> Self {
        Run {
            chunk: 1000,
            chunks: 20,
            hard_limits,
            trace: None,
        }
    }
}

/// Per-step instructions of the step interrupt: `StepDriver::on_interrupt`
/// (the rise runs `Stepper::on_event` while the pulse is high) with every
/// register access on [`BenchHw`]. With `HW` (the boards) a step is one
/// handler and the harness plays the DMA, lowering the pins after each
/// rise outside the timed region; without it (QEMU) each step is a rise
/// and a fall handler, timed apart. Figures are averaged over the run's
/// chunks of steps. The harness plays the counter: in each timed region
/// it first sets CNT to the armed CCR1 (one load and one store, counted).
/// Each chunk is two segments of half its events from the spsc queue, the
/// second continuing the first's block, as the preparer emits them; a
/// chunk's first rise (the kick from rest) and its stop are not timed.
/// With hard limits armed (switches open) every step reads the switch
/// port and checks it. Returns (rise, fall) instructions per step, and
/// with `COUNT` the CNT and IDR reads per step instead.
fn step_event<const HW: bool, const COUNT: bool>(
    clock: &mut Clock,
    steps: [u32; AXES],
    dir_mask: u8,
    run: Run,
) -> (f32, f32) {
    let settings = Settings::default();
    let mut queue: heapless::spsc::Queue<Segment, 4> = heapless::spsc::Queue::new();
    // Switches open (pulled up); the counters at 0 and the pins low; TIM1
    // at the spindle PWM's period (1 kHz at a 48 MHz tick).
    regs::idr().store(0xFFFF, Relaxed);
    regs::cnt().store(0, Relaxed);
    regs::bsrr().store(STEP_OFF, Relaxed);
    regs::tim1_cnt().store(0, Relaxed);
    regs::tim1_arr().store(47_999, Relaxed);
    RT.set_limits_armed(run.hard_limits);
    let (mut tx, rx) = queue.split();
    let mut task = Task::<HW, COUNT> {
        driver: StepDriver::new(),
        stepper: Stepper::new(StepConfig::new(&settings, TICK_HZ)),
        hw: BenchHw {
            bsrr: regs::bsrr(),
            step_on: core::array::from_fn(|m| (m as u32) << 12),
            dirs: core::array::from_fn(|m| ((m as u32) << 4) | ((!m as u32 & 0xF) << 20)),
            step_off: STEP_OFF,
            w1: 2 * 48 + 8,
            arr1: 47_999,
        },
        queue: rx,
    };
    let (mut rise, mut fall, mut rises, mut falls) = (0u32, 0u32, 0u32, 0u32);
    let is_high = || regs::bsrr().load(Relaxed) & 0xF000 != 0;
    // The DMA's pulse end, outside the timed region.
    let dma_fall = || {
        if HW {
            regs::bsrr().store(STEP_OFF, Relaxed);
        }
    };
    let (mut cnt_reads, mut idr_reads) = (0u32, 0u32);
    for chunk in 0..=run.chunks {
        let half = run.chunk / 2;
        let _ = tx.enqueue(segment(steps, half, dir_mask, true));
        let _ = tx.enqueue(segment(steps, half, dir_mask, false));
        // The kick: starts, and (target = now) does the first rise, or a
        // direction change whose first step then follows untimed too.
        isr(&mut task);
        let mut high = is_high();
        while !high {
            regs::cnt().store(regs::ccr1().load(Relaxed), Relaxed);
            isr(&mut task);
            high = is_high();
        }
        dma_fall();
        high = is_high();
        let mut n = 0;
        while task.driver.is_running() && n < 2 * run.chunk {
            let (c0, i0) = (CNT_READS.load(Relaxed), IDR_READS.load(Relaxed));
            if let Some(tag) = run.trace {
                trace_begin(tag);
            }
            let ticks = clock.time(|| {
                regs::cnt().store(regs::ccr1().load(Relaxed), Relaxed);
                isr(&mut task);
            });
            // A fall leaves the step pins low; the slot after the last
            // step (the stop) is no step's cost.
            let was_high = high;
            high = is_high();
            let kept = chunk > 0 && task.driver.is_running();
            if run.trace.is_some() {
                trace_end(match (kept, was_high) {
                    (false, _) => 0,
                    (true, false) => 1,
                    (true, true) => 2,
                });
            }
            if kept {
                cnt_reads += CNT_READS.load(Relaxed) - c0;
                idr_reads += IDR_READS.load(Relaxed) - i0;
                if was_high {
                    fall += ticks.saturating_sub(clock.overhead);
                    falls += 1;
                } else {
                    rise += ticks.saturating_sub(clock.overhead);
                    rises += 1;
                }
            }
            if high {
                dma_fall();
                high = is_high();
            }
            n += 1;
        }
        black_box(task.stepper.position());
    }
    RT.set_limits_armed(false);
    black_box(
        regs::bsrr().load(Relaxed)
            ^ regs::sr().load(Relaxed)
            ^ regs::ccr2().load(Relaxed)
            ^ regs::tim1_ccr2().load(Relaxed),
    );
    if COUNT {
        let per = |n: u32| n as f32 / rises.max(1) as f32;
        return (per(cnt_reads), per(idr_reads));
    }
    let per = |t: u32, n: u32| t as f32 / clock.ticks_per_insn / n.max(1) as f32;
    // Per step: every rise is a step here (no direction changes in the
    // timed region), and with `HW` there are no falls.
    (
        per(rise, rises),
        per(fall, falls) * falls as f32 / rises.max(1) as f32,
    )
}

/// Trace run markers: the cycle model (xtask/src/bench_target/trace.rs)
/// finds them by name in the ELF and reads their argument (r0) from
/// QEMU's register log. `trace_begin(tag)`: the next step handler belongs
/// to phase `tag`; `trace_end(kind)`: it was a rise (1), a fall (2), or
/// not a step's cost (0: the untimed chunk, the stop). Each is an
/// `asm!` block of its own (side effects assumed, so no call is dropped,
/// and no two are alike, so they cannot be merged into one function).
#[no_mangle]
#[inline(never)]
extern "C" fn burin_trace_begin(tag: u32) {
    // SAFETY: no instruction but `nop`; `tag` is only held in r0.
    unsafe { core::arch::asm!("nop", in("r0") tag, options(nostack)) };
}
#[no_mangle]
#[inline(never)]
extern "C" fn burin_trace_end(kind: u32) {
    // SAFETY: as above, two `nop`s.
    unsafe { core::arch::asm!("nop", "nop", in("r0") kind, options(nostack)) };
}
fn trace_begin(tag: u32) {
    burin_trace_begin(black_box(tag));
}
fn trace_end(kind: u32) {
    burin_trace_end(black_box(kind));
}

/// The trace run (QEMU logging every instruction with the registers
/// before it, for the cycle model): the step handler's phases only, a
/// few hundred steps each, no calibration and no planner (the log of the
/// timing run would be gigabytes). Tags: 1 boards 1 axis, 2 the same with
/// hard limits armed, 3 boards 4 axes, 4 the QEMU build's rise and fall.
fn trace_run(clock: &mut Clock) -> ! {
    const ONE: [u32; AXES] = protocol::first_axes([1000, 0, 0, 0, 0, 0]);
    // The benches measure four axes whatever the build drives.
    const FOUR: [u32; AXES] = protocol::first_axes([1000, 750, 500, 250, 0, 0]);
    let run = |hard_limits, tag| Run {
        chunk: 200,
        chunks: 1,
        hard_limits,
        trace: Some(tag),
    };
    step_event::<true, false>(clock, ONE, 0, run(false, 1));
    step_event::<true, false>(clock, ONE, 0, run(true, 2));
    step_event::<true, false>(clock, FOUR, 0b0101, run(false, 3));
    step_event::<false, false>(clock, ONE, 0, run(false, 4));
    hprintln!("# trace run done");
    exit(true)
}

/// The board's `StepTask` on the stand-ins (its layout too: `repr(C)`,
/// the stepper first).
#[repr(C)]
struct Task<'q, const HW: bool, const COUNT: bool> {
    stepper: Stepper,
    driver: StepDriver,
    hw: BenchHw<HW, COUNT>,
    queue: heapless::spsc::Consumer<'q, Segment>,
}

/// Whether the last handler would have woken the parse task.
static WAKE: AtomicU32 = AtomicU32::new(0);

/// The TIM5 vector as RTIC 2 generates it for a priority-3 task
/// (`rtic::export::run`: BASEPRI read, the task, BASEPRI written back;
/// the task body is `StepTask::on_interrupt` and a `try_send` when it
/// says so, here a store).
#[inline(never)]
fn isr<const HW: bool, const COUNT: bool>(task: &mut Task<'_, HW, COUNT>) {
    let initial = cortex_m::register::basepri::read();
    let queue = &mut task.queue;
    if task
        .driver
        .on_interrupt(&mut task.stepper, &mut task.hw, &RT, &mut || {
            queue.dequeue()
        })
    {
        WAKE.fetch_add(1, Relaxed);
    }
    // SAFETY: register level, as RTIC's binding: writes back the BASEPRI
    // value read on entry (0 here: nothing masked).
    unsafe { cortex_m::register::basepri::write(initial) };
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
/// Instructions per block pushed onto a full ring in steady state, on a
/// 10 mm circle in 0.1 mm moves: G1 lines in trapezoid mode (`scurve`
/// false), or the chords of one arc in S-curve mode (the chord's own
/// budget, the jerk cap and the forward pass's run reach).
fn plan_block(clock: &mut Clock, scurve: bool) -> f32 {
    const REPS: u32 = 256;
    let settings = if scurve {
        Settings {
            profile: Profile::SCurve,
            ..Settings::default()
        }
    } else {
        Settings::default()
    };
    let curve = Curve {
        radius: 10.0,
        plane: 0b11,
    };
    let mut planner: Planner<PLANNER_BLOCKS> = Planner::new(settings);
    let speed = Speed::Feed(10_000.0 / 60.0);
    let step = 0.01f32; // 0.1 mm chord on a 10 mm radius
    let point = |k: u32| {
        let a = step * k as f32;
        burin::pad([10.0 * libm::cosf(a), 10.0 * libm::sinf(a)])
    };
    let mut k = 0u32;
    let push = |planner: &mut Planner<PLANNER_BLOCKS>, k: &mut u32| {
        if planner.is_full() {
            planner.pop();
        }
        *k += 1;
        let end = point(*k);
        if scurve {
            return planner.push_chord(&end, speed, *k, curve).is_ok();
        }
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

/// `burin::num::sqrt` (the FPU's VSQRT.F32 on the chip) against libm's
/// software square root, bit for bit: both are IEEE 754's correctly
/// rounded root, so host-sim (libm) and the board plan alike. Zero, a
/// subnormal, squares, non-squares from 1e-30 to 1e30, infinity.
#[allow(clippy::disallowed_methods)]
fn sqrt_mismatches() -> u32 {
    let mut off = 0u32;
    let mut check = |x: f32| {
        if burin::num::sqrt(x).to_bits() != libm::sqrtf(x).to_bits() {
            off += 1;
        }
    };
    for x in [0.0, 1e-40, 1.0, 2.0, 4.0, 1e30, f32::MAX, f32::INFINITY] {
        check(x);
    }
    let mut x = 1e-30f32;
    while x < 1e30 {
        check(x);
        check(x * 1.000_123);
        x *= 1.37;
    }
    for k in 1..2000u32 {
        let f = k as f32;
        check(f * f);
        check(f * 0.013_7);
    }
    off
}

pub fn run() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        hprintln!("# core peripherals already taken");
        exit(false)
    };
    let mut clock = Clock::new(cp.SYST);
    if regs::trace().load(Relaxed) != 0 {
        trace_run(&mut clock);
    }
    clock.calibrate();
    hprintln!(
        "# SysTick ticks per instruction: {} (expected 0.168: 168 MHz core clock, 1 ns per instruction)",
        clock.ticks_per_insn
    );
    if !(0.16..0.176).contains(&clock.ticks_per_insn) {
        hprintln!("# WARNING: not 0.168; is QEMU running with -icount shift=0?");
    }
    const ONE: [u32; AXES] = protocol::first_axes([1000, 0, 0, 0, 0, 0]);
    // The benches measure four axes whatever the build drives.
    const FOUR: [u32; AXES] = protocol::first_axes([1000, 750, 500, 250, 0, 0]);
    let (off, hard) = (Run::timed(false), Run::timed(true));
    // The boards: one interrupt per step, the pulse ended by DMA.
    let (rise1, _) = step_event::<true, false>(&mut clock, ONE, 0, off);
    let (rise1_hard, _) = step_event::<true, false>(&mut clock, ONE, 0, hard);
    let (rise4, _) = step_event::<true, false>(&mut clock, FOUR, 0b0101, off);
    let (cnt_reads, idr_reads) = step_event::<true, true>(&mut clock, ONE, 0, off);
    let (_, idr_reads_hard) = step_event::<true, true>(&mut clock, ONE, 0, hard);
    // The QEMU build: a rise and a fall interrupt per step.
    let (q_rise1, q_fall1) = step_event::<false, false>(&mut clock, ONE, 0, off);
    let line = line(&mut clock);
    let plan = plan_block(&mut clock, false);
    let plan_s = plan_block(&mut clock, true);
    let sqrt_off = sqrt_mismatches();
    let r = |v: f32| libm::roundf(v) as u32;
    hprintln!("step_event_insns_1axis {}", r(rise1));
    hprintln!("step_event_insns_1axis_hard_limits {}", r(rise1_hard));
    hprintln!("step_event_insns_4axis {}", r(rise4));
    hprintln!("step_cnt_reads_1axis {}", cnt_reads);
    hprintln!("step_idr_reads_1axis {}", idr_reads);
    hprintln!("step_idr_reads_1axis_hard_limits {}", idr_reads_hard);
    hprintln!("qemu_step_rise_insns_1axis {}", r(q_rise1));
    hprintln!("qemu_step_fall_insns_1axis {}", r(q_fall1));
    hprintln!("line_insns {}", r(line));
    hprintln!("plan_block_insns {}", r(plan));
    hprintln!("plan_chord_scurve_insns {}", r(plan_s));
    hprintln!("sqrt_mismatches {}", sqrt_off);
    hprintln!("step_path_insns_1axis {}", r(rise1));
    hprintln!(
        "# step_event_insns_*: the whole TIM5 handler per step (RTIC's binding and the harness's counter store included), counted by QEMU -icount. Cycles come from the trace run: cargo xtask bench-target's model charges each executed instruction by Cortex-M4 timings (xtask/src/bench_target/model.rs)."
    );
    exit(true)
}
