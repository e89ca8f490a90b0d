//! `cargo xtask ci`: every check, in the order the README promises.
use anyhow::Result;

pub fn run() -> Result<i32> {
    anyhow::bail!("not yet")
}
