//! Issue 35 item 1, as a property: every arc the interpreter accepts, on
//! any radius from 0.001 mm to 1e9 mm and any chord from one step to the
//! machine's travel, G2 and G3, R and I/J form, ends exactly on its
//! commanded end, keeps every chord end within one step of the true arc,
//! turns the way (and as far as) its geometry says, and its path (the sum
//! of its chords) is as long as that arc, never a stray full circle.
use burin::arc::ArcChords;
use burin::command::{Arc, Command, Pos};
use burin::interp::Interpreter;
use proptest::prelude::*;
use std::f64::consts::PI;

/// The machine: positions within `[-TRAVEL, 0]` on X and Y.
const TRAVEL: f64 = 1000.0;
const TOL: f32 = 0.002;

#[derive(Debug, Clone)]
struct Case {
    /// Steps per mm of X and Y.
    spm: f64,
    start: [f64; 2],
    /// Radius magnitude, mm.
    r: f64,
    /// Where the chord falls in its range, 0..1 (log scale).
    chord_at: f64,
    /// Chord direction, rad.
    psi: f64,
    cw: bool,
    /// The long way round (R < 0); only for radii within the travel.
    long: bool,
    ij: bool,
}

fn case() -> impl Strategy<Value = Case> {
    (
        1.0f64..3.7,  // log10 of steps/mm: 10 to 5000
        0.0f64..1.0,  // start X, fraction of the travel
        0.0f64..1.0,  // start Y
        -3.0f64..9.0, // log10 of the radius
        0.0f64..1.0,
        0.0f64..(2.0 * PI),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|(spm, x, y, r, chord_at, psi, cw, long, ij)| {
            let r = 10f64.powf(r);
            Case {
                spm: 10f64.powf(spm),
                start: [-x * TRAVEL, -y * TRAVEL],
                r,
                chord_at,
                psi,
                cw,
                long: long && r <= TRAVEL / 2.0,
                ij,
            }
        })
}

/// The G-code line for a case, and the start point.
fn line(c: &Case) -> (String, Pos) {
    let step = 1.0 / c.spm;
    let lo = step.min(2.0 * c.r);
    let hi = TRAVEL.min(2.0 * c.r);
    let len = (lo.ln() + (hi.ln() - lo.ln()) * c.chord_at).exp();
    let s = [c.start[0] as f32, c.start[1] as f32];
    let d = [len * c.psi.cos(), len * c.psi.sin()];
    let g = if c.cw { 2 } else { 3 };
    let start = burin::pad([s[0], s[1], 0.0, 0.0]);
    let text = if c.ij {
        // The centre the R form would pick, as I/J from the start.
        let half = len / 2.0;
        let h = (c.r * c.r - half * half).max(0.0).sqrt();
        let left = [-c.psi.sin(), c.psi.cos()];
        // CCW short arcs have their centre on the left of the chord.
        let side = if c.cw != c.long { -h } else { h };
        let i = d[0] / 2.0 + side * left[0];
        let j = d[1] / 2.0 + side * left[1];
        format!(
            "G17 G91 G{g} X{:.12} Y{:.12} I{i:.12} J{j:.12} F600",
            d[0], d[1]
        )
    } else {
        let r = if c.long { -c.r } else { c.r };
        format!("G17 G91 G{g} X{:.12} Y{:.12} R{r:.12} F600", d[0], d[1])
    };
    (text, start)
}

fn parse(start: Pos, text: &str) -> Option<Arc> {
    let mut it = Interpreter::new();
    it.set_machine_position(start);
    let mut arc = None;
    it.execute_line(text.as_bytes(), &mut |c| {
        if let Command::Arc(a) = c {
            arc = Some(a);
        }
    })
    .ok()?;
    arc
}

