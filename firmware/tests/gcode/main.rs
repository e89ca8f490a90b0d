//! G-code: the lexer, the interpreter's API, dialects, golden and bad sets, number parsing, and the
//! third-party corpus (`conformance`, tests named `corpus_*`: `cargo xtask ci` runs them in their own step).
//!
//! One test binary per suite, not one per file: each binary links the whole
//! dependency graph again, and 57 of them cost most of a clean test build (issue 34).
//! Add a file here as a module (`mod name;`), not under `tests/` directly.

mod common_canon;

mod conformance;
mod interp_api;
mod interp_bad;
mod interp_dialect;
mod interp_golden;
mod lexer;
mod num_props;
mod props;
