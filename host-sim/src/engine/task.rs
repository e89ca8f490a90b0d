//! The parse/plan task (RTIC priority 1) in virtual time: it feeds job
//! lines to the executor and refills the segment queue, and with a
//! [`HostModel`](crate::config::HostModel) cost it stays busy for a while
//! after each piece of work (the step timer preempts it meanwhile).

use std::collections::VecDeque;

use burin::controller::{Controller, Event, Inputs, Io, Pass};
use burin::executor::Machine;
use burin::link::{RtFlags, TokenSource};
use burin::realtime::Realtime;
use burin::seams::Storage;
use burin::session::Tx;

use super::{host, machine_error, note, Sim, Stats, PLANNER_BLOCKS};
use crate::record::Recorder;

impl Sim<'_> {
    /// Blocks the planner's passes visited since `work0` in S-curve mode,
    /// which the task's model charges (`HostModel::scurve_visit_ns`); 0 in
    /// trapezoid mode.
    fn s_curve_visits(&self, work0: u32) -> u64 {
        if self.machine.settings().profile == burin::settings::Profile::SCurve {
            u64::from(self.machine.plan_work().wrapping_sub(work0))
        } else {
            0
        }
    }

    /// Prio 1: feed queued commands to the executor and refill the segment
    /// queue. With a task cost it first refills, then takes one line, and is
    /// busy for the line's and its blocks' time; a refill requested
    /// meanwhile waits (the step timer keeps running: it preempts).
    pub(super) fn plan_task(&mut self) {
        if self.now < self.task.busy_until {
            self.task.wake = Some(self.task.busy_until);
            return;
        }
        self.task.wake = None;
        if self.device_mode {
            self.task_wanted = true;
            return;
        }
        self.stats.work += 1;
        self.task.send(&mut self.lines, self.now);
        let blocks0 = self.stats.blocks;
        let work0 = self.machine.plan_work();
        let costed = self.task.costed();
        let Sim {
            machine,
            rt,
            queue,
            lines,
            rec,
            stats,
            world,
            task,
            now,
            ..
        } = self;
        let mut taken = 0u64;
        let mut submit = |machine: &mut Machine<PLANNER_BLOCKS>,
                          lines: &mut VecDeque<host::Line>,
                          task: &mut host::Task,
                          stats: &mut Stats,
                          rec: &mut dyn Recorder,
                          once: bool| {
            taken += submit_lines(machine, rt, lines, task, stats, rec, *now, once);
        };
        if costed {
            machine.poll(rt, queue, world.switches(), &mut |n| {
                note(stats, &mut **rec, n)
            });
            submit(machine, lines, task, stats, &mut **rec, true);
        } else {
            loop {
                submit(machine, lines, task, stats, &mut **rec, false);
                machine.poll(rt, queue, world.switches(), &mut |n| {
                    note(stats, &mut **rec, n)
                });
                let more = lines
                    .front()
                    .is_some_and(|l| l.taken || (l.sent && l.arrival <= *now));
                if !machine.ready() || !more {
                    break;
                }
            }
        }
        let visits = self.s_curve_visits(work0);
        let cost = self.task.cost(taken, self.stats.blocks - blocks0, visits);
        if cost > 0 {
            self.task.busy_until = self.now + cost;
            self.task.wake = Some(self.task.busy_until);
        }
        if taken > 0 {
            self.task.send(&mut self.lines, self.now);
        }
    }

    /// When the task must run next on its own: the end of its busy time, or
    /// the arrival of the next line while the executor could take it.
    pub(super) fn task_due(&self) -> Option<u64> {
        if let Some(w) = self.task.wake {
            return Some(w);
        }
        let l = self.lines.front()?;
        if l.taken || !l.sent || !self.machine.ready() {
            return None;
        }
        Some(l.arrival.max(self.now))
    }
}

