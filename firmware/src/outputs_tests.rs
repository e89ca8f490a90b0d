use super::*;
use crate::command::Command;

fn settings(laser: bool) -> Settings {
    Settings {
        spindle_max: 10_000.0,
        spindle_min: 0.0,
        laser_mode: laser,
        ..Settings::default()
    }
}

fn spindle(dir: SpindleDir, speed: f32) -> Command {
    Command::Spindle { dir, speed }
}

const FEED: Motion = Motion::Feed { ratio: 1.0 };

#[test]
fn m3_m4_m5_drive_enable_dir_and_duty() {
    let mut o = Outputs::new(&settings(false));
    assert!(!o.spindle(Motion::Stopped).enable);
    assert!(o.apply(&spindle(SpindleDir::Cw, 5_000.0)));
    let s = o.spindle(Motion::Stopped);
    assert!(s.enable && !s.ccw);
    assert!((s.duty - 0.5).abs() < 1e-6, "{}", s.duty);
    o.apply(&spindle(SpindleDir::Ccw, 10_000.0));
    let s = o.spindle(Motion::Rapid);
    assert!(s.enable && s.ccw);
    assert_eq!(s.duty, 1.0);
    assert!(o.apply(&spindle(SpindleDir::Off, 10_000.0)));
    assert!(!o.spindle(FEED).enable);
    assert_eq!(o.spindle(FEED).duty, 0.0);
}

#[test]
fn same_command_twice_is_no_change() {
    let mut o = Outputs::new(&settings(false));
    assert!(o.apply(&spindle(SpindleDir::Cw, 100.0)));
    assert!(!o.apply(&spindle(SpindleDir::Cw, 100.0)));
    assert!(
        !o.apply(&Command::Tool { number: 3 }),
        "other commands leave it"
    );
}

#[test]
fn rpm_range_maps_onto_duty() {
    let mut s = settings(false);
    s.spindle_min = 1_000.0;
    s.spindle_max = 11_000.0;
    let mut o = Outputs::new(&s);
    let duty = |o: &mut Outputs, rpm: f32| {
        o.apply(&spindle(SpindleDir::Cw, rpm));
        o.spindle(Motion::Stopped).duty
    };
    assert!((duty(&mut o, 6_000.0) - 0.5).abs() < 1e-6);
    assert_eq!(duty(&mut o, 20_000.0), 1.0, "above $30 clamps to full");
    let low = duty(&mut o, 500.0);
    assert!(
        low > 0.0 && low < 0.01,
        "below $31: lowest on-duty, got {low}"
    );
    assert_eq!(duty(&mut o, 0.0), 0.0, "S0: no PWM");
    assert!(
        o.spindle(Motion::Stopped).enable,
        "S0 keeps M3's enable (GRBL)"
    );
    assert_eq!(duty(&mut o, f32::NAN), 0.0, "a NaN S never reaches the pin");
}

#[test]
fn degenerate_range_is_full_duty() {
    let mut s = settings(false);
    s.spindle_min = 5_000.0;
    s.spindle_max = 5_000.0;
    let mut o = Outputs::new(&s);
    o.apply(&spindle(SpindleDir::Cw, 1.0));
    assert_eq!(o.spindle(Motion::Stopped).duty, 1.0);
}

#[test]
fn coolant_follows_m7_m8_m9() {
    let mut o = Outputs::new(&settings(false));
    assert!(o.apply(&Command::Coolant {
        mist: true,
        flood: false
    }));
    assert!(o.mist && !o.flood);
    o.apply(&Command::Coolant {
        mist: true,
        flood: true,
    });
    assert!(o.mist && o.flood);
    o.apply(&Command::Coolant {
        mist: false,
        flood: false,
    });
    assert!(!o.mist && !o.flood);
}

#[test]
fn program_end_and_alarm_switch_everything_off() {
    let mut o = Outputs::new(&settings(false));
    let on = |o: &mut Outputs| {
        o.apply(&spindle(SpindleDir::Cw, 3_000.0));
        o.apply(&Command::Coolant {
            mist: true,
            flood: true,
        });
    };
    on(&mut o);
    assert!(o.apply(&Command::ProgramEnd));
    assert!(!o.spindle(FEED).enable);
    assert!(!o.mist && !o.flood);
    on(&mut o);
    o.all_off();
    assert_eq!(o.spindle_dir(), SpindleDir::Off);
    assert!(!o.mist && !o.flood);
    // S is forgotten too: a bare M3 after the alarm does not spin at 3000.
    o.apply(&spindle(SpindleDir::Cw, 0.0));
    assert_eq!(o.spindle(FEED).duty, 0.0);
}

#[test]
fn laser_fires_only_on_feed_moves() {
    let mut o = Outputs::new(&settings(true));
    o.apply(&spindle(SpindleDir::Cw, 5_000.0));
    assert_eq!(o.spindle(Motion::Rapid).duty, 0.0, "off on G0");
    assert!(!o.spindle(Motion::Rapid).enable);
    assert_eq!(o.spindle(Motion::Stopped).duty, 0.0, "off while stopped");
    let s = o.spindle(Motion::Feed { ratio: 0.2 });
    assert!(
        (s.duty - 0.5).abs() < 1e-6,
        "M3 is constant power: {}",
        s.duty
    );
    assert!(s.enable);
}

