//! `device`: arbitrary byte streams into the virtual board (the board's own
//! link, session and controller; `receive` takes at most `room()` bytes, as
//! the USB endpoint does). The stream mixes text, realtime bytes (single
//! and their UTF-8 forms `C2 xx`), the switch to framed mode, frames, port
//! closes, and time passing.
//!
//! Invariants:
//! * `?` taken in text mode is answered with a `<…>` report within
//!   [`STATUS_BOUND_MS`] of virtual time;
//! * (gated, issue 15) an override byte in its UTF-8 form leaves nothing
//!   behind: a `$I` right after it is answered within [`STATUS_BOUND_MS`];
//! * after 0x18 in text mode the device answers `$I` within
//!   [`RESET_BOUND_MS`] and makes no step meanwhile (only `$I` was sent);
//! * nothing runs twice: the executor's log of line numbers never goes
//!   back within one session of the link;
//! * nothing acknowledged is lost: a framed line that was acked, of a kind
//!   that always queues a command, is in the executor's log at the end,
//!   unless a reset, port close, error or alarm came after its ack;
//! * no step leaves the box of the moves committed ([`super::envelope`]),
//!   at every step, whether or not the input ends idle.

use burin::link::LinkMode;
use protocol::frame::{self, FrameDecoder, MAX_WIRE};
use protocol::msg::{DeviceMsg, HostMsg, LineText};
use protocol::Rt;

use std::cell::RefCell;

use super::envelope::{Envelope, EnvelopeRec};
use super::Bytes;
use crate::config::HostModel;
use crate::device_sim::VirtualDevice;
use crate::record::Discard;

mod checks;

/// A `?` is answered within this much virtual time.
pub const STATUS_BOUND_MS: u64 = 10;
/// `$I` after a soft reset is answered within this much virtual time
/// (with [`super::CHECK_PROMPT_AFTER_RESET`]; else [`RESET_BOUND_SLOW_MS`]).
pub const RESET_BOUND_MS: u64 = 50;
/// What the device manages today after a reset during motion (issue 15):
/// it reads input again only at the stepper's next event, which at a slow
/// feed is up to the longest step period the timer allows (44.7 s).
pub const RESET_BOUND_SLOW_MS: u64 = 46_000;
/// At the end, time given to queued work before the lost-line check.
const DRAIN_MS: u64 = 3_000;

/// Lines the stream may use, and whether each always queues a command.
const LINES: &[(&str, bool)] = &[
    ("G1 X-9 Y-9.5 F1200", true),
    ("G0 X-11 Y-10", true),
    ("G4 P0.01", true),
    ("G2 X-10 Y-10 I0.5 J0 F600", true),
    ("G91 G1 X0.4 F900", true),
    ("G90", false),
    ("$X", false),
    ("$I", false),
    ("$G", false),
    ("M3 S100", false),
    ("(comment) G1 X-10", true),
];

const RT: &[u8] = &[
    b'?', b'!', b'~', 0x18, 0x85, 0x90, 0x91, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x99, 0x9A, 0x9B,
    0x9C, 0x9D,
];

const RT_FRAMES: &[Rt] = &[
    Rt::StatusQuery,
    Rt::FeedHold,
    Rt::CycleStart,
    Rt::SoftReset,
    Rt::JogCancel,
    Rt::FeedOvPlus10,
];

struct Harness<'d, 'r> {
    dev: &'d mut VirtualDevice<'r>,
    /// The motion envelope, told whenever the device is seen at rest.
    env: &'d RefCell<Envelope>,
    ms: u64,
    dec: FrameDecoder,
    /// Next sequence number the device asked for (from its acks).
    next_seq: u32,
    /// Acks of counting lines: (seq, op index when seen).
    acked: Vec<(u32, usize)>,
    /// Counting line frames sent, by sequence number, and the others.
    counting: Vec<u32>,
    other: Vec<u32>,
    /// Op index of the last event that may void acked lines.
    voided_at: usize,
    /// Something not from the dictionary went in: no lost-line check.
    wild: bool,
    op: usize,
    /// How much of the executor log the order check has read, the last
    /// line number in it, and how often the numbers went back.
    log_mark: usize,
    last_line: Option<u32>,
    drops: usize,
    /// Link mode changes so far.
    mode_changes: usize,
    /// The receive side's mode as last seen.
    framed: bool,
    /// Text with an N or O word went in: `Ln:` is a line's N word when it
    /// has one (issue 29) and an O-word loop runs its lines again (issue
    /// 30), so line numbers may go back by design from then on.
    labeled: bool,
}

impl Harness<'_, '_> {
    fn text_mode(&self) -> bool {
        !self.dev.framed() && self.dev.link_mode() == LinkMode::Text
    }

