//! burin's motion core: everything that decides where the tool goes and when a
//! step happens, with no HAL, no RTIC and no heap.
//!
//! The RTIC binary (`src/bin/burin-fw.rs`) and `host-sim` both drive this same
//! code; they differ only in how bytes and pins reach the outside world, which
//! is why the hardware appears here only as the small traits in [`seams`].
//!
//! Pipeline, one module per stage:
//! `link` (bytes) -> `session` (lines, replies) -> `gcode` (lexer/parser)
//! -> `interp` (modal state) -> [`command`] -> `executor` (sequencer; `arc`
//! makes chords) -> [`motion::Move`] -> `motion` (the one gateway) ->
//! `planner` (look-ahead) -> `stepper` (segments, pulses).
//! [`controller`] is the whole parse/plan task, which both shells drive.
//!
//! Import rule: the modules are declared below bottom up, and each imports
//! only modules declared above it, so no two modules import each other,
//! directly or round a loop. A type two layers share lives in the lower
//! one: the step pins' configuration and switch levels in [`seams`], the
//! step-rate ceiling in [`settings::ceiling`], the step event's attention
//! bits in [`realtime`], the canned cycle in [`command::cycle`]. The
//! compiler accepts cycles within a crate, so `cargo xtask imports` checks
//! the rule (and `cargo test -p xtask`, as
//! `imports::tests::burin_imports_follow_lib_rs_order`, so CI does).
#![cfg_attr(not(test), no_std)]
#![deny(unsafe_code)]
#![warn(missing_debug_implementations)]

// Bottom up (the import rule above). rustfmt sorts the declarations
// between two comment lines, hence a comment per layer.
//
// foundations
pub mod chip;
pub mod num;
pub mod settings;
// the hardware traits and the values they exchange
pub mod seams;
// what a program asks of the machine, in machine mm
pub mod command;
// motion geometry: the planner, then arcs and splines as its chords
pub mod planner;
// (arcs describe their curve to the planner; the interpreter checks radii here)
pub mod arc;
// the language: lexer/parser, cutter compensation, interpreter, O-words
pub mod gcode;
// (compensation takes the interpreter's commands and knows nothing of it)
pub mod comp;
pub mod interp;
// (O-word flow drives the interpreter)
pub mod flow;
// step generation: the interrupts' shared flags, then segments and pulses
pub mod realtime;
pub mod stepper;
// the motion pipeline behind its one gateway (`Move`): planner, preparer
pub mod motion;
// the machine, sequencing the program: soft limits, homing, probing,
// scripts, alarms
pub mod executor;
// the periphery: switches, link, outputs, persistence, suspend
pub mod inputs;
pub mod link;
pub mod outputs;
pub mod persist;
pub mod suspend;
// the device session: lines and frames in, replies out
pub mod session;
// one pass of the parse/plan task, which both shells drive
pub mod controller;

/// Number of axes the core drives and their letters, in the order of every
/// per-axis array: defined once, in `protocol` (whose wire layout depends
/// on it and which cannot depend on burin).
pub use protocol::{AXES, AXIS_NAMES};

/// A per-axis array from its first values, the rest zero: tests and tools
/// write `pad([x, y, z])` so that they hold for any axis count.
///
/// # Panics
/// If more values are given than there are axes.
pub fn pad<T: Copy + Default, const N: usize>(v: [T; N]) -> [T; AXES] {
    assert!(N <= AXES, "more values than axes");
    let mut out = [T::default(); AXES];
    out[..N].copy_from_slice(&v);
    out
}

/// Firmware version reported by `$I`, M115 and the protocol handshake.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
