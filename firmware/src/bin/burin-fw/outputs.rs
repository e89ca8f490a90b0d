//! The parse task's outputs: spindle, coolant and stepper enable, written
//! from the controller's [`Pins`] once per pass (the rules live in
//! `burin::controller` and `burin::outputs`).
//!
//! Everything here runs at the parse task's priority, the only writer of
//! these pins, with two exceptions that need no lock: the step interrupt
//! turns the drivers on when it starts (a BSRR store of the enable bit
//! only) and the e-stop interrupt kills the spindle and coolant pins at
//! once (`board::kill_aux`). The first only moves towards the state this
//! module writes next anyway; the second could be undone by a store of
//! levels computed before it, so [`Io::write`] re-checks the e-stop latch
//! after its stores. The fault path (`fault.rs`) stores over all of them.
use crate::boards::board;
use burin::controller::Pins;
use stm32f4xx_hal::gpio::PinState;

/// Driver wake-up time between enable and the first step, in ms (the
/// controller's `Enable` timer). 0: the common step/dir drivers take steps
/// within microseconds of the enable, and the step interrupt asserts
/// enable itself when it starts and holds the first edge back `$207` µs
/// (see `burin::stepper::driver`).
pub const WAKE_MS: u16 = 0;

/// The stepper-enable pin alone: one BSRR store per change.
pub struct EnablePin {
    bsrr: usize,
    pin: u8,
    active_high: bool,
    on: u32,
    off: u32,
}

impl EnablePin {
    /// `bsrr` is the BSRR of the port holding `pin` (configured as an
    /// output); `active_high` after `$4`.
    pub fn new(bsrr: *mut u32, pin: u8, active_high: bool) -> Self {
        let mut p = EnablePin {
            bsrr: bsrr as usize,
            pin,
            active_high: !active_high,
            on: 0,
            off: 0,
        };
        p.set_active_high(active_high);
        p
    }

    /// `$4` changed: the words for the new polarity (the caller rewrites
    /// the level).
    fn set_active_high(&mut self, active_high: bool) {
        let pin = self.pin & 0xF;
        let (set, reset) = (1u32 << pin, 1u32 << (pin + 16));
        (self.on, self.off) = if active_high {
            (set, reset)
        } else {
            (reset, set)
        };
        self.active_high = active_high;
    }

    fn set(&mut self, on: bool) {
        // SAFETY: `bsrr` is a GPIO port's BSRR (see `new`); the store sets
        // or resets the enable pin only, atomically, so it cannot disturb
        // the step and direction pins the step interrupt drives.
        unsafe {
            core::ptr::write_volatile(self.bsrr as *mut u32, if on { self.on } else { self.off })
        }
    }
}

/// The output pins: spindle PWM/dir/enable, coolant and stepper enable.
pub struct Io {
    aux: board::Aux,
    enable_pin: EnablePin,
    /// What was last written, so a pass that changes nothing writes nothing.
    written: Option<Pins>,
}

impl Io {
    pub fn new(aux: board::Aux, enable_pin: EnablePin) -> Self {
        Io {
            aux,
            enable_pin,
            written: None,
        }
    }

    /// Copy the controller's pin levels to the hardware. The e-stop
    /// interrupt may have killed spindle and coolant after the pass that
    /// computed `p`: its kill wins (`burin::outputs::write_then_recheck`).
    pub fn write(&mut self, p: &Pins) {
        if self.written.as_ref() == Some(p) {
            return;
        }
        // `$4` applies at once: a new polarity rewrites the level.
        if self.enable_pin.active_high != p.enable_invert {
            self.enable_pin.set_active_high(p.enable_invert);
            self.written = None;
        }
        let killed =
            burin::outputs::write_then_recheck(&crate::RT, || self.store(p), board::kill_aux);
        self.written = if killed { None } else { Some(*p) };
    }

    fn store(&mut self, p: &Pins) {
        if self.written.map(|w| w.enable) != Some(p.enable) {
            self.enable_pin.set(p.enable);
        }
        let a = &mut self.aux;
        let max = a.spindle_pwm.get_max_duty();
        let duty = (p.spindle.duty * f32::from(max)) as u16;
        // Any S above zero keeps at least one count: "on" stays on.
        let duty = if p.spindle.duty > 0.0 { duty.max(1) } else { 0 };
        a.spindle_pwm.set_duty(duty.min(max));
        a.spindle_dir.set_state(level(p.spindle.ccw));
        a.spindle_enable.set_state(level(p.spindle.enable));
        a.flood.set_state(level(p.flood));
        a.mist.set_state(level(p.mist));
        defmt::debug!(
            "outputs: enable {} (active high {}), spindle {} ccw {} duty {}/{}, flood {}, mist {}",
            p.enable,
            p.enable_invert,
            p.spindle.enable,
            p.spindle.ccw,
            duty,
            max,
            p.flood,
            p.mist
        );
    }
}

fn level(on: bool) -> PinState {
    if on {
        PinState::High
    } else {
        PinState::Low
    }
}
