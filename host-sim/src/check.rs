//! Check mode: interpret a whole file without motion, report every error,
//! and optionally dump each emitted command as one JSON object per line.
//!
//! The output is a contract other tools diff against reference interpreters:
//!
//! - errors: `FILE:LINE:COL: error[CODE]: message` (CODE from
//!   [`burin::gcode::ErrorKind::code`]); interpretation continues with the
//!   next line, and the failed line leaves no trace (as LinuxCNC's check);
//! - `--dump`: `{"line":N,"kind":K,...}` per command. Motion kinds (`rapid`,
//!   `line`, `arc`, `spline`, `probe`) carry `end` (one number per axis,
//!   machine mm; A in degrees); feed moves carry `feed` (mm/min, or the
//!   inverse-time value with `"feed_mode":"inverse_time"`); arcs add
//!   `center` (the plane's two axes), `plane` (`XY`, `ZX`, `YZ`), `dir`
//!   (`cw`/`ccw`) and `turns` (extra full turns); splines add `p1`, `p2`.
//!   Other kinds: `dwell` (`seconds`), `home`/`verify_home` (`axes`),
//!   `spindle` (`dir`, `speed`), `coolant` (`mist`, `flood`), `aux` (`pin`,
//!   `value`, `synced`), `motors` (`enable`, `axes`), `pause` (`optional`),
//!   `program_end`, `wait_idle`, `message` (`text`), `report` (`what`),
//!   `feed_override` (`percent`), `tool` (`number`), `save_settings`,
//!   `load_settings`, `clear_alarm`.
//!
//! After a home or probe command, check mode assumes the machine ended where
//! the interpreter guessed (homed axes at 0, probes touching at their target).

use burin::command::{ArcDir, Command, Feed, Plane, Pos, ReportKind, SpindleDir};
use burin::flow::Flow;
use burin::interp::Interpreter;
use burin::AXIS_NAMES;
use std::io::{self, Write};

fn nums(v: &[f32]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
    format!("[{}]", parts.join(","))
}

fn axes(mask: u8) -> String {
    let names: Vec<String> = AXIS_NAMES
        .iter()
        .enumerate()
        .filter(|(i, _)| mask & (1 << i) != 0)
        .map(|(_, c)| format!("\"{c}\""))
        .collect();
    format!("[{}]", names.join(","))
}

