//! The virtual device end to end: sessions, settings, persistence, outputs, the link under abuse,
//! recorded pty traces, the three paths agreeing, and the fuzz regressions.
//!
//! One test binary per suite, not one per file: each binary links the whole
//! dependency graph again, and 57 of them cost most of a clean test build (issue 34).
//! Add a file here as a module (`mod name;`), not under `tests/` directly.

#[path = "../common/mod.rs"]
mod common;
#[path = "../rig/mod.rs"]
mod rig;

mod cutter_comp;
mod e2e;
mod fuzz_regressions;
mod late_error;
mod link_abuse;
mod link_props;
mod outputs;
mod oword_flow;
mod panel_inputs;
mod persist;
mod pty_replay;
mod realtime_grbl;
mod reset_now;
mod rt_flood;
mod session;
mod settings_apply;
mod slow_feed;
mod three_paths;
mod toolchange;
mod unlock;
