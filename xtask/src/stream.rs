//! `cargo xtask stream`: send a job to a board over the native protocol.
use anyhow::Result;

#[derive(clap::Args)]
pub struct StreamArgs {
    /// G-code job to stream.
    pub file: std::path::PathBuf,
}

pub fn run(_a: StreamArgs) -> Result<i32> {
    anyhow::bail!("not yet")
}
