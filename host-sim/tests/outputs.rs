//! The output writers on synthetic runs: CSV trace, VCD, SVG plot, JSON
//! summary and the terminal summary.

mod synth;

use std::collections::HashMap;

use host_sim::plot::SvgPlot;
use host_sim::record::{PinEvent, Recorder, Tee};
use host_sim::report::{print_summary, write_json, JsonReport};
use host_sim::trace::TraceCsv;
use host_sim::vcd::{TimeScale, Vcd};

fn ev(tick: u64, dir_mask: u8, step_mask: u8, pos: [i64; 4]) -> PinEvent {
    PinEvent {
        tick,
        dir_mask,
        step_mask,
        dir_changed_tick: 0,
        pos,
    }
}

#[test]
fn csv_header_and_rows_are_exact() {
    let mut t = TraceCsv::new(Vec::new());
    t.step_event(&ev(100, 0, 1, [1, 0, 0, 0]));
    t.step_event(&ev(150, 0, 0, [1, 0, 0, 0])); // no step: no row
    t.step_event(&ev(200, 0b10, 0b11, [2, -1, 0, 0]));
    t.step_event(&ev(u64::MAX, 0b1111, 0b1111, [i64::MIN, -1, 7, i64::MAX]));
    assert_eq!(t.rows(), 3);
    let out = String::from_utf8(t.into_inner().unwrap()).unwrap();
    assert_eq!(
        out,
        format!(
            "tick,X,Y,Z,A\n100,1,0,0,0\n200,2,-1,0,0\n{},{},-1,7,{}\n",
            u64::MAX,
            i64::MIN,
            i64::MAX
        )
    );
}

#[test]
fn csv_of_a_run_ends_at_the_final_position() {
    let mut t = TraceCsv::new(Vec::new());
    let s = synth::run(&mut t);
    let out = String::from_utf8(t.into_inner().unwrap()).unwrap();
    let mut lines = out.lines();
    assert_eq!(lines.next(), Some("tick,X,Y,Z,A"));
    let rows: Vec<Vec<i64>> = lines
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    assert_eq!(
        rows.len() as u64,
        s.steps.iter().sum::<u64>() - count_diagonal(&rows)
    );
    assert!(rows.windows(2).all(|w| w[0][0] < w[1][0]), "ticks increase");
    assert_eq!(rows.last().unwrap()[1..], s.final_position_steps[..]);
}

/// Rows where X and Y both stepped count once, steps twice.
fn count_diagonal(rows: &[Vec<i64>]) -> u64 {
    let mut prev = [-80i64, -80];
    let mut n = 0;
    for r in rows {
        if r[1] != prev[0] && r[2] != prev[1] {
            n += 1;
        }
        prev = [r[1], r[2]];
    }
    n
}

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
    assert_eq!(ids.len(), 8);
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
    v.step_event(&ev(1000, 0, 0b01, [1, 0, 0, 0]));
    v.step_event(&ev(1050, 0, 0b10, [1, 1, 0, 0])); // X still high
    let mut e = ev(1080, 0b01, 0b01, [0, 1, 0, 0]); // X again, reversed, overlapping
    e.dir_changed_tick = 1060;
    v.step_event(&e);
    v.finish(&synth_summary()).unwrap();
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

fn synth_summary() -> host_sim::record::Summary {
    host_sim::record::Summary {
        lines: 0,
        moves: 0,
        job_time_s: 0.0,
        distance_mm: 0.0,
        max_feed_mm_min: 0.0,
        steps: [0; 4],
        final_position_steps: [0; 4],
        final_position_mm: [0.0; 4],
        final_work_position_mm: [0.0; 4],
        planner_underruns: 0,
        errors: vec![],
    }
}

fn check_xml(svg: &str) -> usize {
    let mut r = quick_xml::Reader::from_str(svg);
    r.config_mut().check_end_names = true;
    let mut elements = 0;
    loop {
        match r.read_event() {
            Ok(quick_xml::events::Event::Eof) => break,
            Ok(quick_xml::events::Event::Start(_) | quick_xml::events::Event::Empty(_)) => {
                elements += 1
            }
            Ok(_) => {}
            Err(e) => panic!("not well-formed at {}: {e}", r.buffer_position()),
        }
    }
    elements
}

