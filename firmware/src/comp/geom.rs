//! The corner cases of cutter compensation, one per move kind, in the
//! plane's two axes (`u`, `v` = `Plane::axes`). Angles are in radians.
//!
//! The terms, as LinuxCNC's interpreter uses them:
//! - `op` is the programmed point where the new move starts, `c` the
//!   tool's centre there (one radius off `op`, on the compensation side);
//! - `beta` measures the turn from the last move's direction to the new
//!   one, seen from the compensation side: about 0 is straight on, up to
//!   pi is an outside (convex) corner the tool rolls around, below 0 or
//!   above pi an inside (concave) one where the two offset paths are cut
//!   at their intersection;
//! - `SMALL` (0.05 rad) is the band in which a corner counts as straight.

use super::{corner_arc, corner_feed, Comp, CompOn, Item, Side};
use crate::command::{Arc, ArcDir, Command, Pos};
use crate::gcode::ErrorKind;
use crate::num::trig::sin_cos;
use core::f32::consts::{FRAC_PI_2, PI};
use libm::{atan2f, sqrtf};

/// A point in the plane. The core is `f32` throughout (no soft-float
/// `f64` on the board); near a tangent an intersection is ill-conditioned
/// (an error e in a distance moves it by sqrt(2 r e)), so intersections
/// are worked out as vectors (foot of the perpendicular, half chord), not
/// through angles whose rounding the square root would magnify.
pub(super) type P = [f32; 2];

fn cos(a: f32) -> f32 {
    sin_cos(a).1
}

fn sin(a: f32) -> f32 {
    sin_cos(a).0
}

fn tan(a: f32) -> f32 {
    let (s, c) = sin_cos(a);
    s / c
}

fn sqrt(x: f32) -> f32 {
    sqrtf(x)
}

fn atan2(y: f32, x: f32) -> f32 {
    atan2f(y, x)
}

/// LinuxCNC's `TOLERANCE_CONCAVE_CORNER`.
const SMALL: f32 = 0.05;
/// LinuxCNC's `TOLERANCE_EQUAL`.
const EQUAL: f32 = 0.0001;

pub(super) fn dist(a: P, b: P) -> f32 {
    let (x, y) = (a[0] - b[0], a[1] - b[1]);
    sqrt(x * x + y * y)
}

fn angle(from: P, to: P) -> f32 {
    atan2(to[1] - from[1], to[0] - from[0])
}

fn at(p: P, r: f32, a: f32) -> P {
    let (s, c) = sin_cos(a);
    [p[0] + r * c, p[1] + r * s]
}

pub(super) fn wide(p: [f32; 2]) -> P {
    p
}

fn narrow(p: P) -> [f32; 2] {
    p
}

/// LinuxCNC's signed turn count: +n counterclockwise, -n clockwise.
pub(super) fn turn(a: &Arc) -> i32 {
    let n = 1 + i32::from(a.turns);
    match a.dir {
        ArcDir::Ccw => n,
        ArcDir::Cw => -n,
    }
}

/// The signed angle an arc of `turn` sweeps from `s` to `e` about `c`.
pub(super) fn sweep(s: P, c: P, turn: i32, e: P) -> f32 {
    if turn == 0 {
        return 0.0;
    }
    let t1 = angle(c, s);
    let mut t2 = angle(c, e);
    if turn < 0 {
        if t2 >= t1 {
            t2 -= 2.0 * PI;
        }
        t2 - t1 + (turn + 1) as f32 * 2.0 * PI
    } else {
        if t2 <= t1 {
            t2 += 2.0 * PI;
        }
        t2 - t1 + (turn - 1) as f32 * 2.0 * PI
    }
}

/// The tool runs inside an arc of this turn direction.
fn inside(side: Side, turn: i32) -> bool {
    (side == Side::Left && turn > 0) || (side == Side::Right && turn < 0)
}

fn set_uv(p: &mut Pos, on: &CompOn, uv: P) {
    let (u, v, _) = on.plane.axes();
    p[u] = uv[0];
    p[v] = uv[1];
}

fn uv(p: &Pos, on: &CompOn) -> P {
    let (u, v, _) = on.plane.axes();
    [p[u], p[v]]
}

