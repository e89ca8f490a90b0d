//! A G-code program through the interpreter and the engine with only the
//! envelope check: for tests that a check which finds runaways passes real
//! programs, and that it finds the runaway issue 35 reported.

use std::cell::RefCell;

use burin::interp::Interpreter;

use super::{Envelope, EnvelopeRec};
use crate::config::MachineConfig;
use crate::engine::Sim;
use crate::record::RunError;

/// Runs `text` on `cfg` for at most `max_s` of virtual time per stretch
/// (the program, or up to a line that needs the machine to stop), and
/// panics as the fuzz targets do when a step leaves the commanded box.
/// Returns the step events checked and the errors the run met.
pub fn run_gcode(cfg: &MachineConfig, text: &[u8], max_s: f64) -> (u64, Vec<RunError>) {
    let env = RefCell::new(Envelope::new(cfg.settings.axes.map(|a| a.steps_per_mm)));
    let mut rec = EnvelopeRec(&env);
    let mut sim = Sim::new(cfg, &mut rec);
    let mut it = Interpreter::new();
    it.set_machine_position(sim.machine.commanded_position());
    env.borrow_mut().settle(sim.rt.position());
    let stretch = (max_s * f64::from(cfg.tick_hz)) as u64;
    let run = |sim: &mut Sim| {
        let cap = sim.now() + stretch;
        let round = u64::from(cfg.tick_hz) / 50;
        while sim.now() < cap && !sim.idle() {
            sim.run_until(sim.now() + round);
        }
        if sim.idle() {
            env.borrow_mut().settle(sim.rt.position());
        }
    };
    for (n, line) in text.split(|&c| c == b'\n').enumerate() {
        let n = n as u32 + 1;
        let _ = it.execute_line(line, &mut |c| sim.push_command(n, c));
        if it.needs_sync() {
            run(&mut sim);
            it.set_machine_position(sim.machine.commanded_position());
        }
    }
    run(&mut sim);
    let errors = sim.errors().to_vec();
    drop(sim);
    let checked = env.borrow().checked;
    (checked, errors)
}
