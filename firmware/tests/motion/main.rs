//! Motion core: planner, ramps, arcs, the executor at its extremes, limit races and rebuilds.
//!
//! One test binary per suite, not one per file: each binary links the whole
//! dependency graph again, and 57 of them cost most of a clean test build (issue 34).
//! Add a file here as a module (`mod name;`), not under `tests/` directly.

mod arc;
mod arc_props;
mod cancel;
mod chord_bound;
mod extremes;
mod limit_race;
mod machine_rebuild;
mod planner;
mod quiet;
mod ramp_props;
mod scurve_run;
mod tube;
