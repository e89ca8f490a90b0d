//! Persist over a RAM flash: defaults, round trips, dirty tracking,
//! validation on load, torn writes and wear.

use super::*;
use crate::seams::Storage;

/// The boards' geometry: two 16 KiB sectors.
type Board = RamFlash<{ 2 * 16384 }, 16384>;
/// Small pages so that a few hundred writes wrap the map many times.
type Small = RamFlash<8192, 4096>;

const ITEMS: u16 = (SETTINGS + OFFSET_RECORDS + TOOLS) as u16;

fn persist<F: embedded_storage::nor_flash::NorFlash>(flash: F) -> Persist<FlashMap<F>> {
    Persist::new(FlashMap::new(flash), Settings::default())
}

fn flash_of<F: embedded_storage::nor_flash::NorFlash + Clone>(p: &mut Persist<FlashMap<F>>) -> F {
    p.storage().flash().cloned().expect("map configured")
}

#[test]
fn setting_count_matches_the_table() {
    assert_eq!(table::numbers().count(), SETTINGS);
}

#[test]
fn fresh_flash_gives_defaults_once() {
    let mut p = persist(Board::new());
    let first = p.load();
    assert_eq!(first.settings, Settings::default());
    assert_eq!(first.offsets, Offsets::default());
    assert_eq!(first.report.defaulted, ITEMS);
    assert!(!first.report.failed);
    // The defaults were written back: the next boot has nothing to report.
    let mut again = persist(flash_of(&mut p));
    let second = again.load();
    assert!(second.report.is_clean(), "{:?}", second.report);
    assert_eq!(second.settings, Settings::default());
}

#[test]
fn saves_only_what_changed_and_reads_it_back() {
    let mut p = persist(Board::new());
    let loaded = p.load();
    let mut s = loaded.settings;
    assert_eq!(p.save_settings(&s).ok(), Some(0));
    s.set(110, 1234.0).expect("valid");
    s.set(22, 1.0).expect("valid");
    assert_eq!(p.save_settings(&s).ok(), Some(2));
    assert_eq!(p.save_settings(&s).ok(), Some(0));
    let mut o = loaded.offsets;
    o.wcs[1] = crate::pad([5.0, 0.0, -1.5, 0.0]);
    o.g28 = crate::pad([1.0, 2.0, 3.0, 4.0]);
    assert_eq!(p.save_offsets(&o).ok(), Some(2));

    let mut rebooted = persist(flash_of(&mut p));
    let back = rebooted.load();
    assert!(back.report.is_clean(), "{:?}", back.report);
    assert_eq!(back.settings.axes[0].max_rate, 1234.0);
    assert!(back.settings.homing_enable);
    assert_eq!(back.offsets, o);
}

#[test]
fn tool_table_round_trips_and_rejects_a_bad_number() {
    let mut p = persist(Board::new());
    let mut o = p.load().offsets;
    o.tools[0] = ToolEntry {
        number: 102,
        offset: [0.5, -1.0, 31.25],
        diameter: 6.35,
    };
    // The last slot, and the largest number (above 2^16: both halves).
    o.tools[TOOLS - 1] = ToolEntry {
        number: crate::interp::tools::TOOL_MAX,
        offset: [0.0, 0.0, -2.5],
        diameter: 0.0,
    };
    assert_eq!(p.save_offsets(&o).ok(), Some(2));
    assert_eq!(
        p.save_offsets(&o).ok(),
        Some(0),
        "unchanged: nothing written"
    );
    let mut rebooted = persist(flash_of(&mut p));
    let back = rebooted.load();
    assert!(back.report.is_clean(), "{:?}", back.report);
    assert_eq!(back.offsets.tools, o.tools);
    // A record whose tool number is not a whole number in range is damaged.
    let mut buf = [0u8; MAX_RECORD];
    rebooted
        .storage()
        .store(
            record::TOOLS_KEY,
            record::encode(&[0.0, 1.5, 0.0, 0.0, 1.0, 1.0], &mut buf),
        )
        .expect("store");
    let mut again = persist(flash_of(&mut rebooted));
    let third = again.load();
    assert_eq!(third.report.defaulted, 1);
    assert_eq!(third.offsets.tools[0], ToolEntry::EMPTY);
    assert_eq!(third.offsets.tools[TOOLS - 1], o.tools[TOOLS - 1]);
}

