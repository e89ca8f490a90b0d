//! The step seams on real registers: [`StepPort`] drives every step, direction
//! and enable pin of one GPIO port with single BSRR writes, [`Tim5`] is the
//! 32-bit step timer, and [`StepTask`] runs the motion core's step driver
//! (`burin::stepper::driver`) on them from the TIM5 interrupt. What happens
//! when, and why, is decided there; this file only moves registers.
use burin::realtime::Realtime;
use burin::seams::{StepPins, StepTimer};
use burin::stepper::driver::StepDriver;
use burin::stepper::{Segment, Stepper, Switches};
use burin::AXES;
use heapless::spsc::Consumer;
use stm32f4xx_hal::{pac, rcc::Rcc, timer::Timer};

/// Every axis's bit: masks here have bit n for axis n.
const ALL_AXES: u8 = ((1u16 << AXES) - 1) as u8;

/// One BSRR word per combination of axes.
const MASKS: usize = 1 << AXES;

/// Pin numbers (0..=15) on the step port. Axis n is `burin::AXIS_NAMES[n]`.
#[derive(Clone, Copy)]
pub struct PortPins {
    pub step: [u8; AXES],
    pub dir: [u8; AXES],
    pub enable: u8,
}

impl PortPins {
    /// Every pin exists (0..=15) and no two functions share one; the board
    /// files check this at compile time.
    pub const fn is_valid(&self) -> bool {
        let mut seen = 0u16;
        let mut i = 0;
        while i <= 2 * AXES {
            let pin = if i < AXES {
                self.step[i]
            } else if i < 2 * AXES {
                self.dir[i - AXES]
            } else {
                self.enable
            };
            if pin > 15 || seen & (1 << pin) != 0 {
                return false;
            }
            seen |= 1 << pin;
            i += 1;
        }
        true
    }
}

