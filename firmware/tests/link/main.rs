//! The link: text and framed ports, GRBL replies, settings replies, and abuse of both.
//!
//! One test binary per suite, not one per file: each binary links the whole
//! dependency graph again, and 57 of them cost most of a clean test build (issue 34).
//! Add a file here as a module (`mod name;`), not under `tests/` directly.

mod link_common;

mod abuse;
mod framed;
mod grbl;
mod settings;
mod text;
