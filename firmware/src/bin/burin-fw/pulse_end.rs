//! The step pulse's end on the boards: TIM1's compare 2 raises a DMA
//! request, DMA2 stream 2 (channel 6) copies the step-off word from SRAM to
//! the step port's BSRR, so a step costs one interrupt (the rise) and the
//! fall needs no CPU. `firmware/CHIP.md` lists the facts this relies on;
//! `burin::chip::dma::DmaPath::pulse_end` is the path, checked against the
//! chip's bus matrix by the library and at boot by a test transfer.
//!
//! Why TIM1 and DMA2: only DMA2's peripheral port reaches GPIO (RM0383
//! §2.1.5; DMA1's ports reach APB1 and the memories only, the mistake of
//! burin up to 16ae6d1), and among the timers only TIM1's requests are on
//! DMA2 (RM0383 table 28). TIM1 also carries the spindle PWM on channel 1
//! (1 kHz): channel 2 is free and counts on the same time base, so the
//! pulse end is computed modulo TIM1's period. Its match recurs once per
//! PWM period and rewrites the step-off word: harmless, the pins are low
//! by then and every rise re-arms the compare before it raises them.
use burin::chip::dma::{DmaPath, StreamFlags};
use burin::chip::{Chip, HwFault, PulseEndHw};
use core::sync::atomic::{AtomicU32, Ordering::Relaxed};
use stm32f4xx_hal::pac;

/// The step-off word the stream copies (under `$2`). In SRAM: DMA2's
/// memory port reads it (RM0383 §2.1.4).
static STEP_OFF: AtomicU32 = AtomicU32::new(0);

/// The stream: DMA2 stream 2 (TIM1_CH2 on channel 6, RM0383 table 28).
const STREAM: usize = 2;

/// TIM1 ticks added to every pulse: the counter is read a few core cycles
/// before the rising store, so the compare at read + width + margin lands
/// at least `$0` after the store (8 ticks at 48 MHz: 167 ns).
const MARGIN_TICKS: u32 = 8;

/// From the compare match to the BSRR write by DMA2, in step-timer ticks,
/// as an upper bound: the request, arbitration, the SRAM read and the AHB1
/// write take about a dozen AHB cycles (RM0383 §9.3); 32 leaves room for
/// the CPU holding the bus. Only a scope on a board measures it.
const DMA_LATENCY_TICKS: u32 = 32;

/// TIM1's compare 2 and DMA2 stream 2, as the step interrupt uses them.
pub struct PulseEnd {
    /// The stream's configuration, for a restart.
    path: DmaPath,
    /// TIM1's period minus one (ARR) and its tick rate.
    arr: u32,
    tick_hz: u32,
    /// The step timer's rate, for converting widths.
    step_hz: u32,
    /// The current width in TIM1 ticks, margin included.
    width: u32,
    /// The worst end beyond the width, in step-timer ticks.
    latency: u32,
}

/// TIM1's register block. The HAL's PWM channel owns CCR1 and CCER's
/// channel-1 bits; this module touches CCR2, CNT, CCMR1's channel-2 field,
/// DIER.CC2DE and EGR.CC2G only.
fn tim1() -> &'static pac::tim1::RegisterBlock {
    // SAFETY: register level: TIM1's fixed address from the PAC; the
    // fields used here are disjoint from the PWM channel's (see above).
    unsafe { &*pac::TIM1::ptr() }
}

fn dma2() -> &'static pac::dma1::RegisterBlock {
    // SAFETY: register level: DMA2's fixed address; `PulseEnd::new` took
    // the peripheral, and only this module touches stream 2 and its flags.
    unsafe { &*pac::DMA2::ptr() }
}

impl PulseEnd {
    /// Programs compare 2 and the stream, enables them, and runs the boot
    /// check (`burin::chip::check_pulse_end`). `tim1_clk` is TIM1's kernel
    /// clock (timclk2); TIM1 already runs the spindle PWM.
    pub fn new(
        _dma2: pac::DMA2,
        rcc: &mut stm32f4xx_hal::rcc::Rcc,
        chip: Chip,
        bsrr: u32,
        step_off: u32,
        tim1_clk: u32,
        step_hz: u32,
    ) -> (Self, Result<(), HwFault>) {
        use stm32f4xx_hal::rcc::Enable;
        pac::DMA2::enable(rcc);
        STEP_OFF.store(step_off, Relaxed);
        let tim = tim1();
        let arr = tim.arr().read().bits() & 0xFFFF;
        let psc = tim.psc().read().bits() & 0xFFFF;
        // Compare 2 as a frozen output (no pin), no preload: a CCR2 write
        // takes effect at once; the request on the compare event.
        tim.ccmr1_output()
            .modify(|_, w| w.oc2m().frozen().oc2pe().clear_bit().cc2s().output());
        tim.cr2().modify(|_, w| w.ccds().clear_bit());
        tim.ccr2().write(|w| w.ccr().set(0));
        let path = DmaPath::pulse_end(bsrr, STEP_OFF.as_ptr() as u32);
        Self::arm(&path);
        tim.dier().modify(|_, w| w.cc2de().set_bit());
        let mut pe = PulseEnd {
            path,
            arr,
            tick_hz: tim1_clk / (psc + 1),
            step_hz,
            width: MARGIN_TICKS,
            latency: 0,
        };
        pe.latency = pe.to_step_ticks(MARGIN_TICKS + 1) + DMA_LATENCY_TICKS;
        let check = burin::chip::check_pulse_end(&path, chip, &mut pe);
        (pe, check)
    }

