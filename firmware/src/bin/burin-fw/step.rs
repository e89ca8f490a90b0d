//! The step seams on real registers: [`StepPort`] drives every step, direction
//! and enable pin of one GPIO port with single BSRR writes, [`Tim5`] is the
//! 32-bit step timer, and [`StepDriver`] runs the motion core's [`Stepper`]
//! on them from the TIM5 interrupt.
use burin::realtime::Realtime;
use burin::seams::{StepPins, StepTimer};
use burin::stepper::{Segment, StepEvent, Stepper, Switches};
use core::sync::atomic::{AtomicBool, Ordering};
use heapless::spsc::Consumer;
use stm32f4xx_hal::{pac, rcc::Rcc, timer::Timer};

/// Pin numbers (0..=15) on the step port. Axis n is X, Y, Z, A for n = 0..3.
#[derive(Clone, Copy)]
pub struct PortPins {
    pub step: [u8; 4],
    pub dir: [u8; 4],
    pub enable: u8,
}

impl PortPins {
    /// Every pin exists (0..=15) and no two functions share one; the board
    /// files check this at compile time.
    pub const fn is_valid(&self) -> bool {
        let all = [
            self.step[0],
            self.step[1],
            self.step[2],
            self.step[3],
            self.dir[0],
            self.dir[1],
            self.dir[2],
            self.dir[3],
            self.enable,
        ];
        let mut seen = 0u16;
        let mut i = 0;
        while i < all.len() {
            if all[i] > 15 || seen & (1 << all[i]) != 0 {
                return false;
            }
            seen |= 1 << all[i];
            i += 1;
        }
        true
    }
}

/// BSRR word that drives the pins of the axes in `touched` (bit n = axis n)
/// high where `high` has the bit and low otherwise; other pins are untouched.
const fn bsrr_word(pins: &[u8; 4], high: u8, touched: u8) -> u32 {
    let mut word = 0;
    let mut axis = 0;
    while axis < 4 {
        if touched & (1 << axis) != 0 {
            let pin = (pins[axis] & 0xF) as u32;
            word |= if high & (1 << axis) != 0 {
                1 << pin
            } else {
                1 << (pin + 16)
            };
        }
        axis += 1;
    }
    word
}

// Compile-time checks of the BSRR arithmetic (they run on every build).
const _: () = {
    let pins = [12, 13, 14, 15];
    // X and Z high, Y and A untouched.
    assert!(bsrr_word(&pins, 0b0101, 0b0101) == (1 << 12) | (1 << 14));
    // All four driven: X, Z high; Y, A low (reset half of BSRR).
    assert!(bsrr_word(&pins, 0b0101, 0b1111) == (1 << 12) | (1 << 14) | (1 << 29) | (1 << 31));
    assert!(bsrr_word(&pins, 0, 0) == 0);
};

/// Step, direction and enable outputs of one port. Every call is one store
/// to BSRR, precomputed per mask, so the step ISR never reads-modifies-writes
/// the port and all axes of one event change in the same bus cycle.
pub struct StepPort {
    /// Address of the port's BSRR register.
    bsrr: usize,
    pins: PortPins,
    step_on: [u32; 16],
    step_off: u32,
    dirs: [u32; 16],
    enable_on: u32,
    enable_off: u32,
}

impl StepPort {
    /// `bsrr` is the BSRR address of the port whose pins in `pins` the caller
    /// has configured as push-pull outputs and owns exclusively.
    pub fn new(bsrr: *mut u32, pins: PortPins) -> Self {
        let mut port = StepPort {
            bsrr: bsrr as usize,
            pins,
            step_on: [0; 16],
            step_off: 0,
            dirs: [0; 16],
            enable_on: 0,
            enable_off: 0,
        };
        port.set_invert(0, 0, false);
        port
    }

    /// Applies the `$2` step, `$3` direction and `$4` enable invert settings.
    /// Default polarity: step pulses are high, enable is active low (the
    /// common A4988/DRV8825/TMC convention).
    pub fn set_invert(&mut self, step_invert: u8, dir_invert: u8, enable_invert: bool) {
        let p = self.pins;
        for mask in 0..16u8 {
            self.step_on[usize::from(mask)] = bsrr_word(&p.step, mask & !step_invert, mask);
            self.dirs[usize::from(mask)] = bsrr_word(&p.dir, mask ^ dir_invert, 0xF);
        }
        self.step_off = bsrr_word(&p.step, step_invert, 0xF);
        let en = [p.enable; 4];
        let (low, high) = (bsrr_word(&en, 0, 1), bsrr_word(&en, 1, 1));
        (self.enable_on, self.enable_off) = if enable_invert {
            (high, low)
        } else {
            (low, high)
        };
    }

