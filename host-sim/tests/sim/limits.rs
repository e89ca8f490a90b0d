//! The limit invariants of issue 12, measured on the step trace the way
//! `cargo xtask bench-motion` measures them (`host_sim::bench::limits`):
//! no single step interval below an axis' rate limit (`$110`… and `$201`,
//! one timer tick of slack), every job ends exactly on its commanded
//! position in steps, and no axis accelerates more than 5 % over its
//! limit over 50 ms windows, at corners too. No timings: speed is a bench
//! figure.

use crate::common;
use burin::settings::Profile;
use common::bench_jobs;
use host_sim::bench::limits::jerk_quantum;
use host_sim::bench::{axis_limits, run_job, JobFigures};
use host_sim::config::MachineConfig;

fn machine() -> MachineConfig {
    common::grbl_match()
}

fn check(cfg: &MachineConfig, name: &str, src: &str) -> JobFigures {
    let f = run_job(cfg, src);
    assert!(
        f.summary.errors.is_empty(),
        "{name}: {:?}",
        f.summary.errors
    );
    let l = &f.limits;
    assert_eq!(
        l.short_intervals,
        [0; burin::AXES],
        "{name}: min intervals {:?} (short: {:?})",
        l.min_interval,
        l.short_intervals
    );
    assert_eq!(l.end_steps, f.summary.final_position_steps, "{name}");
    let end = f.bound_end_steps;
    assert_eq!(l.end_steps, end, "{name}: trace ends off the commanded end");
    let (vmax, amax) = axis_limits(cfg);
    for i in 0..3 {
        assert!(
            l.peak_vel[i] <= vmax[i] * 1.01,
            "{name}: axis {i} at {:.2} mm/s, limit {:.2}",
            l.peak_vel[i],
            vmax[i]
        );
        assert!(
            l.peak_acc[i] <= amax[i] * 1.05,
            "{name}: axis {i} at {:.1} mm/s², limit {:.1}",
            l.peak_acc[i],
            amax[i]
        );
    }
    f
}

/// S-curve mode: no axis's jerk over 50 ms windows of the trace above
/// `$203` by more than 5 % plus the step quantisation of the figure
/// (`host_sim::bench::limits`: 400 mm/s³ on an 80 steps/mm axis).
fn check_jerk(cfg: &MachineConfig, name: &str, f: &JobFigures) {
    let j = f64::from(cfg.settings.jerk);
    for i in 0..3 {
        let q = jerk_quantum(f64::from(cfg.settings.axes[i].steps_per_mm));
        assert!(
            f.limits.peak_jerk[i] <= 1.05 * j + q,
            "{name}: axis {i} jerk {:.0} mm/s³, limit {j:.0} (+{q:.0})",
            f.limits.peak_jerk[i]
        );
    }
}

/// S-curve ramps keep the jerk limit where the path itself jerks: round
/// small holes at a steady speed, four turns each. Each axis's
/// acceleration turns with the tool, a jerk of `v³/r²`: at the speeds the
/// acceleration allows, X/Y read 150/156 % of `$203`; `planner::curve`
/// caps the speed there (`cbrt(j·r²)`).
#[test]
fn s_curve_keeps_the_jerk_limit_round_small_holes() {
    let mut cfg = machine();
    cfg.settings.profile = Profile::SCurve;
    let mut holes = String::from("G21 G90 G17\nG1 F3000\n");
    for (k, r) in [0.3, 0.5, 1.0, 3.0].iter().enumerate() {
        let x = 10.0 * k as f64;
        holes.push_str(&format!(
            "G0 X{x} Y0\nG1 X{:.3}\nG2 I{:.3} J0 P4\n",
            x + r,
            -r
        ));
    }
    check_jerk(&cfg, "holes", &check(&cfg, "holes", &holes));
}

/// The same on G1 polylines of the plotter kind (bench-motion's generated
/// jobs: chords of 0.2-0.3 mm wandering at F2500, short hatch strokes at
/// F4500): chords of a curve turn the axes' acceleration as an arc does,
/// and the runs took them at the acceleration's speed, X/Y 154/166 % of
/// `$203` on `gen:plotter_sketch`. The junction's jerk cap on the chords'
/// radius (`Planner::turn_radius`) keeps them.
#[test]
fn s_curve_keeps_the_jerk_limit_on_plotter_polylines() {
    let mut cfg = machine();
    cfg.settings.profile = Profile::SCurve;
    for (name, src) in [
        ("sketch", host_sim::bench::jobs::plotter_sketch(1500)),
        ("hatch", host_sim::bench::jobs::plotter_hatch(600)),
    ] {
        check_jerk(&cfg, name, &check(&cfg, name, &src));
    }
}

