//! Settings, work offsets and the tool table that survive a reset, over the [`Storage`]
//! seam (a record log, [`FlashMap`], in two 16 KiB flash sectors on the
//! boards, RAM on QEMU and in host-sim).
//!
//! [`Persist`] keeps a mirror of what the flash holds, so a save writes only
//! the records whose value changed (dirty tracking by comparison, nothing
//! to forget to mark): `$110=…` costs one 12-byte record, an M500 with
//! nothing changed costs nothing. The mirror uses NaN for "not known to be
//! in flash" (never read, or its write failed), which compares unequal to
//! every value, so the next save writes it.
//!
//! Loading validates every value with the rules `$n=` applies
//! ([`Settings::set`]): flash never brings in a value `$n=` would refuse.
//! A missing, damaged or old-format record falls back to that item's
//! default, and the default is written back at once, so the report (one
//! `[MSG:]` after the banner) appears on one boot, not on every boot.
//!
//! When the device writes (flash writes stall the CPU, and so the step
//! interrupt, which runs from flash too): only while no motion is queued
//! or running. `$n=` is refused unless idle; G10 L2/L20, G28.1, G30.1,
//! M500 and M501 are sync points (see `session::persist`).

pub mod flash;
pub mod record;

pub mod ram;
pub use flash::FlashMap;
pub use ram::RamFlash;

use crate::interp::tools::TOOL_AXES;
use crate::interp::{Offsets, ToolEntry, TOOLS};
use crate::seams::Storage;
use crate::settings::{table, Settings};
use crate::AXES;
use record::{MAX_RECORD, OFFSETS_KEY, OFFSET_RECORDS, TOOLS_KEY, TOOL_VALUES};

/// Number of `$n` settings (`table::numbers()`; a test keeps them equal).
/// 63 with four axes.
pub const SETTINGS: usize = table::COUNT;

/// What a load found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Report {
    /// Items (settings and offset vectors) that were missing, damaged, of
    /// an old format or refused by validation: their defaults are in use.
    pub defaulted: u16,
    /// The storage failed to read or write (the defaults may not stick).
    pub failed: bool,
}

impl Report {
    /// Nothing to tell the operator.
    pub fn is_clean(&self) -> bool {
        self.defaulted == 0 && !self.failed
    }
}

impl core::fmt::Display for Report {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.defaulted > 0 {
            write!(
                f,
                "Stored settings: {} restored to defaults",
                self.defaulted
            )?;
        }
        if self.failed {
            if self.defaulted > 0 {
                f.write_str("; ")?;
            }
            f.write_str("settings storage error")?;
        }
        Ok(())
    }
}

/// Everything a load produced.
#[derive(Clone, Copy, Debug)]
pub struct Loaded {
    pub settings: Settings,
    pub offsets: Offsets,
    pub report: Report,
}

/// Settings and offsets over a key/value store, with a mirror of what the
/// store holds.
#[derive(Debug)]
pub struct Persist<S: Storage> {
    store: S,
    defaults: Settings,
    /// `$n` values as stored, in `table::numbers()` order; NaN: unknown.
    saved: [f32; SETTINGS],
    /// Offset vectors as stored (G54..G59.3, G28, G30); NaN: unknown.
    saved_offsets: [[f32; AXES]; OFFSET_RECORDS],
    /// Tool records as stored, as fingerprints ([`tool_print`]); 0:
    /// unknown. 4 bytes a tool instead of a 28-byte copy: the table is
    /// most of the mirror, and the F401's RAM is short.
    saved_tools: [u32; TOOLS],
}

/// The tool number in two exact halves (an `f32` holds 24 bits), then the
/// X, Y, Z offsets and the diameter.
fn tool_record(e: &ToolEntry) -> [f32; TOOL_VALUES] {
    let mut v = [0.0; TOOL_VALUES];
    v[0] = (e.number >> 16) as f32;
    v[1] = (e.number & 0xFFFF) as f32;
    v[2..2 + TOOL_AXES].copy_from_slice(&e.offset);
    v[TOOL_VALUES - 1] = e.diameter;
    v
}

/// FNV-1a over a record's bits, never 0 (the mirror's "unknown"). A
/// changed entry that kept its fingerprint (odds 2^-32) would go unsaved
/// until its next change.
fn tool_print(v: &[f32; TOOL_VALUES]) -> u32 {
    let mut h: u32 = 0x811C_9DC5;
    for x in v {
        for b in x.to_bits().to_le_bytes() {
            h = (h ^ u32::from(b)).wrapping_mul(0x0100_0193);
        }
    }
    h.max(1)
}

