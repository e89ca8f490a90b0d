//! The firmware's stack high-water mark after a QEMU run: cortex-m-rt
//! paints the stack region at reset (`paint-stack`), the run scrubs what
//! it uses, and QEMU's monitor (`pmemsave`) hands the region to the host,
//! which finds the lowest word that is no longer painted.
use anyhow::{bail, Context, Result};
use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::time::{Duration, Instant};

/// cortex-m-rt's `STACK_PAINT_VALUE`.
const PAINT: u32 = 0xCCCC_CCCC;

/// Bytes of stack used at the deepest point: the stack region
/// `[bottom, top)` as painted words, lowest address first.
pub fn used(region: &[u8], top_minus_bottom: u32) -> u32 {
    let painted = region
        .chunks_exact(4)
        .take_while(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) == PAINT)
        .count() as u32;
    top_minus_bottom.saturating_sub(painted * 4)
}

/// Saves guest RAM `[bottom, top)` through the monitor socket `sock` to
/// `file` and returns its bytes.
pub fn dump(sock: &Path, bottom: u32, top: u32, file: &Path) -> Result<Vec<u8>> {
    let mut mon = UnixStream::connect(sock)
        .with_context(|| format!("connecting to QEMU's monitor at {}", sock.display()))?;
    mon.set_read_timeout(Some(Duration::from_millis(200)))?;
    let _ = std::fs::remove_file(file);
    let len = top - bottom;
    writeln!(mon, "pmemsave {bottom:#x} {len} \"{}\"", file.display())?;
    let end = Instant::now() + Duration::from_secs(10);
    let mut buf = [0u8; 512];
    while Instant::now() < end {
        let _ = mon.read(&mut buf);
        if std::fs::metadata(file).is_ok_and(|m| m.len() == u64::from(len)) {
            return std::fs::read(file).with_context(|| format!("reading {}", file.display()));
        }
    }
    bail!(
        "QEMU's monitor did not save the stack region to {}",
        file.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_from_the_lowest_scrubbed_word() {
        let mut region = Vec::new();
        for _ in 0..10 {
            region.extend(PAINT.to_le_bytes());
        }
        for _ in 0..6 {
            region.extend(0x1234u32.to_le_bytes());
        }
        assert_eq!(used(&region, 64), 24);
        assert_eq!(used(&region[..40], 40), 0);
    }
}