impl Comp {
    /// A G0/G1 while compensation is on.
    pub(super) fn straight(
        &mut self,
        on: CompOn,
        line: u32,
        cmd: Command,
        out: &mut dyn FnMut(u32, Command),
    ) -> Result<(), ErrorKind> {
        let Some(&end) = cmd.end() else {
            return Ok(());
        };
        let p = uv(&end, &on);
        let r = on.radius;
        let c = uv(&self.tool, &on);
        let mut cmd = cmd;
        if self.first {
            // Entry: the tool ends one radius off the programmed end,
            // square to the entry move.
            if dist(p, c) <= r {
                return Err(ErrorKind::CompEntryTooShort);
            }
            let alpha = angle(c, p) + side_turn(on.side);
            let e = at(p, r, alpha);
            self.endpoint = Some(c);
            set_end(&mut cmd, &on, e);
            self.hold(
                line,
                Item::straight(&cmd, narrow([cos(alpha), sin(alpha)]))
                    .ok_or(ErrorKind::CompGouge)?,
            )?;
            self.first = false;
            self.finish(&cmd, p);
            return Ok(());
        }
        let op = self.prog;
        if p == op {
            // No motion in the plane: the tool stays where it is there.
            set_end(&mut cmd, &on, c);
            self.hold(
                line,
                Item::straight(&cmd, [0.0, 0.0]).ok_or(ErrorKind::CompGouge)?,
            )?;
            self.finish(&cmd, p);
            return Ok(());
        }
        let mut theta = angle(op, c);
        let mut alpha = angle(op, p);
        let (beta, gamma) = match on.side {
            Side::Left => {
                if theta < alpha {
                    theta += 2.0 * PI;
                }
                (theta - alpha - FRAC_PI_2, FRAC_PI_2)
            }
            Side::Right => {
                if alpha < theta {
                    alpha += 2.0 * PI;
                }
                (alpha - theta - FRAC_PI_2, -FRAC_PI_2)
            }
        };
        let e = at(p, r, alpha + gamma);
        let mid = at(op, r, alpha + gamma);
        // The "h" shape: coming over an arc the tool is outside of, then
        // turning back along the arc's side; LinuxCNC keeps the tool above
        // and to that side (an inside corner) rather than looping round.
        let h_shape = beta > PI - SMALL
            && matches!(self.front(), Some(Item::Arc { arc, .. })
                if !inside(on.side, turn(arc)) && !self.queue.is_empty());
        let concave = !(-SMALL..=PI + SMALL).contains(&beta) || h_shape;
        if !concave && beta > SMALL {
            // Outside corner: round it on an arc about the programmed
            // corner (a rapid has no arc: a straight traverse instead).
            self.move_endpoint_and_flush(on, c, out)?;
            let feed = match &cmd {
                Command::Line { feed, .. } => Some(corner_feed(*feed, dist(op, p))),
                _ => None,
            };
            self.corner(&on, line, op, mid, &end, feed, out);
            self.endpoint = Some(mid);
        } else if concave {
            let mid = match self.front() {
                Some(Item::Arc { arc, .. }) => {
                    // Arc then line: where the line's offset meets the
                    // arc's offset circle; of the two, the one LinuxCNC
                    // takes (back along the line when the tool is
                    // inside the arc).
                    let prev = *arc;
                    let pc = wide(prev.center);
                    let oldrad = dist(uv(&prev.end, &on), pc);
                    let t = unit(sub(p, op));
                    let q = add(op, scale(side_normal(on.side, t), r));
                    let sigma = if inside(on.side, turn(&prev)) {
                        -1.0
                    } else {
                        1.0
                    };
                    line_meets_circle(q, t, pc, oldrad, sigma)?
                }
                _ => {
                    // Line then line: back along the compensated path by
                    // what the inside corner's half angle leaves.
                    let half = (beta + PI) / 2.0;
                    if half == 0.0 {
                        return Err(ErrorKind::CompGouge);
                    }
                    at(c, r / tan(half), theta + gamma)
                }
            };
            self.move_endpoint_and_flush(on, mid, out)?;
        } else {
            // Straight on (or a tangent arc then line).
            self.dequeue(out);
            self.endpoint = Some(c);
        }
        set_end(&mut cmd, &on, e);
        self.hold(
            line,
            Item::straight(&cmd, narrow([p[0] - op[0], p[1] - op[1]]))
                .ok_or(ErrorKind::CompGouge)?,
        )?;
        self.finish(&cmd, p);
        Ok(())
    }

