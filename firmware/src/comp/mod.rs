//! Cutter radius compensation (G41/G42, G41.1/G42.1, G40): the stage after
//! the interpreter that puts the tool's centre one radius to the left or
//! right of the programmed path, by LinuxCNC's RS274NGC rules.
//!
//! Why a queue: where two compensated moves meet, the tool's path depends
//! on both. At an outside (convex) corner the tool rolls around the
//! programmed corner on an arc of its radius; at an inside (concave) one
//! the two offset paths are cut at their intersection, which moves the
//! *end* of the earlier move. So a compensated move is held until the next
//! move in the plane says where it ends. What comes between (moves with no
//! motion in the plane, dwells, spindle and coolant) waits behind it in
//! order, as LinuxCNC queues those canonical calls; anything else (a
//! pause, an output, a message, the program end) sends the queue on as it
//! stands, first, as LinuxCNC does.
//!
//! The geometry (`geom.rs`) follows LinuxCNC's interpreter case by case
//! (entry move, line-line, line-arc, arc-line, arc-arc, the "h" and "m"
//! shapes, the gouge checks when an end point moves back), so that a
//! compensated program cuts what it cuts on LinuxCNC: `cargo xtask rs274`
//! compares the two path for path. The code is our own.
//!
//! Every call is all-or-nothing for a line: the interpreter runs a line's
//! commands through a copy and keeps it only when the whole line passed
//! (`Interpreter::execute_line_at`), so a refused line leaves nothing queued.

mod geom;
mod plane;

use crate::command::{Arc, ArcDir, Command, Feed, Plane, Pos};
use crate::gcode::ErrorKind;
use heapless::Vec;

/// Commands that can wait behind a held move (the move included). A line
/// that would queue more is refused ([`ErrorKind::CompQueueFull`]).
pub const QUEUE: usize = 6;

/// An arc cut back to within this of its start (mm) has nothing left.
const COLLAPSED: f32 = 1e-4;

/// Most commands one pass can hand on beyond the line's own: the queue and
/// a corner arc.
pub const EXTRA_OUT: usize = QUEUE + 1;

pub use crate::command::{CompOn, CompSide as Side};

/// One held command and the line it came from.
#[derive(Clone, Debug)]
struct Held {
    line: u32,
    item: Item,
}

#[derive(Clone, Debug)]
enum Item {
    /// A G0 (`feed` none) or G1 and the direction its end may move along
    /// without reversing it (LinuxCNC's gouge check); zero: unchecked.
    Straight {
        end: Pos,
        feed: Option<Feed>,
        dir: [f32; 2],
    },
    /// A compensated arc and its sweep as programmed (radians, signed;
    /// zero: unchecked).
    Arc { arc: Arc, sweep: f32 },
    /// A dwell, spindle or coolant command waiting its turn (kept small:
    /// the queue lives in the interpreter, in RAM the F401 has little of).
    Other(Waiting),
}

#[derive(Clone, Copy, Debug)]
enum Waiting {
    Dwell(f32),
    Spindle(crate::command::SpindleDir, f32),
    Coolant { mist: bool, flood: bool },
}

impl Item {
    /// A G0/G1 as held (other commands: none).
    fn straight(cmd: &Command, dir: [f32; 2]) -> Option<Item> {
        match *cmd {
            Command::Rapid { end } => Some(Item::Straight {
                end,
                feed: None,
                dir,
            }),
            Command::Line { end, feed } => Some(Item::Straight {
                end,
                feed: Some(feed),
                dir,
            }),
            _ => None,
        }
    }

    fn command(&self) -> Command {
        match *self {
            Item::Straight {
                end, feed: None, ..
            } => Command::Rapid { end },
            Item::Straight {
                end,
                feed: Some(feed),
                ..
            } => Command::Line { end, feed },
            Item::Arc { arc, .. } => Command::Arc(arc),
            Item::Other(Waiting::Dwell(seconds)) => Command::Dwell { seconds },
            Item::Other(Waiting::Spindle(dir, speed)) => Command::Spindle { dir, speed },
            Item::Other(Waiting::Coolant { mist, flood }) => Command::Coolant { mist, flood },
        }
    }
}

/// The compensation stage's state.
#[derive(Clone, Debug)]
pub struct Comp {
    on: Option<CompOn>,
    /// The next move in the plane is the entry move.
    first: bool,
    /// The programmed point in the plane (its two axes, `Plane::axes`).
    prog: [f32; 2],
    /// Where the tool is after the last command handed on or held.
    tool: Pos,
    /// Where the held moves start in the plane, while that is known.
    endpoint: Option<[f32; 2]>,
    queue: Vec<Held, QUEUE>,
    /// The first held move when the queue was last sent on: LinuxCNC
    /// looks at it for the next corner even then.
    last_front: Option<Item>,
    /// After G40 the next move must be straight.
    arc_not_allowed: bool,
}