fn json_str(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

fn feed(f: &Feed) -> String {
    match f {
        Feed::PerMin(v) => format!(",\"feed\":{v}"),
        Feed::InverseTime(v) => format!(",\"feed\":{v},\"feed_mode\":\"inverse_time\""),
    }
}

fn motion(kind: &str, end: &Pos) -> String {
    format!("\"kind\":\"{kind}\",\"end\":{}", nums(end))
}

/// The JSON object (without the line field) for one command.
pub fn command_json(c: &Command) -> String {
    match c {
        Command::Rapid { end } => motion("rapid", end),
        Command::Line { end, feed: f } => motion("line", end) + &feed(f),
        Command::Arc(a) => {
            let plane = match a.plane {
                Plane::XY => "XY",
                Plane::ZX => "ZX",
                Plane::YZ => "YZ",
            };
            let dir = if a.dir == ArcDir::Cw { "cw" } else { "ccw" };
            format!(
                "{},\"center\":{},\"plane\":\"{plane}\",\"dir\":\"{dir}\",\"turns\":{}{}",
                motion("arc", &a.end),
                nums(&a.center),
                a.turns,
                feed(&a.feed)
            )
        }
        Command::Spline(s) => {
            format!(
                "{},\"p1\":{},\"p2\":{}{}",
                motion("spline", &s.end),
                nums(&s.p1),
                nums(&s.p2),
                feed(&s.feed)
            )
        }
        Command::Probe { end, feed: f, kind } => {
            format!("{},\"probe\":\"{kind:?}\"{}", motion("probe", end), feed(f))
        }
        Command::Dwell { seconds } => format!("\"kind\":\"dwell\",\"seconds\":{seconds}"),
        Command::Home { axes: m } => format!("\"kind\":\"home\",\"axes\":{}", axes(*m)),
        Command::VerifyHome { axes: m } => {
            format!("\"kind\":\"verify_home\",\"axes\":{}", axes(*m))
        }
        Command::Spindle { dir, speed } => {
            let d = match dir {
                SpindleDir::Off => "off",
                SpindleDir::Cw => "cw",
                SpindleDir::Ccw => "ccw",
            };
            format!("\"kind\":\"spindle\",\"dir\":\"{d}\",\"speed\":{speed}")
        }
        Command::Coolant { mist, flood } => {
            format!("\"kind\":\"coolant\",\"mist\":{mist},\"flood\":{flood}")
        }
        Command::Aux { pin, value, synced } => {
            format!("\"kind\":\"aux\",\"pin\":{pin},\"value\":{value},\"synced\":{synced}")
        }
        Command::Motors { enable, axes: m } => {
            format!(
                "\"kind\":\"motors\",\"enable\":{enable},\"axes\":{}",
                axes(*m)
            )
        }
        Command::Pause { optional } => format!("\"kind\":\"pause\",\"optional\":{optional}"),
        Command::ProgramEnd => "\"kind\":\"program_end\"".into(),
        Command::WaitIdle => "\"kind\":\"wait_idle\"".into(),
        Command::Message(m) => format!("\"kind\":\"message\",\"text\":{}", json_str(m)),
        Command::Report(r) => {
            let w = match r {
                ReportKind::Position => "position",
                ReportKind::Firmware => "firmware",
                ReportKind::Endstops => "endstops",
            };
            format!("\"kind\":\"report\",\"what\":\"{w}\"")
        }
        Command::FeedOverride { percent } => {
            format!("\"kind\":\"feed_override\",\"percent\":{percent}")
        }
        Command::Tool { number } => format!("\"kind\":\"tool\",\"number\":{number}"),
        Command::ToolChange { tool } => format!("\"kind\":\"tool_change\",\"tool\":{tool}"),
        Command::Cycle(c) => format!(
            "\"kind\":\"cycle\",\"code\":{},\"repeats\":{}",
            c.kind.tenths(),
            c.repeats
        ),
        Command::SaveSettings => "\"kind\":\"save_settings\"".into(),
        Command::LoadSettings => "\"kind\":\"load_settings\"".into(),
        Command::ClearAlarm => "\"kind\":\"clear_alarm\"".into(),
        // The compensation stage takes these; none leaves the interpreter.
        Command::CutterComp(c) => format!("\"kind\":\"cutter_comp\",\"on\":{}", c.is_some()),
    }
}

/// Interprets `source` line by line; prints errors (and with `dump` the
/// commands) to `out`; returns how many lines failed.
/// `settings` are the machine's (`--machine`): `$210` decides what G28/G30 mean.
pub fn check_file(
    path_label: &str,
    source: &str,
    dump: bool,
    settings: &burin::settings::Settings,
    out: &mut dyn Write,
) -> io::Result<usize> {
    let mut interp = Interpreter::new();
    interp.set_g28_homes(settings.g28_homes);
    let mut flow = Flow::new();
    let mut errors = 0;
    let mut at = interp.state().pos;
    for (i, line) in source.split('\n').enumerate() {
        let n = i + 1;
        // O-word loops and calls run the stored lines they release; each
        // is reported with the line it was written on, and a move cutter
        // compensation held back with its own line.
        let r = flow.feed_line(
            line.as_bytes(),
            n as u32,
            &mut interp,
            MAX_STEPS,
            &mut |interp, text, ln| {
                let mut tagged: Vec<(u32, Command)> = Vec::new();
                at = interp.state().pos;
                interp.execute_line_at(text, ln, &mut |l, c| tagged.push((l, c)))?;
                let cmds: Vec<Command> = tagged.iter().map(|(_, c)| c.clone()).collect();
                if let Some(l) = interp.take_arc_warning() {
                    let _ = writeln!(
                        out,
                        "{path_label}:{ln}: warning: arc offset {}0 is off the plane: ignored",
                        char::from(l)
                    );
                }
                if dump {
                    // A canned cycle is dumped as the moves it expands to.
                    for (l, c) in &tagged {
                        let steps: Vec<Command> = match c {
                            Command::Cycle(cy) => cy.steps(&at).collect(),
                            c => vec![c.clone()],
                        };
                        for s in &steps {
                            // Errors inside `run` abort the replay; a write
                            // error is reported by the next write.
                            let _ = writeln!(out, "{{\"line\":{l},{}}}", command_json(s));
                            if let Some(e) = s.end() {
                                at = *e;
                            }
                        }
                    }
                }
                sync_after(interp, &cmds);
                Ok(())
            },
        );
        if let Err((ln, e)) = r {
            errors += 1;
            writeln!(out, "{path_label}:{ln}:{}: error[{}]: {e}", e.col, e.code())?;
        }
    }
    Ok(errors)
}

/// What a move is, as LinuxCNC's canonical calls name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveKind {
    /// `STRAIGHT_TRAVERSE`
    Traverse,
    /// `STRAIGHT_FEED`
    Feed,
    /// `ARC_FEED`
    Arc,
    /// `NURBS_FEED` (G5, G5.1)
    Spline,
    /// `STRAIGHT_PROBE`
    Probe,
}

