//! The `$n` settings table and the GRBL text replies, byte for byte.

use burin::link::reply::{self, BuildInfo, Cadence, Extras, Format, ReplyBuf};
use burin::settings::table::{self, SettingError};
use burin::settings::{Profile, Settings};
use protocol::msg::pins;
use protocol::{MachineState, Overrides, Status};

#[test]
fn numbers_are_ascending_unique_and_all_readable() {
    let s = Settings::default();
    let nums: Vec<u16> = table::numbers().collect();
    assert!(nums.windows(2).all(|w| w[0] < w[1]));
    // Five per-axis groups ($100 $110 $120 $130 $160).
    // Then burin's ten, the tool change's nine, `$220` and `$376`.
    assert_eq!(nums.len(), 23 + 5 * burin::AXES + 10 + 9 + 1 + 1);
    for n in &nums {
        let v = s.get(*n).unwrap_or_else(|| panic!("${n} unreadable"));
        let mut t = s;
        assert_eq!(t.set(*n, v), Ok(()), "${n}={v} default must be valid");
        assert_eq!(t, s);
    }
    let past = burin::AXES as u16;
    for n in [
        7,
        15,
        99,
        100 + past,
        110 + past,
        140,
        160 + past,
        199,
        209,
        375,
        377,
        65535,
    ] {
        assert_eq!(s.get(n), None, "${n}");
    }
}

#[test]
fn rotary_axes_are_a_mask_of_the_axes() {
    let mut s = Settings::default();
    assert_eq!(s.get(376), Some(0.0));
    let all = f32::from((1u16 << burin::AXES) as u8 - 1);
    assert_eq!(s.set(376, all), Ok(()));
    assert_eq!(s.rotary_axes, (1u16 << burin::AXES) as u8 - 1);
    assert!(s.set(376, all + 1.0).is_err(), "a bit past the axes");
    assert!(s.set(376, 1.5).is_err());
}

#[test]
fn backlash_is_160_to_163_in_mm_up_to_10() {
    let mut s = Settings::default();
    assert_eq!(s.backlash_mm, [0.0; burin::AXES], "off by default");
    assert_eq!(s.set(160, 0.1), Ok(()));
    assert_eq!(s.set(163, 10.0), Ok(()));
    assert_eq!(s.backlash_mm, burin::pad([0.1, 0.0, 0.0, 10.0]));
    assert_eq!(s.get(161), Some(0.0));
    assert_eq!(s.set(162, 10.5), Err(SettingError::OutOfRange));
    assert_eq!(s.set(161, -0.1), Err(SettingError::Negative));
    let past = 160 + burin::AXES as u16;
    assert_eq!(s.set(past, 0.1), Err(SettingError::Unknown));
    assert_eq!(s.backlash_mm, burin::pad([0.1, 0.0, 0.0, 10.0]));
}

#[test]
fn control_invert_is_a_three_bit_mask() {
    let mut s = Settings::default();
    assert_eq!(s.set(14, 1.0), Ok(()));
    assert_eq!(s.control_invert, 1);
    assert_eq!(s.set(14, 7.0), Ok(()));
    assert_eq!(s.get(14), Some(7.0));
    assert!(s.set(14, 8.0).is_err());
    assert!(s.set(14, 0.5).is_err());
    assert_eq!(s.control_invert, 7);
}

#[test]
fn writes_are_validated_and_errors_change_nothing() {
    let mut s = Settings::default();
    let before = s;
    let cases: [(u16, f32, SettingError, u16); 9] = [
        (999, 1.0, SettingError::Unknown, 3),
        (110, f32::NAN, SettingError::NotANumber, 2),
        (110, -5.0, SettingError::Negative, 4),
        (100, 0.0, SettingError::OutOfRange, 110),
        (1, 2.5, SettingError::NotInteger, 111),
        (20, 2.0, SettingError::OutOfRange, 110),
        // A direction invert bit past the last axis.
        (
            3,
            f32::from(1u16 << burin::AXES),
            SettingError::BadMask,
            112,
        ),
        (10, 4.0, SettingError::BadMask, 112),
        (12, 0.0, SettingError::OutOfRange, 110),
    ];
    for (n, v, err, code) in cases {
        assert_eq!(s.set(n, v), Err(err), "${n}={v}");
        assert_eq!(err.code().code(), code);
        assert_eq!(s, before, "a refused write changes nothing");
    }
    assert_eq!(s.set(110, 6000.0), Ok(()));
    assert_eq!(s.axes[0].max_rate, 6000.0);
    assert_eq!(s.set(133, 45.0), Ok(()));
    assert_eq!(s.axes[3].max_travel, 45.0);
    assert_eq!(s.set(202, 1.0), Ok(()));
    assert_eq!(s.profile, Profile::SCurve);
    assert_eq!(s.set(3, 5.0), Ok(()));
    assert_eq!(s.get(3), Some(5.0));
}