fn polyline(pts: impl Iterator<Item = (f64, f64)>, feed: f64) -> String {
    let mut s = format!("G21 G90 G94\nG1 F{feed}\n");
    for (x, y) in pts {
        s.push_str(&format!("G1 X{x:.4} Y{y:.4}\n"));
    }
    s
}

#[test]
fn near_diagonal_moves_at_the_rate_limit_keep_every_step_interval() {
    let src =
        "G21 G90\nG1 X100 Y95 F20000\nG1 X0 Y3\nG0 X-80 Y-76\nG0 X0 Y0\nG4 P0\nG0 Z2\nG0 Z0\n";
    check(&machine(), "diagonal", src);
}

#[test]
fn dense_g1_circle_keeps_the_limits() {
    let n = 3000;
    let pts = (0..=n).map(|k| {
        let t = k as f64 / n as f64 * std::f64::consts::TAU;
        (10.0 * t.cos() - 10.0, 10.0 * t.sin())
    });
    check(&machine(), "g1-circle", &polyline(pts, 5000.0));
}

#[test]
fn small_arcs_and_helices_keep_the_limits() {
    let src = "G21 G90 G17\nG1 X2 F3000\nG2 X2 Y0 I-2 J0\nG3 X2 Y0 I-2 J0 Z-1\nG2 X2 Y0 I-1 J0 Z-2\nG1 X20\nG2 X20 Y0 I-8 J0\nG0 X0 Y0 Z0\n";
    check(&machine(), "arcs", src);
}

/// Arcs in planes whose axes differ (Y and X at 500 mm/s², Z at 100):
/// each chord turns at what its own normal allows (`planner::curve`), so
/// where the normal lies along Y the circle runs faster than Z's budget
/// alone would let it, and every axis still keeps its limit.
#[test]
fn arcs_across_unequal_axes_keep_each_axis_limit_and_use_the_faster_one() {
    let src = "G21 G90 G19\nG1 Y6 F6000\nG2 Y6 Z0 J-3 K0\nG2 Y6 Z0 J-3 K0\nG18 G1 X6\nG3 X6 Z0 I-3 K0\nG0 X0 Y0 Z0\n";
    let f = check(&machine(), "yz-xz arcs", src);
    // Held to Z's 100 mm/s² all the way round (one budget for the plane,
    // the smallest axis's), a circle of 3 mm at `sqrt(0.8·a·r)` takes
    // this long at the least (1.217 s; that rule ran it in 1.326 s, the
    // per-chord one in 1.209 s: the speed rises where the normal turns
    // towards Y, as far as Z's ramp allows before it turns back).
    let r = 3.0f64;
    let held = std::f64::consts::TAU * r / (0.8 * 100.0 * r).sqrt();
    // Line 4: the second YZ circle, entered and left at its own speed.
    let l = f.losses.iter().find(|l| l.line == 4).expect("arc located");
    let t = l.bound_s + l.lost_s;
    assert!(
        t < held,
        "YZ circle: {t:.3} s, Z's budget alone {held:.3} s"
    );
}

#[test]
fn collinear_short_blocks_keep_the_limits() {
    let pts = (1..=400).map(|k| (k as f64 * 0.025, k as f64 * 0.0125));
    check(&machine(), "short", &polyline(pts, 3000.0));
}

/// Corners with the speed ramping into and out of them: Z valleys and
/// ridges of a 3-D polyline (Z reverses at every vertex, its limit is a
/// fifth of X's) and square XY corners. The instant velocity change at a
/// corner comes on top of the ramps unless the speed holds there for it
/// (`planner::passes`, corner holds): without the holds Z reached 150 %.
#[test]
fn corners_between_ramps_keep_the_axis_limits() {
    check(&machine(), "corners", &corners_job());
}

fn corners_job() -> String {
    let mut src = String::from("G21 G90 G94\nG1 F4000\n");
    for k in 1..=12 {
        let z = if k % 2 == 1 { -1.0 } else { 0.0 };
        src.push_str(&format!("G1 X{} Z{z}\n", k as f64 * 3.0));
    }
    for (x, y) in [(36.0, 20.0), (16.0, 20.0), (16.0, 5.0), (30.0, 5.0)] {
        src.push_str(&format!("G1 X{x} Y{y}\n"));
    }
    src
}