#[test]
fn svg_is_well_formed_and_has_both_paths() {
    let mut out = Vec::new();
    let mut p = SvgPlot::new(&mut out, "synthetic <square> & circle");
    let s = synth::run(&mut p);
    drop(p);
    let svg = String::from_utf8(out).unwrap();
    assert!(check_xml(&svg) > 50);
    assert!(svg.contains(r#"class="stepped""#), "stepped path");
    for k in ["k0", "k1", "k2", "k3"] {
        assert!(
            svg.contains(&format!(r#"<polyline class="{k}""#)),
            "commanded {k}"
        );
    }
    assert!(svg.contains("synthetic &lt;square&gt; &amp; circle"));
    assert!(svg.contains(r#"class="vline""#), "velocity profile");
    assert!(svg.contains(&format!("{:.0} mm/min", s.max_feed_mm_min)));
    if let Some(dir) = option_env!("CARGO_TARGET_TMPDIR") {
        std::fs::write(format!("{dir}/synthetic.svg"), &svg).unwrap();
    }
}

#[test]
fn svg_stays_small_on_millions_of_steps() {
    let mut out = Vec::new();
    let mut p = SvgPlot::new(&mut out, "spiral");
    p.start(&synth::info());
    // A 40-turn spiral in 4 million step events, chords every degree.
    let n = 4_000_000u64;
    for i in 0..n {
        let a = i as f64 / n as f64 * 40.0 * std::f64::consts::TAU;
        let r = 8000.0 * (0.2 + 0.8 * i as f64 / n as f64);
        let pos = [(r * a.cos()) as i64, (r * a.sin()) as i64, 0, 0];
        p.step_event(&ev(i * 1000, 0, 1, pos));
        if i % 1000 == 0 {
            p.commanded(
                1,
                host_sim::record::MoveKind::Arc,
                [pos[0] as f32 / 80.0, pos[1] as f32 / 80.0, 0.0, 0.0],
            );
            p.velocity(i * 1000, 1000.0 + (i % 7919) as f32);
        }
    }
    p.finish(&synth_summary()).unwrap();
    drop(p);
    let svg = String::from_utf8(out).unwrap();
    check_xml(&svg);
    if let Some(dir) = option_env!("CARGO_TARGET_TMPDIR") {
        std::fs::write(format!("{dir}/spiral.svg"), &svg).unwrap();
    }
    assert!(svg.len() < 3_000_000, "{} bytes", svg.len());
    let points = svg.matches(',').count();
    assert!(points < 110_000, "{points} points");
    assert!(points > 2_000, "{points} points: the spiral must survive");
}

#[test]
fn json_has_every_contract_field() {
    let mut out = Vec::new();
    let mut j = JsonReport::new(&mut out);
    let s = synth::run(&mut j);
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let nums = |k: &str| -> Vec<f64> {
        let a = v[k].as_array().unwrap_or_else(|| panic!("{k} is an array"));
        assert_eq!(a.len(), 4, "{k}");
        a.iter().map(|x| x.as_f64().unwrap()).collect()
    };
    assert_eq!(nums("final_position_mm"), s.final_position_mm.to_vec());
    let st = v["final_position_steps"].as_array().unwrap();
    assert_eq!(
        st.iter().map(|x| x.as_i64().unwrap()).collect::<Vec<_>>(),
        s.final_position_steps
    );
    let steps = v["steps"].as_array().unwrap();
    assert_eq!(
        steps
            .iter()
            .map(|x| x.as_u64().unwrap())
            .collect::<Vec<_>>(),
        s.steps
    );
    assert_eq!(v["job_time_s"].as_f64(), Some(s.job_time_s));
    assert_eq!(v["max_feed_mm_min"].as_f64(), Some(s.max_feed_mm_min));
    assert_eq!(v["planner_underruns"].as_u64(), Some(0));
    assert_eq!(v["tick_hz"].as_u64(), Some(96_000_000));
    let e = &v["errors"][0];
    assert_eq!(e["line"].as_u64(), Some(7));
    assert_eq!(e["code"].as_u64(), Some(33));
    assert_eq!(
        e["message"].as_str(),
        Some("invalid target: \"quoted\" & <odd>")
    );
    let axes = v["machine"]["axes"].as_array().unwrap();
    assert_eq!(axes.len(), 4);
    assert_eq!(axes[0]["name"], "X");
    assert_eq!(axes[3]["name"], "A");
    assert_eq!(axes[2]["steps_per_mm"].as_f64(), Some(400.0));
    for k in ["max_rate_mm_min", "max_accel_mm_s2", "travel_mm"] {
        assert!(axes[1][k].is_f64(), "{k}");
    }
}

#[test]
fn json_writes_settings_as_typed() {
    let mut info = synth::info();
    info.axes[0].steps_per_mm = 0.002;
    let mut out = Vec::new();
    write_json(&mut out, &info, &synth_summary()).unwrap();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("\"steps_per_mm\": 0.002,"), "{text}");
}

#[test]
fn terminal_summary_lists_everything() {
    let mut sink = Vec::new();
    let mut j = host_sim::record::Discard;
    let mut tee = Tee(vec![&mut j]);
    let s = synth::run(&mut tee);
    print_summary(&mut sink, &synth::info(), &s, "square.nc").unwrap();
    let text = String::from_utf8(sink).unwrap();
    for label in [
        "square.nc",
        "lines",
        "moves",
        "job time",
        "distance",
        "max feed",
        "steps",
        "machine position",
        "work position",
        "planner underruns",
        "errors",
    ] {
        assert!(text.contains(label), "{label} missing:\n{text}");
    }
    assert!(text.contains("line      7  error  33"), "{text}");
    assert!(text.contains(&format!("X {:>10}", s.steps[0])), "{text}");
}

#[test]
fn terminal_summary_caps_the_error_list() {
    let mut s = synth_summary();
    s.errors = (1..=25)
        .map(|line| host_sim::record::RunError {
            line,
            code: 300,
            message: "unsupported command M300".into(),
        })
        .collect();
    let mut sink = Vec::new();
    print_summary(&mut sink, &synth::info(), &s, "many.nc").unwrap();
    let text = String::from_utf8(sink).unwrap();
    assert_eq!(text.matches("unsupported command").count(), 20);
    assert!(text.contains("and 5 more"), "{text}");
}
