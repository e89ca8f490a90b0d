//! `cargo xtask stream` driven over a pty and through its keys.
//!
//! One test binary per suite, not one per file: each binary links the whole
//! dependency graph again, and 57 of them cost most of a clean test build (issue 34).
//! Add a file here as a module (`mod name;`), not under `tests/` directly.

mod pty_stream;
mod stream_keys;