    /// Offer bytes; returns how many the device took.
    fn send(&mut self, bytes: &[u8]) -> usize {
        self.note_labels(bytes);
        let n = self.dev.receive(bytes);
        if trace() {
            eprintln!("  send {:?} -> {n}", String::from_utf8_lossy(bytes));
        }
        self.watch_mode();
        n
    }

    /// See [`Harness::labeled`]: any N or O in what is sent (a coarse test,
    /// it only ever turns the order check off for the rest of an input).
    fn note_labels(&mut self, bytes: &[u8]) {
        self.labeled |= bytes
            .iter()
            .any(|c| matches!(c.to_ascii_uppercase(), b'N' | b'O'));
    }

    /// Count a change of the receive side's mode (0x00, `Bye`, port close).
    fn watch_mode(&mut self) {
        let framed = self.dev.framed();
        if framed != self.framed {
            self.framed = framed;
            self.new_session();
        }
    }

    fn advance_ms(&mut self, ms: u64) {
        let t = self.dev.sim.now() + ms * self.ms;
        self.dev.advance_to(t);
        self.read_output();
    }

    /// Read frames out of the output (text in between fails its CRC).
    fn read_output(&mut self) {
        let out = std::mem::take(&mut self.dev.tx.0);
        for &x in &out {
            let m = self.dec.push::<DeviceMsg>(x);
            if trace() {
                if let Some(m) = &m {
                    eprintln!("  device: {m:?}");
                }
            }
            match m {
                Some(Ok(DeviceMsg::Ack { seq, next, .. })) => {
                    // Executed now (not a duplicate's ack), and every frame
                    // sent under this number was a counting line.
                    let executed = seq == self.next_seq && next == seq.wrapping_add(1);
                    if executed && self.counting.contains(&seq) && !self.other.contains(&seq) {
                        self.acked.push((seq, self.op));
                    }
                    self.next_seq = next;
                }
                Some(Ok(DeviceMsg::Welcome(i))) => self.next_seq = i.next_seq,
                Some(Ok(DeviceMsg::Error { seq, .. })) => {
                    // A line that failed is not lost (its ack may come later:
                    // a credit refresh looks the same).
                    self.other.extend(seq);
                    self.voided_at = self.op
                }
                Some(Ok(DeviceMsg::Alarm { .. })) => self.voided_at = self.op,
                _ => {}
            }
        }
        // Give the buffer back: no allocation on the next round.
        let mut out = out;
        out.clear();
        if self.dev.tx.0.is_empty() {
            self.dev.tx.0 = out;
        }
        self.watch_mode();
        self.check_log_order();
    }

    /// Line numbers never go back, except once per change of link mode
    /// (text lines and framed sequence numbers are counted apart, and
    /// lines of the old mode may still be queued at the change).
    fn check_log_order(&mut self) {
        let log = self.dev.log.as_deref().unwrap_or(&[]);
        // Line 0: the session's own commands (the ClearAlarm after its own
        // flush), not a line of input.
        for &n in log.get(self.log_mark..).unwrap_or(&[]) {
            if n == 0 {
                continue;
            }
            if !self.labeled {
                self.drops += usize::from(self.last_line.is_some_and(|l| n < l));
            }
            self.last_line = Some(n);
        }
        self.log_mark = log.len();
        if self.drops > self.mode_changes {
            let tail = &log[log.len().saturating_sub(24)..];
            panic!(
                "a line ran again or out of order: {} drops in line numbers, {} mode \
                 changes (op {}, log {tail:?})",
                self.drops, self.mode_changes, self.op
            );
        }
    }

    /// A change of link mode (0x00 switch, `Bye`, port close).
    fn new_session(&mut self) {
        self.mode_changes += 1;
        self.voided_at = self.op;
    }

    fn frame(&mut self, msg: &HostMsg) {
        let mut w = [0u8; MAX_WIRE];
        if let Ok(n) = frame::encode(msg, &mut w) {
            self.send(&w[..n]);
        }
    }

    fn line(&mut self, b: &mut Bytes) {
        let (text, counts) = b.pick(LINES);
        if self.text_mode() {
            self.send(text.as_bytes());
            self.send(b"\n");
            return;
        }
        let seq = match b.u8() % 4 {
            0 => b.u32(),
            1 => self.next_seq.wrapping_sub(1),
            _ => self.next_seq,
        };
        if counts {
            self.counting.push(seq);
        } else {
            self.other.push(seq);
            self.voided_at = self.op;
        }
        if trace() {
            eprintln!("  line frame {seq} {text:?}");
        }
        self.note_labels(text.as_bytes());
        let text = LineText::from_slice(text.as_bytes()).unwrap_or_default();
        self.frame(&HostMsg::Line { seq, text });
    }

