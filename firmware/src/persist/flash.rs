//! The key/value [`Storage`] over NOR flash: sequential-storage's map on
//! any blocking `embedded-storage` flash, plus [`RamFlash`], a flash in RAM
//! for tests, host-sim and the QEMU board (whose flash controller QEMU does
//! not model).
//!
//! sequential-storage is async; flash here is not. Code runs from the same
//! flash, so an erase or a write stalls the CPU whatever an executor does,
//! and awaiting would buy nothing. [`Blocking`] gives a blocking flash the
//! async traits (its futures are ready at the first poll) and [`block_on`]
//! polls them to completion, so the device session stays a plain function.

use crate::seams::Storage;
use core::future::Future;
use core::task::{Context, Poll, Waker};
use embedded_storage::nor_flash::{self as blocking, NorFlashError, NorFlashErrorKind};
use embedded_storage_async::nor_flash as nb;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

/// Longest record value ([`super::record`]); key and value together must fit
/// the map's work buffer.
pub const MAX_VALUE: usize = 24;

/// Runs a future to completion by polling it. Meant for futures that never
/// wait (those of [`Blocking`]); one that does is polled again at once,
/// spinning, which is correct but wasteful.
pub fn block_on<F: Future>(f: F) -> F::Output {
    let mut f = core::pin::pin!(f);
    let mut cx = Context::from_waker(Waker::noop());
    loop {
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
}

/// A blocking flash seen through the async NOR flash traits.
#[derive(Debug)]
pub struct Blocking<F>(pub F);

impl<F: blocking::ErrorType> blocking::ErrorType for Blocking<F> {
    type Error = F::Error;
}

impl<F: blocking::ReadNorFlash> nb::ReadNorFlash for Blocking<F> {
    const READ_SIZE: usize = F::READ_SIZE;
    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes)
    }
    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl<F: blocking::NorFlash> nb::NorFlash for Blocking<F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;
    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.0.erase(from, to)
    }
    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.write(offset, bytes)
    }
}

/// No RAM cache: every look-up scans the flash (a few ms on the MCU;
/// reads are rare: boot and M501).
type NoCache = Cache<Uncached, Uncached, Uncached, u16>;

/// Why a record could not be read or written.
#[derive(Debug)]
pub enum MapError<E> {
    /// The flash range cannot hold a map (fewer than two erase pages).
    Config,
    /// A stored record is longer than [`MAX_VALUE`].
    TooLong,
    /// sequential-storage's error (flash, corruption it could not repair, full).
    Map(sequential_storage::Error<E>),
}

/// A key/value map over the whole of `F` (which must be the settings
/// region only: the map erases every page of it over time).
pub struct FlashMap<F: blocking::NorFlash> {
    map: Option<MapStorage<u16, Blocking<F>, NoCache>>,
    /// Key, value and the flash's word alignment (see `MapStorage::fetch_item`).
    buf: [u8; 2 + MAX_VALUE + 8],
}

impl<F: blocking::NorFlash> core::fmt::Debug for FlashMap<F> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FlashMap")
            .field("configured", &self.map.is_some())
            .finish()
    }
}

impl<F: blocking::NorFlash> FlashMap<F> {
    /// A map over all whole erase pages of `flash`. Needs at least two:
    /// with fewer every operation fails with [`MapError::Config`].
    pub fn new(flash: F) -> Self {
        let pages = flash.capacity() / F::ERASE_SIZE;
        let end = u32::try_from(pages * F::ERASE_SIZE).unwrap_or(0);
        let map = MapConfig::try_new(0..end)
            .ok()
            .map(|cfg| MapStorage::new(Blocking(flash), cfg, Cache::new_uncached()));
        FlashMap {
            map,
            buf: [0; 2 + MAX_VALUE + 8],
        }
    }

    /// The flash underneath (tests and host-sim read or clone it).
    pub fn flash(&mut self) -> Option<&mut F> {
        self.map.as_mut().map(|m| &mut m.flash().0)
    }
}

impl<F: blocking::NorFlash> Storage for FlashMap<F> {
    type Error = MapError<F::Error>;

    fn load(&mut self, key: u16, out: &mut [u8]) -> Result<Option<usize>, Self::Error> {
        let map = self.map.as_mut().ok_or(MapError::Config)?;
        let got = block_on(map.fetch_item::<&[u8]>(&mut self.buf, &key)).map_err(MapError::Map)?;
        let Some(v) = got else { return Ok(None) };
        let dst = out.get_mut(..v.len()).ok_or(MapError::TooLong)?;
        dst.copy_from_slice(v);
        Ok(Some(v.len()))
    }

    fn store(&mut self, key: u16, data: &[u8]) -> Result<(), Self::Error> {
        let map = self.map.as_mut().ok_or(MapError::Config)?;
        if data.len() > MAX_VALUE {
            return Err(MapError::TooLong);
        }
        block_on(map.store_item(&mut self.buf, &key, &data)).map_err(MapError::Map)
    }
}

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
