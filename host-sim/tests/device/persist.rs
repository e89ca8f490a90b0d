//! Settings and work offsets survive a power cycle of the virtual device:
//! the same record log as the boards, over a RAM copy of their
//! two flash sectors that a "rebooted" device is handed.

use host_sim::config::MachineConfig;
use host_sim::device_sim::{SimFlash, VirtualDevice};
use host_sim::record::Discard;
use protocol::client::grbl::parse_status;

fn origin() -> MachineConfig {
    MachineConfig {
        start_position_mm: [0.0; burin::AXES],
        ..MachineConfig::default()
    }
}

struct Rig<'r> {
    dev: VirtualDevice<'r>,
    text: String,
    step: u64,
    /// Lines that came with status reports (see `state`).
    other: Vec<String>,
}

impl<'r> Rig<'r> {
    /// Power-up on `flash`; the boot output stays in `text`.
    fn boot(cfg: &MachineConfig, rec: &'r mut Discard, flash: SimFlash) -> Self {
        let dev = VirtualDevice::with_flash(cfg, rec, flash);
        let mut r = Rig {
            dev,
            text: String::new(),
            step: u64::from(cfg.tick_hz) / 500,
            other: Vec::new(),
        };
        r.run(1);
        r
    }
    fn run(&mut self, rounds: usize) {
        for _ in 0..rounds {
            let t = self.dev.sim.now() + self.step;
            self.dev.advance_to(t);
            self.text
                .push_str(&String::from_utf8_lossy(&self.dev.take_output()));
        }
    }
    fn lines(&mut self) -> Vec<String> {
        let t = std::mem::take(&mut self.text);
        t.split("\r\n")
            .filter(|l| !l.is_empty())
            .map(str::to_string)
            .collect()
    }
    fn send_line(&mut self, line: &str) {
        let bytes = format!("{line}\n");
        assert_eq!(self.dev.receive(bytes.as_bytes()), bytes.len(), "link full");
    }
    fn cmd(&mut self, line: &str) -> Vec<String> {
        self.send_line(line);
        self.run(2);
        self.lines()
    }
    fn state(&mut self) -> String {
        self.dev.receive(b"?");
        self.run(1);
        let lines = self.lines();
        let st = lines.iter().rev().find_map(|l| parse_status(l));
        let st = st.unwrap_or_else(|| panic!("no status in {lines:?}")).state;
        let rest = lines.into_iter().filter(|l| parse_status(l).is_none());
        self.other.extend(rest);
        st
    }
    fn until_idle(&mut self) {
        for _ in 0..10_000 {
            self.run(10);
            // The status reads Idle for a moment at a sync point too (the
            // next move is not parsed yet): wait for the device as well.
            if self.state() == "Idle" && self.dev.idle() {
                return;
            }
        }
        panic!("never idle");
    }
}

fn has(lines: &[String], want: &str) -> bool {
    lines.iter().any(|l| l == want)
}

#[test]
fn settings_and_offsets_survive_a_reboot() {
    let cfg = origin();
    let mut rec = Discard;
    let mut a = Rig::boot(&cfg, &mut rec, SimFlash::new());
    // Erased flash: every item defaulted, said once after the banner.
    let boot = a.lines();
    // Every setting, offset vector and tool slot (138 with four axes).
    let items =
        burin::persist::SETTINGS + burin::persist::record::OFFSET_RECORDS + burin::interp::TOOLS;
    let want = format!("[MSG:Stored settings: {items} restored to defaults]");
    assert!(has(&boot, &want), "{boot:?}");
    assert_eq!(a.cmd("$110=1234"), ["ok"]);
    assert_eq!(a.cmd("G10 L2 P2 X5"), ["ok"]);
    assert_eq!(a.cmd("M500"), ["ok"]);
    let flash = a.dev.flash();

    let mut rec2 = Discard;
    let mut b = Rig::boot(&cfg, &mut rec2, flash);
    let boot = b.lines();
    assert!(!boot.iter().any(|l| l.starts_with("[MSG")), "{boot:?}");
    let all = b.cmd("$$");
    assert!(has(&all, "$110=1234.000"), "{all:?}");
    let params = b.cmd("$#");
    assert!(has(&params, "[G55:5.000,0.000,0.000,0.000]"), "{params:?}");
    // The machine runs on the loaded settings, not just lists them.
    assert_eq!(b.dev.sim.machine.settings().axes[0].max_rate, 1234.0);
}

#[test]
fn g10_saves_at_once_and_m501_drops_unsaved_parameter_writes() {
    let cfg = origin();
    let mut rec = Discard;
    let mut a = Rig::boot(&cfg, &mut rec, SimFlash::new());
    a.lines();
    // No M500: G10 L2 saves by itself (as GRBL does).
    assert_eq!(a.cmd("G10 L2 P1 X3"), ["ok"]);
    // A parameter write changes the offset now but is not saved ...
    assert_eq!(a.cmd("#5241=7"), ["ok"]);
    assert!(has(&a.cmd("$#"), "[G55:7.000,0.000,0.000,0.000]"));
    // ... so M501 (reload as at boot) brings back the stored value.
    assert_eq!(a.cmd("M501"), ["ok"]);
    let params = a.cmd("$#");
    assert!(has(&params, "[G55:0.000,0.000,0.000,0.000]"), "{params:?}");
    assert!(has(&params, "[G54:3.000,0.000,0.000,0.000]"), "{params:?}");

    let mut rec2 = Discard;
    let mut b = Rig::boot(&cfg, &mut rec2, a.dev.flash());
    b.lines();
    let params = b.cmd("$#");
    assert!(has(&params, "[G54:3.000,0.000,0.000,0.000]"), "{params:?}");
}

