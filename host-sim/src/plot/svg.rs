//! Drawing the collected plot data as one self-contained SVG: plain text,
//! CSS classes for the styles, no scripts, so browsers, Inkscape and
//! `rsvg-convert` all render it the same.

use std::fmt::Write as _;
use std::io::{self, Write};

use burin::{AXES, AXIS_NAMES};

use super::frame::{polyline, Frame};
use super::Series;
use crate::record::{AxisInfo, RunInfo, Summary};
use crate::report::format_duration;

pub(super) struct Plot<'a> {
    pub job_name: &'a str,
    pub info: &'a RunInfo,
    pub summary: &'a Summary,
    pub start: Option<[f64; 2]>,
    pub commanded: &'a [([f64; 2], u8)],
    pub stepped: &'a [([f64; 2], u8)],
    pub velocity: &'a Series,
    pub z: &'a Series,
    pub end_tick: u64,
}

/// Used when a run never called `start` (nothing to scale steps by).
pub(super) fn fallback_info() -> RunInfo {
    RunInfo {
        tick_hz: 1,
        axes: AXIS_NAMES.map(|name| AxisInfo {
            name,
            steps_per_mm: 1.0,
            max_rate_mm_min: 0.0,
            max_accel_mm_s2: 0.0,
            travel_mm: 0.0,
        }),
        pulse_ticks: 1,
        dir_setup_ticks: 0,
    }
}

/// Move kinds by tag: legend name, CSS for the stroke.
const KINDS: [(&str, &str); 6] = [
    (
        "rapid",
        "stroke:#8a8a8a;stroke-width:1;stroke-dasharray:5 3",
    ),
    ("feed", "stroke:#1565c0;stroke-width:1.7"),
    ("arc", "stroke:#7e3bbf;stroke-width:1.7"),
    ("spline", "stroke:#e7298a;stroke-width:1.7"),
    ("probe", "stroke:#d62728;stroke-width:1.7"),
    ("home", "stroke:#8c564b;stroke-width:1.7"),
];
const STEPPED: &str =
    "stroke:#ffc857;stroke-opacity:0.5;stroke-width:6;stroke-linejoin:round;stroke-linecap:round";
const FONT: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";
const W: f64 = 1000.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 30.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Bounds of everything drawn in XY, padded, never degenerate.
fn xy_bounds(p: &Plot) -> ((f64, f64), (f64, f64)) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let pts = p
        .commanded
        .iter()
        .chain(p.stepped)
        .map(|k| k.0)
        .chain(p.start);
    for q in pts.filter(|q| q[0].is_finite() && q[1].is_finite()) {
        for i in 0..2 {
            lo[i] = lo[i].min(q[i]);
            hi[i] = hi[i].max(q[i]);
        }
    }
    if lo[0] > hi[0] {
        return ((-10.0, 10.0), (-10.0, 10.0));
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
    let pad = span * 0.04;
    let r = |i: usize| {
        let half = ((hi[i] - lo[i]).max(1.0) / 2.0) + pad;
        let mid = (hi[i] + lo[i]) / 2.0;
        (mid - half, mid + half)
    };
    (r(0), r(1))
}

fn xy_panel(s: &mut String, p: &Plot, top: f64) -> f64 {
    let ((x0, x1), (y0, y1)) = xy_bounds(p);
    let pw = W - LEFT - RIGHT;
    let ph = (pw * (y1 - y0) / (x1 - x0)).clamp(240.0, 680.0);
    // Equal aspect: one scale, the data centred in the other direction.
    let scale = (pw / (x1 - x0)).min(ph / (y1 - y0));
    let (hx, hy) = (pw / scale / 2.0, ph / scale / 2.0);
    let (mx, my) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let f = Frame {
        left: LEFT,
        top,
        w: pw,
        h: ph,
        x: (mx - hx, mx + hx),
        y: (my - hy, my + hy),
        equal: true,
    };
    let (xn, yn) = (AXIS_NAMES[0], AXIS_NAMES[1]);
    f.axes(
        s,
        &format!("{xn} (machine mm)"),
        &format!("{yn} (machine mm)"),
    );
    f.clip(s, "xyclip");
    s.push_str("<g clip-path=\"url(#xyclip)\">\n");
    polyline(s, "stepped", &f, p.stepped.iter().map(|k| k.0));
    // Runs of one kind become one polyline, each starting where the last ended.
    let mut prev = p.start;
    let mut i = 0;
    while i < p.commanded.len() {
        let tag = p.commanded[i].1;
        let mut j = i;
        while j < p.commanded.len() && p.commanded[j].1 == tag {
            j += 1;
        }
        let run = prev
            .into_iter()
            .chain(p.commanded[i..j].iter().map(|k| k.0));
        polyline(s, &format!("k{tag}"), &f, run);
        prev = Some(p.commanded[j - 1].0);
        i = j;
    }
    let end = p.stepped.last().or(p.commanded.last()).map(|k| k.0);
    if let Some(q) = p.start {
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="5" fill="#2ca02c" stroke="#fff"/>"##,
            f.px(q[0]),
            f.py(q[1])
        );
    }
    if let Some(q) = end {
        let _ = writeln!(
            s,
            r##"<rect x="{:.1}" y="{:.1}" width="9" height="9" fill="#d62728" stroke="#fff"/>"##,
            f.px(q[0]) - 4.5,
            f.py(q[1]) - 4.5
        );
    }
    s.push_str("</g>\n");
    top + ph
}

