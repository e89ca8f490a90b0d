//! The key/value [`Storage`] over NOR flash: a log of records in two or
//! more erase pages, the newest record of a key winning.
//!
//! Why not sequential-storage: its async map costs about 11 KB of code on
//! the Cortex-M4 (a twelfth of the image budget, then 128 KiB, now
//! 192 KiB), for a store that holds some fifty small records written a
//! few times a day. This one is under 2 KB and keeps the same guarantees:
//!
//! - **Power loss.** A record is `key, len, crc, data`, written in one
//!   go after the last one; a torn record fails its CRC and the value
//!   before it stays the newest. Bytes are never written twice.
//! - **Wear.** Records append until the page is full; then the newest
//!   record of every key moves to the next page, whose header (magic,
//!   sequence number, CRC) is written last, and only then is the old page
//!   erased. Every page takes its turn, one erase per page-full of writes.
//! - **Interrupted moves.** A page without a valid header is never read;
//!   of two valid pages the higher sequence number wins. A leftover page is
//!   erased before it is reused.
//!
//! The first use scans the current page once and keeps an index of the
//! newest record of each key and of where the free space starts; appends
//! keep it current. A boot's sixty-odd loads and writes then cost one scan,
//! not one each (the index is a few hundred bytes of RAM; with more keys
//! than it holds, reads fall back to scanning).

use crate::seams::Storage;
use embedded_storage::nor_flash::NorFlash;
use protocol::frame::crc16;

/// Longest record value ([`super::record`]).
pub const MAX_VALUE: usize = 28;

const MAGIC: [u8; 2] = *b"bS";
/// Page header: magic, sequence number (u32 LE), CRC-16 of those six.
const HEADER: usize = 8;
/// Record head: key (u16 LE, 0xFFFF is erased), value length, CRC-16 of
/// key, length and value.
const HEAD: usize = 5;
/// Longest record with the widest write size this supports.
const RECORD_MAX: usize = HEAD + MAX_VALUE + MAX_ALIGN;
const MAX_ALIGN: usize = 8;

/// Why a record could not be read or written.
#[derive(Debug)]
pub enum MapError<E> {
    /// The flash has fewer than two erase pages, or an unsupported write size.
    Config,
    /// A value longer than [`MAX_VALUE`].
    TooLong,
    /// The newest record of every key does not fit one page.
    Full,
    /// The flash failed.
    Flash(E),
}

/// A record found by a scan: key, where its value starts, its length.
#[derive(Clone, Copy)]
struct Found {
    key: u16,
    at: u32,
    len: usize,
}

/// Keys the index holds: every setting, offset and tool record with room
/// to spare.
const INDEX: usize = 160;

/// An index entry: key, and where its value starts and how long it is
/// (page-relative, so two bytes suffice for pages up to 64 KiB).
#[derive(Clone, Copy, Debug)]
struct Entry {
    key: u16,
    at: u16,
    len: u8,
}

/// What [`FlashMap::scan`] calls for each valid record.
type Visit<'a, F> = dyn FnMut(
        &mut FlashMap<F>,
        Found,
    ) -> Result<(), MapError<<F as embedded_storage::nor_flash::ErrorType>::Error>>
    + 'a;

/// The log over all whole erase pages of `F` (which must be the settings
/// region only: every page of it is erased over time).
pub struct FlashMap<F: NorFlash> {
    flash: F,
    pages: u32,
    /// Current page and its sequence number; `None` until first used.
    current: Option<(u32, u32)>,
    /// Newest record of each key in the current page, valid while
    /// `free` is `Some`.
    index: heapless::Vec<Entry, INDEX>,
    /// Where the current page's free space starts (page-relative); `None`
    /// until indexed, and again after a page move or a failed write.
    free: Option<u32>,
    /// The page holds more keys than the index: reads scan.
    overflow: bool,
}

impl<F: NorFlash> core::fmt::Debug for FlashMap<F> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("FlashMap")
            .field("pages", &self.pages)
            .field("current", &self.current)
            .finish()
    }
}

const fn align(n: usize, to: usize) -> usize {
    n.div_ceil(to) * to
}

impl<F: NorFlash> FlashMap<F> {
    const PAGE: u32 = F::ERASE_SIZE as u32;
    const FIRST: u32 = align(HEADER, F::WRITE_SIZE) as u32;

    pub fn new(flash: F) -> Self {
        let pages = (flash.capacity() / F::ERASE_SIZE) as u32;
        FlashMap {
            flash,
            pages,
            current: None,
            index: heapless::Vec::new(),
            free: None,
            overflow: false,
        }
    }