    /// (Re)starts the stream on `path`: direct mode preloads the word at
    /// enable (RM0383 §9.3.11), so a new step-off word needs a restart.
    fn arm(path: &DmaPath) {
        let st = dma2().st(STREAM);
        st.cr().modify(|_, w| w.en().clear_bit());
        while st.cr().read().en().bit_is_set() {}
        clear_flags();
        // SAFETY: register level: PAR is the step port's BSRR and M0AR the
        // static step-off word; the stream writes only that word, to pins
        // only `StepPort` drives.
        unsafe {
            st.par().write(|w| w.pa().bits(path.par));
            st.m0ar().write(|w| w.m0a().bits(path.m0ar));
        }
        st.ndtr().write(|w| w.ndt().set(1));
        st.cr().write(|w| {
            w.chsel().set(path.channel);
            w.pl().very_high();
            w.msize().bits32();
            w.psize().bits32();
            w.minc().fixed();
            w.pinc().fixed();
            w.circ().enabled();
            w.dir().memory_to_peripheral();
            w.en().enabled()
        });
    }

    /// A new step-off word (`$2` changed): stored and the stream restarted,
    /// only while no pulse is high (the step timer is stopped).
    pub fn set_step_off(&mut self, word: u32) {
        if STEP_OFF.swap(word, Relaxed) != word {
            Self::arm(&self.path);
        }
    }

    fn to_step_ticks(&self, tim1_ticks: u32) -> u32 {
        let t = u64::from(tim1_ticks) * u64::from(self.step_hz);
        t.div_ceil(u64::from(self.tick_hz.max(1))) as u32
    }

    /// The width in step-timer ticks, kept in TIM1 ticks with the margin.
    pub fn set_width(&mut self, step_ticks: u32) {
        let t = u64::from(step_ticks) * u64::from(self.tick_hz);
        let w = t.div_ceil(u64::from(self.step_hz.max(1))) as u32 + MARGIN_TICKS;
        // `$0` is at most 100 µs, TIM1's period 1 ms: a width never wraps.
        self.width = w.min(self.arr);
    }

    pub fn latency(&self) -> u32 {
        self.latency
    }

    /// The width and TIM1's ARR, loaded before the masked window.
    #[inline(always)]
    pub fn params(&self) -> (u32, u32) {
        (self.width, self.arr)
    }

    /// Arms the end of a pulse that rises right after: compare 2 at the
    /// counter now + `width`, on TIM1's period (`arr` + 1).
    #[inline(always)]
    pub fn arm_end(width: u32, arr: u32) {
        let tim = tim1();
        let mut end = tim.cnt().read().bits() + width;
        if end > arr {
            end -= arr + 1;
        }
        tim.ccr2().write(|w| w.ccr().set(end as u16));
    }

    /// The stream's error flags, or the hardware disabled it.
    pub fn failed(&self) -> bool {
        flags().failed()
    }
}

fn flags() -> StreamFlags {
    let d = dma2();
    let enabled = d.st(STREAM).cr().read().en().bit_is_set();
    StreamFlags::from_isr(d.lisr().read().bits(), STREAM as u8, enabled)
}

fn clear_flags() {
    dma2().lifcr().write(|w| {
        w.ctcif2().set_bit();
        w.chtif2().set_bit();
        w.cteif2().set_bit();
        w.cdmeif2().set_bit();
        w.cfeif2().set_bit()
    });
}

impl PulseEndHw for PulseEnd {
    /// A software compare-2 event (EGR.CC2G): the same request a match
    /// makes. The step pins are at rest, so the word changes nothing.
    fn request_once(&mut self) {
        tim1().egr().write(|w| w.cc2g().set_bit());
    }
    fn flags(&self) -> StreamFlags {
        flags()
    }
    fn clear_flags(&mut self) {
        clear_flags();
    }
}