#[test]
fn laser_m4_scales_with_speed() {
    let mut o = Outputs::new(&settings(true));
    o.apply(&spindle(SpindleDir::Ccw, 10_000.0));
    let s = o.spindle(Motion::Feed { ratio: 0.25 });
    assert!((s.duty - 0.25).abs() < 1e-6, "{}", s.duty);
    assert!(!s.ccw, "a laser has no direction");
    assert_eq!(o.spindle(Motion::Feed { ratio: 3.0 }).duty, 1.0);
}

#[test]
fn configure_switches_laser_mode() {
    let mut o = Outputs::new(&settings(false));
    o.apply(&spindle(SpindleDir::Cw, 10_000.0));
    assert_eq!(o.spindle(Motion::Rapid).duty, 1.0);
    o.configure(&settings(true));
    assert_eq!(o.spindle(Motion::Rapid).duty, 0.0);
}

#[test]
fn enable_lingers_for_the_idle_delay() {
    let mut e = Enable::new(25, 0);
    assert!(!e.update(0, false, false, false), "off at power-up");
    assert!(e.update(10, true, false, false), "on before motion");
    assert!(e.may_step());
    assert!(e.update(100, false, false, false), "still on right after");
    assert!(e.update(124, false, false, false));
    assert!(
        !e.update(125, false, false, false),
        "off $1 ms after the last step"
    );
    assert!(!e.may_step());
}

#[test]
fn motion_during_the_delay_keeps_it_on() {
    let mut e = Enable::new(25, 0);
    e.update(0, true, false, false);
    e.update(10, false, false, false);
    assert!(e.update(20, true, false, false));
    e.update(30, false, false, false);
    assert!(e.update(50, false, false, false), "delay restarted at 30");
    assert!(!e.update(55, false, false, false));
}

#[test]
fn always_on_and_zero_delay() {
    let mut e = Enable::new(ALWAYS_ON, 0);
    assert!(
        e.update(0, false, false, false),
        "$1=255: on from the start"
    );
    e.update(1, true, false, false);
    assert!(e.update(1_000_000, false, false, false));
    let mut e = Enable::new(0, 0);
    e.update(0, true, false, false);
    assert!(!e.update(1, false, false, false), "$1=0: off at once");
}

#[test]
fn hold_keeps_the_drivers_on() {
    let mut e = Enable::new(25, 0);
    e.update(0, true, false, false);
    assert!(e.update(10, false, true, false));
    assert!(e.update(10_000, false, true, false), "a long hold stays on");
    assert!(
        e.update(10_001, false, false, false),
        "resume: the delay starts"
    );
    assert!(!e.update(10_026, false, false, false));
}

#[test]
fn alarm_disables_once_stopped() {
    let mut e = Enable::new(ALWAYS_ON, 0);
    e.update(0, true, false, false);
    assert!(
        e.update(1, true, false, true),
        "never off under moving steps"
    );
    assert!(!e.update(2, false, false, true));
}

#[test]
fn wake_delay_holds_back_the_first_step() {
    let mut e = Enable::new(25, 5);
    assert!(e.update(100, true, false, false));
    assert!(!e.may_step(), "driver powered, not yet awake");
    e.update(104, true, false, false);
    assert!(!e.may_step());
    e.update(105, true, false, false);
    assert!(e.may_step());
    // Re-use within the idle delay needs no new wake-up.
    e.update(110, false, false, false);
    e.update(120, true, false, false);
    assert!(e.may_step());
}

#[test]
fn setting_change_applies() {
    let mut e = Enable::new(25, 0);
    e.update(0, true, false, false);
    e.update(1, false, false, false);
    e.set_idle_ms(ALWAYS_ON);
    assert!(e.update(1_000, false, false, false));
}

/// The pin state a write/kill sequence leaves: `true` = spindle on.
fn race(estop_during_write: bool, estop_before: bool) -> (bool, bool) {
    let rt = crate::realtime::Realtime::new();
    rt.set_estop(estop_before);
    let pin = core::cell::Cell::new(false);
    let killed = write_then_recheck(
        &rt,
        || {
            // The task stores the levels its pass computed (spindle on)...
            pin.set(true);
            // ...and the e-stop interrupt lands right after that store:
            // it latches, kills, and returns into the task.
            if estop_during_write {
                rt.set_estop(true);
                pin.set(false);
            }
        },
        || pin.set(false),
    );
    (pin.get(), killed)
}

#[test]
fn an_estop_during_the_output_write_wins() {
    // Interrupt between the pass and the store (the latch was set, the
    // interrupt's kill came before the task's stale store).
    assert_eq!(race(false, true), (false, true));
    // Interrupt in the middle of the stores.
    assert_eq!(race(true, false), (false, true));
    // No e-stop: the levels stand and nothing is killed.
    assert_eq!(race(false, false), (true, false));
}