/// The 16-tool firmware stored `[number, length, diameter]`: an update
/// keeps those tools (length as the Z offset) and rewrites them in the
/// new form once.
#[test]
fn old_three_value_tool_records_are_migrated() {
    let mut p = persist(Board::new());
    p.load();
    let mut buf = [0u8; MAX_RECORD];
    p.storage()
        .store(
            record::TOOLS_KEY + 3,
            record::encode(&[7.0, 12.5, 3.0], &mut buf),
        )
        .expect("store");
    let mut q = persist(flash_of(&mut p));
    let back = q.load();
    let t = back.offsets.tools[3];
    assert_eq!((t.number, t.offset, t.diameter), (7, [0.0, 0.0, 12.5], 3.0));
    assert!(back.report.is_clean(), "{:?}", back.report);
    // Rewritten: the next boot reads it in today's format.
    let mut r = persist(flash_of(&mut q));
    assert_eq!(r.load().offsets.tools[3], t);
    assert_eq!(r.save_offsets(&back.offsets).ok(), Some(0));
}

/// A build that drove four axes stored offset vectors of four values: an
/// update keeps them (the axes they lacked at 0), rewrites them at this
/// build's length once, and a damaged one (a value not finite) still
/// falls back to its default.
#[test]
fn offset_vectors_of_fewer_axes_are_kept_and_rewritten() {
    let mut p = persist(Board::new());
    p.load();
    let mut buf = [0u8; MAX_RECORD];
    let g55 = record::OFFSETS_KEY + 1;
    let g28 = record::OFFSETS_KEY + crate::interp::WCS_COUNT as u16;
    let four = record::encode(&[5.0, -1.5, 2.0, 90.0], &mut buf).to_vec();
    p.storage().store(g55, &four).expect("store");
    let mut nan = record::encode(&[1.0; AXES], &mut buf).to_vec();
    nan[1..5].copy_from_slice(&f32::NAN.to_le_bytes());
    p.storage().store(g28, &nan).expect("store");
    let mut q = persist(flash_of(&mut p));
    let back = q.load();
    let mut want = [0.0; AXES];
    want[..4].copy_from_slice(&[5.0, -1.5, 2.0, 90.0]);
    assert_eq!(back.offsets.wcs[1], want);
    assert_eq!(back.offsets.g28, [0.0; AXES], "the damaged vector");
    assert_eq!(back.report.defaulted, 1, "{:?}", back.report);
    // Rewritten at this build's length: the next boot reads it whole and
    // has nothing to write.
    let mut r = persist(flash_of(&mut q));
    let again = r.load();
    assert!(again.report.is_clean(), "{:?}", again.report);
    assert_eq!(again.offsets.wcs[1], want);
    let mut whole = [0u8; MAX_RECORD];
    let len = r.storage().load(g55, &mut whole).expect("load");
    assert_eq!(len, Some(1 + 4 * AXES));
}

#[test]
fn values_set_would_refuse_fall_back_to_their_default() {
    let mut p = persist(Board::new());
    p.load();
    let mut buf = [0u8; MAX_RECORD];
    // $0 (pulse) above its range, $2 a mask with a bit past the last axis,
    // $1 in an unknown format, an offset with a NaN.
    let store = p.storage();
    store
        .store(0, record::encode(&[1000.0], &mut buf))
        .expect("store");
    store
        .store(2, record::encode(&[f32::from(1u16 << AXES)], &mut buf))
        .expect("store");
    store
        .store(1, &[record::FORMAT + 1, 0, 0, 0x80, 0x3F])
        .expect("store");
    let nan = record::encode(&crate::pad([0.0, f32::NAN]), &mut buf);
    store.store(OFFSETS_KEY, nan).expect("store");
    store
        .store(110, record::encode(&[777.0], &mut buf))
        .expect("store");

    let mut rebooted = persist(flash_of(&mut p));
    let back = rebooted.load();
    assert_eq!(back.report.defaulted, 4);
    let d = Settings::default();
    assert_eq!(back.settings.step_pulse_us, d.step_pulse_us);
    assert_eq!(back.settings.step_invert, d.step_invert);
    assert_eq!(back.settings.idle_delay_ms, d.idle_delay_ms);
    assert_eq!(back.offsets.wcs[0], [0.0; AXES]);
    // Good records next to bad ones still load.
    assert_eq!(back.settings.axes[0].max_rate, 777.0);
    // The defaults went back to flash: reported once.
    assert!(persist(flash_of(&mut rebooted)).load().report.is_clean());
}