    /// Index the current page if it is not; returns where its free space
    /// starts (`None`: the page is full or its tail unreadable).
    fn indexed(&mut self) -> Result<Option<u32>, MapError<F::Error>> {
        if let Some(at) = self.free {
            return Ok(Some(at));
        }
        let (page, _) = self.open()?;
        self.index.clear();
        self.overflow = false;
        let free = self.scan(page, &mut |me, r| {
            me.note(r);
            Ok(())
        })?;
        self.free = free;
        Ok(free)
    }

    /// Record `r` as its key's newest.
    fn note(&mut self, r: Found) {
        let at = (r.at % Self::PAGE) as u16;
        let e = Entry {
            key: r.key,
            at,
            len: r.len as u8,
        };
        if let Some(old) = self.index.iter_mut().find(|o| o.key == r.key) {
            *old = e;
        } else if self.index.push(e).is_err() {
            self.overflow = true;
        }
    }

    /// The flash underneath (tests and host-sim read or clone it).
    pub fn flash(&mut self) -> Option<&mut F> {
        // The caller may change it: index afresh.
        self.free = None;
        Some(&mut self.flash)
    }

    fn usable(&self) -> bool {
        self.pages >= 2 && F::WRITE_SIZE <= MAX_ALIGN && (256..=1 << 16).contains(&F::ERASE_SIZE)
    }

    fn read(&mut self, at: u32, buf: &mut [u8]) -> Result<(), MapError<F::Error>> {
        self.flash.read(at, buf).map_err(MapError::Flash)
    }

    /// The page's sequence number if its header is valid.
    fn header(&mut self, page: u32) -> Result<Option<u32>, MapError<F::Error>> {
        let mut h = [0u8; HEADER];
        self.read(page * Self::PAGE, &mut h)?;
        let crc = u16::from_le_bytes([h[6], h[7]]);
        let ok = h[..2] == MAGIC && crc16(&h[..6]) == crc;
        Ok(ok.then(|| u32::from_le_bytes([h[2], h[3], h[4], h[5]])))
    }

    /// The current page, found on first use (or a fresh one made).
    fn open(&mut self) -> Result<(u32, u32), MapError<F::Error>> {
        if let Some(c) = self.current {
            return Ok(c);
        }
        if !self.usable() {
            return Err(MapError::Config);
        }
        let mut best: Option<(u32, u32)> = None;
        for page in 0..self.pages {
            if let Some(seq) = self.header(page)? {
                if best.is_none_or(|(_, s)| seq > s) {
                    best = Some((page, seq));
                }
            }
        }
        let c = match best {
            Some(c) => c,
            None => {
                self.erase(0)?;
                self.write_header(0, 1)?;
                (0, 1)
            }
        };
        self.current = Some(c);
        Ok(c)
    }

    fn erase(&mut self, page: u32) -> Result<(), MapError<F::Error>> {
        let from = page * Self::PAGE;
        self.flash
            .erase(from, from + Self::PAGE)
            .map_err(MapError::Flash)
    }

    fn write_header(&mut self, page: u32, seq: u32) -> Result<(), MapError<F::Error>> {
        let mut h = [0xFFu8; align(HEADER, MAX_ALIGN)];
        h[..2].copy_from_slice(&MAGIC);
        h[2..6].copy_from_slice(&seq.to_le_bytes());
        let crc = crc16(&h[..6]);
        h[6..8].copy_from_slice(&crc.to_le_bytes());
        let n = align(HEADER, F::WRITE_SIZE);
        self.flash
            .write(page * Self::PAGE, &h[..n])
            .map_err(MapError::Flash)
    }

    /// Walks the valid records of `page` in order, then returns where the
    /// next record may go (`None`: a torn head leaves no safe place).
    fn scan(&mut self, page: u32, f: &mut Visit<'_, F>) -> Result<Option<u32>, MapError<F::Error>> {
        let base = page * Self::PAGE;
        let mut at = Self::FIRST;
        while at as usize + HEAD <= F::ERASE_SIZE {
            let mut rec = [0u8; HEAD + MAX_VALUE];
            self.read(base + at, &mut rec[..HEAD])?;
            let key = u16::from_le_bytes([rec[0], rec[1]]);
            let len = usize::from(rec[2]);
            if key == 0xFFFF && rec[2] == 0xFF {
                return Ok(Some(at));
            }
            let size = align(HEAD + len, F::WRITE_SIZE) as u32;
            if len > MAX_VALUE || at + size > Self::PAGE {
                return Ok(None);
            }
            self.read(base + at + HEAD as u32, &mut rec[HEAD..HEAD + len])?;
            let crc = u16::from_le_bytes([rec[3], rec[4]]);
            rec[3..5].copy_from_slice(&[0xFF; 2]);
            if crc16(&rec[..HEAD + len]) == crc {
                let at = base + at + HEAD as u32;
                f(self, Found { key, at, len })?;
            }
            at += size;
        }
        Ok(None)
    }