fn text(f: impl FnOnce(&mut ReplyBuf) -> core::fmt::Result) -> String {
    let mut b = ReplyBuf::new();
    f(&mut b).expect("fits");
    b.as_str().to_string()
}

#[test]
fn simple_replies() {
    assert_eq!(text(reply::ok), "ok\r\n");
    assert_eq!(text(|w| reply::error(w, 22)), "error:22\r\n");
    assert_eq!(text(|w| reply::alarm(w, 1)), "ALARM:1\r\n");
    assert_eq!(text(reply::banner), "\r\nGrbl 1.1h ['$' for help]\r\n");
    assert_eq!(text(|w| reply::msg(w, "Pgm End")), "[MSG:Pgm End]\r\n");
    assert_eq!(
        text(|w| reply::gc(w, "G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0")),
        "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\n"
    );
    let info = BuildInfo {
        firmware: "0.1.0",
        board: "blackpill-f411",
        options: "VNMH",
        planner_blocks: 32,
        axes: 3,
    };
    assert_eq!(
        text(|w| reply::build_info(w, &info)),
        "[VER:1.1h.burin-0.1.0:blackpill-f411]\r\n[OPT:VNMH,32,128]\r\n[AXS:3:XYZ]\r\n"
    );
    let f = Format {
        axes: 3,
        inches: false,
    };
    assert_eq!(
        text(|w| reply::param(w, "G54", &[1.0, -2.0, 0.0004, 9.0], f)),
        "[G54:1.000,-2.000,0.000]\r\n"
    );
    assert_eq!(text(|w| reply::tlo(w, -1.5, f)), "[TLO:-1.500]\r\n");
    assert_eq!(
        text(|w| reply::probe(w, &[1.0, 2.0, -0.00001], true, f)),
        "[PRB:1.000,2.000,0.000:1]\r\n"
    );
}

#[test]
fn settings_listing() {
    let out = text(|w| {
        let s = Settings::default();
        for n in [0u16, 1, 10, 110, 206] {
            reply::setting(w, n, s.get(n).unwrap_or(-1.0))?;
        }
        Ok(())
    });
    assert_eq!(
        out,
        "$0=2.000\r\n$1=25\r\n$10=1\r\n$110=5000.000\r\n$206=52\r\n"
    );
    let mut all = String::new();
    reply::settings(&mut all, &Settings::default()).expect("string sink");
    assert_eq!(all.lines().count(), burin::persist::SETTINGS);
    assert!(all.contains("$220=4.000\r\n"), "spin-up delay, GRBL's 4 s");
    // The last travel, then one backlash setting per axis, then burin's.
    let mut backlash = format!("${}=0.000\r\n", 130 + burin::AXES - 1);
    for i in 0..burin::AXES {
        backlash += &format!("${}=0.000\r\n", 160 + i);
    }
    assert!(
        all.contains(&format!("{backlash}$200=")),
        "backlash, grblHAL's numbers, off by default"
    );
    assert!(
        all.contains("$210=0\r\n"),
        "G28 meaning listed, RS274NGC by default"
    );
    assert!(all.starts_with("$0=2.000\r\n$1=25\r\n$2=0\r\n"));
}

fn status() -> Status {
    Status {
        state: MachineState::Run,
        mpos: burin::pad([10.0, 20.5, -1.25, 0.0]),
        wco: burin::pad([5.0, 0.5, -1.0, 0.0]),
        feed: 1500.0,
        spindle: 12000.0,
        planner_free: 15,
        rx_free: 128,
        line: Some(42),
        pins: pins::LIMIT_X | pins::PROBE | pins::HOLD,
        ..Status::default()
    }
}

