//! Firmware images: build per board, size report against the budget, and the
//! ELF checks `ci` and `flash` rely on (vector table, RTIC handlers, raw
//! image). Everything after the build is pure functions over bytes, so it is
//! unit-tested without a cross toolchain.
use crate::util;
use anyhow::{bail, Context, Result};
use object::elf::{PT_LOAD, SHF_ALLOC};
use object::read::elf::{ElfFile32, FileHeader, ProgramHeader, SectionHeader};
use object::{Object, ObjectSection};
use std::path::{Path, PathBuf};

mod checks;
pub use checks::{check_fault_layout, check_vectors};
use checks::{check_machine_slot_in_bss, check_no_float_text, check_no_soft_double, word};

pub const FLASH_BASE: u32 = 0x0800_0000;
/// Flash sectors 1 and 2 of both Black Pills: the settings and work
/// offsets (firmware/src/bin/burin-fw/storage.rs). The image leaves them
/// out (`_stext` in memory-f4x1.x) and flashing must never write them.
pub const SETTINGS: std::ops::Range<u32> = 0x0800_4000..0x0800_C000;
/// Segments closer than this are written as one piece, the gap as 0xFF.
const MERGE_GAP: u32 = 1024;
pub const RAM_BASE: u32 = 0x2000_0000;
const KIB: u32 = 1024;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Board {
    /// WeAct Black Pill STM32F411CEU6 (default).
    F411,
    /// WeAct Black Pill STM32F401CCU6.
    F401,
}

impl Board {
    pub const ALL: [Board; 2] = [Board::F411, Board::F401];

    pub fn name(self) -> &'static str {
        match self {
            Board::F411 => "f411",
            Board::F401 => "f401",
        }
    }
    /// Cargo arguments selecting this board for the firmware package.
    /// Cargo flags that select the board.
    pub fn cargo_features(self) -> &'static [&'static str] {
        match self {
            Board::F411 => &[],
            Board::F401 => &["--no-default-features", "--features", "board-f401"],
        }
    }
    /// The board's cargo feature when it is not the default one.
    pub fn features(self) -> Option<&'static str> {
        self.cargo_features().get(2).copied()
    }
    /// probe-rs' name for the chip.
    pub fn chip(self) -> &'static str {
        match self {
            Board::F411 => "STM32F411CEUx",
            Board::F401 => "STM32F401CCUx",
        }
    }
    pub fn flash_bytes(self) -> u32 {
        match self {
            Board::F411 => 512 * KIB,
            Board::F401 => 256 * KIB,
        }
    }
    pub fn ram_bytes(self) -> u32 {
        match self {
            Board::F411 => 128 * KIB,
            Board::F401 => 64 * KIB,
        }
    }
    /// The project's budget: flash 192 KiB on both (issue 2 set 128 KiB; the
    /// project raised it once the whole app outgrew that); static RAM
    /// 64 KiB on the F411 and 43 KiB on the F401: what its fixed 21 KiB
    /// stack at the bottom of SRAM leaves (memory-f401.x).
    pub fn budget(self) -> Sizes {
        let ram = match self {
            Board::F411 => 64 * KIB,
            Board::F401 => 43 * KIB,
        };
        Sizes {
            flash: 192 * KIB,
            ram,
            ..Sizes::default()
        }
    }
}