/// A sample holds until the next one ("recorded whenever it changes"), so
/// a series is drawn as a staircase, not as a line between samples.
fn staircase(series: &Series, hz: f64, t_end: f64) -> Vec<[f64; 2]> {
    // More samples than pixel columns only add bytes: fold to min/max per column.
    let folded;
    let samples = if series.samples.len() > 4 * W as usize {
        folded = super::fold_min_max(&series.samples, W as usize);
        &folded
    } else {
        &series.samples
    };
    let mut pts: Vec<[f64; 2]> = Vec::with_capacity(samples.len() * 2 + 1);
    for &(t, v) in samples {
        let q = [t as f64 / hz, f64::from(v)];
        if let Some(&[_, held]) = pts.last() {
            pts.push([q[0], held]);
        }
        pts.push(q);
    }
    if let Some(&[t, v]) = pts.last() {
        if t < t_end {
            pts.push([t_end, v]);
        }
    }
    pts
}

fn time_span(p: &Plot) -> (f64, f64) {
    let hz = f64::from(p.info.tick_hz.max(1));
    let t_end = (p.end_tick as f64 / hz).max(p.summary.job_time_s).max(1e-3);
    (hz, t_end)
}

/// Z over time, when Z moved at all: plunges and retracts at a glance.
fn z_panel(s: &mut String, p: &Plot, top: f64) -> Option<f64> {
    let (lo, hi) = (f64::from(p.z.min), f64::from(p.z.max));
    // Also false when Z never moved (min +inf, max -inf).
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let (hz, t_end) = time_span(p);
    let pad = ((hi - lo) * 0.12).max(0.2);
    let f = Frame {
        left: LEFT,
        top,
        w: W - LEFT - RIGHT,
        h: 130.0,
        x: (0.0, t_end),
        y: (lo - pad, hi + pad),
        equal: false,
    };
    f.axes(s, "time (s)", &format!("{} (machine mm)", AXIS_NAMES[2]));
    f.clip(s, "zclip");
    s.push_str("<g clip-path=\"url(#zclip)\">\n");
    polyline(s, "zline", &f, staircase(p.z, hz, t_end).into_iter());
    s.push_str("</g>\n");
    Some(top + f.h)
}

fn velocity_panel(s: &mut String, p: &Plot, top: f64) -> f64 {
    let (hz, t_end) = time_span(p);
    let vmax = f64::from(p.velocity.max)
        .max(p.summary.max_feed_mm_min)
        .max(1.0);
    let f = Frame {
        left: LEFT,
        top,
        w: W - LEFT - RIGHT,
        h: 210.0,
        x: (0.0, t_end),
        y: (0.0, vmax * 1.12),
        equal: false,
    };
    f.axes(s, "time (s)", "path speed (mm/min)");
    f.clip(s, "vclip");
    s.push_str("<g clip-path=\"url(#vclip)\">\n");
    let pts = staircase(p.velocity, hz, t_end);
    if let (Some(a), Some(b)) = (pts.first(), pts.last()) {
        let area = std::iter::once([a[0], 0.0])
            .chain(pts.iter().copied())
            .chain(std::iter::once([b[0], 0.0]));
        polyline(s, "varea", &f, area);
        polyline(s, "vline", &f, pts.iter().copied());
    } else {
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">no speed samples</text>"#,
            f.left + f.w / 2.0,
            f.top + f.h / 2.0
        );
    }
    let ym = f.py(vmax);
    let _ = writeln!(
        s,
        r##"<line x1="{:.1}" y1="{ym:.1}" x2="{:.1}" y2="{ym:.1}" stroke="#d62728" stroke-width="1" stroke-dasharray="6 4"/>"##,
        f.left,
        f.left + f.w
    );
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" text-anchor="end" fill="#d62728">max {vmax:.0} mm/min</text>"##,
        f.left + f.w - 6.0,
        ym - 5.0
    );
    s.push_str("</g>\n");
    top + f.h
}

