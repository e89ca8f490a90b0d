//! The wire format (frames) and the host client's stream over it (needs the `std` feature).
//!
//! One test binary per suite, not one per file: each binary links the whole
//! dependency graph again, and 57 of them cost most of a clean test build (issue 34).
//! Add a file here as a module (`mod name;`), not under `tests/` directly.

mod common;

mod frames;
mod stream;