    /// A G2/G3 while compensation is on.
    pub(super) fn arc(
        &mut self,
        on: CompOn,
        line: u32,
        a: Arc,
        out: &mut dyn FnMut(u32, Command),
    ) -> Result<(), ErrorKind> {
        if a.plane != on.plane {
            return Err(ErrorKind::CompPlane);
        }
        let r = on.radius;
        let p = uv(&a.end, &on);
        let centre = wide(a.center);
        let tn = turn(&a);
        let ins = inside(on.side, tn);
        let arc_radius = dist(centre, p);
        let c = uv(&self.tool, &on);
        if self.first {
            return self.arc_entry(on, line, a, out);
        }
        let op = self.prog;
        let theta = angle(op, c) - side_turn(on.side);
        let mut delta = angle(op, centre);
        let alpha = if tn > 0 {
            delta - FRAC_PI_2
        } else {
            delta + FRAC_PI_2
        };
        let mut beta = match on.side {
            Side::Left => theta - alpha,
            Side::Right => alpha - theta,
        };
        if beta > 1.5 * PI {
            beta -= 2.0 * PI;
        } else if beta < -FRAC_PI_2 {
            beta += 2.0 * PI;
        }
        let gamma = if ins {
            if arc_radius <= r {
                return Err(ErrorKind::CompToolTooBig);
            }
            angle(p, centre)
        } else {
            delta += PI;
            angle(centre, p)
        };
        let new_end = at(p, r, gamma);
        let mut cmd = a;
        set_uv(&mut cmd.end, &on, new_end);
        let main = Item::Arc {
            arc: cmd,
            sweep: sweep(op, centre, tn, p),
        };
        let concave = !(-SMALL..=PI + SMALL).contains(&beta) || ((beta - PI).abs() < SMALL && !ins);
        if concave {
            let mid = match self.front() {
                Some(Item::Arc { arc: prev, .. }) => {
                    // Arc then arc: where the two offset circles meet.
                    let prev = *prev;
                    let pc = wide(prev.center);
                    let oldrad = dist(pc, uv(&prev.end, &on));
                    let newrad = if ins { arc_radius - r } else { arc_radius + r };
                    let cc = dist(pc, centre);
                    if oldrad == 0.0 || cc == 0.0 {
                        return Err(ErrorKind::CompGouge);
                    }
                    // Along the line of centres, then across it.
                    let e = scale(sub(centre, pc), 1.0 / cc);
                    let x = (oldrad * oldrad + cc * cc - newrad * newrad) / (2.0 * cc);
                    let h = across(oldrad, x)?;
                    let across_dir = [-e[1], e[0]];
                    let sign = if inside(on.side, turn(&prev)) == (tn > 0) {
                        1.0
                    } else {
                        -1.0
                    };
                    add(add(pc, scale(e, x)), scale(across_dir, sign * h))
                }
                _ => {
                    // Line then arc: where the last line's offset meets
                    // the arc's offset circle (on along the line when the
                    // tool is inside the arc).
                    let from_centre = if ins { arc_radius - r } else { arc_radius + r };
                    let t = prev_direction(on.side, sub(c, op));
                    let sigma = if ins { 1.0 } else { -1.0 };
                    line_meets_circle(c, t, centre, from_centre, sigma)?
                }
            };
            self.move_endpoint_and_flush(on, mid, out)?;
        } else if beta > SMALL {
            // Outside corner: roll around it, then the arc.
            let mid = at(op, r, delta);
            self.dequeue(out);
            let feed = Some(corner_feed(a.feed, dist(op, p)));
            self.corner(&on, line, op, mid, &a.end, feed, out);
            self.endpoint = Some(mid);
        } else {
            self.dequeue(out);
            self.endpoint = Some(c);
        }
        self.hold(line, main)?;
        self.finish(&Command::Arc(cmd), p);
        Ok(())
    }

    /// An arc as the entry move: it keeps the tool tangent to an arc
    /// through the programmed end, from where the tool is.
    fn arc_entry(
        &mut self,
        on: CompOn,
        line: u32,
        a: Arc,
        _out: &mut dyn FnMut(u32, Command),
    ) -> Result<(), ErrorKind> {
        let r = on.radius;
        let c = uv(&self.tool, &on);
        let p = uv(&a.end, &on);
        let tn = turn(&a);
        let ins = inside(on.side, tn);
        let ac = wide(a.center);
        if dist(p, c) <= r {
            return Err(ErrorKind::CompEntryTooShort);
        }
        if ins && dist(ac, c) <= r {
            return Err(ErrorKind::CompToolTooBig);
        }
        let gamma = if ins { angle(p, ac) } else { angle(ac, p) };
        let e = at(p, r, gamma);
        // The new centre: equally far from the start and the moved end,
        // on the line from the moved end towards the old centre.
        let b_len = dist(c, e) / 2.0;
        let ab = angle(e, ac);
        let ang = angle(e, c) - ab;
        if cos(ang).abs() < EQUAL {
            return Err(ErrorKind::CompToolTooBig);
        }
        let centre = at(e, b_len / cos(ang), ab);
        let mut cmd = a;
        set_uv(&mut cmd.end, &on, e);
        cmd.center = narrow(centre);
        self.hold(
            line,
            Item::Arc {
                arc: cmd,
                sweep: sweep(c, centre, tn, e),
            },
        )?;
        self.first = false;
        self.finish(&Command::Arc(cmd), p);
        Ok(())
    }

