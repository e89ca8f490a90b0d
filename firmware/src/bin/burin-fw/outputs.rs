//! The parse task's outputs: spindle, coolant and stepper enable, driven
//! from `burin::outputs` (the rules) once per pass of the session.
//!
//! Everything here runs at the parse task's priority, the only writer of
//! these pins, with two exceptions that need no lock: the step interrupt
//! turns the drivers on when it starts (a BSRR store of the enable bit
//! only) and the e-stop interrupt kills the spindle and coolant pins at
//! once (`board::kill_aux`); both only ever move towards the state this
//! module writes next anyway.
use crate::boards::board;
use burin::command::SpindleDir;
use burin::machine::State;
use burin::outputs::{Enable, Motion, Outputs, Spindle};
use burin::settings::Settings;
use stm32f4xx_hal::gpio::PinState;

/// Driver wake-up time between enable and the first step, in ms. 0: the
/// common step/dir drivers take steps within microseconds of the enable,
/// and the step interrupt asserts enable itself when it starts and holds
/// the first edge back `$207` µs (see `burin::stepper::driver`).
const WAKE_MS: u16 = 0;

/// The stepper-enable pin alone: one BSRR store per change.
pub struct EnablePin {
    bsrr: usize,
    on: u32,
    off: u32,
}

impl EnablePin {
    /// `bsrr` is the BSRR of the port holding `pin` (configured as an
    /// output); `active_high` after `$4`.
    pub fn new(bsrr: *mut u32, pin: u8, active_high: bool) -> Self {
        let (set, reset) = (1u32 << (pin & 0xF), 1u32 << ((pin & 0xF) + 16));
        let (on, off) = if active_high {
            (set, reset)
        } else {
            (reset, set)
        };
        EnablePin {
            bsrr: bsrr as usize,
            on,
            off,
        }
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

/// What was last written, so a pass that changes nothing writes nothing.
#[derive(Clone, Copy, PartialEq)]
struct Written {
    spindle: Spindle,
    flood: bool,
    mist: bool,
}

pub struct Io {
    aux: board::Aux,
    enable_pin: EnablePin,
    pub state: Outputs,
    enable: Enable,
    written: Option<Written>,
    enabled: Option<bool>,
}

impl Io {
    pub fn new(aux: board::Aux, enable_pin: EnablePin, s: &Settings) -> Self {
        Io {
            aux,
            enable_pin,
            state: Outputs::new(s),
            enable: Enable::new(s.idle_delay_ms, WAKE_MS),
            written: None,
            enabled: None,
        }
    }

    /// Steps may start (drivers on and awake).
    pub fn may_step(&self) -> bool {
        self.enable.may_step()
    }

    /// One pass: settings, alarm, enable timer, then the pins. `busy`:
    /// segments queued or the step timer running.
    pub fn update(&mut self, now_ms: u32, busy: bool, state: State, s: &Settings) {
        self.state.configure(s);
        self.enable.set_idle_ms(s.idle_delay_ms);
        let alarm = state == State::Alarm;
        if alarm {
            self.state.all_off();
        }
        let on = self
            .enable
            .update(now_ms, busy, state == State::Hold, alarm);
        if self.enabled != Some(on) {
            self.enabled = Some(on);
            self.enable_pin.set(on);
        }
        // The step interrupt does not say whether it runs a G0 or a G1:
        // laser mode fires whenever steps run, see the report in README.
        let motion = if busy {
            Motion::Feed { ratio: 1.0 }
        } else {
            Motion::Stopped
        };
        let want = Written {
            spindle: self.state.spindle(motion),
            flood: self.state.flood,
            mist: self.state.mist,
        };
        if self.written != Some(want) {
            self.written = Some(want);
            self.write(&want);
        }
    }

    fn write(&mut self, w: &Written) {
        let a = &mut self.aux;
        let max = a.spindle_pwm.get_max_duty();
        let duty = (w.spindle.duty * f32::from(max)) as u16;
        // Any S above zero keeps at least one count: "on" stays on.
        let duty = if w.spindle.duty > 0.0 { duty.max(1) } else { 0 };
        a.spindle_pwm.set_duty(duty.min(max));
        a.spindle_dir.set_state(level(w.spindle.ccw));
        a.spindle_enable.set_state(level(w.spindle.enable));
        a.flood.set_state(level(w.flood));
        a.mist.set_state(level(w.mist));
        defmt::debug!(
            "outputs: spindle {} {} duty {}/{}, flood {}, mist {}",
            w.spindle.enable,
            matches!(self.state.spindle_dir(), SpindleDir::Ccw),
            duty,
            max,
            w.flood,
            w.mist
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
