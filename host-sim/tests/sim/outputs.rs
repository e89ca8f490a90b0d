//! The output writers on synthetic runs: CSV trace, SVG plot, JSON summary
//! and the terminal summary (VCD: vcd.rs).

use crate::synth;

use host_sim::plot::SvgPlot;
use host_sim::record::{Recorder, Tee};
use host_sim::report::{print_summary, write_json, JsonReport};
use host_sim::trace::TraceCsv;

#[test]
fn csv_header_and_rows_are_exact() {
    let mut t = TraceCsv::new(Vec::new());
    t.step_event(&synth::event(100, 0, 1, burin::pad([1, 0, 0, 0])));
    t.step_event(&synth::event(150, 0, 0, burin::pad([1, 0, 0, 0]))); // no step: no row
    t.step_event(&synth::event(200, 0b10, 0b11, burin::pad([2, -1, 0, 0])));
    t.step_event(&synth::event(
        u64::MAX,
        0b1111,
        0b1111,
        burin::pad([i64::MIN, -1, 7, i64::MAX]),
    ));
    assert_eq!(t.rows(), 3);
    let out = String::from_utf8(t.into_inner().unwrap()).unwrap();
    // One column per axis this build drives; the axes past A stood still.
    let rest = ",0".repeat(burin::AXES - 4);
    assert_eq!(
        out,
        format!(
            "{}\n100,1,0,0,0{rest}\n200,2,-1,0,0{rest}\n{},{},-1,7,{}{rest}\n",
            header(),
            u64::MAX,
            i64::MIN,
            i64::MAX
        )
    );
}

/// `tick` and a column per axis this build drives.
fn header() -> String {
    let names: Vec<String> = burin::AXIS_NAMES.iter().map(char::to_string).collect();
    format!("tick,{}", names.join(","))
}

#[test]
fn csv_of_a_run_ends_at_the_final_position() {
    let mut t = TraceCsv::new(Vec::new());
    let s = synth::run(&mut t);
    let out = String::from_utf8(t.into_inner().unwrap()).unwrap();
    let mut lines = out.lines();
    assert_eq!(lines.next(), Some(header().as_str()));
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
    assert!(
        !svg.contains(r#"class="zline""#),
        "Z never moved: no Z panel"
    );
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
        // Z steps down 1 of every 1000 events: a helical ramp.
        let pos = burin::pad([
            (r * a.cos()) as i64,
            (r * a.sin()) as i64,
            -((i / 1000) as i64),
            0,
        ]);
        p.step_event(&synth::event(i * 1000, 0b100, 1, pos));
        // A speed sample on every event: folding must keep this linear.
        p.velocity(i * 1000, 1000.0 + (i % 7919) as f32);
        if i % 1000 == 0 {
            p.commanded(
                1,
                host_sim::record::PathKind::Arc,
                burin::pad([pos[0] as f32 / 80.0, pos[1] as f32 / 80.0, 0.0, 0.0]),
            );
        }
    }
    p.finish(&synth::empty_summary()).unwrap();
    drop(p);
    let svg = String::from_utf8(out).unwrap();
    check_xml(&svg);
    if let Some(dir) = option_env!("CARGO_TARGET_TMPDIR") {
        std::fs::write(format!("{dir}/spiral.svg"), &svg).unwrap();
    }
    assert!(svg.len() < 4_000_000, "{} bytes", svg.len());
    assert!(svg.contains(r#"class="zline""#), "Z moved: Z panel");
    let points = svg.matches(',').count();
    assert!(points < 200_000, "{points} points");
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
        assert_eq!(a.len(), burin::AXES, "{k}");
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
    assert_eq!(axes.len(), burin::AXES);
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
    write_json(&mut out, &info, &synth::empty_summary()).unwrap();
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
    assert!(text.contains("square.nc:7: error[33]: "), "{text}");
    assert!(text.contains(&format!("X {:>10}", s.steps[0])), "{text}");
}

#[test]
fn terminal_summary_caps_the_error_list() {
    let mut s = synth::empty_summary();
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
