//! The step seams on real registers: [`StepPort`] drives every step, direction
//! and enable pin of one GPIO port with single BSRR writes, and [`Tim5`] is the
//! 32-bit step timer. The TIM5 task only ever talks to these two through
//! `burin::seams`, so the motion core's step generator drops in unchanged.
use burin::seams::{StepPins, StepTimer};
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

/// Shortest period the step timer accepts: below this the ISR could not
/// finish before the next update (about 1 µs at 96 MHz).
pub const MIN_TICKS: u32 = 96;

/// TIM5 as the step timer: prescaler 1, so one tick is one timer-clock cycle
/// (96 MHz on the F411, 84 MHz on the F401), and a 32-bit auto-reload, so
/// even a 1 step/min move is a single period.
///
/// Each event is an update (overflow). The next period goes into ARR with
/// ARPE set: the write lands in the preload register and takes effect at the
/// next update, so it can never be "missed" by a counter that already passed
/// it (which would wrap through 2^32 ticks, 45 s). The price is a pipeline
/// of one: the period written at event k is the one from event k+1 to k+2.
pub struct Tim5 {
    tim: pac::TIM5,
    tick_hz: u32,
}

impl Tim5 {
    pub fn new(tim: pac::TIM5, rcc: &mut Rcc) -> Self {
        // Timer::new enables and resets the peripheral clock; from here on
        // the registers are driven directly (Counter::start would reset CNT).
        let tim = Timer::new(tim, rcc).release();
        let tick_hz = rcc.clocks.timclk1().raw();
        tim.psc().write(|w| w.psc().set(0));
        // URS: only a real overflow raises the update interrupt, not the UG
        // used below to load the first period.
        tim.cr1().write(|w| w.arpe().set_bit().urs().set_bit());
        Tim5 { tim, tick_hz }
    }

    /// Starts firing update events, the first after `first_ticks`.
    pub fn start(&mut self, first_ticks: u32) {
        self.schedule_in(first_ticks);
        self.tim.cnt().reset();
        // UG copies the preloaded ARR into the shadow register now.
        self.tim.egr().write(|w| w.ug().set_bit());
        self.clear_update();
        self.tim.dier().write(|w| w.uie().set_bit());
        self.tim.cr1().modify(|_, w| w.cen().set_bit());
    }

    /// Acknowledges the update event (first thing in the ISR, so that a
    /// late write cannot clear the next event's flag).
    #[inline(always)]
    pub fn clear_update(&mut self) {
        self.tim.sr().write(|w| w.uif().clear_bit());
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
    }
}

/// Stand-in for the motion core's step generator until it is wired in: a
/// square wave on X at a fixed rate, with the drivers left disabled so that
/// nothing moves. It has the generator's shape, one call per timer event
/// through the seams, so replacing it changes no other code.
pub struct FixedRate {
    half_period: u32,
    high: bool,
}

impl FixedRate {
    pub fn new(step_hz: u32, tick_hz: u32) -> Self {
        let half_period = (tick_hz / step_hz.max(1) / 2).max(MIN_TICKS);
        FixedRate {
            half_period,
            high: false,
        }
    }

    /// Ticks to the first event.
    pub fn first(&self) -> u32 {
        self.half_period
    }

    #[inline(always)]
    pub fn on_event(&mut self, pins: &mut impl StepPins, timer: &mut impl StepTimer) {
        if self.high {
            pins.step_low();
        } else {
            pins.step_high(0b0001);
        }
        self.high = !self.high;
        timer.schedule_in(self.half_period);
    }
}
