//! `cargo xtask flash`: build, check the image, then flash it with probe-rs
//! (SWD probe) or dfu-util (the ROM's USB DFU bootloader).
//!
//! Neither may touch flash sectors 1-2 (the settings, [`image::SETTINGS`]):
//! probe-rs erases only the sectors it writes; dfu-util gets the image as
//! its pieces (vector table; code and data from sector 3), one download
//! each, instead of one .bin whose 0xFF gap would erase the settings.
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
    // The padded raw image is only checked (boot vectors), never written.
    let (_bin, boot) = image::boot_image(&elf, a.board)?;
    println!(
        "  boot: vector table at {FLASH_BASE:#010x}, initial SP {:#010x}, reset {:#010x}, image ends at +{} B of {} B",
        boot.initial_sp,
        boot.reset,
        boot.len,
        a.board.flash_bytes()
    );

    let (tool, install, cmds) = if a.dfu {
        let pieces = leave_last(image::flash_pieces(&elf, a.board)?);
        let last = pieces.len().saturating_sub(1);
        let mut cmds = Vec::new();
        for (i, p) in pieces.iter().enumerate() {
            let path = elf.with_extension(format!("{:08x}.bin", p.addr));
            std::fs::write(&path, &p.data)
                .with_context(|| format!("writing {}", path.display()))?;
            println!(
                "  piece: {} ({} B at {:#010x})",
                path.display(),
                p.data.len(),
                p.addr
            );
            // The last download leaves DFU and starts the firmware.
            let leave = if i == last { ":leave" } else { "" };
            let mut c = Command::new("dfu-util");
            c.args(["-a", "0", "-s", &format!("{:#010x}{leave}", p.addr), "-D"])
                .arg(&path);
            cmds.push(c);
        }
        (
            "dfu-util",
            "apt-get install dfu-util (or your OS's dfu-util package)",
            cmds,
        )
    } else {
        // `probe-rs run` flashes, resets and then streams the defmt log;
        // Ctrl-C detaches and the board keeps running. It erases only the
        // sectors the ELF's segments cover, so the settings stay.
        let mut c = Command::new("probe-rs");
        c.args(["run", "--chip", a.board.chip()]).arg(&elf);
        ("probe-rs", "cargo install probe-rs-tools --locked", vec![c])
    };

    if a.dry_run {
        for cmd in &cmds {
            println!("dry run, would run: {}", util::show(cmd));
        }
        return Ok(0);
    }
    if !util::have(tool) {
        bail!("`{tool}` not found on PATH; install it with: {install}");
    }
    for mut cmd in cmds {
        let status = cmd.status().with_context(|| format!("starting {tool}"))?;
        if !status.success() {
            return Ok(status.code().unwrap_or(1));
        }
    }
    Ok(0)
}

/// DfuSe's `:leave` starts the firmware at the address of the last
/// download, which the bootloader takes for a vector table (initial SP,
/// reset handler): the vector table at FLASH_BASE goes last, never the code
/// after the settings sectors.
fn leave_last(mut pieces: Vec<image::Piece>) -> Vec<image::Piece> {
    pieces.sort_by_key(|p| p.addr == FLASH_BASE);
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dfu_leaves_at_the_vector_table() {
        let piece = |addr| image::Piece {
            addr,
            data: vec![0; 4],
        };
        let order: Vec<u32> = leave_last(vec![piece(FLASH_BASE), piece(0x0800_C000)])
            .iter()
            .map(|p| p.addr)
            .collect();
        assert_eq!(order, [0x0800_C000, FLASH_BASE]);
    }
}