/// A stored tool record back to an entry; `None` if its number is not a
/// valid tool number (a damaged record).
fn tool_entry(v: &[f32; TOOL_VALUES]) -> Option<ToolEntry> {
    let half = |x: f32| (0.0..=65535.0).contains(&x) && libm::truncf(x) == x;
    let n = (v[0] as u32) << 16 | v[1] as u32;
    let valid = half(v[0]) && half(v[1]) && n <= crate::interp::tools::TOOL_MAX;
    let mut offset = [0.0; TOOL_AXES];
    offset.copy_from_slice(v.get(2..2 + TOOL_AXES)?);
    valid.then_some(ToolEntry {
        number: n,
        offset,
        diameter: v[TOOL_VALUES - 1],
    })
}

/// A record of the 16-tool firmware (`[number, length, diameter]`) as
/// today's record, so an update keeps the table.
fn old_tool(v: &[f32; 3]) -> [f32; TOOL_VALUES] {
    let n = if v[0] >= 0.0 && v[0] < 16_777_216.0 && libm::truncf(v[0]) == v[0] {
        v[0] as u32
    } else {
        u32::MAX
    };
    let mut r = [0.0; TOOL_VALUES];
    r[0] = (n >> 16) as f32;
    r[1] = (n & 0xFFFF) as f32;
    r[4] = v[1];
    r[TOOL_VALUES - 1] = v[2];
    r
}

fn vectors(o: &Offsets) -> impl Iterator<Item = &[f32; AXES]> {
    o.wcs.iter().chain([&o.g28, &o.g30])
}

fn vectors_mut(o: &mut Offsets) -> impl Iterator<Item = &mut [f32; AXES]> {
    o.wcs.iter_mut().chain([&mut o.g28, &mut o.g30])
}

fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits()
}

impl<S: Storage> Persist<S> {
    /// `defaults` are what a missing record and `$RST=$` give.
    pub fn new(store: S, defaults: Settings) -> Self {
        Persist {
            store,
            defaults,
            saved: [f32::NAN; SETTINGS],
            saved_offsets: [[f32::NAN; AXES]; OFFSET_RECORDS],
            saved_tools: [0; TOOLS],
        }
    }

    /// The defaults this store falls back to.
    pub fn defaults(&self) -> &Settings {
        &self.defaults
    }

    /// The store underneath.
    pub fn storage(&mut self) -> &mut S {
        &mut self.store
    }

    /// Reads `out.len()` values stored under `key`. `Ok(false)`: missing,
    /// damaged or of another format.
    fn read(&mut self, key: u16, out: &mut [f32]) -> Result<bool, S::Error> {
        Ok(self.read_upto(key, out)? == Some(out.len()))
    }

    /// Reads 1 to `out.len()` values stored under `key` into the front of
    /// `out` ([`record::decode_upto`]); `Ok(None)` as `read`'s `false`.
    fn read_upto(&mut self, key: u16, out: &mut [f32]) -> Result<Option<usize>, S::Error> {
        let mut buf = [0u8; MAX_RECORD];
        let Some(len) = self.store.load(key, &mut buf)? else {
            return Ok(None);
        };
        Ok(buf.get(..len).and_then(|rec| record::decode_upto(rec, out)))
    }