impl std::fmt::Display for Board {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[derive(clap::Args)]
pub struct BuildArgs {
    /// Board to build for.
    #[arg(long, value_enum, default_value_t = Board::F411)]
    pub board: Board,
    /// Build every supported board instead.
    #[arg(long, conflicts_with = "board")]
    pub all: bool,
}

pub fn run(a: &BuildArgs) -> Result<i32> {
    let boards: &[Board] = if a.all {
        &Board::ALL
    } else {
        std::slice::from_ref(&a.board)
    };
    for &board in boards {
        build_and_check(board)?;
    }
    Ok(0)
}

/// The `cargo xtask ci` step for one board: see [`build_and_check`].
pub fn ci_check(board: Board) -> Result<()> {
    build_and_check(board).map(drop)
}

/// Build, print the figures, and fail on unbound RTIC vectors or an image
/// over budget: the whole of `cargo xtask build` for one board.
pub fn build_and_check(board: Board) -> Result<Sizes> {
    let elf = build_board(board)?;
    let sizes = size_report(&elf)?;
    print_sizes(board, &elf, &sizes);
    check_vectors(&elf)?;
    check_fault_layout(&elf)?;
    check_no_float_text(&elf)?;
    check_no_soft_double(&elf)?;
    check_machine_slot_in_bss(&elf)?;
    check_budget(board, &sizes)?;
    Ok(sizes)
}

/// Builds the image for `board` (`burin-fw-<board>.elf`).
pub fn build_board(board: Board) -> Result<PathBuf> {
    util::build_firmware("burin-fw", board.features(), board.name())
}

/// Bytes per region, plus the sections behind them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sizes {
    /// Everything programmed into flash: PT_LOAD file bytes at flash addresses
    /// (vector table, .text, .rodata and the .data initialisers); not the
    /// settings sectors between the vector table and .text.
    pub flash: u32,
    /// Static RAM: allocated sections in RAM (.data, .bss, .uninit), above
    /// the fixed stack at the bottom of SRAM (memory-*.x).
    pub ram: u32,
    pub vector_table: u32,
    pub text: u32,
    pub rodata: u32,
    pub data: u32,
    pub bss: u32,
    pub uninit: u32,
}

fn read(elf: &Path) -> Result<Vec<u8>> {
    std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))
}

fn parse(bytes: &[u8]) -> Result<ElfFile32<'_>> {
    ElfFile32::parse(bytes).context("not a 32-bit ELF")
}

/// The stack region `[bottom, top)`: cortex-m-rt's `_stack_end` (the top
/// of the statics) and `_stack_start` (the initial stack pointer).
pub fn stack_region(elf: &Path) -> Result<(u32, u32)> {
    let bytes = read(elf)?;
    let file = parse(&bytes)?;
    let bottom = checks::symbol(&file, "_stack_end")?;
    let top = checks::symbol(&file, "_stack_start")?;
    if top <= bottom {
        bail!("stack region {bottom:#x}..{top:#x} is empty");
    }
    Ok((bottom, top))
}

pub fn size_report(elf: &Path) -> Result<Sizes> {
    let bytes = read(elf)?;
    sizes_of(&parse(&bytes)?)
}

fn sizes_of(file: &ElfFile32<'_>) -> Result<Sizes> {
    let endian = file.endian();
    let mut s = Sizes {
        flash: image_bytes(&load_segments(file)?)?,
        ..Sizes::default()
    };
    for section in file.elf_section_table().iter() {
        if section.sh_flags(endian) & SHF_ALLOC == 0 {
            continue;
        }
        let name = file
            .elf_section_table()
            .section_name(endian, section)
            .unwrap_or_default();
        let (addr, size) = (section.sh_addr(endian), section.sh_size(endian));
        match name {
            b".vector_table" => s.vector_table += size,
            b".text" => s.text += size,
            b".rodata" => s.rodata += size,
            b".data" => s.data += size,
            b".bss" => s.bss += size,
            b".uninit" => s.uninit += size,
            _ => {}
        }
        if (RAM_BASE..RAM_BASE + 0x1000_0000).contains(&addr) {
            s.ram += size;
        }
    }
    Ok(s)
}

fn kib(b: u32) -> String {
    format!("{:.1} KiB", f64::from(b) / 1024.0)
}

fn pct(part: u32, whole: u32) -> f64 {
    100.0 * f64::from(part) / f64::from(whole.max(1))
}