/// Submit queued lines while the executor is ready; `once`: take at most
/// one new line. Returns the lines taken.
#[allow(clippy::too_many_arguments)]
pub(super) fn submit_lines(
    machine: &mut Machine<PLANNER_BLOCKS>,
    rt: &Realtime,
    lines: &mut VecDeque<host::Line>,
    task: &mut host::Task,
    stats: &mut Stats,
    rec: &mut dyn Recorder,
    now: u64,
    once: bool,
) -> u64 {
    let mut taken = 0;
    while machine.may_plan() {
        let Some(l) = lines.front_mut() else { break };
        if !l.taken {
            if l.arrival > now || !l.sent || (once && taken > 0) {
                break;
            }
            l.taken = true;
            taken += 1;
            task.consumed(l.bytes);
        }
        let Some(cmd) = l.cmds.pop_front() else {
            lines.pop_front();
            task.popped();
            continue;
        };
        let line = l.line;
        let motion = cmd.end().is_some();
        match machine.submit(rt, &cmd, line, &mut |n| note(stats, rec, n)) {
            Ok(()) => stats.moves += u32::from(motion),
            Err(e) => {
                // The board's rule for a refusal after the line was taken
                // (`session::late`): the job stops there as an alarm and
                // nothing queued behind it runs. Skipping the command and
                // running on, as this runner once did, runs the rest of
                // the job from a place the program did not mean.
                // The alarm's note records the error; in alarm already
                // there is none, so it is recorded here.
                if machine.alarm().is_some() {
                    stats.errors.push(machine_error(line, e));
                }
                machine.fault(e, line);
                let _ = machine.take_fault();
                lines.clear();
                task.popped();
                break;
            }
        }
    }
    taken
}

/// Device mode: the parse/plan task is the firmware's own controller.
pub struct DeviceTask<'a, S: Storage, R, T> {
    pub controller: &'a mut Controller<S>,
    pub flags: &'a RtFlags,
    pub rx: &'a mut R,
    pub tx: &'a mut T,
    /// Inputs for the status report.
    pub pins: u16,
    pub port_closed: bool,
    pub port_opened: bool,
    /// Line numbers of the commands the executor accepted, in order.
    pub log: Option<&'a mut Vec<u32>>,
}

impl Sim<'_> {
    /// Hand the parse/plan task to `burin::controller` (see `device_sim`).
    pub fn set_device_mode(&mut self) {
        self.device_mode = true;
        self.auto_resume = false;
    }

    /// Device mode: the task is due (a segment was taken, the stepper
    /// stopped, or its busy time ended); [`Sim::run_until`] returned early.
    pub fn task_wanted(&self) -> bool {
        self.task_wanted
    }

    /// One pass of the controller at the current tick, as the board's
    /// parse task runs it. While the task is still busy with its last pass
    /// (the host model's cost), it runs when that ends instead; `None`.
    pub fn controller_pass<S: Storage>(
        &mut self,
        t: DeviceTask<'_, S, impl TokenSource, impl Tx>,
    ) -> Option<Pass> {
        if self.now < self.task.busy_until {
            self.task.wake = Some(self.task.busy_until);
            return None;
        }
        self.task_wanted = false;
        self.task.wake = None;
        let tick_hz = u64::from(self.cfg.tick_hz.max(1));
        let input = Inputs {
            now_ms: (self.now * 1000 / tick_hz) as u32,
            switches: self.world.switches(),
            pins: t.pins,
            port_closed: t.port_closed,
            port_opened: t.port_opened,
        };
        let stats0 = t.controller.session.stats;
        let blocks0 = self.stats.blocks;
        let work0 = self.machine.plan_work();
        let Sim {
            machine,
            rt,
            queue,
            stats,
            rec,
            ..
        } = self;
        let mut log = t.log;
        let io = Io {
            rt,
            flags: t.flags,
            rx: t.rx,
            segments: queue,
            tx: t.tx,
        };
        let pass = t.controller.pass(machine, io, input, &mut |e| match e {
            Event::Note(n) => note(stats, &mut **rec, n.clone()),
            Event::Accepted { line, motion } => {
                stats.moves += u32::from(motion);
                if let Some(l) = log.as_deref_mut() {
                    l.push(line);
                }
            }
        });
        self.stats.work += 1;
        let spm = self.machine.settings().axes.map(|a| a.steps_per_mm);
        if spm != self.stats.steps_per_mm {
            self.stats.steps_per_mm = spm;
            self.rec.rescaled(spm);
        }
        let s = t.controller.session.stats;
        let lines = (s.lines_ok + s.lines_err).wrapping_sub(stats0.lines_ok + stats0.lines_err);
        let visits = self.s_curve_visits(work0);
        let cost = self
            .task
            .cost(u64::from(lines), self.stats.blocks - blocks0, visits);
        if cost > 0 {
            self.task.busy_until = self.now + cost;
        }
        // The board pends the step interrupt; it enters once unmasked,
        // also ahead of an armed compare.
        if pass.kick {
            let now = self.masks.unmasked_at(self.now);
            self.next_step = Some(self.next_step.map_or(now, |t| t.min(now)));
        }
        Some(pass)
    }
}