    /// Hands on the move round an outside corner at `op`, to `mid` (the
    /// next move's offset start): an arc at `feed`, or for a rapid (`None`)
    /// a straight traverse. The plane and helix axes stay where the tool
    /// is; the others go to the next move's `end` (LinuxCNC).
    #[allow(clippy::too_many_arguments)]
    fn corner(
        &mut self,
        on: &CompOn,
        line: u32,
        op: P,
        mid: P,
        end: &Pos,
        feed: Option<crate::command::Feed>,
        out: &mut dyn FnMut(u32, Command),
    ) {
        let mut to = self.tool;
        set_uv(&mut to, on, mid);
        for (i, x) in to.iter_mut().enumerate() {
            if !is_plane_or_helix(on, i) {
                *x = end[i];
            }
        }
        let cmd = match feed {
            Some(f) => Command::Arc(corner_arc(on, to, op, f)),
            None => Command::Rapid { end: to },
        };
        out(
            line,
            super::lathe_origin(cmd, super::lathe_orientation(on), on.radius),
        );
        self.tool = to;
    }

    /// After a move was taken: the tool is at its (compensated) end, the
    /// programmed point at `p`.
    fn finish(&mut self, cmd: &Command, p: P) {
        if let Some(end) = cmd.end() {
            self.tool = *end;
        }
        self.prog = p;
    }
}

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1]]
}

fn scale(a: P, k: f32) -> P {
    [a[0] * k, a[1] * k]
}

fn dot(a: P, b: P) -> f32 {
    a[0] * b[0] + a[1] * b[1]
}

fn unit(a: P) -> P {
    scale(a, 1.0 / sqrt(dot(a, a)))
}

/// The normal of direction `t` on the compensation side.
fn side_normal(side: Side, t: P) -> P {
    match side {
        Side::Left => [-t[1], t[0]],
        Side::Right => [t[1], -t[0]],
    }
}

/// The direction of the last move, from the tool's offset `n` off the
/// programmed point (square to it, the side's normal turned back).
fn prev_direction(side: Side, n: P) -> P {
    let n = unit(n);
    match side {
        Side::Left => [n[1], -n[0]],
        Side::Right => [-n[1], n[0]],
    }
}

/// Half the chord where a line `x` from the centre cuts a circle of radius
/// `r`; a line beyond the circle cannot be reached without gouging
/// (LinuxCNC's `|l| > 1`), a few ulp over is a tangent.
fn across(r: f32, x: f32) -> Result<f32, ErrorKind> {
    let h2 = (r - x) * (r + x);
    if h2 < -1e-6 * r * r {
        return Err(ErrorKind::CompGouge);
    }
    Ok(sqrt(h2.max(0.0)))
}

/// Where the line through `q` along unit `t` meets the circle about `o` of
/// radius `rho`: the foot of `o` on the line, then `sigma` times half the
/// chord along `t`. Vector form: exact for lines along the axes, and no
/// angle's rounding is magnified near a tangent.
fn line_meets_circle(q: P, t: P, o: P, rho: f32, sigma: f32) -> Result<P, ErrorKind> {
    let foot = add(q, scale(t, dot(sub(o, q), t)));
    let off = dist(foot, o);
    let h = across(rho, off)?;
    Ok(add(foot, scale(t, sigma * h)))
}

/// +90 degrees for the left side, -90 for the right.
fn side_turn(side: Side) -> f32 {
    match side {
        Side::Left => FRAC_PI_2,
        Side::Right => -FRAC_PI_2,
    }
}

fn is_plane_or_helix(on: &CompOn, i: usize) -> bool {
    let (u, v, h) = on.plane.axes();
    i == u || i == v || i == h
}

fn set_end(cmd: &mut Command, on: &CompOn, e: P) {
    if let Command::Rapid { end } | Command::Line { end, .. } = cmd {
        set_uv(end, on, e);
    }
}
