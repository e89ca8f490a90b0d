//! rs274's canonical output read into the moves `host_sim::check::canon_moves`
//! gives for burin, and the comparison of the two sequences.
//!
//! Reading rs274's output: positions are program coordinates in the
//! program's units (`USE_LENGTH_UNITS`); machine = program + G5x + G92 +
//! tool length offset. Offsets are converted to mm with the units in force
//! when rs274 announced them (it announces an offset after the block's
//! G20/G21 and does not announce it again when the units change). A feed
//! (`SET_FEED_RATE`) comes before the block's G20/G21 (RS274NGC sets F
//! first), so it is converted with the units of the first move after it.
//! `NURBS_FEED` (G5, G5.1) prints neither end nor control points: only its
//! kind and feed are compared, and the next move's end shows where it went.

use host_sim::check::{CanonMove, MoveKind};

/// Agreement required on every end point, centre and offset, mm.
pub const TOL: f64 = 0.003;

type P = [f64; 4];

/// One rs274 move, machine mm.
#[derive(Clone, Debug)]
pub struct Theirs {
    pub kind: MoveKind,
    /// `None` for `NURBS_FEED`.
    pub end: Option<P>,
    /// Plane (0 XY, 1 XZ, 2 YZ), centre on its two axes, rotation.
    pub arc: Option<(u8, [f64; 2], i32)>,
    /// mm/min (or the inverse-time value), for feed moves.
    pub feed: Option<f64>,
    pub tlo: P,
}

/// rs274's verdict on one file.
pub enum Canon {
    /// The moves, cut after a probe (rs274 simulates a contact).
    Ok(Vec<Theirs>),
    Rejected(String),
}

fn args_of(line: &str) -> Vec<f64> {
    let (Some(a), Some(b)) = (line.find('('), line.rfind(')')) else {
        return Vec::new();
    };
    line.get(a + 1..b)
        .unwrap_or("")
        .split([',', ' '])
        .filter_map(|x| x.trim().parse::<f64>().ok())
        .collect()
}

