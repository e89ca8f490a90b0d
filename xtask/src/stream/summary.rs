//! The closing summary: what was sent, what failed where, how long it took
//! against the simulation, and where the machine stands.

use super::job::Job;
use super::run::{clock, Stream};
use super::Outcome;
use anyhow::Result;
use protocol::{HostMsg, Status};
use std::io::{Read, Write};
use std::time::Duration;

#[derive(Default)]
pub struct Summary {
    pub outcome: Option<Outcome>,
    pub sent: usize,
    pub errors: usize,
    error_list: Vec<(usize, u16, String)>,
    alarms: Vec<(usize, u16)>,
    /// Wall seconds from the first line to the end, and paused within.
    pub wall_s: f64,
    pub paused_s: f64,
    pub simulated_s: Option<f64>,
    pub last: Option<Status>,
    /// (active s, ETA shown s) while running.
    pub samples: Vec<(f64, f64)>,
}

/// Read the final position, close the session, collect the figures.
pub fn finish<T: Read + Write>(mut s: Stream<'_, T>, outcome: Outcome) -> Result<Summary> {
    let wall_s = s.started.map_or(0.0, |t| t.elapsed().as_secs_f64());
    let active = s.active_s();
    if let Ok(Some(st)) = super::board::query_status(&mut s.client) {
        s.last = Some(st);
    }
    let _ = s.client.request(&HostMsg::Bye);
    // Let the device read the `Bye` before the port closes.
    let _ = s.client.get_mut().flush();
    std::thread::sleep(Duration::from_millis(50));
    Ok(Summary {
        outcome: Some(outcome),
        sent: s.sent,
        errors: s.errors.len(),
        error_list: std::mem::take(&mut s.errors),
        alarms: std::mem::take(&mut s.alarms),
        wall_s,
        paused_s: wall_s - active,
        simulated_s: s.eta.as_ref().map(|e| e.simulated_s()),
        last: s.last,
        samples: std::mem::take(&mut s.samples),
    })
}

impl Summary {
    pub fn print(&self, job: &Job) {
        let how = match self.outcome {
            Some(Outcome::Done) => "finished",
            Some(Outcome::Alarm) => "stopped by an alarm",
            Some(Outcome::Reset) => "aborted (soft reset)",
            Some(Outcome::Interrupted) => "interrupted",
            None => "not started",
        };
        eprintln!(
            "{}: {how}: {}/{} lines sent, {} error(s), {} alarm(s)",
            job.name,
            self.sent,
            job.lines.len(),
            self.errors,
            self.alarms.len()
        );
        for (line, code, text) in &self.error_list {
            eprintln!("  {}: error[{code}]: {text}", job.at(*line));
        }
        for (line, code) in &self.alarms {
            eprintln!("  {}: alarm[{code}]", job.at(*line));
        }
        let sim = self
            .simulated_s
            .map_or(String::new(), |s| format!(", simulated {}", clock(s)));
        eprintln!(
            "  time {} ({} paused, {} running){sim}",
            clock(self.wall_s),
            clock(self.paused_s),
            clock(self.wall_s - self.paused_s)
        );
        if let Some(st) = &self.last {
            let (m, w) = (st.mpos, st.wpos());
            eprintln!(
                "  final MPos X{:.3} Y{:.3} Z{:.3}  WPos X{:.3} Y{:.3} Z{:.3}",
                m[0], m[1], m[2], w[0], w[1], w[2]
            );
        }
    }
}
