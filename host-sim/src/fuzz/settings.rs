//! `settings`: `$` system commands and `$n=` values, then a machine built
//! from whatever was accepted. Invariants: the parser is total; a refused
//! `$n=` changes nothing; an accepted one reads back as written; every
//! listed setting reads back finite; `Machine::new` and a short move on the
//! result neither panic nor produce a non-finite position.

use burin::command::{Command, Feed};
use burin::link::syscmd::{self, SysCmd};
use burin::settings::{table, Settings};

use super::Bytes;
use crate::config::{HostModel, MachineConfig};
use crate::engine::Sim;
use crate::record::Discard;

const TICKS: &[u32] = &[96_000_000, 84_000_000, 1_000_000, 48_000];

pub fn settings(data: &[u8]) {
    let mut b = Bytes::new(data);
    let tick_hz = b.pick(TICKS);
    let target = burin::pad([
        f32::from(b.u8() as i8) / 8.0,
        f32::from(b.u8() as i8) / 8.0,
        f32::from(b.u8() as i8) / 16.0,
        f32::from(b.u8() as i8),
    ]);
    let mut s = Settings::default();
    for line in b.rest().split(|&c| c == b'\n') {
        let Some(Ok(cmd)) = syscmd::parse(line) else {
            continue;
        };
        if let SysCmd::SetSetting { n, value } = cmd {
            let before = s;
            match s.set(n, value) {
                Err(e) => assert!(
                    s == before,
                    "refused $${n}={value} ({e:?}) changed settings"
                ),
                Ok(()) => {
                    let got = s.get(n);
                    let want = match table::kind(n) {
                        Some(table::Kind::Bool) => f32::from(u8::from(value != 0.0)),
                        _ => value,
                    };
                    assert_eq!(got, Some(want), "$${n}={value} reads back {got:?}");
                }
            }
        }
    }
    for n in table::numbers() {
        let v = s.get(n);
        assert!(v.is_some_and(f32::is_finite), "$${n} lists as {v:?}");
    }
    motion(s, tick_hz, target);
}

/// A machine on these settings: built, then one short move for at most
/// 5 ms of virtual time.
fn motion(settings: Settings, tick_hz: u32, target: [f32; burin::AXES]) {
    let cfg = MachineConfig {
        tick_hz,
        settings,
        limits: [None; burin::AXES],
        probe: None,
        start_position_mm: [0.0; burin::AXES],
        host: HostModel::INSTANT,
        interrupts: Default::default(),
        wiring: None,
        slack_mm: Default::default(),
    };
    let mut rec = Discard;
    let mut sim = Sim::new(&cfg, &mut rec);
    sim.push_command(
        1,
        Command::Line {
            end: target,
            feed: Feed::PerMin(600.0),
        },
    );
    sim.run_until(u64::from(tick_hz) / 200);
    let p = sim.machine.commanded_position();
    assert!(p.iter().all(|v| v.is_finite()), "position {p:?}");
}