#[test]
fn status_report_fields_in_grbl_order() {
    let f = Format {
        axes: 3,
        inches: false,
    };
    let all = Extras {
        wco: true,
        ov: true,
    };
    assert_eq!(
        text(|w| reply::status(w, &status(), 3, f, all)),
        "<Run|MPos:10.000,20.500,-1.250|Bf:15,128|Ln:42|FS:1500,12000|Pn:XPH|WCO:5.000,0.500,-1.000|Ov:100,100,100>\r\n"
    );
    let mut hold = status();
    hold.state = MachineState::Hold;
    hold.substate = 1;
    hold.line = None;
    hold.pins = 0;
    assert_eq!(
        text(|w| reply::status(
            w,
            &hold,
            0,
            Format {
                axes: 4,
                inches: false
            },
            Extras::default()
        )),
        "<Hold:1|WPos:5.000,20.000,-0.250,0.000|FS:1500,12000>\r\n"
    );
    assert_eq!(
        text(|w| reply::status(
            w,
            &hold,
            1,
            Format {
                axes: 3,
                inches: true
            },
            Extras::default()
        )),
        "<Hold:1|MPos:0.3937,0.8071,-0.0492|FS:59,12000>\r\n"
    );
    // Issue 29: `A:` follows `Ov:` when something is on, in GRBL's order.
    use protocol::msg::accessory::{FLOOD, MIST, SPINDLE_CCW};
    let mut door = status();
    door.state = MachineState::Door;
    door.substate = 3;
    door.pins = 0;
    door.line = None;
    door.accessories = SPINDLE_CCW | FLOOD | MIST;
    let ov = Extras {
        wco: false,
        ov: true,
    };
    assert_eq!(
        text(|w| reply::status(w, &door, 1, f, ov)),
        "<Door:3|MPos:10.000,20.500,-1.250|FS:1500,12000|Ov:100,100,100|A:CFM>\r\n"
    );
}

#[test]
fn wco_and_overrides_every_tenth_report_or_on_change() {
    let mut c = Cadence::default();
    let mut s = status();
    let first = c.next(&s);
    assert!(first.wco && first.ov, "first report carries everything");
    let mut wco_count = 0;
    let mut ov_count = 0;
    for _ in 0..20 {
        let e = c.next(&s);
        wco_count += usize::from(e.wco);
        ov_count += usize::from(e.ov);
    }
    assert_eq!((wco_count, ov_count), (2, 2));
    s.overrides = Overrides {
        feed: 110,
        ..Overrides::default()
    };
    assert!(c.next(&s).ov, "a change shows at once");
    s.wco[0] = 1.0;
    assert!(c.next(&s).wco);
}

#[test]
fn enable_delay_is_checked() {
    let mut s = Settings::default();
    assert_eq!(s.get(207), Some(0.0));
    assert_eq!(s.set(207, 5.0), Ok(()));
    assert_eq!(s.enable_delay_us, 5.0);
    assert_eq!(s.set(207, -1.0), Err(SettingError::Negative));
    assert_eq!(s.set(207, 20_000.0), Err(SettingError::OutOfRange));
    assert_eq!(s.set(207, f32::NAN), Err(SettingError::NotANumber));
    assert_eq!(s.enable_delay_us, 5.0);
}

/// Issue 28: one step-rate ceiling. `$201` above what the CPU sustains
/// (450 kHz, once accepted) and a `$0` that makes the current `$201`
/// impossible are refused with `error:114`, and nothing changes; a `$201`
/// within the ceiling of the new `$0` makes that `$0` acceptable.
#[test]
fn step_rate_beyond_the_ceiling_is_refused() {
    use burin::settings::ceiling;
    let mut s = Settings::default();
    let before = s;
    assert_eq!(s.set(201, 450_000.0), Err(SettingError::StepRateCeiling));
    assert_eq!(SettingError::StepRateCeiling.code().code(), 114);
    assert_eq!(s, before);
    // `$0=5` needs 5 + 1 + 5 µs a step: 91 kHz, not the default 200 kHz.
    assert_eq!(s.set(0, 5.0), Err(SettingError::StepRateCeiling));
    assert_eq!(s, before);
    let top = libm::floorf(ceiling::ceiling_hz(5.0));
    assert!((90_000.0..100_000.0).contains(&top), "{top}");
    assert_eq!(s.set(201, top), Ok(()));
    assert_eq!(s.set(0, 5.0), Ok(()));
    // And back: `$201` above the new `$0`'s ceiling is refused.
    assert_eq!(s.set(201, 200_000.0), Err(SettingError::StepRateCeiling));
    assert_eq!(s.max_step_rate_hz, top);
    // The CPU's share is the top whatever `$0`: the default fits.
    assert!(ceiling::settings_fit(&Settings::default()));
    assert_eq!(
        s.set(201, libm::floorf(ceiling::CPU_RATE_HZ) + 1.0),
        Err(SettingError::StepRateCeiling)
    );
}
