//! Shared by the interp_* tests: a canonical one-line text form of every
//! command (LinuxCNC tests/interp style, 4 decimals so f32 noise does not
//! make goldens flaky) and a file runner.

#![allow(dead_code)]

use burin::command::{ArcDir, Command, Feed, Plane};
use burin::interp::Interpreter;

fn p(v: &[f32]) -> String {
    v.iter()
        .map(|x| format!("{:.4}", if x.abs() < 5e-5 { 0.0 } else { *x }))
        .collect::<Vec<_>>()
        .join(", ")
}

fn f(feed: &Feed) -> String {
    match feed {
        Feed::PerMin(v) => format!("F{v:.4}"),
        Feed::InverseTime(v) => format!("F1/{v:.4}"),
    }
}

pub fn canon(c: &Command) -> String {
    match c {
        Command::Rapid { end } => format!("RAPID({})", p(end)),
        Command::Line { end, feed } => format!("LINE({}) {}", p(end), f(feed)),
        Command::Arc(a) => format!(
            "ARC({}) C({}) {} {} T{} {}",
            p(&a.end),
            p(&a.center),
            match a.plane {
                Plane::XY => "XY",
                Plane::ZX => "ZX",
                Plane::YZ => "YZ",
            },
            if a.dir == ArcDir::Cw { "CW" } else { "CCW" },
            a.turns,
            f(&a.feed)
        ),
        Command::Spline(s) => format!(
            "SPLINE({}) P1({}) P2({}) {}",
            p(&s.end),
            p(&s.p1),
            p(&s.p2),
            f(&s.feed)
        ),
        Command::Probe { end, feed, kind } => format!("PROBE({}) {} {kind:?}", p(end), f(feed)),
        Command::Dwell { seconds } => format!("DWELL({seconds:.4})"),
        Command::Message(m) => format!("MESSAGE({m:?})"),
        other => format!("{other:?}"),
    }
}

/// Runs a whole program; one output line per command or error.
/// A program whose first line mentions `$210=1` runs with BeagleG's G28/G30.
pub fn run(src: &str) -> String {
    let mut it = Interpreter::new();
    it.set_g28_homes(src.lines().next().is_some_and(|l| l.contains("$210=1")));
    let mut out = String::new();
    for (i, line) in src.split('\n').enumerate() {
        let n = i + 1;
        let mut cmds = Vec::new();
        let mut at = it.state().pos;
        match it.execute_line(line.as_bytes(), &mut |c| cmds.push(c)) {
            Ok(()) => {
                for c in &cmds {
                    // A canned cycle prints as the moves it expands to.
                    let steps: Vec<Command> = match c {
                        Command::Cycle(cy) => cy.steps(&at).collect(),
                        c => vec![c.clone()],
                    };
                    for s in &steps {
                        out.push_str(&format!("{n}: {}\n", canon(s)));
                        if let Some(e) = s.end() {
                            at = *e;
                        }
                    }
                }
                if it.needs_sync() {
                    match cmds
                        .iter()
                        .rev()
                        .find(|c| matches!(c, Command::Probe { .. }))
                    {
                        Some(Command::Probe { end, .. }) => it.probe_finished(*end, true),
                        _ => it.set_machine_position(it.state().pos),
                    }
                }
            }
            Err(e) => out.push_str(&format!("{n}: ERROR {} col {}: {e}\n", e.code(), e.col)),
        }
    }
    out
}