/// One motion for the whole-path comparison with rs274 (machine mm, A in
/// degrees): a canned cycle is its moves, as check mode dumps them.
#[derive(Clone, Debug, PartialEq)]
pub struct CanonMove {
    pub kind: MoveKind,
    pub end: Pos,
    /// Arcs: the plane, the centre on the plane's two axes
    /// ([`Plane::axes`] order) and the rotation as LinuxCNC counts it
    /// (turns including the partial one; positive counter-clockwise).
    pub arc: Option<(Plane, [f32; 2], i32)>,
    /// Feed moves.
    pub feed: Option<Feed>,
    /// The tool length offset in force (machine mm per axis).
    pub tlo: Pos,
}

/// Every motion of `source` up to the first M2/M30, after `prelude` (lines
/// run first and not reported: the comparison's tool table), or the first
/// error as `(line, "CODE message")` (lines of `source`, 1-based).
pub fn canon_moves(
    source: &str,
    prelude: &str,
    settings: &burin::settings::Settings,
) -> Result<Vec<CanonMove>, (usize, String)> {
    let mut interp = Interpreter::new();
    interp.set_g28_homes(settings.g28_homes);
    for line in prelude.lines() {
        interp
            .execute_line(line.as_bytes(), &mut |_| {})
            .map_err(|e| (0, format!("prelude `{line}`: error[{}]: {e}", e.code())))?;
    }
    let mut moves = Vec::new();
    let mut flow = Flow::new();
    let mut ended = false;
    for (i, line) in source.split('\n').enumerate() {
        // O-word loops and calls run the stored lines they release.
        flow.feed_line(
            line.as_bytes(),
            i as u32 + 1,
            &mut interp,
            MAX_STEPS,
            &mut |interp, text, _| {
                if ended {
                    return Ok(());
                }
                let mut cmds: Vec<Command> = Vec::new();
                let mut at = interp.state().pos;
                interp.execute_line(text, &mut |c| cmds.push(c))?;
                let tlo = interp.state().tlo;
                for c in &cmds {
                    if matches!(c, Command::ProgramEnd) {
                        ended = true;
                        return Ok(());
                    }
                    let steps: Vec<Command> = match c {
                        Command::Cycle(cy) => cy.steps(&at).collect(),
                        c => vec![c.clone()],
                    };
                    for s in &steps {
                        moves.extend(canon_move(s, tlo));
                        if let Some(e) = s.end() {
                            at = *e;
                        }
                    }
                }
                sync_after(interp, &cmds);
                Ok(())
            },
        )
        .map_err(|(l, e)| (l as usize, format!("error[{}]: {e}", e.code())))?;
        if ended {
            return Ok(moves);
        }
    }
    Ok(moves)
}

/// One command as the comparison's move (none for what does not move).
fn canon_move(s: &Command, tlo: Pos) -> Option<CanonMove> {
    let m = |kind, end: &Pos, feed: Option<Feed>| CanonMove {
        kind,
        end: *end,
        arc: None,
        feed,
        tlo,
    };
    match s {
        Command::Rapid { end } => Some(m(MoveKind::Traverse, end, None)),
        Command::Line { end, feed } => Some(m(MoveKind::Feed, end, Some(*feed))),
        Command::Probe { end, feed, .. } => Some(m(MoveKind::Probe, end, Some(*feed))),
        Command::Spline(sp) => Some(m(MoveKind::Spline, &sp.end, Some(sp.feed))),
        Command::Arc(a) => {
            let turns = i32::from(a.turns) + 1;
            let rot = if a.dir == ArcDir::Cw { -turns } else { turns };
            Some(CanonMove {
                arc: Some((a.plane, a.center, rot)),
                ..m(MoveKind::Arc, &a.end, Some(a.feed))
            })
        }
        _ => None,
    }
}

/// Replay steps one line may release (an endless O-word loop ends there).
const MAX_STEPS: u64 = 50_000_000;

/// After a home or probe: the machine is where the interpreter guessed.
fn sync_after(interp: &mut Interpreter, cmds: &[Command]) {
    if interp.needs_sync() {
        match cmds
            .iter()
            .rev()
            .find(|c| matches!(c, Command::Probe { .. }))
        {
            Some(Command::Probe { end, .. }) => interp.probe_finished(*end, true),
            _ => interp.set_machine_position(interp.state().pos),
        }
    }
}