    /// Reads everything (boot, M501). Items that fall back to their
    /// defaults are written back; see the module docs.
    pub fn load(&mut self) -> Loaded {
        let mut report = Report::default();
        let mut settings = self.defaults;
        // `$0` is checked against `$201` (the step-rate ceiling), which is
        // read after it: a `$0` refused for the default `$201` gets a
        // second try once the stored `$201` is in.
        let mut again = None;
        for (i, n) in table::numbers().enumerate().take(SETTINGS) {
            let mut v = [0.0];
            let ok = match self.read(record::setting_key(n), &mut v) {
                Ok(found) => {
                    found && {
                        let r = settings.set(n, v[0]);
                        if r == Err(table::SettingError::StepRateCeiling) {
                            again = Some((i, n, v[0]));
                        }
                        r.is_ok()
                    }
                }
                Err(_) => {
                    report.failed = true;
                    false
                }
            };
            self.saved[i] = if ok { v[0] } else { f32::NAN };
            report.defaulted += u16::from(!ok);
        }
        if let Some((i, n, v)) = again {
            if n == 0 && settings.set(0, v).is_err() {
                // A pair older firmware took ($0=5 with $201=200000): the
                // drivers need the pulse width, a lower rate is only
                // slower, so `$201` comes down to the ceiling (and is
                // written back as a changed item).
                let ceiling = libm::floorf(crate::settings::ceiling::ceiling_hz(v));
                if settings
                    .set(201, ceiling.min(settings.max_step_rate_hz))
                    .is_ok()
                {
                    if let Some(k) = table::numbers().position(|m| m == 201) {
                        if let Some(s) = self.saved.get_mut(k) {
                            *s = f32::NAN;
                            report.defaulted += 1;
                        }
                    }
                }
            }
            if settings.set(n, v).is_ok() {
                self.saved[i] = v;
                report.defaulted -= 1;
            }
        }
        let mut offsets = Offsets::default();
        let mut shorter = false;
        for (k, o) in vectors_mut(&mut offsets).enumerate() {
            let mut v = [0.0; AXES];
            // k < OFFSET_RECORDS (11): the key stays below 1011. A vector
            // of fewer axes (a four-axis build's) is kept, the axes it
            // did not have at 0, and rewritten at this build's length.
            let held = match self.read_upto(OFFSETS_KEY + k as u16, &mut v) {
                Ok(held) => held,
                Err(_) => {
                    report.failed = true;
                    None
                }
            };
            let ok = held.is_some();
            if ok {
                *o = v;
            }
            let whole = held == Some(AXES);
            shorter |= ok && !whole;
            if let Some(s) = self.saved_offsets.get_mut(k) {
                *s = if whole { v } else { [f32::NAN; AXES] };
            }
            report.defaulted += u16::from(!ok);
        }
        for (k, e) in offsets.tools.iter_mut().enumerate() {
            let mut v = [0.0; TOOL_VALUES];
            // k < TOOLS (64): the key stays below 1164.
            let key = TOOLS_KEY + k as u16;
            let mut old = [0.0; 3];
            let (entry, migrated) = match self.read(key, &mut v) {
                Ok(true) => (tool_entry(&v), false),
                Ok(false) => match self.read(key, &mut old) {
                    Ok(true) => {
                        v = old_tool(&old);
                        (tool_entry(&v), true)
                    }
                    Ok(false) => (None, false),
                    Err(_) => {
                        report.failed = true;
                        (None, false)
                    }
                },
                Err(_) => {
                    report.failed = true;
                    (None, false)
                }
            };
            if let Some(t) = entry {
                *e = t;
            }
            if let Some(s) = self.saved_tools.get_mut(k) {
                // A migrated record is rewritten in today's format.
                *s = if entry.is_some() && !migrated {
                    tool_print(&v)
                } else {
                    0
                };
            }
            report.defaulted += u16::from(entry.is_none());
            if migrated && entry.is_some() {
                report.failed |= self.save_tool(k, e).is_err();
            }
        }
        if report.defaulted > 0 || shorter {
            let wrote = self
                .save_settings(&settings)
                .and(self.save_offsets(&offsets));
            report.failed |= wrote.is_err();
        }
        Loaded {
            settings,
            offsets,
            report,
        }
    }

    /// Writes the settings whose value differs from the stored one;
    /// returns how many records were written.
    pub fn save_settings(&mut self, s: &Settings) -> Result<u16, S::Error> {
        let mut written = 0;
        for (i, n) in table::numbers().enumerate().take(SETTINGS) {
            let (Some(v), Some(saved)) = (s.get(n), self.saved.get_mut(i)) else {
                continue;
            };
            if same(*saved, v) {
                continue;
            }
            let mut buf = [0u8; MAX_RECORD];
            let rec = record::encode(&[v], &mut buf);
            *saved = f32::NAN;
            self.store.store(record::setting_key(n), rec)?;
            *saved = v;
            written += 1;
        }
        Ok(written)
    }

    /// Writes the offset vectors and tool entries that differ from the
    /// stored ones.
    pub fn save_offsets(&mut self, o: &Offsets) -> Result<u16, S::Error> {
        let mut written = 0;
        for (k, e) in o.tools.iter().enumerate() {
            written += u16::from(self.save_tool(k, e)?);
        }
        for (k, (v, saved)) in vectors(o).zip(self.saved_offsets.iter_mut()).enumerate() {
            if v.iter().zip(saved.iter()).all(|(a, b)| same(*a, *b)) {
                continue;
            }
            let mut buf = [0u8; MAX_RECORD];
            let rec = record::encode(v, &mut buf);
            *saved = [f32::NAN; AXES];
            self.store.store(OFFSETS_KEY + k as u16, rec)?;
            *saved = *v;
            written += 1;
        }
        Ok(written)
    }

    /// Writes tool slot `k` if it differs from the stored record.
    fn save_tool(&mut self, k: usize, e: &ToolEntry) -> Result<bool, S::Error> {
        let v = tool_record(e);
        let print = tool_print(&v);
        let Some(saved) = self.saved_tools.get_mut(k) else {
            return Ok(false);
        };
        if *saved == print {
            return Ok(false);
        }
        *saved = 0;
        let mut buf = [0u8; MAX_RECORD];
        let rec = record::encode(&v, &mut buf);
        self.store.store(TOOLS_KEY + k as u16, rec)?;
        if let Some(s) = self.saved_tools.get_mut(k) {
            *s = print;
        }
        Ok(true)
    }
}

#[cfg(test)]
mod tests;