/// A helix that ends climbing at its feed into a move down in Z (from
/// linuxcnc/tort.ngc). The corner's hold costs more than a stop would
/// (`m > 1/a`), so the chord before it must be entered slower than the
/// incremental replan had already settled: before the backward pass could
/// lower settled entries, that chord kept its speed and Z reached 112 %.
#[test]
fn a_helix_into_a_plunge_slows_the_chord_before_the_corner() {
    let src = "G21\nG0 X6.894910 Y26.787653 Z29.282038\nF690\n\
               G17 G2 I-4.330127 J2.500000 X3.858878 Y24.458024 Z31.282038\n\
               G1 X0 Y0 Z20\n";
    check(&machine(), "helix-plunge", src);
}

/// S-curve runs never take in the newest block: the planner may still
/// merge the next collinear move into it, and a run planned on its old
/// length went on at speed into the corner it had planned as the path's
/// end (X at 1,225 % on short_segments, with the host's 145 µs a line).
/// Here 1,000 collinear 0.025 mm moves end in a square corner, at the
/// default jerk and at 50,000 mm/s³.
#[test]
fn s_curve_runs_wait_for_collinear_moves_to_merge() {
    let mut src = String::from("G21 G90 G1 F5000\n");
    for k in 1..=1000 {
        src += &format!("X{:.3}\n", k as f64 * 0.025);
    }
    for k in 1..=400 {
        src += &format!("Y{:.3}\n", k as f64 * 0.025);
    }
    for jerk in [5000.0, 50_000.0] {
        let mut cfg = machine();
        cfg.settings.profile = Profile::SCurve;
        cfg.settings.jerk = jerk;
        let f = check(&cfg, "collinear-corner", &src);
        check_jerk(&cfg, "collinear-corner", &f);
    }
}

/// A 1 mm YZ helix between a rapid and an XZ arc, then a plunge and a
/// small XZ arc: planes whose axes accelerate differently.
const SMALL_ARCS: &str = "G21 G90\n\
    G0 X0 Y0 Z20\n\
    G0 X-9.5 Y1.66 Z20\n\
    G0 X-9.0 Y-0.340 Z19.020\n\
    G19 G2 F900 J0.7071 K0.7071 X-10.5 Y0.8671 Z18.8611\n\
    G18 G2 F630 I-8.7 K-2.33 X-21.6815 Y1.8671 Z25.1891\n\
    G1 F1000 X-4.5 Z2\nG2 X-4.7629 Z1.0790 I-1.85 K0.03\nG1 X-10\n";

/// Small arcs in planes whose axes differ, entered from rapids and
/// plunges, in S-curve mode at a stiff jerk (50,000 mm/s³, almost
/// trapezoids): curves keep one isotropic budget there
/// (`planner::curve`). With per-chord budgets an S ramp spanning chords
/// that each allowed another split read 122 % of Z's acceleration here
/// (a 1 mm YZ helix between a rapid and an XZ arc). Trapezoid mode, with
/// per-chord budgets, keeps them too.
#[test]
fn s_curve_small_arcs_across_unequal_axes_keep_the_limits() {
    let src = SMALL_ARCS;
    check(&machine(), "small arcs", src);
    for jerk in [5000.0, 50_000.0] {
        let mut cfg = machine();
        cfg.settings.profile = Profile::SCurve;
        cfg.settings.jerk = jerk;
        let f = check(&cfg, "s-curve small arcs", src);
        check_jerk(&cfg, "s-curve small arcs", &f);
    }
}

/// S-curve planning three times as slow as bench-target measures it (a
/// slower chip, or stepping that takes two thirds of the CPU) still
/// leaves the step interrupt its segments: the planner stops for a
/// segment fill every `PLAN_BURST_SCURVE` moves. Planning the helix's
/// chords in one go instead emptied the 30 ms segment queue in the middle
/// of the rapid before it (Z 116 % of its acceleration here).
#[test]
fn slow_s_curve_planning_still_leaves_the_step_interrupt_its_segments() {
    let src = SMALL_ARCS;
    let mut cfg = machine();
    cfg.settings.profile = Profile::SCurve;
    cfg.settings.jerk = 50_000.0;
    cfg.host.scurve_visit_ns *= 3;
    assert!(cfg.host.scurve_visit_ns > 0);
    check(&cfg, "slow s-curve planning", src);
}

