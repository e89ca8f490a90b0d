//! The parse/plan task (RTIC priority 1) in virtual time: it feeds job
//! lines to the executor and refills the segment queue, and with a
//! [`HostModel`](crate::config::HostModel) cost it stays busy for a while
//! after each piece of work (the step timer preempts it meanwhile).

use std::collections::VecDeque;

use burin::machine::Machine;
use burin::realtime::Realtime;

use super::{host, machine_error, note, Sim, Stats, PLANNER_BLOCKS};
use crate::record::Recorder;

impl Sim<'_> {
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
        self.task.send(&mut self.lines, self.now);
        let blocks0 = self.stats.blocks;
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
        let cost = self.task.cost(taken, self.stats.blocks - blocks0);
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
    while machine.ready() {
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
            Err(e) => stats.errors.push(machine_error(line, e)),
        }
    }
    taken
}
