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
use crate::command::{Arc, Command, Pos};
use crate::gcode::ErrorKind;
use core::f32::consts::{FRAC_PI_2, PI};

use super::plane::*;

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