#[test]
fn nothing_is_written_while_the_machine_moves() {
    let cfg = origin();
    let mut rec = Discard;
    let mut a = Rig::boot(&cfg, &mut rec, SimFlash::new());
    a.lines();
    let before = a.dev.flash().written;
    a.send_line("G1 X20 F300");
    a.send_line("G10 L2 P3 Y2");
    a.send_line("G1 X0");
    // Taken with the last move, while it runs: refused (error 8, not idle).
    a.send_line("$110=999");
    a.run(3);
    assert_eq!(a.state(), "Run");
    assert_eq!(a.dev.flash().written, before, "flash written mid-move");
    a.until_idle();
    let replies = std::mem::take(&mut a.other);
    assert_eq!(replies, ["ok", "ok", "ok", "error:8"]);
    // The offsets went out at the sync point, and the job went on after it.
    assert!(a.dev.flash().written > before);
    assert_eq!(a.dev.position_steps()[0], 0);
    let mut rec2 = Discard;
    let mut b = Rig::boot(&cfg, &mut rec2, a.dev.flash());
    b.lines();
    assert!(has(&b.cmd("$#"), "[G56:0.000,2.000,0.000,0.000]"));
    assert_eq!(b.dev.sim.machine.settings().axes[0].max_rate, {
        cfg.settings.axes[0].max_rate
    });
}

#[test]
fn rst_restores_defaults_and_saves_them() {
    let cfg = origin();
    let default_rate = cfg.settings.axes[0].max_rate;
    let mut rec = Discard;
    let mut a = Rig::boot(&cfg, &mut rec, SimFlash::new());
    a.lines();
    assert_eq!(a.cmd("$110=1234"), ["ok"]);
    assert_eq!(a.cmd("G10 L2 P1 Z-4"), ["ok"]);
    assert_eq!(a.cmd("$RST=$"), ["[MSG:Restoring defaults]", "ok"]);
    assert_eq!(a.dev.sim.machine.settings().axes[0].max_rate, default_rate);
    // `$RST=$` leaves the offsets; `$RST=#` clears them.
    assert!(has(&a.cmd("$#"), "[G54:0.000,0.000,-4.000,0.000]"));
    assert_eq!(a.cmd("$RST=#"), ["[MSG:Restoring defaults]", "ok"]);

    let mut rec2 = Discard;
    let mut b = Rig::boot(&cfg, &mut rec2, a.dev.flash());
    b.lines();
    assert!(has(&b.cmd("$$"), &format!("$110={default_rate:.3}")));
    assert!(has(&b.cmd("$#"), "[G54:0.000,0.000,0.000,0.000]"));
}

/// `$RST=$` and M501 replace the settings one `$n=` at a time: the default
/// `$0=2` checked against the old `$201=203000` (over its 200 kHz ceiling)
/// was refused and dropped without a word, so `$0` stayed 1 (issue 34).
/// A second pass applies it once `$201` is back at 200000 (M501 takes the
/// same `replace_settings`).
#[test]
fn rst_applies_a_pulse_width_refused_against_the_old_rate() {
    let cfg = origin();
    let mut rec = Discard;
    let mut a = Rig::boot(&cfg, &mut rec, SimFlash::new());
    a.lines();
    assert_eq!(a.cmd("$0=1"), ["ok"]);
    assert_eq!(a.cmd("$201=203000"), ["ok"]);
    assert_eq!(a.cmd("$RST=$"), ["[MSG:Restoring defaults]", "ok"]);
    let s = a.dev.sim.machine.settings();
    assert_eq!((s.step_pulse_us, s.max_step_rate_hz), (2.0, 200_000.0));
}

/// Issue 13 item 5c: no flash write while the spindle or coolant is on (a
/// sector erase stalls the e-stop handler for up to 0.8 s). The refused
/// line leaves no trace; once M5 M9 have run the same writes go through.
#[test]
fn no_flash_write_with_spindle_or_coolant_on() {
    let cfg = origin();
    let mut rec = Discard;
    let mut a = Rig::boot(&cfg, &mut rec, SimFlash::new());
    a.lines();
    assert_eq!(a.cmd("M3 S1000"), ["ok"]);
    assert_eq!(a.cmd("G10 L2 P1 X3"), ["error:8"]);
    assert_eq!(a.cmd("G28.1"), ["error:8"]);
    assert_eq!(a.cmd("M500"), ["error:8"]);
    assert_eq!(a.cmd("$110=1234"), ["error:113"]);
    assert_eq!(a.cmd("$RST=#"), ["error:113"]);
    let params = a.cmd("$#");
    assert!(has(&params, "[G54:0.000,0.000,0.000,0.000]"), "{params:?}");
    // Coolant alone counts too.
    assert_eq!(a.cmd("M5 M8"), ["ok"]);
    assert_eq!(a.cmd("G10 L2 P1 X3"), ["error:8"]);
    // Reading is no write.
    assert_eq!(a.cmd("M501"), ["ok"]);
    // Turned off in the same line: written after the outputs are off.
    assert_eq!(a.cmd("M9 G10 L2 P2 X5"), ["ok"]);
    assert_eq!(a.cmd("$110=1234"), ["ok"]);
    let flash = a.dev.flash();
    let mut rec2 = Discard;
    let mut b = Rig::boot(&cfg, &mut rec2, flash);
    b.lines();
    let params = b.cmd("$#");
    assert!(has(&params, "[G55:5.000,0.000,0.000,0.000]"), "{params:?}");
    assert!(has(&params, "[G54:0.000,0.000,0.000,0.000]"), "{params:?}");
    assert_eq!(b.dev.sim.machine.settings().axes[0].max_rate, 1234.0);
}