    /// Appends a record at `at` (page-relative) of `page`.
    fn append(
        &mut self,
        page: u32,
        at: u32,
        key: u16,
        data: &[u8],
    ) -> Result<u32, MapError<F::Error>> {
        let mut rec = [0xFFu8; RECORD_MAX];
        rec[..2].copy_from_slice(&key.to_le_bytes());
        rec[2] = data.len() as u8;
        rec[HEAD..HEAD + data.len()].copy_from_slice(data);
        let crc = crc16(&rec[..HEAD + data.len()]);
        rec[3..5].copy_from_slice(&crc.to_le_bytes());
        let size = align(HEAD + data.len(), F::WRITE_SIZE);
        if at as usize + size > F::ERASE_SIZE {
            return Err(MapError::Full);
        }
        self.flash
            .write(page * Self::PAGE + at, &rec[..size])
            .map_err(MapError::Flash)?;
        Ok(at + size as u32)
    }

    /// Moves the newest record of every key but `skip` to the next page,
    /// adds `key = data` there, makes it current, erases the old page.
    fn migrate(&mut self, key: u16, data: &[u8]) -> Result<(), MapError<F::Error>> {
        let (old, seq) = self.open()?;
        let new = (old + 1) % self.pages;
        self.erase(new)?;
        let mut end = Self::FIRST;
        let mut failed = None;
        self.scan(old, &mut |me, r| {
            if r.key == key || failed.is_some() || me.newer(old, r)? {
                return Ok(());
            }
            let mut v = [0u8; MAX_VALUE];
            me.read(r.at, &mut v[..r.len])?;
            match me.append(new, end, r.key, &v[..r.len]) {
                Ok(next) => end = next,
                Err(e) => failed = Some(e),
            }
            Ok(())
        })?;
        if let Some(e) = failed {
            return Err(e);
        }
        self.append(new, end, key, data)?;
        self.write_header(new, seq.wrapping_add(1))?;
        self.current = Some((new, seq.wrapping_add(1)));
        self.erase(old)
    }

    /// A valid record of the same key follows `r` in `page`.
    fn newer(&mut self, page: u32, r: Found) -> Result<bool, MapError<F::Error>> {
        let mut later = false;
        self.scan(page, &mut |_, o| {
            later |= o.key == r.key && o.at > r.at;
            Ok(())
        })?;
        Ok(later)
    }
}

impl<F: NorFlash> Storage for FlashMap<F> {
    type Error = MapError<F::Error>;

    fn load(&mut self, key: u16, out: &mut [u8]) -> Result<Option<usize>, Self::Error> {
        self.indexed()?;
        let (page, _) = self.open()?;
        let last = if self.free.is_some() && !self.overflow {
            let e = self.index.iter().find(|e| e.key == key);
            e.map(|e| Found {
                key,
                at: page * Self::PAGE + u32::from(e.at),
                len: usize::from(e.len),
            })
        } else {
            let mut last = None;
            self.scan(page, &mut |_, r| {
                if r.key == key {
                    last = Some(r);
                }
                Ok(())
            })?;
            last
        };
        let Some(r) = last else { return Ok(None) };
        let dst = out.get_mut(..r.len).ok_or(MapError::TooLong)?;
        self.read(r.at, dst)?;
        Ok(Some(r.len))
    }

    fn store(&mut self, key: u16, data: &[u8]) -> Result<(), Self::Error> {
        if data.len() > MAX_VALUE || key == 0xFFFF {
            return Err(MapError::TooLong);
        }
        let free = self.indexed()?;
        let (page, _) = self.open()?;
        // Whatever happens below but a clean append, index afresh next time.
        self.free = None;
        match free {
            Some(at) => match self.append(page, at, key, data) {
                Ok(next) => {
                    self.note(Found {
                        key,
                        at: page * Self::PAGE + at + HEAD as u32,
                        len: data.len(),
                    });
                    self.free = Some(next);
                    Ok(())
                }
                Err(_) => self.migrate(key, data),
            },
            None => self.migrate(key, data),
        }
    }
}