    #[inline(always)]
    fn write(&mut self, word: u32) {
        // SAFETY: `bsrr` is the BSRR of a GPIO port (see `new`). BSRR is a
        // write-only set/reset register: one store changes exactly the pins
        // whose bits are set, atomically, and every word written here only
        // has bits of pins this struct owns.
        unsafe { core::ptr::write_volatile(self.bsrr as *mut u32, word) }
    }
}

impl StepPins for StepPort {
    #[inline(always)]
    fn set_dirs(&mut self, dir_mask: u8) {
        self.write(self.dirs[usize::from(dir_mask & 0xF)]);
    }
    #[inline(always)]
    fn step_high(&mut self, step_mask: u8) {
        self.write(self.step_on[usize::from(step_mask & 0xF)]);
    }
    #[inline(always)]
    fn step_low(&mut self) {
        self.write(self.step_off);
    }
    fn set_enabled(&mut self, on: bool) {
        self.write(if on { self.enable_on } else { self.enable_off });
    }
}

impl StepPort {
    /// One step event in ONE store: direction pins of every axis (a no-op
    /// unless they changed, and the stepper gives a change its own event
    /// `dir_setup` ahead of the first step) plus the step pins that rise.
    #[inline(always)]
    pub fn fire(&mut self, dir_mask: u8, step_mask: u8) {
        let word =
            self.dirs[usize::from(dir_mask & 0xF)] | self.step_on[usize::from(step_mask & 0xF)];
        self.write(word);
    }
}

/// Shortest period the step timer accepts: below this the ISR could not
/// finish before the next update (about 1 µs at 96 MHz).
pub const MIN_TICKS: u32 = 96;

/// QEMU 7.2's TIM2-5 model (`stm32f2xx_timer`) counts at a fixed 1 GHz,
/// whatever RCC says, and has no ARR preload: an ARR write schedules the
/// next update ARR ticks after the write. It also adds the counter's offset
/// (set by a CNT or UG write, the time of that write) to every delay, so
/// the QEMU variant never writes CNT or EGR: the offset then stays at its
/// reset value, 0, and periods are what ARR says. Writing the period from
/// the ISR moves each event by the ISR's latency and the pipeline applies
/// each period one event early; QEMU runs jobs, it does not measure timing.
#[cfg(feature = "board-qemu")]
pub const QEMU_TICK_HZ: u32 = 1_000_000_000;

/// True while TIM5 runs step events. The parse task reads it to know when
/// the queue needs a kick (pend TIM5 while stopped, see [`StepDriver`]).
pub static STEPPING: AtomicBool = AtomicBool::new(false);

/// TIM5 as the step timer: prescaler 1, so one tick is one timer-clock cycle
/// (96 MHz on the F411, 84 MHz on the F401), and a 32-bit auto-reload, so
/// even a 1 step/min move is a single period.
///
/// Each step event is an update (overflow). The next period goes into ARR
/// with ARPE set: the write lands in the preload register and takes effect
/// at the next update, so it can never be "missed" by a counter that
/// already passed it (which would wrap through 2^32 ticks, 45 s). The price
/// is a pipeline of one, which [`StepDriver`] absorbs by computing each
/// event one period ahead. Compare channel 1 ends the step pulse: the
/// counter restarts at every update, so a fixed CCR1 = pulse width fires
/// exactly that long after each event, with no busy-wait in the ISR.
pub struct Tim5 {
    tim: pac::TIM5,
    tick_hz: u32,
}

/// Which of the timer's events raised the interrupt.
pub struct Flags {
    pub update: bool,
    pub pulse_end: bool,
}

impl Tim5 {
    pub fn new(tim: pac::TIM5, rcc: &mut Rcc) -> Self {
        // Timer::new enables and resets the peripheral clock; from here on
        // the registers are driven directly (Counter::start would reset CNT).
        let tim = Timer::new(tim, rcc).release();
        #[cfg(not(feature = "board-qemu"))]
        let tick_hz = rcc.clocks.timclk1().raw();
        #[cfg(feature = "board-qemu")]
        let tick_hz = QEMU_TICK_HZ;
        tim.psc().write(|w| w.psc().set(0));
        // URS: only a real overflow raises the update interrupt, not the UG
        // used below to load the first period.
        tim.cr1().write(|w| w.arpe().set_bit().urs().set_bit());
        Tim5 { tim, tick_hz }
    }

    /// Pulse width in ticks (`$0`): CC1 fires this long after each update.
    pub fn set_pulse(&mut self, ticks: u32) {
        self.tim.ccr1().write(|w| w.ccr().set(ticks.max(1)));
    }

