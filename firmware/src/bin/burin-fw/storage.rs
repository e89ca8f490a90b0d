//! Where settings and work offsets live: `burin::persist`'s record log
//! ([`FlashMap`](burin::persist::FlashMap)) on flash sectors 1 and 2 of the Black Pills
//! (16 KiB each, 0x0800_4000..0x0800_C000; `memory-f4x1.x` starts `.text`
//! after them). Small sectors erase in about 0.3 s instead of 1-2 s for a
//! 128 KiB one, and every F4 has them.
//!
//! The HAL's own `NorFlash` erases in 128 KiB units (its largest sector),
//! which would take the code with it, so [`SectorFlash`] implements the
//! traits with 16 KiB pages on the HAL's sector erase and byte programming.
//!
//! QEMU does not model the flash controller: its board (`boards/qemu.rs`)
//! keeps the same map in RAM instead, so the same code runs there but
//! nothing survives a restart of QEMU.

pub use board_flash::{open, Store};

mod board_flash {
    use burin::persist::FlashMap;
    use embedded_storage::nor_flash::{
        check_erase, check_write, ErrorType, NorFlash, NorFlashError, NorFlashErrorKind,
        ReadNorFlash,
    };
    use stm32f4xx_hal::flash::{self, FlashExt};
    use stm32f4xx_hal::pac;

    /// Settings region: from 0x0800_4000, sectors 1 and 2.
    const BASE: usize = 0x4000;
    const SECTOR: usize = 16 * 1024;
    const FIRST_SECTOR: u8 = 1;
    const SECTORS: usize = 2;

    /// The settings map on the flash.
    pub type Store = FlashMap<SectorFlash>;

    /// Takes the flash controller for the settings map.
    pub fn open(flash: pac::FLASH) -> Store {
        FlashMap::new(SectorFlash { flash })
    }

    /// Sectors 1 and 2 as a NOR flash of two 16 KiB pages, offsets from
    /// 0x0800_4000.
    pub struct SectorFlash {
        flash: pac::FLASH,
    }

    #[derive(Clone, Copy, Debug, defmt::Format)]
    pub enum Error {
        /// Outside the settings region or misaligned.
        Bounds,
        /// The flash controller reported an error.
        Controller,
    }

    impl NorFlashError for Error {
        fn kind(&self) -> NorFlashErrorKind {
            match self {
                Error::Bounds => NorFlashErrorKind::OutOfBounds,
                Error::Controller => NorFlashErrorKind::Other,
            }
        }
    }

    impl From<flash::Error> for Error {
        fn from(_: flash::Error) -> Self {
            Error::Controller
        }
    }

    impl SectorFlash {
        /// Clear the controller's error flags (write 1 to clear). The HAL
        /// reads them after an operation but never clears them, so one
        /// stale error would fail every later erase and write until reset.
        fn clear_errors(&mut self) {
            self.flash.sr().write(|w| {
                w.operr().clear();
                w.wrperr().clear();
                w.pgaerr().clear();
                w.pgperr().clear();
                w.pgserr().clear()
            });
        }

        /// The ART data cache may hold lines of what was just erased or
        /// programmed; reset it (RM0383 3.4.2: only while it is disabled).
        fn flush_data_cache(&mut self) {
            let acr = self.flash.acr();
            let on = acr.read().dcen().bit_is_set();
            acr.modify(|_, w| w.dcen().clear_bit());
            acr.modify(|_, w| w.dcrst().set_bit());
            acr.modify(|_, w| w.dcrst().clear_bit());
            if on {
                acr.modify(|_, w| w.dcen().set_bit());
            }
        }
    }

    impl ErrorType for SectorFlash {
        type Error = Error;
    }

    impl ReadNorFlash for SectorFlash {
        const READ_SIZE: usize = 1;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Error> {
            if offset as usize + bytes.len() > self.capacity() {
                return Err(Error::Bounds);
            }
            let start = BASE + offset as usize;
            let src = FlashExt::read(&self.flash)
                .get(start..start + bytes.len())
                .ok_or(Error::Bounds)?;
            bytes.copy_from_slice(src);
            Ok(())
        }
        fn capacity(&self) -> usize {
            SECTORS * SECTOR
        }
    }

    impl NorFlash for SectorFlash {
        const WRITE_SIZE: usize = 4;
        const ERASE_SIZE: usize = SECTOR;

        fn erase(&mut self, from: u32, to: u32) -> Result<(), Error> {
            check_erase(self, from, to).map_err(|_| Error::Bounds)?;
            let pages = from as usize / SECTOR..to as usize / SECTOR;
            self.clear_errors();
            let result = pages.into_iter().try_for_each(|page| {
                // page < SECTORS (2): the sector number stays 1 or 2.
                self.flash.unlocked().erase(FIRST_SECTOR + page as u8)
            });
            self.flush_data_cache();
            Ok(result?)
        }

        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Error> {
            check_write(self, offset, bytes.len()).map_err(|_| Error::Bounds)?;
            self.clear_errors();
            let result = self
                .flash
                .unlocked()
                .program(BASE + offset as usize, bytes.iter());
            self.flush_data_cache();
            Ok(result?)
        }
    }
}