pub fn parse(out: &str) -> Canon {
    let mut unit = 1.0;
    let (mut g5x, mut g92, mut tlo) = ([0.0; 4], [0.0; 4], [0.0; 4]);
    let mut plane = 0u8;
    // The raw feed waiting for a move's units, and the feed in mm/min.
    let (mut raw_feed, mut feed) = (None::<f64>, 0.0);
    // rs274 prints `SET_FEED_MODE(0, 0)` for G93 as for G94 (2.9), so
    // inverse-time feeds are left out on burin's side ([`ours`]).
    let inverse = false;
    let mut moves = Vec::new();
    for line in out.lines() {
        let t = line.trim_start();
        let body = match t.split_once(" N") {
            Some((n, rest)) if n.chars().all(|c| c.is_ascii_digit()) => {
                rest.split_once(' ').map_or("", |x| x.1).trim()
            }
            _ => {
                // rs274 wants M2 or `%` at the end; burin does not.
                if t.starts_with("File ended with no percent sign") {
                    return Canon::Ok(moves);
                }
                if t.is_empty() || t == "executing" {
                    continue;
                }
                return Canon::Rejected(t.to_string());
            }
        };
        let name = body.split('(').next().unwrap_or("");
        let a = args_of(body);
        let v = |i: usize| a.get(i).copied().unwrap_or(0.0);
        let mm = |p: [f64; 4]| -> P { [p[0] * unit, p[1] * unit, p[2] * unit, p[3]] };
        let machine = |p: [f64; 4]| -> P {
            let mut m = [0.0; 4];
            for i in 0..4 {
                let u = if i < 3 { unit } else { 1.0 };
                m[i] = p[i] * u + g5x[i] + g92[i] + tlo[i];
            }
            m
        };
        let kind = match name {
            "USE_LENGTH_UNITS" => {
                unit = if body.contains("INCHES") { 25.4 } else { 1.0 };
                continue;
            }
            "SET_G5X_OFFSET" => {
                g5x = mm([v(1), v(2), v(3), v(4)]);
                continue;
            }
            "SET_G92_OFFSET" => {
                g92 = mm([v(0), v(1), v(2), v(3)]);
                continue;
            }
            // (x y z, a b c, u v w)
            "USE_TOOL_LENGTH_OFFSET" => {
                if v(4) != 0.0 || v(5) != 0.0 {
                    return Canon::Rejected("B/C tool offsets (burin drives XYZA)".into());
                }
                tlo = mm([v(0), v(1), v(2), v(3)]);
                continue;
            }
            "SET_FEED_RATE" => {
                raw_feed = Some(v(0));
                continue;
            }
            "SET_XY_ROTATION" if v(0) != 0.0 => {
                return Canon::Rejected("G10 R rotation (not in burin)".into())
            }
            "SELECT_PLANE" => {
                plane = if body.contains("XZ") {
                    1
                } else if body.contains("YZ") {
                    2
                } else {
                    0
                };
                continue;
            }
            "STRAIGHT_TRAVERSE" => MoveKind::Traverse,
            "STRAIGHT_FEED" => MoveKind::Feed,
            "STRAIGHT_PROBE" => MoveKind::Probe,
            "ARC_FEED" => MoveKind::Arc,
            "NURBS_FEED" | "SPLINE_FEED" => MoveKind::Spline,
            _ => continue,
        };
        if let Some(r) = raw_feed.take() {
            feed = if inverse { r } else { r * unit };
        }
        let feed = (kind != MoveKind::Traverse).then_some(feed);
        let m = match kind {
            MoveKind::Traverse | MoveKind::Feed | MoveKind::Probe => {
                if v(4) != 0.0 || v(5) != 0.0 {
                    return Canon::Rejected("B/C axes (burin drives XYZA)".into());
                }
                Theirs {
                    kind,
                    end: Some(machine([v(0), v(1), v(2), v(3)])),
                    arc: None,
                    feed,
                    tlo,
                }
            }
            MoveKind::Arc => {
                // (first_end, second_end, first_axis, second_axis, rotation,
                //  axis_end, a, b, c)
                let (f, s, ax) = (v(0), v(1), v(5));
                let (end, axes) = match plane {
                    0 => ([f, s, ax, v(6)], [0, 1]),
                    1 => ([s, ax, f, v(6)], [2, 0]),
                    _ => ([ax, f, s, v(6)], [1, 2]),
                };
                if v(7) != 0.0 || v(8) != 0.0 {
                    return Canon::Rejected("B/C axes (burin drives XYZA)".into());
                }
                let centre = [
                    v(2) * unit + g5x[axes[0]] + g92[axes[0]] + tlo[axes[0]],
                    v(3) * unit + g5x[axes[1]] + g92[axes[1]] + tlo[axes[1]],
                ];
                Theirs {
                    kind,
                    end: Some(machine(end)),
                    arc: Some((plane, centre, v(4) as i32)),
                    feed,
                    tlo,
                }
            }
            MoveKind::Spline => Theirs {
                kind,
                end: None,
                arc: None,
                feed,
                tlo,
            },
        };
        moves.push(m);
        if kind == MoveKind::Probe {
            return Canon::Ok(moves);
        }
    }
    Canon::Ok(moves)
}

/// burin's moves in the same shape.
pub fn ours(moves: &[CanonMove]) -> Vec<Theirs> {
    // rs274's XYZA; burin's other axes (B, C) never reach here (`parse`
    // rejects them).
    let p = |v: &[f32; burin::AXES]| [v[0] as f64, v[1] as f64, v[2] as f64, v[3] as f64];
    moves
        .iter()
        .map(|m| Theirs {
            kind: m.kind,
            end: Some(p(&m.end)),
            arc: m.arc.map(|(pl, c, r)| {
                let pl = match pl {
                    burin::command::Plane::XY => 0,
                    burin::command::Plane::ZX => 1,
                    burin::command::Plane::YZ => 2,
                };
                (pl, [c[0] as f64, c[1] as f64], r)
            }),
            // Inverse-time values are not compared (see `parse`).
            feed: match m.feed {
                Some(burin::command::Feed::PerMin(v)) => Some(v as f64),
                _ => None,
            },
            tlo: p(&m.tlo),
        })
        .collect()
}

