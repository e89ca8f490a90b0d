//! Flashing with probe-rs or DFU.
use anyhow::Result;

#[derive(clap::Args)]
pub struct FlashArgs {
    #[arg(long, default_value = "f411")]
    pub board: String,
}

pub fn run(_a: &FlashArgs) -> Result<i32> {
    anyhow::bail!("not yet")
}
