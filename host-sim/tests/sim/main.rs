//! The motion core under the host simulator: jobs, traces, limits, step timing, the chip's facts, and
//! the outputs (SVG, VCD, JSON). `corpus` holds the corpus test (`corpus_*`, its own CI step).
//!
//! One test binary per suite, not one per file: each binary links the whole
//! dependency graph again, and 57 of them cost most of a clean test build (issue 34).
//! Add a file here as a module (`mod name;`), not under `tests/` directly.

#[path = "../common/mod.rs"]
mod common;
#[path = "../rig/mod.rs"]
mod rig;
mod synth;

mod backlash;
mod chip_facts;
mod corpus;
mod feed;
mod gcode;
mod gcode_g28;
mod gcode_round3;
mod helix;
mod hold_props;
mod host;
mod jobs;
mod limits;
mod machine;
mod machine_config;
mod outputs;
mod override_limits;
mod realtime;
mod smoke;
mod step_ceiling;
mod step_latency;
mod trace;
mod vcd;