    fn step(&mut self, b: &mut Bytes) {
        self.op += 1;
        let op = b.u8() % 12;
        if trace() {
            eprintln!(
                "op {} kind {op} at {} ms, framed {}, next {}",
                self.op,
                self.dev.sim.now() / self.ms,
                self.dev.framed(),
                self.next_seq
            );
        }
        match op {
            0 => {
                self.wild = true;
                let t = b.take(64);
                let n = self.send(t);
                if t[..n].contains(&0) {
                    // A mode switch: line numbers are sequence numbers now.
                    self.new_session();
                }
            }
            1 | 2 => self.line(b),
            3 => {
                let r = b.pick(RT);
                if self.send(&[r]) == 1 && (r == 0x18 || r == 0x85) {
                    self.voided_at = self.op;
                }
            }
            4 => {
                // UTF-8 form of a realtime byte (C2 80..=C2 BF).
                let r = 0x80 | b.u8() & 0x3F;
                self.voided_at = self.op;
                self.utf8_realtime(r);
            }
            5 => {
                self.send(&[0]);
                self.new_session();
            }
            6 => {
                let rt = b.pick(RT_FRAMES);
                if matches!(rt, Rt::SoftReset | Rt::JogCancel) {
                    self.voided_at = self.op;
                }
                self.frame(&HostMsg::Realtime(rt));
            }
            7 => {
                let m = match b.u8() % 3 {
                    0 => HostMsg::Hello { version: 1 },
                    1 => HostMsg::Bye,
                    _ => HostMsg::ListSettings,
                };
                self.frame(&m);
                self.new_session();
            }
            8 => {
                self.dev.port_closed();
                self.new_session();
                if b.u8() & 1 == 0 {
                    self.dev.port_opened();
                }
            }
            9 => self.status_check(),
            10 => self.reset_check(),
            _ => {
                let ms = u64::from(b.u8() % 40);
                self.advance_ms(ms);
            }
        }
        self.read_output();
        if self.dev.idle() {
            self.env.borrow_mut().settle(self.dev.position_steps());
        }
    }

    /// Let queued work finish, then check no acked counting line was lost.
    fn finish(&mut self) {
        self.op += 1;
        let to_check = self
            .acked
            .iter()
            .any(|&(s, at)| at > self.voided_at && !self.other.contains(&s));
        if self.wild || !to_check {
            return;
        }
        if self.text_mode() {
            self.send(b"~");
        } else {
            self.frame(&HostMsg::Realtime(Rt::CycleStart));
        }
        for _ in 0..DRAIN_MS / 10 {
            self.advance_ms(10);
            if self.dev.idle() {
                break;
            }
        }
        if self.wild || !self.dev.idle() {
            return;
        }
        let log = self.dev.log.as_deref().unwrap_or(&[]);
        for &(seq, at) in &self.acked {
            if at > self.voided_at && !self.other.contains(&seq) {
                assert!(
                    log.contains(&seq),
                    "line {seq} was acked (op {at}) but never ran"
                );
            }
        }
    }
}

/// `BURIN_FUZZ_TRACE=1`: print each op (to read a failing input).
fn trace() -> bool {
    static T: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *T.get_or_init(|| std::env::var_os("BURIN_FUZZ_TRACE").is_some())
}

/// The settings flash as the first power-up on erased flash leaves it.
/// Every input starts from a copy: that first boot writes all 59 records
/// (a fifth of an input's time), and it is the same for every input.
fn booted_flash(cfg: &crate::config::MachineConfig) -> crate::device_sim::SimFlash {
    static FLASH: std::sync::OnceLock<crate::device_sim::SimFlash> = std::sync::OnceLock::new();
    FLASH
        .get_or_init(|| {
            let mut rec = Discard;
            VirtualDevice::new(cfg, &mut rec).flash()
        })
        .clone()
}

pub fn device(data: &[u8]) {
    let mut cfg = super::executor::small_machine(false, false);
    cfg.host = HostModel::INSTANT;
    cfg.start_position_mm = burin::pad([-10.0, -10.0, -1.0, 0.0]);
    let env = RefCell::new(Envelope::new(cfg.settings.axes.map(|a| a.steps_per_mm)));
    let mut rec = EnvelopeRec(&env);
    let mut dev = VirtualDevice::with_flash(&cfg, &mut rec, booted_flash(&cfg));
    env.borrow_mut().settle(dev.position_steps());
    dev.log = Some(Vec::new());
    dev.tx.0.clear();
    let mut h = Harness {
        dev: &mut dev,
        env: &env,
        ms: u64::from(cfg.tick_hz) / 1000,
        dec: FrameDecoder::new(),
        next_seq: 1,
        acked: Vec::new(),
        counting: Vec::new(),
        other: Vec::new(),
        voided_at: 0,
        wild: false,
        op: 0,
        log_mark: 0,
        last_line: None,
        drops: 0,
        labeled: false,
        mode_changes: 0,
        framed: false,
    };
    let mut b = Bytes::new(data);
    while !b.is_empty() {
        h.step(&mut b);
    }
    h.finish();
}
