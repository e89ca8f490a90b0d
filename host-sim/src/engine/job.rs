//! `run_job`: G-code text through the virtual board, as `cargo xtask sim`
//! runs it (one path for every offline run: see [`crate::offline`]).

use crate::config::MachineConfig;
use crate::record::{Recorder, Summary};

/// Simulate a G-code job from source text.
pub fn run_job(config: &MachineConfig, source: &str, recorder: &mut dyn Recorder) -> Summary {
    crate::offline::run_file(config, source, recorder)
}
