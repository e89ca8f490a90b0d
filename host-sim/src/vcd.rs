//! `--vcd FILE`: the step and direction pins as a Value Change Dump that
//! PulseView, GTKWave and Surfer open.
//!
//! Eight 1-bit wires, `X_step X_dir … A_step A_dir`, at their logical levels
//! (the invert masks are not applied: this shows what the core asked for).
//! A step pin rises at the event's tick and falls when the engine reports
//! its real fall (`Recorder::step_fall`: late step interrupts stretch
//! pulses), or `pulse_ticks` later from sources that report no falls; a
//! direction pin changes at the event's `dir_changed_tick`.
//!
//! Time: VCD only allows time units of 1, 10 or 100 s/ms/us/ns/ps/fs. The
//! writer picks the coarsest such unit that is an exact divisor of one tick
//! (1 MHz ticks → `1 us`, 16 MHz → `100 ps`). When none is (96 MHz: a tick is
//! 10.41 6̅ ns), it uses `1 ns` and rounds each edge to the nearest
//! nanosecond: edges keep their order and no interval is off by more than
//! 1 ns. PulseView turns the timescale into a sample rate, so a coarse unit
//! keeps its memory use sane; for long jobs use its downsampling option.

use std::collections::VecDeque;
use std::io::{self, Write};

use burin::{AXES, AXIS_NAMES};

use crate::record::{PinEvent, Recorder, RunInfo, Summary};

const BLOCK: usize = 1 << 16;

/// Maps timer ticks to VCD time units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimeScale {
    /// Femtoseconds per VCD time unit (a power of ten).
    pub unit_fs: u64,
    pub tick_hz: u32,
    /// Every tick lands on a whole unit.
    pub exact: bool,
}

impl TimeScale {
    pub fn for_tick_hz(tick_hz: u32) -> Self {
        let hz = u128::from(tick_hz.max(1));
        const FS_PER_S: u128 = 1_000_000_000_000_000;
        for k in (0..=15).rev() {
            let unit = 10u128.pow(k);
            // `is_multiple_of` is newer than the workspace's rust-version.
            #[allow(clippy::manual_is_multiple_of)]
            if FS_PER_S % (hz * unit) == 0 {
                return TimeScale {
                    unit_fs: unit as u64,
                    tick_hz,
                    exact: true,
                };
            }
        }
        let unit_fs = if tick_hz <= 1_000_000_000 {
            1_000_000
        } else {
            1_000
        };
        TimeScale {
            unit_fs,
            tick_hz,
            exact: false,
        }
    }

    /// The `$timescale` text, e.g. `1 ns`.
    pub fn text(&self) -> String {
        let units = ["fs", "ps", "ns", "us", "ms", "s"];
        let k = self.unit_fs.ilog10() as usize;
        let i = (k / 3).min(units.len() - 1);
        format!("{} {}", 10u64.pow((k - 3 * i) as u32), units[i])
    }

    /// Ticks to VCD units, rounded to nearest. Whole seconds are split off
    /// first so the common case stays in u64 (u128 division is slow, and
    /// this runs for every edge).
    pub fn to_units(&self, tick: u64) -> u64 {
        let hz = u64::from(self.tick_hz.max(1));
        let per_s = 1_000_000_000_000_000 / self.unit_fs;
        let (q, r) = (tick / hz, tick % hz);
        let frac = match r.checked_mul(per_s).and_then(|n| n.checked_add(hz / 2)) {
            Some(n) => n / hz,
            None => {
                ((u128::from(r) * u128::from(per_s) + u128::from(hz / 2)) / u128::from(hz)) as u64
            }
        };
        q.saturating_mul(per_s).saturating_add(frac)
    }
}

/// Wire identifiers are plain letters: `$` or `#` are legal VCD ids but
/// trip up readers that look for keywords and timestamps by first character.
fn step_id(axis: usize) -> u8 {
    b'a' + 2 * axis as u8
}
fn dir_id(axis: usize) -> u8 {
    b'a' + 2 * axis as u8 + 1
}

pub struct Vcd<W: Write> {
    out: Option<W>,
    buf: Vec<u8>,
    error: Option<io::Error>,
    scale: TimeScale,
    pulse_ticks: u64,
    started: bool,
    /// Tick of the last edge written (edges are written in time order).
    now: u64,
    /// Last timestamp line written, in VCD units.
    stamp: Option<u64>,
    step_level: u8,
    dir_level: u8,
    /// Falling edges still to come, in time order: (tick, axes).
    falls: VecDeque<(u64, u8)>,
}

impl<W: Write> Vcd<W> {
    /// The header is written by [`Recorder::start`], which knows the tick rate.
    pub fn new(out: W) -> Self {
        Vcd {
            out: Some(out),
            buf: Vec::with_capacity(BLOCK + 256),
            error: None,
            scale: TimeScale::for_tick_hz(1),
            pulse_ticks: 1,
            started: false,
            now: 0,
            stamp: None,
            step_level: 0,
            dir_level: 0,
            falls: VecDeque::new(),
        }
    }

    pub fn time_scale(&self) -> TimeScale {
        self.scale
    }