    /// Starts firing update events, the first after `first_ticks`.
    pub fn start(&mut self, first_ticks: u32) {
        self.schedule_in(first_ticks);
        // UG copies the preloaded ARR into the shadow register now. Not on
        // QEMU: see [`QEMU_TICK_HZ`].
        #[cfg(not(feature = "board-qemu"))]
        {
            self.tim.cnt().reset();
            self.tim.egr().write(|w| w.ug().set_bit());
        }
        self.tim
            .sr()
            .write(|w| w.uif().clear_bit().cc1if().clear_bit());
        self.tim
            .dier()
            .write(|w| w.uie().set_bit().cc1ie().set_bit());
        self.tim.cr1().modify(|_, w| w.cen().set_bit());
    }

    /// Reads and acknowledges the pending events (first thing in the ISR,
    /// so that a late write cannot clear the next event's flag).
    #[inline(always)]
    pub fn take_flags(&mut self) -> Flags {
        let sr = self.tim.sr().read();
        let flags = Flags {
            update: sr.uif().bit_is_set(),
            pulse_end: sr.cc1if().bit_is_set(),
        };
        // rc_w0 bits: writing 1 leaves a flag alone, 0 clears it.
        self.tim.sr().write(|w| {
            w.uif().bit(!flags.update);
            w.cc1if().bit(!flags.pulse_end)
        });
        flags
    }
}

impl StepTimer for Tim5 {
    fn tick_hz(&self) -> u32 {
        self.tick_hz
    }
    #[inline(always)]
    fn schedule_in(&mut self, ticks: u32) {
        self.tim
            .arr()
            .write(|w| w.arr().set(ticks.max(MIN_TICKS) - 1));
    }
    fn stop(&mut self) {
        self.tim.cr1().modify(|_, w| w.cen().clear_bit());
        // Stopping happens a whole period after the last event, so its
        // pulse (ended by CC1 at `pulse_ticks`) is already over.
    }
}

/// The TIM5 task's state: the core's [`Stepper`] fed from the segment queue,
/// its events on [`StepPort`] and [`Tim5`].
///
/// Pipeline: at update k the event computed at update k-1 is applied (one
/// BSRR write) and event k+1 is computed, its period going into ARR's
/// preload, which the hardware loads at update k+1: exactly when it is due.
/// So switches are sampled one event ahead of the pulse they gate; a trip
/// still stops pulses within one step event.
pub struct StepDriver {
    timer: Tim5,
    port: StepPort,
    stepper: Stepper,
    queue: Consumer<'static, Segment>,
    next: Option<StepEvent>,
}

impl StepDriver {
    pub fn new(
        mut timer: Tim5,
        port: StepPort,
        stepper: Stepper,
        queue: Consumer<'static, Segment>,
        pulse_ticks: u32,
    ) -> Self {
        timer.set_pulse(pulse_ticks);
        StepDriver {
            timer,
            port,
            stepper,
            queue,
            next: None,
        }
    }

    /// The whole TIM5 interrupt. Returns true when the planner should run
    /// (a segment was taken, so there is room, or the timer stopped).
    pub fn on_interrupt(&mut self, rt: &Realtime, sw: Switches) -> bool {
        let flags = self.timer.take_flags();
        if flags.pulse_end {
            self.port.step_low();
        }
        if flags.update {
            return match self.next.take() {
                Some(ev) if ev.ticks > 0 => {
                    self.port.fire(ev.dir_mask, ev.step_mask);
                    self.prepare(rt, sw)
                }
                // The last period has elapsed: go on if more was queued
                // meanwhile, else stop.
                _ => self.begin(rt, sw),
            };
        }
        // A pend from the parse task (segments queued while stopped).
        if !flags.pulse_end && !STEPPING.load(Ordering::Acquire) {
            return self.begin(rt, sw);
        }
        false
    }

    /// Fires the first event now and primes the pipeline, or stops.
    fn begin(&mut self, rt: &Realtime, sw: Switches) -> bool {
        let (ev, took) = self.step(rt, sw);
        if ev.ticks == 0 {
            self.timer.stop();
            STEPPING.store(false, Ordering::Release);
            return true;
        }
        STEPPING.store(true, Ordering::Release);
        self.port.set_enabled(true);
        self.port.fire(ev.dir_mask, ev.step_mask);
        self.timer.start(ev.ticks);
        self.prepare(rt, sw) | took
    }

    /// Computes the next event and queues its period.
    fn prepare(&mut self, rt: &Realtime, sw: Switches) -> bool {
        let (ev, took) = self.step(rt, sw);
        if ev.ticks > 0 {
            self.timer.schedule_in(ev.ticks);
        }
        self.next = Some(ev);
        took
    }

    #[inline(always)]
    fn step(&mut self, rt: &Realtime, sw: Switches) -> (StepEvent, bool) {
        let queue = &mut self.queue;
        let mut took = false;
        let ev = self.stepper.on_event(
            rt,
            &mut || {
                let s = queue.dequeue();
                took |= s.is_some();
                s
            },
            sw,
        );
        (ev, took)
    }
}
