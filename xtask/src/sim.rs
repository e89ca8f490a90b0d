//! `cargo xtask sim`: the host simulator front end.
use anyhow::Result;

#[derive(clap::Args)]
pub struct SimArgs {
    /// G-code job (default: the bundled demo).
    pub file: Option<std::path::PathBuf>,
}

pub fn run(_a: SimArgs) -> Result<i32> {
    anyhow::bail!("not yet")
}