pub fn print_sizes(board: Board, elf: &Path, s: &Sizes) {
    let b = board.budget();
    println!(
        "burin-fw for {} ({}): {}",
        board.name(),
        board.chip(),
        elf.display()
    );
    println!(
        "  flash {:>7} B = {:>9}  ({:4.1}% of the {} budget, chip {})",
        s.flash,
        kib(s.flash),
        pct(s.flash, b.flash),
        kib(b.flash),
        kib(board.flash_bytes())
    );
    println!(
        "        vector table {} + .text {} + .rodata {} + .data load image {}",
        s.vector_table, s.text, s.rodata, s.data
    );
    println!(
        "  RAM   {:>7} B = {:>9}  ({:4.1}% of the {} budget, chip {})",
        s.ram,
        kib(s.ram),
        pct(s.ram, b.ram),
        kib(b.ram),
        kib(board.ram_bytes())
    );
    let stack = stack_region(elf).map_or(0, |(bottom, top)| top - bottom);
    println!(
        "        .data {} + .bss {} + .uninit {}; stack {} at the bottom of SRAM, {} unused",
        s.data,
        s.bss,
        s.uninit,
        kib(stack),
        kib(board.ram_bytes().saturating_sub(s.ram + stack))
    );
}

/// Fails when the image is over the board's budget (or over the chip).
pub fn check_budget(board: Board, s: &Sizes) -> Result<()> {
    let b = board.budget();
    if s.flash > b.flash {
        bail!(
            "{}: flash {} B is over the {} budget",
            board.name(),
            s.flash,
            kib(b.flash)
        );
    }
    if s.ram > b.ram {
        bail!(
            "{}: static RAM {} B is over the {} budget",
            board.name(),
            s.ram,
            kib(b.ram)
        );
    }
    Ok(())
}

/// A PT_LOAD segment's file bytes at its physical (load) address.
pub struct Segment<'a> {
    pub paddr: u32,
    pub data: &'a [u8],
}

pub fn load_segments<'a>(file: &ElfFile32<'a>) -> Result<Vec<Segment<'a>>> {
    let endian = file.endian();
    let mut out = Vec::new();
    for ph in file.elf_header().program_headers(endian, file.data())? {
        if ph.p_type(endian) != PT_LOAD || ph.p_filesz(endian) == 0 {
            continue;
        }
        let data = ph
            .data(endian, file.data())
            .ok()
            .context("PT_LOAD segment outside the file")?;
        out.push(Segment {
            paddr: ph.p_paddr(endian),
            data,
        });
    }
    Ok(out)
}

