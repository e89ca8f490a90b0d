//! host-sim: the firmware's motion core on the host, in virtual time.
//!
//! Nothing here decides where the tool goes or when a step happens: that is
//! the firmware library's job. host-sim supplies a virtual clock, recording
//! pins, simulated switches and files.

pub mod bench;
pub mod check;
pub mod config;
pub mod device_sim;
pub mod engine;
pub mod feed;
pub mod fuzz;
pub mod offline;
pub mod outputs;
pub mod par;
pub mod plot;
pub mod pty;
pub mod record;
pub mod report;
pub mod trace;
pub mod vcd;
