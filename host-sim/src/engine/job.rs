//! `run_job`: G-code text through the firmware's interpreter into a [`Sim`].

use burin::interp::Interpreter;

use super::Sim;
use crate::config::MachineConfig;
use crate::record::{Recorder, RunError, Summary};

/// Simulate a G-code job from source text.
pub fn run_job(config: &MachineConfig, source: &str, recorder: &mut dyn Recorder) -> Summary {
    let mut sim = Sim::new(config, recorder);
    let mut interp = Interpreter::new();
    interp.set_machine_position(sim.machine.commanded_position());
    let mut lines = 0u32;
    let mut gcode_errors = Vec::new();
    for (i, text) in source.lines().enumerate() {
        let line_no = i as u32 + 1;
        lines = line_no;
        let mut cmds = Vec::new();
        match interp.execute_line(text.as_bytes(), &mut |c| cmds.push(c)) {
            Ok(()) => {}
            Err(e) => {
                // It still crossed the link and cost parse time.
                sim.push_line(line_no, text.len() as u32 + 1, Vec::new());
                gcode_errors.push(RunError {
                    line: line_no,
                    code: e.kind.code(),
                    message: e.to_string(),
                });
                continue;
            }
        }
        sim.push_line(line_no, text.len() as u32 + 1, cmds);
        if interp.needs_sync() {
            // Homing and probing end where only the machine knows: run to idle.
            sim.run();
            let _ = sim.take_barrier();
            match sim.stats.probe.take() {
                Some((pos, contact)) => {
                    // Parameters get the trip point; the position is where the
                    // ramp-down after it actually stopped.
                    interp.probe_finished(pos, contact);
                    interp.set_machine_position(sim.machine.commanded_position());
                }
                None => interp.set_machine_position(sim.machine.commanded_position()),
            }
        }
        if sim.machine.alarm().is_some() {
            sim.run();
            break;
        }
    }
    sim.run();
    let mut summary = sim.summary(lines, interp.wco());
    let mut errors = gcode_errors;
    errors.append(&mut summary.errors);
    errors.sort_by_key(|e| e.line);
    summary.errors = errors;
    // A recorder's I/O error cannot be reported through the Summary; callers
    // that care use `Sim` and `finish` directly.
    let _ = sim.finish(&summary);
    summary
}