impl Default for Comp {
    fn default() -> Self {
        Self::new()
    }
}

impl Comp {
    pub const fn new() -> Self {
        Comp {
            on: None,
            first: true,
            prog: [0.0; 2],
            tool: [0.0; crate::AXES],
            endpoint: None,
            queue: Vec::new(),
            last_front: None,
            arc_not_allowed: false,
        }
    }

    /// Compensation is on (G41/G42 in effect).
    pub fn side(&self) -> Option<Side> {
        self.on.map(|o| o.side)
    }

    /// Nothing to carry from one line to the next: compensation off,
    /// nothing held, no rule pending (a new stage would do the same).
    pub fn idle(&self) -> bool {
        self.on.is_none() && self.queue.is_empty() && !self.arc_not_allowed
    }

    /// Commands one line's pass may hand on beyond the line's own: what is
    /// held, and a corner arc.
    pub fn max_extra(&self) -> usize {
        if self.idle() {
            0
        } else {
            self.queue.len() + 1
        }
    }

    /// A reset or an alarm: compensation off, held commands dropped with
    /// the rest of the motion.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// Takes one command of the line `line` and hands on what may run now,
    /// in order.
    pub fn push(
        &mut self,
        line: u32,
        cmd: Command,
        out: &mut dyn FnMut(u32, Command),
    ) -> Result<(), ErrorKind> {
        match cmd {
            Command::CutterComp(Some(on)) => {
                self.on = Some(on);
                self.last_front = None;
                self.first = true;
                self.tool = on.start;
                let (u, v, _) = on.plane.axes();
                self.prog = [on.start[u], on.start[v]];
                Ok(())
            }
            Command::CutterComp(None) => self.off(out),
            Command::Rapid { .. } | Command::Line { .. } => {
                self.arc_not_allowed = false;
                match self.active() {
                    Some(on) => self.straight(on, line, cmd, out),
                    None => self.pass(line, cmd, out),
                }
            }
            Command::Arc(a) => {
                if self.arc_not_allowed {
                    return Err(ErrorKind::CompArcAfterG40);
                }
                match self.active() {
                    Some(on) => self.arc(on, line, a, out),
                    None => self.pass(line, Command::Arc(a), out),
                }
            }
            Command::Dwell { seconds } if !self.queue.is_empty() => {
                self.hold(line, Item::Other(Waiting::Dwell(seconds)))
            }
            Command::Spindle { dir, speed } if !self.queue.is_empty() => {
                self.hold(line, Item::Other(Waiting::Spindle(dir, speed)))
            }
            Command::Coolant { mist, flood } if !self.queue.is_empty() => {
                self.hold(line, Item::Other(Waiting::Coolant { mist, flood }))
            }
            Command::ProgramEnd => {
                // M2/M30: held moves run as they stand, compensation off.
                self.dequeue(out);
                self.on = None;
                self.first = true;
                self.arc_not_allowed = false;
                self.pass(line, cmd, out)
            }
            other => {
                self.dequeue(out);
                self.pass(line, other, out)
            }
        }
    }

    /// Compensation on with a radius that moves the path.
    fn active(&self) -> Option<CompOn> {
        self.on.filter(|o| o.radius > 0.0)
    }

    /// Hands a command on unchanged, following the tool.
    fn pass(
        &mut self,
        line: u32,
        cmd: Command,
        out: &mut dyn FnMut(u32, Command),
    ) -> Result<(), ErrorKind> {
        if let Some(end) = cmd.end() {
            self.tool = *end;
        }
        out(line, cmd);
        Ok(())
    }

    fn hold(&mut self, line: u32, item: Item) -> Result<(), ErrorKind> {
        self.queue
            .push(Held { line, item })
            .map_err(|_| ErrorKind::CompQueueFull)
    }

    /// G40: the held moves end where they are; the next move goes from the
    /// compensated point straight to its programmed end (the exit move).
    fn off(&mut self, out: &mut dyn FnMut(u32, Command)) -> Result<(), ErrorKind> {
        if let Some(on) = self.active() {
            if !self.first {
                let (u, v, _) = on.plane.axes();
                let at = [self.tool[u], self.tool[v]];
                self.move_endpoint_and_flush(on, at, out)?;
                self.arc_not_allowed = true;
            }
        }
        self.dequeue(out);
        self.on = None;
        self.first = true;
        Ok(())
    }

    /// Sends the held commands on as they stand.
    fn dequeue(&mut self, out: &mut dyn FnMut(u32, Command)) {
        self.endpoint = None;
        if let Some(h) = self.queue.first() {
            self.last_front = Some(h.item.clone());
        }
        let orient = self.on.map_or(0, |o| lathe_orientation(&o));
        let radius = self.on.map_or(0.0, |o| o.radius);
        for h in self.queue.iter() {
            out(h.line, lathe_origin(h.item.command(), orient, radius));
        }
        self.queue.clear();
    }