/// Bytes from FLASH_BASE to the end of the last loaded byte.
fn image_len(segments: &[Segment<'_>]) -> Result<u32> {
    let mut end = FLASH_BASE;
    for s in segments {
        if s.paddr < FLASH_BASE || s.paddr >= RAM_BASE {
            bail!("segment loads at {:#010x}, outside flash", s.paddr);
        }
        let len = u32::try_from(s.data.len()).context("segment too large")?;
        end = end.max(
            s.paddr
                .checked_add(len)
                .context("segment wraps the address space")?,
        );
    }
    Ok(end - FLASH_BASE)
}

/// Bytes programmed: the loaded segments, without the gaps between them.
fn image_bytes(segments: &[Segment<'_>]) -> Result<u32> {
    image_len(segments)?;
    let mut n = 0u32;
    for s in segments {
        n = n
            .checked_add(u32::try_from(s.data.len()).context("segment too large")?)
            .context("image too large")?;
    }
    Ok(n)
}

/// One contiguous run of flash to write.
#[derive(Debug, PartialEq, Eq)]
pub struct Piece {
    pub addr: u32,
    pub data: Vec<u8>,
}

/// The image as the runs a flasher writes: segments merged across small
/// gaps (filled with 0xFF), split across large ones such as the settings
/// sectors, which no piece may touch.
pub fn pieces(segments: &[Segment<'_>], flash_bytes: u32) -> Result<Vec<Piece>> {
    let len = image_len(segments)?;
    if len > flash_bytes {
        bail!("image is {len} B but the chip has {flash_bytes} B of flash");
    }
    let mut order: Vec<&Segment<'_>> = segments.iter().collect();
    order.sort_by_key(|s| s.paddr);
    let mut out: Vec<Piece> = Vec::new();
    for s in order {
        match out.last_mut() {
            Some(p) if s.paddr >= p.addr && s.paddr - p.addr <= p.data.len() as u32 + MERGE_GAP => {
                let at = (s.paddr - p.addr) as usize;
                if p.data.len() < at {
                    p.data.resize(at, 0xFF);
                }
                let end = at + s.data.len();
                if p.data.len() < end {
                    p.data.resize(end, 0xFF);
                }
                p.data[at..end].copy_from_slice(s.data);
            }
            _ => out.push(Piece {
                addr: s.paddr,
                data: s.data.to_vec(),
            }),
        }
    }
    for p in &out {
        let end = p.addr + p.data.len() as u32;
        if p.addr < SETTINGS.end && SETTINGS.start < end {
            bail!(
                "image piece {:#010x}..{end:#010x} overlaps the settings sectors {:#010x}..{:#010x}",
                p.addr,
                SETTINGS.start,
                SETTINGS.end
            );
        }
    }
    Ok(out)
}

/// [`pieces`] of an ELF.
pub fn flash_pieces(elf: &Path, board: Board) -> Result<Vec<Piece>> {
    let bytes = read(elf)?;
    let file = parse(&bytes)?;
    pieces(&load_segments(&file)?, board.flash_bytes())
}

/// The raw flash image from FLASH_BASE, gaps filled with 0xFF (erased
/// flash), which is what dfu-util writes at 0x0800_0000.
pub fn raw_image(segments: &[Segment<'_>], flash_bytes: u32) -> Result<Vec<u8>> {
    let len = image_len(segments)?;
    if len > flash_bytes {
        bail!("image is {len} B but the chip has {flash_bytes} B of flash");
    }
    let mut bin = vec![0xFF; len as usize];
    for s in segments {
        let at = (s.paddr - FLASH_BASE) as usize;
        bin[at..at + s.data.len()].copy_from_slice(s.data);
    }
    Ok(bin)
}

/// What the dry run checks, from the raw image the board boots from.
#[derive(Debug, PartialEq, Eq)]
pub struct BootInfo {
    pub initial_sp: u32,
    pub reset: u32,
    pub len: u32,
}

/// The chip boots from the vector table at FLASH_BASE: word 0 is the initial
/// stack pointer, word 1 the reset handler. Both must make sense.
pub fn check_boot(bin: &[u8], board: Board) -> Result<BootInfo> {
    let (Some(initial_sp), Some(reset)) = (word(bin, 0), word(bin, 4)) else {
        bail!("image shorter than a vector table");
    };
    let len = u32::try_from(bin.len()).context("image too large")?;
    let ram_end = RAM_BASE + board.ram_bytes();
    if !(RAM_BASE < initial_sp && initial_sp <= ram_end) {
        bail!("initial SP {initial_sp:#010x} is outside RAM {RAM_BASE:#010x}..={ram_end:#010x}");
    }
    if initial_sp % 8 != 0 {
        bail!("initial SP {initial_sp:#010x} is not 8-byte aligned (AAPCS)");
    }
    if reset & 1 == 0 {
        bail!("reset vector {reset:#010x} is even: not a Thumb address");
    }
    if !(FLASH_BASE + 8..FLASH_BASE + len).contains(&(reset & !1)) {
        bail!("reset vector {reset:#010x} is outside the image");
    }
    if len > board.flash_bytes() {
        bail!(
            "image is {len} B; the {} has {} B of flash",
            board.chip(),
            board.flash_bytes()
        );
    }
    Ok(BootInfo {
        initial_sp,
        reset,
        len,
    })
}

/// Builds the raw image of `elf` and checks it boots on `board`; also checks
/// that the ELF's vector table section sits at FLASH_BASE.
pub fn boot_image(elf: &Path, board: Board) -> Result<(Vec<u8>, BootInfo)> {
    let bytes = read(elf)?;
    let file = parse(&bytes)?;
    let table = file
        .section_by_name(".vector_table")
        .context("no .vector_table section")?;
    if table.address() != u64::from(FLASH_BASE) {
        bail!(
            "vector table at {:#010x}, not at {FLASH_BASE:#010x}",
            table.address()
        );
    }
    let bin = raw_image(&load_segments(&file)?, board.flash_bytes())?;
    let info = check_boot(&bin, board)?;
    Ok((bin, info))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vectors(sp: u32, reset: u32) -> Vec<u8> {
        let mut v = sp.to_le_bytes().to_vec();
        v.extend(reset.to_le_bytes());
        v.resize(0x200, 0);
        v
    }

    #[test]
    fn raw_image_pads_gaps_with_erased_flash() {
        let a = [1u8, 2, 3, 4];
        let b = [9u8, 8];
        let segs = [
            Segment {
                paddr: FLASH_BASE,
                data: &a,
            },
            Segment {
                paddr: FLASH_BASE + 8,
                data: &b,
            },
        ];
        let bin = raw_image(&segs, 512 * KIB).unwrap();
        assert_eq!(bin, [1, 2, 3, 4, 0xFF, 0xFF, 0xFF, 0xFF, 9, 8]);
    }

    #[test]
    fn pieces_skip_the_settings_sectors_and_sizes_count_bytes() {
        let table = [0xAAu8; 0x198];
        let text = [1u8; 64];
        let rodata = [2u8; 8];
        let segs = [
            Segment {
                paddr: FLASH_BASE,
                data: &table,
            },
            Segment {
                paddr: SETTINGS.end + 64 + 4,
                data: &rodata,
            },
            Segment {
                paddr: SETTINGS.end,
                data: &text,
            },
        ];
        let p = pieces(&segs, 512 * KIB).unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!((p[0].addr, p[0].data.len()), (FLASH_BASE, 0x198));
        assert_eq!((p[1].addr, p[1].data.len()), (SETTINGS.end, 64 + 4 + 8));
        assert_eq!(p[1].data[64..68], [0xFF; 4]);
        assert_eq!(p[1].data[68], 2);
        assert_eq!(image_bytes(&segs).unwrap(), 0x198 + 64 + 8);
        // Code placed in the settings sectors is refused.
        let bad = [Segment {
            paddr: SETTINGS.start + 16,
            data: &text,
        }];
        assert!(pieces(&bad, 512 * KIB).is_err());
    }

    #[test]
    fn raw_image_rejects_ram_segments_and_oversize() {
        let a = [0u8; 16];
        let in_ram = [Segment {
            paddr: RAM_BASE,
            data: &a,
        }];
        assert!(raw_image(&in_ram, 512 * KIB).is_err());
        let far = [Segment {
            paddr: FLASH_BASE + 256 * KIB,
            data: &a,
        }];
        assert!(raw_image(&far, 256 * KIB).is_err());
        assert!(raw_image(&far, 512 * KIB).is_ok());
    }

    #[test]
    fn boot_checks_accept_a_sane_table() {
        let bin = vectors(0x2002_0000, 0x0800_0199);
        let info = check_boot(&bin, Board::F411).unwrap();
        assert_eq!(info.initial_sp, 0x2002_0000);
        // The F401 has 64 KiB: the F411's stack top is outside its RAM.
        assert!(check_boot(&bin, Board::F401).is_err());
    }

    #[test]
    fn boot_checks_reject_bad_sp_and_reset() {
        assert!(check_boot(&vectors(0x2002_0004, 0x0800_0199), Board::F411).is_err());
        assert!(check_boot(&vectors(0x1000_0000, 0x0800_0199), Board::F411).is_err());
        assert!(check_boot(&vectors(0x2002_0000, 0x0800_0198), Board::F411).is_err());
        assert!(check_boot(&vectors(0x2002_0000, 0x0810_0001), Board::F411).is_err());
        assert!(check_boot(&[0; 6], Board::F411).is_err());
    }

    #[test]
    fn budgets_fail_when_exceeded() {
        let ok = Sizes {
            flash: 192 * KIB,
            ram: 64 * KIB,
            ..Sizes::default()
        };
        assert!(check_budget(Board::F411, &ok).is_ok());
        assert!(check_budget(Board::F401, &ok).is_err());
        let big = Sizes {
            flash: 192 * KIB + 1,
            ..ok
        };
        assert!(check_budget(Board::F411, &big).is_err());
    }
}
