//! `--json FILE` and the terminal summary of a run.
//!
//! The JSON object is a contract (issue 4, item 6) that other tools read:
//! `final_position_mm`, `final_position_steps`, `job_time_s`, `steps`,
//! `max_feed_mm_min`, `planner_underruns`, `errors` (`{line, code, message}`),
//! `tick_hz`, and `machine.axes` (`{name, steps_per_mm, max_rate_mm_min,
//! max_accel_mm_s2, travel_mm}`); `max_tool_deviation_mm` (the modelled
//! tool's largest distance from the commanded path, see `Summary`). Per-axis
//! arrays are in X, Y, Z, A order.
//! Extra fields may be added; none of these may change meaning.

use std::io::{self, Write};

use serde::Serialize;

use crate::record::{Recorder, RunInfo, Summary};

/// f32 settings as the decimal a person typed (80.0, 0.002), not the f64
/// expansion of the nearest binary float (0.0020000000949949026).
fn tidy(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::NAN)
}

#[derive(Serialize)]
struct Json<'a> {
    final_position_mm: &'a [f64],
    final_position_steps: &'a [i64],
    final_work_position_mm: &'a [f64],
    job_time_s: f64,
    steps: &'a [u64],
    max_feed_mm_min: f64,
    planner_underruns: u32,
    errors: Vec<JsonError<'a>>,
    tick_hz: u32,
    machine: JsonMachine,
    lines: u32,
    moves: u32,
    distance_mm: f64,
    max_tool_deviation_mm: f64,
}

#[derive(Serialize)]
struct JsonError<'a> {
    line: u32,
    code: u16,
    message: &'a str,
}

#[derive(Serialize)]
struct JsonMachine {
    axes: Vec<JsonAxis>,
    step_pulse_ticks: u32,
    dir_setup_ticks: u32,
}

#[derive(Serialize)]
struct JsonAxis {
    name: String,
    steps_per_mm: f64,
    max_rate_mm_min: f64,
    max_accel_mm_s2: f64,
    travel_mm: f64,
}

/// Writes the summary object (pretty-printed, newline-terminated).
pub fn write_json<W: Write>(mut w: W, info: &RunInfo, s: &Summary) -> io::Result<()> {
    let j = Json {
        final_position_mm: &s.final_position_mm,
        final_position_steps: &s.final_position_steps,
        final_work_position_mm: &s.final_work_position_mm,
        job_time_s: s.job_time_s,
        steps: &s.steps,
        max_feed_mm_min: s.max_feed_mm_min,
        planner_underruns: s.planner_underruns,
        errors: s
            .errors
            .iter()
            .map(|e| JsonError {
                line: e.line,
                code: e.code,
                message: &e.message,
            })
            .collect(),
        tick_hz: info.tick_hz,
        machine: JsonMachine {
            axes: info
                .axes
                .iter()
                .map(|a| JsonAxis {
                    name: a.name.to_string(),
                    steps_per_mm: tidy(a.steps_per_mm),
                    max_rate_mm_min: tidy(a.max_rate_mm_min),
                    max_accel_mm_s2: tidy(a.max_accel_mm_s2),
                    travel_mm: tidy(a.travel_mm),
                })
                .collect(),
            step_pulse_ticks: info.pulse_ticks,
            dir_setup_ticks: info.dir_setup_ticks,
        },
        lines: s.lines,
        moves: s.moves,
        distance_mm: s.distance_mm,
        max_tool_deviation_mm: s.max_tool_deviation_mm,
    };
    serde_json::to_writer_pretty(&mut w, &j)?;
    w.write_all(b"\n")?;
    w.flush()
}

/// A recorder that writes the JSON summary when the run finishes.
pub struct JsonReport<W: Write> {
    out: Option<W>,
    info: Option<RunInfo>,
}

impl<W: Write> JsonReport<W> {
    pub fn new(out: W) -> Self {
        JsonReport {
            out: Some(out),
            info: None,
        }
    }
}

impl<W: Write> Recorder for JsonReport<W> {
    fn start(&mut self, info: &RunInfo) {
        self.info = Some(info.clone());
    }

    fn finish(&mut self, summary: &Summary) -> io::Result<()> {
        match (self.out.take(), self.info.as_ref()) {
            (Some(out), Some(info)) => write_json(out, info, summary),
            _ => Err(io::Error::other(
                "JSON report finished twice or without start",
            )),
        }
    }
}

/// `83.456` → `1:23.456`; hours appear when needed.
pub fn format_duration(secs: f64) -> String {
    if !secs.is_finite() || secs < 0.0 {
        return format!("{secs} s");
    }
    let ms = (secs * 1000.0).round() as u64;
    let (h, m, s, frac) = (ms / 3_600_000, ms / 60_000 % 60, ms / 1000 % 60, ms % 1000);
    if h > 0 {
        format!("{h}:{m:02}:{s:02}.{frac:03}")
    } else {
        format!("{m}:{s:02}.{frac:03}")
    }
}

fn axes_line<T>(info: &RunInfo, vals: &[T], f: impl Fn(&T) -> String) -> String {
    let cells: Vec<String> = info
        .axes
        .iter()
        .zip(vals)
        .map(|(a, v)| format!("{} {:>10}", a.name, f(v)))
        .collect();
    cells.join("   ")
}

/// Errors listed one per line in the terminal summary; a job that repeats
/// one unsupported word hundreds of times should not bury the figures.
pub const MAX_LISTED_ERRORS: usize = 20;

/// The terminal summary `cargo xtask sim` prints.
pub fn print_summary<W: Write>(
    mut w: W,
    info: &RunInfo,
    s: &Summary,
    job_name: &str,
) -> io::Result<()> {
    let label = |w: &mut W, l: &str, v: &str| writeln!(w, "  {l:<20}{v}");
    writeln!(w, "burin host-sim: {job_name}")?;
    label(&mut w, "lines", &s.lines.to_string())?;
    label(&mut w, "moves", &s.moves.to_string())?;
    let time = format!("{}  ({:.3} s)", format_duration(s.job_time_s), s.job_time_s);
    label(&mut w, "job time", &time)?;
    label(&mut w, "distance", &format!("{:.3} mm", s.distance_mm))?;
    label(
        &mut w,
        "max feed",
        &format!("{:.1} mm/min", s.max_feed_mm_min),
    )?;
    let steps = axes_line(info, &s.steps, |v| v.to_string());
    label(&mut w, "steps", &steps)?;
    let mpos = axes_line(info, &s.final_position_mm, |v| format!("{v:.3}"));
    label(&mut w, "machine position", &mpos)?;
    let wpos = axes_line(info, &s.final_work_position_mm, |v| format!("{v:.3}"));
    label(&mut w, "work position", &wpos)?;
    let spos = axes_line(info, &s.final_position_steps, |v| v.to_string());
    label(&mut w, "position (steps)", &spos)?;
    label(
        &mut w,
        "planner underruns",
        &s.planner_underruns.to_string(),
    )?;
    if s.errors.is_empty() {
        label(&mut w, "errors", "none")?;
    } else {
        label(&mut w, "errors", &s.errors.len().to_string())?;
        for e in s.errors.iter().take(MAX_LISTED_ERRORS) {
            writeln!(
                w,
                "    {job_name}:{}: error[{}]: {}",
                e.line, e.code, e.message
            )?;
        }
        if s.errors.len() > MAX_LISTED_ERRORS {
            let more = s.errors.len() - MAX_LISTED_ERRORS;
            writeln!(w, "    … and {more} more (all of them are in --json)")?;
        }
    }
    w.flush()
}
