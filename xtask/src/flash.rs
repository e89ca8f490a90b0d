//! `cargo xtask flash`: build, check the image, then flash it with probe-rs
//! (SWD probe) or dfu-util (the ROM's USB DFU bootloader).
use crate::image::{self, Board, FLASH_BASE};
use crate::util;
use anyhow::{bail, Context, Result};
use std::process::Command;

#[derive(clap::Args)]
pub struct FlashArgs {
    /// Board to build and flash.
    #[arg(long, value_enum, default_value_t = Board::F411)]
    pub board: Board,
    /// Flash over USB with the ROM DFU bootloader (hold BOOT0, tap NRST)
    /// instead of an SWD probe.
    #[arg(long)]
    pub dfu: bool,
    /// Build and check the image, print the command, flash nothing.
    #[arg(long)]
    pub dry_run: bool,
}

pub fn run(a: &FlashArgs) -> Result<i32> {
    let elf = image::build_board(a.board)?;
    let sizes = image::size_report(&elf)?;
    image::print_sizes(a.board, &elf, &sizes);
    let (bin, boot) = image::boot_image(&elf, a.board)?;
    println!(
        "  boot: vector table at {FLASH_BASE:#010x}, initial SP {:#010x}, reset {:#010x}, image {} B fits {} B",
        boot.initial_sp,
        boot.reset,
        boot.len,
        a.board.flash_bytes()
    );

    let (tool, install, mut cmd) = if a.dfu {
        let path = elf.with_extension("bin");
        std::fs::write(&path, &bin).with_context(|| format!("writing {}", path.display()))?;
        println!("  raw image: {} ({} B)", path.display(), bin.len());
        let mut c = Command::new("dfu-util");
        c.args(["-a", "0", "-s", &format!("{FLASH_BASE:#010x}:leave"), "-D"])
            .arg(&path);
        (
            "dfu-util",
            "apt-get install dfu-util (or your OS's dfu-util package)",
            c,
        )
    } else {
        // `probe-rs run` flashes, resets and then streams the defmt log;
        // Ctrl-C detaches and the board keeps running.
        let mut c = Command::new("probe-rs");
        c.args(["run", "--chip", a.board.chip()]).arg(&elf);
        ("probe-rs", "cargo install probe-rs-tools --locked", c)
    };

    if a.dry_run {
        println!("dry run, would run: {}", util::show(&cmd));
        return Ok(0);
    }
    if !util::have(tool) {
        bail!("`{tool}` not found on PATH; install it with: {install}");
    }
    let status = cmd.status().with_context(|| format!("starting {tool}"))?;
    Ok(status.code().unwrap_or(1))
}
