//! burin's motion core: everything that decides where the tool goes and when a
//! step happens, with no HAL, no RTIC and no heap.
//!
//! The RTIC binary (`src/bin/burin-fw.rs`) and `host-sim` both drive this same
//! code; they differ only in how bytes and pins reach the outside world, which
//! is why the hardware appears here only as the small traits in [`seams`].
//!
//! Pipeline, one module per stage:
//! `link` (bytes) -> `session` (lines, replies) -> `gcode` (lexer/parser)
//! -> `interp` (modal state) -> [`command`] -> `executor` -> `arc`
//! (segmenter) -> `planner` (look-ahead) -> `stepper` (segments, pulses).
//! [`controller`] is the whole parse/plan task, which both shells drive.
#![cfg_attr(not(test), no_std)]
#![deny(unsafe_code)]
#![warn(missing_debug_implementations)]

// In pipeline order. From `executor` on, a module imports only from modules
// above it. Above that line imports run both ways: `stepper` owns types the
// earlier modules use (`StepConfig`, `Switches` in `seams`; the step-rate
// ceiling in `settings`; the step-config cell in `realtime`; `planner`'s
// intervals), `command` uses `interp::Cycle`, and `interp` -> `arc` ->
// `planner`; so `seams`, `settings`, `command`, `interp`, `arc`, `planner`,
// `realtime` and `stepper` form one import cycle. The order is the reading
// order, not a layering the compiler checks.
pub mod chip;
pub mod num;
pub mod seams;
pub mod settings;

pub mod command;
pub mod comp;
pub mod flow;
pub mod gcode;
pub mod interp;

pub mod arc;
pub mod planner;

pub mod realtime;
pub mod stepper;

pub mod executor;

pub mod inputs;
pub mod link;
pub mod outputs;
pub mod persist;
pub mod suspend;

pub mod session;

pub mod controller;

/// Number of axes the core drives: X, Y, Z and A.
pub const AXES: usize = 4;

/// Axis letters in the order used by every per-axis array in the core.
pub const AXIS_NAMES: [char; AXES] = ['X', 'Y', 'Z', 'A'];

/// Firmware version reported by `$I`, M115 and the protocol handshake.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