fn f64s(p: Pos) -> [f64; 2] {
    [p[0] as f64, p[1] as f64]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn arcs_end_on_their_end_and_are_as_long_as_their_sweep(c in case()) {
        let (text, start) = line(&c);
        let step = (1.0 / c.spm) as f32;
        let arc = parse(start, &text);
        // The interpreter refuses nothing of this (radii agree to rounding).
        prop_assert!(arc.is_some(), "refused: {text}");
        let arc = arc.unwrap();
        let ch = ArcChords::new(&start, &arc, TOL, step).unwrap();
        let pts: Vec<Pos> = ch.clone().collect();
        prop_assert_eq!(*pts.last().unwrap(), arc.end, "{}", text);

        // The true arc, in f64, from the f32 start, end and centre.
        let (s, e, cc) = (f64s(start), f64s(arc.end), [arc.center[0] as f64, arc.center[1] as f64]);
        let (sv, ev) = ([s[0] - cc[0], s[1] - cc[1]], [e[0] - cc[0], e[1] - cc[1]]);
        let (r0, r1) = (sv[0].hypot(sv[1]), ev[0].hypot(ev[1]));
        let mut th = (sv[0] * ev[1] - sv[1] * ev[0]).atan2(sv[0] * ev[0] + sv[1] * ev[1]);
        if c.cw && th >= 0.0 {
            th -= 2.0 * PI;
        } else if !c.cw && th <= 0.0 {
            th += 2.0 * PI;
        }
        let sweep = ch.sweep() as f64;
        prop_assert!(
            (sweep - th).abs() <= 1e-4 * th.abs() + 1e-6,
            "{}: sweep {} want {}", text, sweep, th
        );
        // Short arcs are short, long ones long: the sweep the case asked
        // for, unless the chord is so near the diameter that the f32
        // quantum of the coordinates (6e-5 mm at 1 m) decides the side.
        let quantum = f32::EPSILON as f64 * s[0].abs().max(s[1].abs()).max(e[0].abs()).max(e[1].abs());
        prop_assert!(
            (th.abs() > PI) == c.long || (th.abs() - PI).abs() < 1e-3 + 4.0 * quantum / c.r,
            "{}: {}", text, th
        );

        // Every chord end within one step of the circle (radius between the
        // two end radii: the spiral the segmenter blends).
        let step = 1.0 / c.spm;
        for p in &pts {
            let q = f64s(*p);
            let r = (q[0] - cc[0]).hypot(q[1] - cc[1]);
            prop_assert!(
                r >= r0.min(r1) - step && r <= r0.max(r1) + step,
                "{}: point {:?} at radius {} of {} .. {}", text, p, r, r0, r1
            );
        }

        // The soft-limit box holds every point, and is no wider than the
        // points' own box plus a chord's sagitta (the tolerance) and a step.
        let (lo, hi) = ch.bounds();
        for k in 0..2 {
            let pmin = pts.iter().chain([&start]).map(|p| p[k] as f64).fold(f64::MAX, f64::min);
            let pmax = pts.iter().chain([&start]).map(|p| p[k] as f64).fold(f64::MIN, f64::max);
            // f32 rounding of coordinates as far out as the arc goes.
            let quantum = 2.0 * f32::EPSILON as f64 * pmin.abs().max(pmax.abs()).max(1.0);
            let slack = TOL as f64 + step + 4.0 * quantum;
            prop_assert!(
                lo[k] as f64 <= pmin + quantum && hi[k] as f64 >= pmax - quantum,
                "{}: box {:?}..{:?} misses points {}..{} on axis {}", text, lo, hi, pmin, pmax, k
            );
            prop_assert!(
                lo[k] as f64 >= pmin - slack && hi[k] as f64 <= pmax + slack,
                "{}: box {:?}..{:?} beyond points {}..{} on axis {}", text, lo, hi, pmin, pmax, k
            );
        }

        // Path length: no longer than the arc, no shorter than its
        // inscribed polygon of this many chords.
        let mut len = 0.0;
        let mut prev = s;
        for p in &pts {
            let q = f64s(*p);
            len += (q[0] - prev[0]).hypot(q[1] - prev[1]);
            prev = q;
        }
        let n = ch.chords() as f64;
        let phi = th.abs() / n;
        let shrink = if phi > 0.0 { (phi / 2.0).sin() / (phi / 2.0) } else { 1.0 };
        let (arc_min, arc_max) = (r0.min(r1) * th.abs(), r0.max(r1) * th.abs());
        prop_assert!(
            len <= arc_max * (1.0 + 1e-6) + step && len >= arc_min * shrink * (1.0 - 1e-6) - step,
            "{}: path {} for an arc of {} .. {} ({} chords)", text, len, arc_min, arc_max, n
        );
    }
}