/// An S-curve run goes on across the chords of an arc whose caps differ
/// by a little from chord to chord (a feed above the axes' rates: each
/// chord's direction caps it anew), cruising at the lowest of them; it
/// stopped at every chord whose cap was not exactly the first one's, and
/// took 3.52 s here against 1.76 s in trapezoid mode (3.12 s now).
#[test]
fn s_curve_runs_take_in_chords_whose_caps_differ_a_little() {
    let src = "G21 G90 G0 X0 Y0\nG1 F5840 X10\nG2 X70 Y0 I30 J0\nG1 X80\n";
    let trapezoid = check(&machine(), "arc, trapezoid", src).time_s;
    let mut cfg = machine();
    cfg.settings.profile = Profile::SCurve;
    let f = check(&cfg, "arc, S-curve", src);
    check_jerk(&cfg, "arc, S-curve", &f);
    assert!(
        f.time_s < 1.9 * trapezoid,
        "S-curve {:.2} s against trapezoid {trapezoid:.2} s",
        f.time_s
    );
}

/// The bench-motion jobs (outside the repo; skipped when absent): step
/// intervals, end positions and the per-axis acceleration (≤ 105 % over
/// 50 ms windows, corners included) hold on every one.
#[test]
fn bench_motion_jobs_keep_step_intervals_and_end_exactly() {
    let cfg = machine();
    for (name, src) in bench_jobs() {
        check(&cfg, &name, &src);
    }
}

/// The same jobs with S-curve ramps: the limits hold, jerk included
/// (`check_jerk`), and no job crawls
/// (at most 3× its trapezoid reference with burin's curvature rule, issue
/// 12's bound, `JobFigures::curved_ref_s`; the worst is circle_small at
/// 2.1×; against the bound of the stated limits alone, circle_small's
/// noisy 0.016 mm chords allow 4.83 s, no measure of crawling).
/// An exit hold planned for a corner the ramp could not reach ran at a
/// near-zero speed: Cereal took 107,863 s and stellabee 29,860 s.
#[test]
fn bench_motion_jobs_in_s_curve_mode_keep_the_limits_and_their_pace() {
    let mut cfg = machine();
    cfg.settings.profile = Profile::SCurve;
    for (name, src) in bench_jobs() {
        let f = check(&cfg, &name, &src);
        check_jerk(&cfg, &name, &f);
        assert!(
            f.time_s <= 3.0 * f.curved_ref_s,
            "{name}: {:.2} s against a reference of {:.2} s",
            f.time_s,
            f.curved_ref_s
        );
    }
}

/// Corners and a helix into a plunge streamed over slow links, so blocks
/// arrive one by one while the one before them already runs: the planner
/// then settles entries before the corner after them is known, and a hold
/// that costs more than stopping lowers a settled entry
/// (`planner::passes`): the running block, already slowing to stop, then
/// cannot come down to the corner speed and still hold it, and arriving
/// fast cut the speed at the corner (Z at 122 % at 200 B/s). It now slows
/// to the fastest corner it can hold (`Profile::plan_held`).
#[test]
fn corners_streamed_block_by_block_keep_the_axis_limits() {
    let corners = corners_job();
    let helix = "G21\nG0 X6.894910 Y26.787653 Z29.282038\nF690\n\
                 G17 G2 I-4.330127 J2.500000 X3.858878 Y24.458024 Z31.282038\n\
                 G1 X0 Y0 Z20\nG1 X3 Y1 Z19\nG0 Z25\nG1 X0 Y4 Z20 F900\n";
    for profile in [Profile::Trapezoid, Profile::SCurve] {
        for rate in [100, 200, 300, 600, 2_000, 11_520] {
            let mut cfg = machine();
            cfg.settings.profile = profile;
            cfg.host.link_bytes_per_s = rate;
            let at = format!("at {rate} B/s, {profile:?}");
            check(&cfg, &format!("corners {at}"), &corners);
            check(&cfg, &format!("helix-plunge {at}"), helix);
        }
    }
}

