//! Boot checks of the clock tree and the two timers the step timing rests
//! on, each a zero-effect measurement: a wrong belief about the clocks
//! (an APB prescaler's timer-clock doubling, RM0383 §6.2; a PLL that fell
//! back to HSI) would make every step interval and pulse width wrong
//! without any other sign. A failure latches a `burin::chip::HwFault`.
//! Runs in init, with interrupts still masked, so nothing stretches the
//! measurement.
use burin::chip::{judge_rate, HwFault};
use burin::realtime::Realtime;
use cortex_m::peripheral::{DCB, DWT};
use stm32f4xx_hal::{pac, rcc::Clocks};

/// Core cycles each rate is measured over: about 0.2 ms, inside one
/// period of TIM1 (1 ms) so its 16-bit count does not wrap twice.
const WINDOW_CYCLES: u32 = 20_000;

/// Core cycles and the counter's readings before and after, over
/// `WINDOW_CYCLES`.
fn measure(count: impl Fn() -> u32) -> (u32, u32, u32) {
    let (c0, t0) = (DWT::cycle_count(), count());
    while DWT::cycle_count().wrapping_sub(c0) < WINDOW_CYCLES {}
    let (c1, t1) = (DWT::cycle_count(), count());
    (c1.wrapping_sub(c0), t0, t1)
}

pub fn clocks_and_timers(dcb: &mut DCB, dwt: &mut DWT, clocks: &Clocks, rt: &Realtime) {
    dcb.enable_trace();
    dwt.enable_cycle_counter();
    // SAFETY: register level: reads of RCC's configuration registers,
    // which have no side effects.
    let rcc = unsafe { &*pac::RCC::ptr() };
    let on_pll = rcc.cfgr().read().sws().is_pll();
    let from_hse = rcc.pllcfgr().read().pllsrc().is_hse();
    if !(on_pll && from_hse) {
        fail(rt, HwFault::Clock);
    }
    let core = clocks.sysclk().raw();
    // SAFETY: register level: reads of TIM5's and TIM1's counters and
    // TIM1's prescaler and period, no side effects.
    let (tim5, tim1) = unsafe { (&*pac::TIM5::ptr(), &*pac::TIM1::ptr()) };
    let (cycles, t0, t1) = measure(|| tim5.cnt().read().bits());
    if !judge_rate(cycles, t1.wrapping_sub(t0), clocks.timclk1().raw(), core) {
        fail(rt, HwFault::StepTimer);
    }
    let period = (tim1.arr().read().bits() & 0xFFFF) + 1;
    let psc = (tim1.psc().read().bits() & 0xFFFF) + 1;
    let (cycles, t0, t1) = measure(|| tim1.cnt().read().bits() & 0xFFFF);
    // Up to one wrap at the period (the window is shorter than it).
    let ticks = (t1 + period - t0) % period;
    if !judge_rate(cycles, ticks, clocks.timclk2().raw() / psc, core) {
        fail(rt, HwFault::PulseTimer);
    }
}

fn fail(rt: &Realtime, fault: HwFault) {
    defmt::error!("boot check: {}", fault.message());
    rt.set_hw_fault(fault);
}