    fn header(&mut self, info: &RunInfo) {
        self.scale = TimeScale::for_tick_hz(info.tick_hz);
        self.pulse_ticks = u64::from(info.pulse_ticks.max(1));
        let mut h = String::new();
        h.push_str("$version burin host-sim ");
        h.push_str(env!("CARGO_PKG_VERSION"));
        h.push_str(" $end\n");
        h.push_str(&format!(
            "$comment step timer {} Hz, step pulse {} ticks, dir setup {} ticks; \
             logical levels (invert masks not applied); dir 1 = negative $end\n",
            info.tick_hz, info.pulse_ticks, info.dir_setup_ticks
        ));
        h.push_str(&format!("$timescale {} $end\n", self.scale.text()));
        h.push_str("$scope module burin $end\n");
        for (i, name) in AXIS_NAMES.iter().enumerate() {
            h.push_str(&format!(
                "$var wire 1 {} {name}_step $end\n",
                step_id(i) as char
            ));
            h.push_str(&format!(
                "$var wire 1 {} {name}_dir $end\n",
                dir_id(i) as char
            ));
        }
        h.push_str("$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n");
        for i in 0..AXES {
            h.push_str(&format!(
                "0{}\n0{}\n",
                step_id(i) as char,
                dir_id(i) as char
            ));
        }
        h.push_str("$end\n");
        self.buf.extend_from_slice(h.as_bytes());
        self.stamp = Some(0);
        self.started = true;
    }

    /// Moves the clock to `tick` (never backwards) and writes its timestamp.
    fn at(&mut self, tick: u64) {
        self.now = self.now.max(tick);
        let t = self.scale.to_units(self.now);
        if self.stamp != Some(t) {
            self.buf.push(b'#');
            self.buf
                .extend_from_slice(itoa::Buffer::new().format(t).as_bytes());
            self.buf.push(b'\n');
            self.stamp = Some(t);
        }
    }

    fn wire(&mut self, id: u8, high: bool) {
        self.buf.push(if high { b'1' } else { b'0' });
        self.buf.push(id);
        self.buf.push(b'\n');
    }

    /// Writes every falling edge due at or before `tick`.
    fn falls_until(&mut self, tick: u64) {
        while let Some(&(t, mask)) = self.falls.front() {
            if t > tick {
                break;
            }
            self.falls.pop_front();
            let mask = mask & self.step_level;
            if mask == 0 {
                continue;
            }
            self.at(t);
            for i in (0..AXES).filter(|i| mask & (1 << i) != 0) {
                self.wire(step_id(i), false);
            }
            self.step_level &= !mask;
        }
    }

    fn event(&mut self, ev: &PinEvent) {
        if ev.dir_mask != self.dir_level {
            let when = ev.dir_changed_tick.min(ev.tick);
            self.falls_until(when);
            self.at(when);
            let changed = ev.dir_mask ^ self.dir_level;
            for i in (0..AXES).filter(|i| changed & (1 << i) != 0) {
                self.wire(dir_id(i), ev.dir_mask & (1 << i) != 0);
            }
            self.dir_level = ev.dir_mask;
        }
        self.falls_until(ev.tick);
        let rise = ev.step_mask & !self.step_level;
        if ev.step_mask != 0 {
            // An axis still high from an earlier pulse: that pulse is
            // stretched to end with this one, so it must not fall early.
            let overlap = ev.step_mask & self.step_level;
            for f in self.falls.iter_mut() {
                f.1 &= !overlap;
            }
            self.at(ev.tick);
            for i in (0..AXES).filter(|i| rise & (1 << i) != 0) {
                self.wire(step_id(i), true);
            }
            self.step_level |= ev.step_mask;
            self.falls
                .push_back((ev.tick + self.pulse_ticks, ev.step_mask));
        }
        if self.buf.len() >= BLOCK {
            self.drain();
        }
    }

    fn drain(&mut self) {
        if self.error.is_none() {
            let r = self.out.as_mut().map_or(Ok(()), |o| o.write_all(&self.buf));
            if let Err(e) = r {
                self.error = Some(e);
            }
        }
        self.buf.clear();
    }

    /// Ends every pending pulse, writes a final timestamp and flushes.
    pub fn close(&mut self, end_tick: u64) -> io::Result<()> {
        self.falls_until(u64::MAX);
        self.at(end_tick.max(self.now + self.pulse_ticks));
        self.drain();
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.out.as_mut().map_or(Ok(()), |o| o.flush())
    }

    /// Gives the writer back, with everything buffered written to it (call
    /// `close` or `finish` first to end pending pulses).
    pub fn into_inner(mut self) -> W {
        self.drain();
        match self.out.take() {
            Some(out) => out,
            None => unreachable!("the writer is only taken here"),
        }
    }
}

impl<W: Write> Recorder for Vcd<W> {
    fn start(&mut self, info: &RunInfo) {
        self.header(info);
    }

    fn step_event(&mut self, ev: &PinEvent) {
        if self.started {
            self.event(ev);
        }
    }

    fn step_fall(&mut self, tick: u64, mask: u8) {
        // The pulses still queued to fall at `pulse_ticks` end later.
        for f in self.falls.iter_mut().filter(|f| f.1 & mask != 0) {
            f.0 = f.0.max(tick);
        }
    }

    fn finish(&mut self, summary: &Summary) -> io::Result<()> {
        if !self.started {
            return Err(io::Error::other("VCD recorder finished without start"));
        }
        let end = (summary.job_time_s.max(0.0) * f64::from(self.scale.tick_hz)) as u64;
        self.close(end)
    }
}

impl<W: Write> Drop for Vcd<W> {
    /// A run that ends without `finish` still leaves the edges written so
    /// far; errors here have nowhere to go.
    fn drop(&mut self) {
        if self.out.is_some() && !self.buf.is_empty() {
            self.drain();
            if let Some(o) = self.out.as_mut() {
                let _ = o.flush();
            }
        }
    }
}
