//! Laser mode's spindle commands, in step with the motion.
//!
//! With `$32=1` a spindle command does not wait for the moves before it to
//! finish (GRBL's laser mode: a new S between G1 moves takes effect without
//! a stop). The executor passes it on at once; this queue holds it, tagged
//! with its machine line, until the step interrupt runs a segment of that
//! line or later (`Realtime::running`), or the motion has stopped. So the
//! power changes exactly where the program changes it.

use super::Outputs;
use crate::command::{Command, SpindleDir};
use heapless::Deque;

/// Spindle commands in flight: more than the planner's blocks plus the
/// segment queue hold lines, so a raster job with a new S on every move
/// never has to apply one early.
pub const LASER_QUEUE: usize = 128;

/// Spindle commands executed ahead of the motion they belong to.
#[derive(Debug, Default)]
pub struct LaserQueue {
    queue: Deque<(u32, SpindleDir, f32), LASER_QUEUE>,
}

impl LaserQueue {
    pub const fn new() -> Self {
        LaserQueue {
            queue: Deque::new(),
        }
    }

    /// Queues `cmd` (a spindle command of machine line `line`); anything
    /// else goes to `outputs` at once. Full (never with the queue sizes
    /// above), the oldest entry is applied now rather than lost.
    pub fn push(&mut self, outputs: &mut Outputs, line: u32, cmd: &Command) {
        let Command::Spindle { dir, speed } = *cmd else {
            outputs.apply(cmd);
            return;
        };
        if self.queue.is_full() {
            self.pop_into(outputs);
        }
        let _ = self.queue.push_back((line, dir, speed));
    }

    /// Applies the commands of every line up to `running` (the line of the
    /// segment the stepper runs), or all of them when `running` is `None`
    /// (the motion has stopped).
    pub fn release(&mut self, outputs: &mut Outputs, running: Option<u32>) {
        while let Some(&(line, _, _)) = self.queue.front() {
            // Machine line numbers only grow (wrapping).
            let due = running.is_none_or(|r| r.wrapping_sub(line) as i32 >= 0);
            if !due {
                break;
            }
            self.pop_into(outputs);
        }
    }

    /// A reset, alarm or program end: nothing queued applies any more.
    pub fn clear(&mut self) {
        self.queue.clear();
    }

    pub fn len(&self) -> usize {
        self.queue.len()
    }

    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    fn pop_into(&mut self, outputs: &mut Outputs) {
        if let Some((_, dir, speed)) = self.queue.pop_front() {
            outputs.apply(&Command::Spindle { dir, speed });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Settings;

    fn laser() -> Outputs {
        Outputs::new(&Settings {
            laser_mode: true,
            spindle_max: 1000.0,
            ..Settings::default()
        })
    }

    fn s(speed: f32) -> Command {
        Command::Spindle {
            dir: SpindleDir::Cw,
            speed,
        }
    }

    #[test]
    fn each_s_applies_when_its_line_runs() {
        let mut o = laser();
        let mut q = LaserQueue::new();
        q.push(&mut o, 3, &s(100.0));
        q.push(&mut o, 5, &s(500.0));
        assert_eq!(o.speed(), 0.0, "applied before its line");
        q.release(&mut o, Some(2));
        assert_eq!(o.speed(), 0.0);
        q.release(&mut o, Some(4));
        assert_eq!(o.speed(), 100.0);
        q.release(&mut o, Some(5));
        assert_eq!(o.speed(), 500.0);
        assert!(q.is_empty());
    }

    #[test]
    fn stopped_applies_everything_and_clear_drops_it() {
        let mut o = laser();
        let mut q = LaserQueue::new();
        q.push(&mut o, 7, &s(300.0));
        q.push(
            &mut o,
            8,
            &Command::Spindle {
                dir: SpindleDir::Off,
                speed: 300.0,
            },
        );
        q.release(&mut o, None);
        assert_eq!(o.spindle_dir(), SpindleDir::Off);
        q.push(&mut o, 9, &s(300.0));
        q.clear();
        q.release(&mut o, None);
        assert_eq!(o.spindle_dir(), SpindleDir::Off);
    }

    #[test]
    fn full_queue_applies_the_oldest_early() {
        let mut o = laser();
        let mut q = LaserQueue::new();
        for line in 0..LASER_QUEUE as u32 + 1 {
            q.push(&mut o, line + 10, &s(line as f32));
        }
        assert_eq!(q.len(), LASER_QUEUE);
        assert_eq!(o.speed(), 0.0, "the oldest (S0) went out early");
        q.push(&mut o, 1000, &s(1.0));
        assert_eq!(o.speed(), 1.0, "S1 of line 11 went out early");
    }
}