#[test]
fn a_torn_write_keeps_the_previous_value() {
    // A setting's record is 10 bytes (5 of head, 5 of value): every cut
    // inside it leaves a torn record.
    for cut in [1, 3, 5, 7, 9] {
        let mut p = persist(Board::new());
        let mut s = p.load().settings;
        s.set(110, 1000.0).expect("valid");
        assert_eq!(p.save_settings(&s).ok(), Some(1));

        // The power goes `cut` bytes into the next record.
        let mut flash = flash_of(&mut p);
        flash.cut_power_after(cut);
        let mut torn = persist(flash);
        torn.load();
        s.set(110, 2000.0).expect("valid");
        assert!(torn.save_settings(&s).is_err(), "cut at {cut}");

        let mut flash = flash_of(&mut torn);
        flash.power_on();
        let mut rebooted = persist(flash);
        let back = rebooted.load();
        assert_eq!(back.settings.axes[0].max_rate, 1000.0, "cut at {cut}");
        assert!(!back.report.failed, "cut at {cut}: {:?}", back.report);
        // And the store still takes writes afterwards.
        s.set(110, 3000.0).expect("valid");
        assert_eq!(rebooted.save_settings(&s).ok(), Some(1), "cut at {cut}");
        let after = persist(flash_of(&mut rebooted)).load();
        assert_eq!(after.settings.axes[0].max_rate, 3000.0, "cut at {cut}");
    }
}

#[test]
fn many_saves_wrap_the_pages_without_losing_anything() {
    let mut p = persist(Small::new());
    let mut s = p.load().settings;
    let mut o = Offsets::default();
    o.wcs[8] = crate::pad([9.0, 8.0, 7.0, 6.0]);
    p.save_offsets(&o).expect("save");
    for i in 0..400u16 {
        s.set(110, 100.0 + f32::from(i)).expect("valid");
        p.save_settings(&s).expect("save");
    }
    let flash = flash_of(&mut p);
    // Pages were recycled, each about equally often.
    assert!(flash.erases >= 4, "erases {}", flash.erases);
    let back = persist(flash).load();
    assert!(back.report.is_clean(), "{:?}", back.report);
    assert_eq!(back.settings.axes[0].max_rate, 499.0);
    assert_eq!(back.settings, s);
    assert_eq!(back.offsets, o);
}

#[test]
fn a_flash_too_small_for_a_map_reports_failure() {
    let mut p = persist(RamFlash::<2048, 2048>::new());
    let loaded = p.load();
    assert!(loaded.report.failed);
    assert_eq!(loaded.settings, Settings::default());
}

/// A page move cut short at every byte: before the new page's header is
/// complete the old page stays current; after it, the new one. No key is
/// ever lost, and the store works again after power-up.
#[test]
fn an_interrupted_page_move_loses_nothing() {
    type F = RamFlash<4096, 2048>;
    // 4-byte values make 12-byte records: 170 of them fill a page exactly
    // (2048 - 8 bytes of header), so the 171st store moves pages.
    let mut full = FlashMap::new(F::new());
    for i in 0..170u32 {
        let key = (i % 3 + 1) as u16;
        full.store(key, &i.to_le_bytes()).expect("store");
    }
    let full = full.flash().cloned().expect("flash");
    let read = |m: &mut FlashMap<F>, key: u16| {
        let mut v = [0u8; 4];
        assert_eq!(m.load(key, &mut v).expect("load"), Some(4));
        u32::from_le_bytes(v)
    };
    // The move writes keys 1 and 3 (24 bytes), the new key 2 (12), then
    // the header (8): 44 bytes before the old page is erased.
    for cut in 0..=50 {
        let mut flash = full.clone();
        flash.cut_power_after(cut);
        let mut m = FlashMap::new(flash);
        let stored = m.store(2, &999u32.to_le_bytes());
        assert_eq!(stored.is_ok(), cut > 44, "cut at {cut}");
        let mut flash = m.flash().cloned().expect("flash");
        flash.power_on();
        let mut m = FlashMap::new(flash);
        assert_eq!(read(&mut m, 1), 168, "cut at {cut}");
        assert_eq!(read(&mut m, 3), 167, "cut at {cut}");
        let want = if cut >= 44 { 999 } else { 169 };
        assert_eq!(read(&mut m, 2), want, "cut at {cut}");
        // Power back: the next writes land (moving pages again if needed).
        for v in 0..200u32 {
            m.store(3, &v.to_le_bytes()).expect("store after power-up");
        }
        assert_eq!(read(&mut m, 3), 199, "cut at {cut}");
        assert_eq!(read(&mut m, 1), 168, "cut at {cut}");
    }
}

