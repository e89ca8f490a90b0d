//! Firmware images: build per board, size report, ELF sanity checks.
use anyhow::Result;

#[derive(clap::Args)]
pub struct BuildArgs {
    /// Board to build for.
    #[arg(long, default_value = "f411")]
    pub board: String,
}

pub fn run(_a: &BuildArgs) -> Result<i32> {
    anyhow::bail!("not yet")
}