/// BSRR word that drives the pins of the axes in `touched` (bit n = axis n)
/// high where `high` has the bit and low otherwise; other pins are untouched.
const fn bsrr_word<const N: usize>(pins: &[u8; N], high: u8, touched: u8) -> u32 {
    let mut word = 0;
    let mut axis = 0;
    while axis < N {
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
    let pins = [12u8, 13, 14, 15];
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
    step_on: [u32; MASKS],
    step_off: u32,
    dirs: [u32; MASKS],
    enable_on: u32,
    enable_off: u32,
}

impl StepPort {
    /// `bsrr` is the BSRR address of the port whose pins in `pins` the caller
    /// has configured as push-pull outputs and owns exclusively; the pins
    /// go (stay) at their idle levels under the `$2`/`$3`/`$4` given, which
    /// the board set before they became outputs: one store of the default
    /// levels here would be a step edge under `$2` and enabled drivers
    /// under `$4=1`.
    pub fn new(
        bsrr: *mut u32,
        pins: PortPins,
        step_invert: u8,
        dir_invert: u8,
        enable_invert: bool,
    ) -> Self {
        let mut port = StepPort {
            bsrr: bsrr as usize,
            pins,
            step_on: [0; MASKS],
            step_off: 0,
            dirs: [0; MASKS],
            enable_on: 0,
            enable_off: 0,
        };
        port.set_invert(step_invert, dir_invert, enable_invert);
        port
    }

    /// Applies the `$2` step, `$3` direction and `$4` enable invert settings
    /// at power-up. Default polarity: step pulses are high, enable is active
    /// low (the common A4988/DRV8825/TMC convention).
    pub fn set_invert(&mut self, step_invert: u8, dir_invert: u8, enable_invert: bool) {
        self.tables(step_invert, dir_invert, enable_invert);
        // The idle levels under these inverts, at once and in one store:
        // step pins at rest (so the first pulse has an edge with `$2`),
        // directions for "positive" (so `$3` never changes DIR in the same
        // store as a first STEP), drivers off (`$4`).
        self.write(self.step_off | self.dirs[0] | self.enable_off);
    }

    /// After [`StepPort::tables`] for a `$2`/`$3` change while the step
    /// driver is stopped (`StepPins::apply_config`): step pins at rest and
    /// directions `dir_mask` under the new inverts, in one store. The
    /// enable pin is the parse task's at rest (`outputs::Io` rewrites it
    /// under `$4`).
    pub fn rest(&mut self, dir_mask: u8) {
        self.write(self.step_off | self.dirs[usize::from(dir_mask & ALL_AXES)]);
    }

    /// The BSRR words under `$2`/`$3`/`$4`; writes nothing.
    pub fn tables(&mut self, step_invert: u8, dir_invert: u8, enable_invert: bool) {
        let p = self.pins;
        for mask in 0..=ALL_AXES {
            self.step_on[usize::from(mask)] = bsrr_word(&p.step, mask & !step_invert, mask);
            self.dirs[usize::from(mask)] = bsrr_word(&p.dir, mask ^ dir_invert, ALL_AXES);
        }
        self.step_off = bsrr_word(&p.step, step_invert, ALL_AXES);
        let en = [p.enable];
        let (low, high) = (bsrr_word(&en, 0, 1), bsrr_word(&en, 1, 1));
        (self.enable_on, self.enable_off) = if enable_invert {
            (high, low)
        } else {
            (low, high)
        };
    }

    /// The BSRR word that lowers every step pin (under `$2`), and the
    /// register's address: what the pulse-end DMA writes where.
    #[cfg(not(feature = "board-qemu"))]
    pub fn step_off_store(&self) -> (u32, u32) {
        (self.step_off, self.bsrr as u32)
    }

    /// The BSRR address and the rising word for `step_mask` (the store
    /// [`StepPins::step_high`] makes), for a caller that stores it itself.
    #[cfg(not(feature = "board-qemu"))]
    #[inline(always)]
    pub fn rise_store(&self, step_mask: u8) -> (usize, u32) {
        (self.bsrr, self.step_on[usize::from(step_mask & ALL_AXES)])
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
    /// The step pins that rise, in ONE store (the set half of BSRR only
    /// for them: the direction pins are not in the word).
    #[inline(always)]
    fn step_high(&mut self, step_mask: u8) {
        self.write(self.step_on[usize::from(step_mask & ALL_AXES)]);
    }
    /// Direction pins of every axis (a no-op unless they changed).
    #[inline(always)]
    fn set_directions(&mut self, dir_mask: u8) {
        self.write(self.dirs[usize::from(dir_mask & ALL_AXES)]);
    }
    #[inline(always)]
    fn step_low(&mut self) {
        self.write(self.step_off);
    }
    fn set_enabled(&mut self, on: bool) {
        self.write(if on { self.enable_on } else { self.enable_off });
    }
    #[inline(always)]
    fn switches(&self) -> Switches {
        crate::boards::board::switches()
    }
}

/// QEMU 7.2's TIM2-5 model (`stm32f2xx_timer`) counts at a fixed 1 GHz,
/// whatever RCC says, raises only update interrupts and has no ARR preload:
/// an ARR write schedules the next update ARR ticks after the write. It also
/// adds the counter's offset (set by a CNT or UG write, the time of that
/// write) to every delay, so the QEMU variant never writes CNT or EGR: the
/// offset then stays at its reset value, 0, and CNT reads the virtual clock
/// in ns. There the compare is an update `target - now` ticks after the
/// write; it lands a little late (the write follows the read), which the
/// driver treats like any late interrupt. QEMU runs jobs, it does not
/// measure timing.
#[cfg(feature = "board-qemu")]
pub const QEMU_TICK_HZ: u32 = 1_000_000_000;

/// TIM5 as the step timer: prescaler 1, so one tick is one timer-clock cycle
/// (96 MHz on the F411, 84 MHz on the F401), free-running over its full 32
/// bits (a wrap every 44.7 s) from `new` on and never reset, so a tick
/// value means the same instant to every handler. Compare channel 1 (no
/// preload: a CCR1 write takes effect at once) raises the interrupt at the
/// absolute target the driver asks for.
pub struct Tim5 {
    tim: pac::TIM5,
    tick_hz: u32,
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
        tim.dier().reset();
        #[cfg(not(feature = "board-qemu"))]
        {
            tim.arr().write(|w| w.arr().set(u32::MAX));
            // UG loads the prescaler; URS keeps it from raising an update.
            tim.cr1().write(|w| w.urs().set_bit());
            tim.egr().write(|w| w.ug().set_bit());
            tim.cr1().modify(|_, w| w.cen().set_bit());
        }
        #[cfg(feature = "board-qemu")]
        tim.cr1().write(|w| w.urs().set_bit());
        Tim5 { tim, tick_hz }
    }
}

impl StepTimer for Tim5 {
    fn tick_hz(&self) -> u32 {
        self.tick_hz
    }
    #[inline(always)]
    fn now(&self) -> u32 {
        self.tim.cnt().read().bits()
    }
    #[inline(always)]
    fn schedule_at(&mut self, at: u32) {
        // Drop a match of the previous target first (rc_w0: 0 clears, 1
        // leaves a flag alone), then arm the new one.
        #[cfg(not(feature = "board-qemu"))]
        {
            self.tim.sr().write(|w| w.cc1if().clear_bit());
            self.tim.ccr1().write(|w| w.ccr().set(at));
        }
        #[cfg(feature = "board-qemu")]
        {
            self.tim.sr().write(|w| w.uif().clear_bit());
            let ahead = at.wrapping_sub(self.now()) as i32;
            self.tim.arr().write(|w| w.arr().set(ahead.max(1) as u32));
        }
    }
    fn start(&mut self) {
        // A stale match from before the stop must not raise the interrupt.
        self.tim
            .sr()
            .write(|w| w.cc1if().clear_bit().uif().clear_bit());
        #[cfg(not(feature = "board-qemu"))]
        self.tim.dier().write(|w| w.cc1ie().set_bit());
        #[cfg(feature = "board-qemu")]
        {
            self.tim.dier().write(|w| w.uie().set_bit());
            self.tim.cr1().modify(|_, w| w.cen().set_bit());
        }
    }
    fn stop(&mut self) {
        // The last pulse still ends on time: its end is TIM1's and DMA2's
        // (`pulse_end.rs`), not this timer's.
        #[cfg(not(feature = "board-qemu"))]
        self.tim.dier().reset();
        #[cfg(feature = "board-qemu")]
        {
            self.tim.dier().reset();
            self.tim.cr1().modify(|_, w| w.cen().clear_bit());
        }
    }
}

/// The pins and the timers as the one hardware object the driver drives.
pub struct StepHw {
    pub port: StepPort,
    pub timer: Tim5,
    /// TIM1 compare 2 and DMA2: the pulse's end (`pulse_end.rs`).
    #[cfg(not(feature = "board-qemu"))]
    pub pulse: crate::boards::pulse_end::PulseEnd,
}

impl StepPins for StepHw {
    /// The boards end pulses by DMA (`pulse_end.rs`); QEMU's timer model
    /// has neither compare channels nor DMA.
    const ENDS_PULSES: bool = cfg!(not(feature = "board-qemu"));
    /// The end is armed before the rise, both with interrupts masked: an
    /// EXTI handler (priority 4, above this one) landing between the
    /// counter read and the compare store would otherwise leave the
    /// compare in the past, and the pin high for a whole PWM period.
    #[cfg(not(feature = "board-qemu"))]
    #[inline(always)]
    fn step_high(&mut self, step_mask: u8) {
        // From RAM first: inside the masked window only the registers.
        let (bsrr, word) = self.port.rise_store(step_mask);
        let (width, arr) = self.pulse.params();
        cortex_m::interrupt::disable();
        crate::boards::pulse_end::PulseEnd::arm_end(width, arr);
        // SAFETY: register level: `bsrr` is the step port's BSRR and `word`
        // one of `StepPort`'s precomputed words (see `StepPort::write`).
        unsafe { core::ptr::write_volatile(bsrr as *mut u32, word) };
        // SAFETY: register level (PRIMASK): the TIM5 handler runs with
        // PRIMASK clear (RTIC masks by BASEPRI), so this restores what it
        // found; nothing between the two changes the mask.
        unsafe { cortex_m::interrupt::enable() };
    }
    #[cfg(feature = "board-qemu")]
    #[inline(always)]
    fn step_high(&mut self, step_mask: u8) {
        self.port.step_high(step_mask);
    }
    #[inline(always)]
    fn set_directions(&mut self, dir_mask: u8) {
        self.port.set_directions(dir_mask);
    }
    #[cfg(not(feature = "board-qemu"))]
    fn set_pulse_width(&mut self, ticks: u32) {
        self.pulse.set_width(ticks);
    }
    #[cfg(not(feature = "board-qemu"))]
    fn pulse_end_latency(&self) -> u32 {
        self.pulse.latency()
    }
    #[cfg(not(feature = "board-qemu"))]
    fn pulse_end_failed(&self) -> bool {
        self.pulse.failed()
    }
    #[inline(always)]
    fn step_low(&mut self) {
        self.port.step_low();
    }
    fn set_enabled(&mut self, on: bool) {
        self.port.set_enabled(on);
    }
    /// `$2`/`$3`/`$4` (and `$0`) after a `$n=`, while the timer is stopped.
    fn apply_config(&mut self, cfg: &burin::stepper::StepConfig, dir_mask: u8) {
        self.port
            .tables(cfg.step_invert, cfg.dir_invert, cfg.enable_invert);
        // The pulse-end hardware first: its step-off word under the new
        // `$2` (the stream restarted so it preloads it), so no stray match
        // can restore the old rest level after the store below. Its width
        // follows at the next start (`set_pulse_width`).
        #[cfg(not(feature = "board-qemu"))]
        self.pulse.set_step_off(self.port.step_off_store().0);
        self.port.rest(dir_mask);
    }
    #[inline(always)]
    fn switches(&self) -> Switches {
        self.port.switches()
    }
}

impl StepTimer for StepHw {
    fn tick_hz(&self) -> u32 {
        self.timer.tick_hz()
    }
    #[inline(always)]
    fn now(&self) -> u32 {
        self.timer.now()
    }
    #[inline(always)]
    fn schedule_at(&mut self, at: u32) {
        self.timer.schedule_at(at);
    }
    fn start(&mut self) {
        self.timer.start();
    }
    fn stop(&mut self) {
        self.timer.stop();
    }
}

/// The TIM5 task's state: the core's [`StepDriver`] and [`Stepper`] fed from
/// the segment queue, on [`StepHw`].
/// `repr(C)`, the stepper first: its per-event fields then sit within
/// reach of Thumb's 16-bit loads and stores from the task's base
/// (`burin::stepper::Stepper`'s layout note; bench-target's `Task` too).
#[repr(C)]
pub struct StepTask {
    stepper: Stepper,
    driver: StepDriver,
    hw: StepHw,
    queue: Consumer<'static, Segment>,
}

impl StepTask {
    pub fn new(hw: StepHw, stepper: Stepper, queue: Consumer<'static, Segment>) -> Self {
        StepTask {
            driver: StepDriver::new(),
            stepper,
            hw,
            queue,
        }
    }

    /// The whole TIM5 interrupt (a compare, or a kick from `parse` while
    /// stopped); the switches are read by the driver after each rise. Returns true when the planner should run (a segment was
    /// taken, so there is room, or the driver stopped).
    #[inline(always)]
    pub fn on_interrupt(&mut self, rt: &Realtime) -> bool {
        let queue = &mut self.queue;
        self.driver
            .on_interrupt(&mut self.stepper, &mut self.hw, rt, &mut || queue.dequeue())
    }
}
