//! The VCD writer: structure, exact pulse widths, edge order, time scales.

use crate::synth;

use std::collections::HashMap;

use host_sim::record::Recorder;
use host_sim::vcd::{TimeScale, Vcd};
use synth::{empty_summary, event as ev};

/// A small VCD reader: checks the structure and returns, per wire name,
/// its value changes as (time, value).
fn parse_vcd(text: &str) -> (String, HashMap<String, Vec<(u64, bool)>>) {
    let mut ids: HashMap<char, String> = HashMap::new();
    let mut timescale = String::new();
    let mut toks = text.split_whitespace().peekable();
    let mut sections = Vec::new();
    while let Some(t) = toks.next() {
        match t {
            "$enddefinitions" => {
                assert_eq!(toks.next(), Some("$end"));
                break;
            }
            "$var" => {
                let body: Vec<&str> = toks.by_ref().take_while(|&x| x != "$end").collect();
                assert_eq!(body[0], "wire");
                assert_eq!(body[1], "1");
                let id = body[2].chars().next().unwrap();
                assert!(
                    ids.insert(id, body[3].to_string()).is_none(),
                    "duplicate id"
                );
            }
            "$timescale" => {
                let body: Vec<&str> = toks.by_ref().take_while(|&x| x != "$end").collect();
                timescale = body.join(" ");
            }
            s if s.starts_with('$') => {
                sections.push(s.to_string());
                for x in toks.by_ref() {
                    if x == "$end" {
                        break;
                    }
                }
            }
            other => panic!("stray header token {other}"),
        }
    }
    for s in ["$version", "$scope", "$upscope"] {
        assert!(sections.iter().any(|x| x == s), "missing {s}");
    }
    let mut waves: HashMap<String, Vec<(u64, bool)>> = HashMap::new();
    let mut now: Option<u64> = None;
    for t in toks {
        if let Some(n) = t.strip_prefix('#') {
            let n: u64 = n.parse().unwrap();
            assert!(now.is_none_or(|p| n > p), "time {n} after {now:?}");
            now = Some(n);
        } else if t == "$dumpvars" || t == "$end" {
        } else {
            let (v, id) = t.split_at(1);
            let name = &ids[&id.chars().next().unwrap()];
            let v = match v {
                "0" => false,
                "1" => true,
                _ => panic!("bad value {t}"),
            };
            waves
                .entry(name.clone())
                .or_default()
                .push((now.unwrap(), v));
        }
    }
    assert_eq!(ids.len(), 2 * burin::AXES, "a step and a dir wire per axis");
    (timescale, waves)
}

#[test]
fn vcd_of_a_run_is_well_formed_with_exact_pulses() {
    let mut v = Vcd::new(Vec::new());
    let s = synth::run(&mut v);
    let text = String::from_utf8(v.into_inner()).unwrap();
    if let Some(dir) = option_env!("CARGO_TARGET_TMPDIR") {
        std::fs::write(format!("{dir}/synthetic.vcd"), &text).unwrap();
    }
    let (ts, waves) = parse_vcd(&text);
    assert_eq!(ts, "1 ns");
    for (axis, name) in ["X", "Y"].iter().enumerate() {
        let w = &waves[&format!("{name}_step")];
        let rises: Vec<u64> = w.iter().filter(|x| x.1).map(|x| x.0).collect();
        assert_eq!(rises.len() as u64, s.steps[axis], "{name} pulses");
        // Initial 0, then strict alternation 1, 0, 1, 0 ... each high 2 µs.
        for pair in w[1..].chunks(2) {
            assert!(pair[0].1 && !pair[1].1);
            assert_eq!(pair[1].0 - pair[0].0, 2000, "pulse width ns");
        }
        // Every direction change comes at least 1 µs before the next rise.
        let dirs = &waves[&format!("{name}_dir")];
        for d in &dirs[1..] {
            if let Some(r) = rises.iter().find(|&&r| r >= d.0) {
                assert!(r - d.0 >= 1000, "dir setup at {}", d.0);
            }
        }
    }
    assert_eq!(waves["Z_step"].len(), 1, "Z only has its initial value");
}

#[test]
fn vcd_orders_edges_when_pulses_overlap_and_dirs_change_mid_pulse() {
    let mut v = Vcd::new(Vec::new());
    let mut info = synth::info();
    info.pulse_ticks = 100;
    v.start(&info);
    v.step_event(&ev(1000, 0, 0b01, burin::pad([1, 0, 0, 0])));
    v.step_event(&ev(1050, 0, 0b10, burin::pad([1, 1, 0, 0]))); // X still high
    let mut e = ev(1080, 0b01, 0b01, burin::pad([0, 1, 0, 0])); // X again, reversed, overlapping
    e.dir_changed_tick = 1060;
    v.step_event(&e);
    v.finish(&empty_summary()).unwrap();
    let text = String::from_utf8(v.into_inner()).unwrap();
    let (_, waves) = parse_vcd(&text);
    let ns = |t: u64| TimeScale::for_tick_hz(synth::TICK_HZ).to_units(t);
    // X: one stretched pulse from 1000 to 1180; its direction flips at 1060.
    assert_eq!(
        waves["X_step"],
        vec![(0, false), (ns(1000), true), (ns(1180), false)]
    );
    assert_eq!(waves["X_dir"], vec![(0, false), (ns(1060), true)]);
    assert_eq!(
        waves["Y_step"],
        vec![(0, false), (ns(1050), true), (ns(1150), false)]
    );
}

#[test]
fn vcd_timescale_is_exact_when_a_unit_divides_the_tick() {
    let t = TimeScale::for_tick_hz(1_000_000);
    assert_eq!((t.text().as_str(), t.exact), ("1 us", true));
    assert_eq!(t.to_units(12345), 12345);
    let t = TimeScale::for_tick_hz(16_000_000);
    assert_eq!((t.text().as_str(), t.exact), ("100 ps", true));
    assert_eq!(t.to_units(3), 1875);
    let t = TimeScale::for_tick_hz(96_000_000);
    assert_eq!((t.text().as_str(), t.exact), ("1 ns", false));
    assert_eq!(t.to_units(96_000_000 * 3600), 3_600_000_000_000);
    assert_eq!(t.to_units(1), 10);
    // The u64 fast path rounds exactly as the u128 formula does.
    for hz in [
        96_000_000u32,
        84_000_000,
        16_000_000,
        1_000,
        3_000_000_007,
        u32::MAX,
    ] {
        let t = TimeScale::for_tick_hz(hz);
        for tick in [
            0u64,
            1,
            7,
            hz as u64 / 2,
            hz as u64 - 1,
            1 << 40,
            123_456_789_012_345,
        ] {
            let num = u128::from(tick) * 1_000_000_000_000_000;
            let den = u128::from(hz) * u128::from(t.unit_fs);
            assert_eq!(
                u128::from(t.to_units(tick)),
                (num + den / 2) / den,
                "{hz} Hz, tick {tick}"
            );
        }
    }
    assert_eq!(t.to_units(2), 21);
}
