//! [`RamFlash`]: NOR flash in RAM for tests, host-sim and the QEMU board
//! (whose flash controller QEMU does not model).

use embedded_storage::nor_flash::{self as blocking, NorFlashError, NorFlashErrorKind};

/// Why a [`RamFlash`] operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RamFlashError {
    /// Misaligned or outside the flash.
    Bounds,
    /// The simulated power cut happened during (or before) this operation.
    PowerLost,
}

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            RamFlashError::Bounds => NorFlashErrorKind::OutOfBounds,
            RamFlashError::PowerLost => NorFlashErrorKind::Other,
        }
    }
}

/// NOR flash in RAM: `N` bytes in pages of `PAGE`, 4-byte words. Writes
/// only clear bits, as real NOR does, so writing a word twice shows up as
/// corruption instead of silently working. [`RamFlash::cut_power_after`]
/// simulates a power cut in the middle of a write.
#[derive(Clone, Debug)]
pub struct RamFlash<const N: usize, const PAGE: usize> {
    mem: [u8; N],
    /// Bytes that may still be written before the power goes.
    budget: Option<usize>,
    /// Bytes written and pages erased so far (wear, for tests).
    pub written: usize,
    pub erases: usize,
}

impl<const N: usize, const PAGE: usize> Default for RamFlash<N, PAGE> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, const PAGE: usize> RamFlash<N, PAGE> {
    /// Erased (all ones), as a new chip.
    pub const fn new() -> Self {
        RamFlash {
            mem: [0xFF; N],
            budget: None,
            written: 0,
            erases: 0,
        }
    }

    /// After `bytes` more bytes have been written the power goes: that
    /// write stops midway (a torn record) and every later write or erase
    /// fails, until [`RamFlash::power_on`].
    pub fn cut_power_after(&mut self, bytes: usize) {
        self.budget = Some(bytes);
    }

    /// Power back: the contents stay as the cut left them.
    pub fn power_on(&mut self) {
        self.budget = None;
    }

    /// The raw contents.
    pub fn bytes(&self) -> &[u8] {
        &self.mem
    }
}

impl<const N: usize, const PAGE: usize> blocking::ErrorType for RamFlash<N, PAGE> {
    type Error = RamFlashError;
}

impl<const N: usize, const PAGE: usize> blocking::ReadNorFlash for RamFlash<N, PAGE> {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let start = offset as usize;
        let src = self
            .mem
            .get(start..start + bytes.len())
            .ok_or(RamFlashError::Bounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }
    fn capacity(&self) -> usize {
        N
    }
}

impl<const N: usize, const PAGE: usize> blocking::NorFlash for RamFlash<N, PAGE> {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = PAGE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        blocking::check_erase(self, from, to).map_err(|_| RamFlashError::Bounds)?;
        if self.budget == Some(0) {
            return Err(RamFlashError::PowerLost);
        }
        let page = self
            .mem
            .get_mut(from as usize..to as usize)
            .ok_or(RamFlashError::Bounds)?;
        page.fill(0xFF);
        self.erases += (to - from) as usize / PAGE;
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        blocking::check_write(self, offset, bytes.len()).map_err(|_| RamFlashError::Bounds)?;
        let start = offset as usize;
        let dst = self
            .mem
            .get_mut(start..start + bytes.len())
            .ok_or(RamFlashError::Bounds)?;
        for (d, s) in dst.iter_mut().zip(bytes) {
            if let Some(b) = self.budget.as_mut() {
                if *b == 0 {
                    return Err(RamFlashError::PowerLost);
                }
                *b -= 1;
            }
            *d &= *s;
            self.written += 1;
        }
        Ok(())
    }
}