/// The map's index against a plain model: random keys and values, loads
/// between stores, page moves, more keys than the index holds, and a
/// fresh map over the same flash (which indexes from scratch) agreeing.
#[test]
fn the_index_reads_what_a_scan_reads() {
    let mut map = FlashMap::new(Small::new());
    let mut model = [None::<[u8; 4]>; 160];
    let mut x: u32 = 12345;
    for i in 0..3000u32 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        // Keys beyond the index's capacity after a while.
        let span = if i < 1500 { 40 } else { 160 };
        let key = (x % span) as usize;
        let v = i.to_le_bytes();
        map.store(key as u16, &v).expect("store");
        model[key] = Some(v);
        if i % 7 == 0 {
            let probe = ((x >> 8) % 160) as usize;
            let mut out = [0u8; 8];
            let got = map.load(probe as u16, &mut out).expect("load");
            assert_eq!(
                got.map(|n| &out[..n]),
                model[probe].as_ref().map(|v| &v[..])
            );
        }
    }
    let flash = map.flash().cloned().expect("flash");
    assert!(flash.erases >= 2, "the pages moved: {}", flash.erases);
    let mut fresh = FlashMap::new(flash);
    for (key, want) in model.iter().enumerate() {
        let mut a = [0u8; 8];
        let mut b = [0u8; 8];
        let got = map.load(key as u16, &mut a).expect("load");
        let again = fresh.load(key as u16, &mut b).expect("load");
        assert_eq!(
            got.map(|n| &a[..n]),
            want.as_ref().map(|v| &v[..]),
            "key {key}"
        );
        assert_eq!(
            again.map(|n| &b[..n]),
            want.as_ref().map(|v| &v[..]),
            "key {key}"
        );
    }
}

/// `$0` loads before `$201` and is checked against it (the one step-rate
/// ceiling, issue 28): a stored wide pulse with a matching low `$201`
/// comes back whole, and a pair older firmware took (`$0=5` with
/// `$201=200000`) keeps the pulse the drivers need and lowers `$201` to
/// its ceiling, written back.
#[test]
fn a_wide_pulse_survives_the_step_rate_ceiling_on_load() {
    use crate::settings::ceiling::ceiling_hz;
    let mut p = persist(Board::new());
    let mut s = p.load().settings;
    s.set(201, 90_000.0).expect("valid");
    s.set(0, 5.0).expect("valid with $201 at 90 kHz");
    p.save_settings(&s).expect("saved");
    let back = persist(flash_of(&mut p)).load();
    assert!(back.report.is_clean(), "{:?}", back.report);
    assert_eq!(back.settings.step_pulse_us, 5.0);
    assert_eq!(back.settings.max_step_rate_hz, 90_000.0);

    let mut p = persist(Board::new());
    let mut old = p.load().settings;
    old.step_pulse_us = 5.0;
    old.max_step_rate_hz = 200_000.0;
    p.save_settings(&old).expect("saved");
    let mut again = persist(flash_of(&mut p));
    let back = again.load();
    assert_eq!(back.settings.step_pulse_us, 5.0);
    assert_eq!(
        back.settings.max_step_rate_hz,
        libm::floorf(ceiling_hz(5.0))
    );
    assert_eq!(back.report.defaulted, 1, "{:?}", back.report);
    // Written back by the load: the next boot is clean.
    assert_eq!(again.save_settings(&back.settings).ok(), Some(0));
    let third = persist(flash_of(&mut again)).load();
    assert!(third.report.is_clean(), "{:?}", third.report);
}