    /// The first held move, or the one LinuxCNC still sees after a flush.
    fn front(&self) -> Option<&Item> {
        match self.queue.first() {
            Some(h) => Some(&h.item),
            None => self.last_front.as_ref(),
        }
    }

    /// Moves the end of every held move to `to` (in the plane), refusing
    /// an end that would run a move backwards or an arc past its sweep
    /// (the tool would gouge), then sends them on.
    fn move_endpoint_and_flush(
        &mut self,
        on: CompOn,
        to: [f32; 2],
        out: &mut dyn FnMut(u32, Command),
    ) -> Result<(), ErrorKind> {
        let (u, v, _) = on.plane.axes();
        let start = self.endpoint;
        let (tu, tv) = (to[0], to[1]);
        for h in self.queue.iter_mut() {
            match &mut h.item {
                Item::Arc { arc, sweep } => {
                    let c = plane::wide(arc.center);
                    let r1 = plane::dist(plane::wide([arc.end[u], arc.end[v]]), c);
                    let r2 = plane::dist(to, c);
                    if (r1 - r2).abs() > 0.01 {
                        return Err(ErrorKind::CompGouge);
                    }
                    // Cut back to its own start (a U-turn off an arc the
                    // next line is tangent to): nothing of it is left. As
                    // an arc it would be a full circle, so it becomes a
                    // move of no length (a programmed full circle already
                    // ends at its start and stays one).
                    let was = [arc.end[u], arc.end[v]];
                    let onto_start = |s: [f32; 2]| {
                        plane::dist(s, to) <= COLLAPSED && plane::dist(s, was) > COLLAPSED
                    };
                    if start.is_some_and(onto_start) {
                        let mut end = arc.end;
                        end[u] = tu;
                        end[v] = tv;
                        h.item = Item::Straight {
                            end,
                            feed: Some(arc.feed),
                            dir: [0.0; 2],
                        };
                        continue;
                    }
                    if let Some(s) = start {
                        if *sweep != 0.0 {
                            let sweep = *sweep;
                            let turn = plane::turn(arc);
                            let l2 = plane::sweep(s, c, turn, to);
                            if l2.abs() > sweep.abs() + 0.001 {
                                return Err(ErrorKind::CompGouge);
                            }
                        }
                    }
                    arc.end[u] = tu;
                    arc.end[v] = tv;
                }
                Item::Straight { end, dir, .. } => {
                    if let Some(s) = start {
                        let dot = dir[0] * (to[0] - s[0]) + dir[1] * (to[1] - s[1]);
                        if dot < 0.0 {
                            return Err(ErrorKind::CompGouge);
                        }
                    }
                    end[u] = tu;
                    end[v] = tv;
                }
                Item::Other(_) => {}
            }
        }
        self.dequeue(out);
        self.endpoint = Some(to);
        Ok(())
    }
}

/// Lathe orientations 1-8 put the controlled point off the radius centre
/// (G18 only; 0 and 9 are mill-like).
fn lathe_orientation(on: &CompOn) -> u8 {
    if on.plane == Plane::ZX {
        on.orientation
    } else {
        0
    }
}

/// From the radius centre the geometry works with to the tool's origin
/// (LinuxCNC's lathe tool orientations, X and Z by orientation).
fn lathe_origin(mut cmd: Command, orient: u8, r: f32) -> Command {
    if orient == 0 || orient == 9 || r == 0.0 {
        return cmd;
    }
    let dx = match orient {
        1 | 2 | 6 => -r,
        3 | 4 | 8 => r,
        _ => 0.0,
    };
    let dz = match orient {
        2 | 3 | 7 => -r,
        1 | 4 | 5 => r,
        _ => 0.0,
    };
    match &mut cmd {
        Command::Rapid { end } | Command::Line { end, .. } => {
            end[0] += dx;
            end[2] += dz;
        }
        Command::Arc(a) => {
            a.end[0] += dx;
            a.end[2] += dz;
            // ZX plane: centre is (Z, X).
            a.center[0] += dz;
            a.center[1] += dx;
        }
        _ => {}
    }
    cmd
}

/// A corner arc's feed: the move's own, or in inverse time the speed the
/// programmed move will go at (the arc has no time of its own).
fn corner_feed(feed: Feed, programmed_len: f32) -> Feed {
    match feed {
        Feed::PerMin(f) => Feed::PerMin(f),
        Feed::InverseTime(f) => Feed::PerMin(f * programmed_len),
    }
}

/// The arc that rolls the tool around a programmed corner.
fn corner_arc(on: &CompOn, end: Pos, corner: [f32; 2], feed: Feed) -> Arc {
    Arc {
        end,
        center: corner,
        plane: on.plane,
        dir: match on.side {
            Side::Left => ArcDir::Cw,
            Side::Right => ArcDir::Ccw,
        },
        turns: 0,
        feed,
    }
}