/// Bench jobs of short lines streamed at a serial line's pace and slower:
/// the link, not the motion, sets their pace (circle_small takes 186 s at
/// 1,500 B/s against 20 s), so the planner runs starved and corners
/// become known while the block before them already runs. The limits
/// hold as they do with the whole job queued.
#[test]
fn bench_jobs_streamed_slowly_keep_the_limits() {
    for (name, src) in bench_jobs() {
        if !["stellabee", "zigzag", "circle_small", "short_segments"]
            .iter()
            .any(|j| name.contains(j))
        {
            continue;
        }
        for rate in [1_500, 11_520] {
            let mut cfg = machine();
            cfg.host.link_bytes_per_s = rate;
            let f = check(&cfg, &format!("{name} at {rate} B/s"), &src);
            println!("{name} at {rate} B/s: {:.2} s", f.time_s);
        }
    }
}

/// Zigzags whose corners stop holding once quiet blocks surround them
/// (`planner::quiet`), between long fast moves on both sides, in XY and
/// in XZ (Z's limit is a fifth of X's), at pitches and amplitudes from
/// quiet (every corner released) to loud (every corner held), and one
/// whose amplitude grows from one to the other. No window may see more
/// than the axis's acceleration. (With a spread of 2 and a quiet time of
/// 0.3 window, which the argument does not allow, Z reaches 108 %.)
#[test]
fn zigzags_between_long_moves_keep_the_axis_limits() {
    let cfg = machine();
    for plane in ['Y', 'Z'] {
        for pitch in [0.02, 0.05, 0.1] {
            for amp in [0.01, 0.025, 0.05, 0.1, 0.3, -1.0] {
                let mut src = String::from("G21 G90 G94\nG1 F5000\nG1 X-20\n");
                src.push_str(&format!("G1 X0 {plane}0\n"));
                for k in 1..=120 {
                    // amp < 0: growing from 0.005 to 0.6 mm.
                    let a = if amp < 0.0 {
                        0.005 * k as f64 / 1.2
                    } else {
                        amp
                    };
                    let side = if k % 2 == 1 { a } else { -a };
                    src.push_str(&format!("G1 X{:.4} {plane}{side:.4}\n", k as f64 * pitch));
                }
                src.push_str(&format!("G1 X{:.4} {plane}0\nG1 X40\n", 121.0 * pitch));
                check(&cfg, &format!("zigzag {plane} {pitch} {amp}"), &src);
            }
        }
    }
}

/// bench-motion's own jobs (`host_sim::bench::jobs`, issue 31): pen
/// plotter polylines of thousands of sub-millimetre moves near the axis
/// rates, and a 3-D line contour whose Z turns at every vertex. The
/// limits hold as on the corpus, and so does the curvature check (each
/// axis's centripetal acceleration where the polyline curves,
/// `host_sim::bench::curvature`), which the 50 ms windows cannot see.
#[test]
fn generated_bench_jobs_keep_the_limits_and_the_curvature_check() {
    let cfg = machine();
    let (_, amax) = axis_limits(&cfg);
    for (name, src) in host_sim::bench::jobs::all() {
        let f = check(&cfg, name, &src);
        for (i, (c, a)) in f.curv.peak.iter().zip(amax).enumerate().take(3) {
            assert!(
                *c <= 1.05 * a,
                "{name}: axis {i} centripetal {c:.1} mm/s², limit {a:.1}"
            );
        }
    }
}

/// A long arc at the rate limit into a 0.75 mm one (plasmatest.ngc,
/// N3840-N3870) in S-curve mode. The planner's limits ahead can fall a
/// little after a plan that brought the tool to them (an S ramp's length
/// is not monotone in where it ends); block by block, an S ramp per
/// 0.7 mm chord then slowed 0.1 mm/s a chord, and the tool ran on at
/// 81 mm/s into the small arc's 14 mm/s (X at 258 %). It slows over the
/// rest of its run instead (`stepper::prep::run`).
#[test]
fn s_curve_slows_over_its_run_when_a_limit_ahead_fell() {
    let src = "G21 G90 G17\nG0 X378.8665 Y101.9348\nG1 F5840\n\
               G3 X360.2318 Y159.2867 I-9.3174 J28.6760\n\
               G2 X359.4047 Y159.5438 I-0.2318 J0.7133\n\
               G1 X326.2568 Y202.8062\n\
               G2 X326.6386 Y203.9813 I0.5953 J0.4562\n\
               G1 X378.8848 Y219.4975\n";
    let mut cfg = machine();
    cfg.settings.profile = Profile::SCurve;
    let f = check(&cfg, "arc-into-hole", src);
    check_jerk(&cfg, "arc-into-hole", &f);
}