/// Drops straight moves that end where the previous move did (the first
/// one too when it ends at machine zero, where both start): LinuxCNC emits
/// G28's intermediate move even when it has no length, burin may not.
/// Arcs and splines are never dropped (a full circle ends where it began).
pub fn dedup(v: Vec<Theirs>) -> Vec<Theirs> {
    let mut out: Vec<Theirs> = Vec::new();
    let mut last = Some([0.0; 4]);
    for m in v {
        let straight = matches!(m.kind, MoveKind::Traverse | MoveKind::Feed);
        if let (true, Some(a), Some(b)) = (straight, last, m.end) {
            if same_point(&a, &b) {
                continue;
            }
        }
        // rs274 prints no spline end: after one, nothing is dropped on
        // either side.
        last = if m.kind == MoveKind::Spline {
            None
        } else {
            m.end
        };
        out.push(m);
    }
    out
}

/// Far below rs274's printed 0.0001 and the tolerance, so a 0.003 mm move
/// (Cereal.ngc has them) is never dropped on one side and kept on the other.
fn same_point(a: &P, b: &P) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 5e-4)
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// What a comparison found: the worst point difference, how many moves,
/// and the first difference if any.
pub struct Verdict {
    pub worst: f64,
    pub moves: usize,
    pub diff: Option<String>,
}

/// rs274's moves for the program `src` against burin's, whole: both
/// without repeats ([`dedup`]), cut after a probe when `src` has one.
pub fn compare_program(theirs: Vec<Theirs>, ours_: &[CanonMove], src: &str) -> Verdict {
    let theirs = dedup(theirs);
    let ours_ = dedup(ours(ours_));
    compare(&theirs, &ours_, src.to_ascii_uppercase().contains("G38"))
}

/// Compares two whole sequences move by move; `probe_cut`: rs274 stops
/// after its first probe, so burin's later moves are not compared.
pub fn compare(theirs: &[Theirs], ours: &[Theirs], probe_cut: bool) -> Verdict {
    let mut worst = 0.0f64;
    let mut diff = None;
    for (i, t) in theirs.iter().enumerate() {
        let Some(o) = ours.get(i) else {
            diff = Some(format!("move {i}: burin ends early ({} moves)", ours.len()));
            break;
        };
        let mut d = Vec::new();
        if t.kind != o.kind {
            d.push(format!("kind {:?} vs {:?}", t.kind, o.kind));
        }
        if let (Some(a), Some(b), false) = (t.end, o.end, t.kind == MoveKind::Spline) {
            let e = dist(&a, &b);
            worst = worst.max(e);
            if e > TOL {
                d.push(format!("end {a:?} vs {b:?}"));
            }
        }
        match (t.arc, o.arc) {
            (Some((pa, ca, ra)), Some((pb, cb, rb))) => {
                let e = dist(&ca, &cb);
                worst = worst.max(e);
                if pa != pb || e > TOL || ra != rb {
                    d.push(format!(
                        "arc plane {pa} centre {ca:?} rotation {ra} vs plane {pb} centre {cb:?} rotation {rb}"
                    ));
                }
            }
            (None, None) => {}
            (a, b) => d.push(format!("arc {a:?} vs {b:?}")),
        }
        if let (Some(a), Some(b)) = (t.feed, o.feed) {
            if (a - b).abs() > 1e-3 + 1e-4 * a.abs() {
                d.push(format!("feed {a} vs {b}"));
            }
        }
        let e = dist(&t.tlo, &o.tlo);
        worst = worst.max(e);
        if e > TOL {
            d.push(format!("tool offset {:?} vs {:?}", t.tlo, o.tlo));
        }
        if !d.is_empty() {
            diff = Some(format!("move {i}: rs274 vs burin: {}", d.join("; ")));
            break;
        }
    }
    if diff.is_none() && ours.len() != theirs.len() && !probe_cut {
        diff = Some(format!(
            "{} moves in rs274, {} in burin",
            theirs.len(),
            ours.len()
        ));
    }
    Verdict {
        worst,
        moves: theirs.len(),
        diff,
    }
}