fn legend(s: &mut String, p: &Plot, y: f64) {
    let mut present = [false; KINDS.len()];
    for k in p.commanded {
        if let Some(b) = present.get_mut(usize::from(k.1)) {
            *b = true;
        }
    }
    let mut x = LEFT;
    let mut item = |s: &mut String, class: &str, name: &str| {
        let _ = writeln!(
            s,
            r#"<line class="{class}" x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}"/><text x="{:.1}" y="{:.1}">{name}</text>"#,
            x + 26.0,
            x + 32.0,
            y + 4.0
        );
        x += 44.0 + 7.5 * name.len() as f64;
    };
    for (tag, (name, _)) in KINDS.iter().enumerate().filter(|(i, _)| present[*i]) {
        item(s, &format!("k{tag}"), name);
    }
    item(s, "stepped", "stepped (actual)");
    let _ = writeln!(
        s,
        r##"<circle cx="{:.1}" cy="{y:.1}" r="5" fill="#2ca02c"/><text x="{:.1}" y="{:.1}">start</text>"##,
        x + 5.0,
        x + 14.0,
        y + 4.0
    );
    let _ = writeln!(
        s,
        r##"<rect x="{:.1}" y="{:.1}" width="9" height="9" fill="#d62728"/><text x="{:.1}" y="{:.1}">end</text>"##,
        x + 60.0,
        y - 4.5,
        x + 74.0,
        y + 4.0
    );
}

fn subtitle(p: &Plot) -> String {
    let sm = p.summary;
    let steps: u64 = sm.steps.iter().sum();
    let mut t = format!(
        "{} lines · {} moves · job time {} · distance {:.1} mm · max feed {:.0} mm/min · {} steps",
        sm.lines,
        sm.moves,
        format_duration(sm.job_time_s),
        sm.distance_mm,
        sm.max_feed_mm_min,
        steps
    );
    if sm.planner_underruns > 0 {
        let n = sm.planner_underruns;
        let _ = write!(t, " · {n} underrun{}", if n == 1 { "" } else { "s" });
    }
    if !sm.errors.is_empty() {
        let n = sm.errors.len();
        let _ = write!(t, " · {n} error{}", if n == 1 { "" } else { "s" });
    }
    t
}

pub(super) fn write<W: Write>(mut out: W, p: &Plot) -> io::Result<()> {
    let mut body = String::with_capacity(1 << 20);
    let _ = writeln!(
        body,
        r##"<text x="{LEFT}" y="34" font-size="22" font-weight="bold" fill="#222">{}</text>"##,
        esc(p.job_name)
    );
    let _ = writeln!(
        body,
        r##"<text x="{LEFT}" y="58" font-size="13" fill="#555">{}</text>"##,
        esc(&subtitle(p))
    );
    legend(&mut body, p, 84.0);
    let xy_bottom = xy_panel(&mut body, p, 102.0);
    let mut bottom = velocity_panel(&mut body, p, xy_bottom + 58.0);
    if let Some(b) = z_panel(&mut body, p, bottom + 58.0) {
        bottom = b;
    }
    let h = bottom + 52.0;
    let mut head = String::new();
    let _ = writeln!(
        head,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{h:.0}" viewBox="0 0 {W} {h:.0}" font-family="{FONT}" font-size="12">"#
    );
    let _ = writeln!(head, "<title>burin host-sim: {}</title>", esc(p.job_name));
    head.push_str("<style>\npolyline { fill: none; stroke-linejoin: round; }\n");
    for (tag, (_, css)) in KINDS.iter().enumerate() {
        let _ = writeln!(head, ".k{tag} {{ {css}; fill: none; }}");
    }
    let _ = writeln!(head, ".stepped {{ {STEPPED}; fill: none; }}");
    head.push_str(
        ".grid { stroke: #e4e4e4; stroke-width: 1; }\n\
         .lab { font-size: 13px; fill: #333; }\n\
         text { fill: #444; }\n\
         .vline { stroke: #1f6fb4; stroke-width: 1.2; fill: none; }\n\
         .zline { stroke: #16877a; stroke-width: 1.2; fill: none; }\n\
         polyline.varea { fill: #1f6fb4; fill-opacity: 0.12; stroke: none; }\n</style>\n",
    );
    let _ = writeln!(head, r#"<rect width="{W}" height="{h:.0}" fill="white"/>"#);
    out.write_all(head.as_bytes())?;
    out.write_all(body.as_bytes())?;
    out.write_all(b"</svg>\n")?;
    out.flush()
}

const _: () = assert!(AXES >= 2);
