//! `cargo xtask sim FILE`: a job streamed through the virtual board, as
//! burin's own streamer sends it to the real one (framed protocol, line
//! credits) over an in-memory link at the host model's byte rate. The device session, the
//! executor and the stepper are the board's; this module is only the
//! sender and the operator: it sends lines as credits allow, resumes
//! program pauses (M0/M1: nobody is at a batch run to press cycle start),
//! stops at an alarm, and maps every reply back to its file line.
//!
//! So an offline run, `sim --pty` and the board agree by construction: a
//! line the device rejects is an error here too, with its file line, and
//! a program end (`M2`/`M30`) or a line that queues several non-motion
//! commands is handled by the same session code as on the board.

use std::io::{Read, Write};

use protocol::client::mem::MemPipe;
use protocol::client::{Client, ClientEvent};
use protocol::{DeviceMsg, Rt};

use crate::config::MachineConfig;
use crate::device_sim::VirtualDevice;
use crate::record::{Recorder, RunError, Summary};

/// Rounds without progress (no reply, step timer stopped) before the run
/// is declared stuck: 1000 s of virtual time at [`IDLE_STEP_S`].
const STUCK_ROUNDS: u32 = 100_000;
/// Virtual time one round covers when the device has nothing to say.
const IDLE_STEP_S: f64 = 0.01;

/// Stream `source` into a fresh virtual board on `config`; the recorder
/// gets the board's steps and commanded path.
pub fn run_file(config: &MachineConfig, source: &str, recorder: &mut dyn Recorder) -> Summary {
    run_file_watched(config, source, recorder, &mut |_| {})
}

/// What the board is doing after one round of [`run_file_watched`]: the
/// same facts its status report gives (`Ln:`), in virtual time, so a
/// streamer can turn the line a real board reports into time left.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Virtual time, in timer ticks.
    pub tick: u64,
    /// File line (1-based) of the segment the stepper runs; 0 before the
    /// first motion.
    pub line: u32,
    /// The stepper has motion or a dwell left: the board reports Run. False
    /// from the last step of a motion on (its rise computes the end), while
    /// the step timer still runs to that step's slot, up to a step interval
    /// longer.
    pub running: bool,
    /// Machine position in steps, as the status report's `MPos` gives it.
    pub steps: [i32; burin::AXES],
}

/// [`run_file`], calling `watch` after every round (at most
/// `IDLE_STEP_S` of virtual time apart, more often while the board talks).
pub fn run_file_watched(
    config: &MachineConfig,
    source: &str,
    recorder: &mut dyn Recorder,
    watch: &mut dyn FnMut(Progress),
) -> Summary {
    run_file_with(config, source, recorder, watch, &[])
}

/// [`run_file`] with realtime input (feed hold, cycle start, overrides,
/// reset) acting at given virtual times, seconds from the start, as the
/// panel buttons or realtime bytes would: holds and overrides on whole
/// jobs.
pub fn run_file_with_inputs(
    config: &MachineConfig,
    source: &str,
    recorder: &mut dyn Recorder,
    inputs: &[(f64, crate::engine::Input)],
) -> Summary {
    run_file_with(config, source, recorder, &mut |_| {}, inputs)
}

fn run_file_with(
    config: &MachineConfig,
    source: &str,
    recorder: &mut dyn Recorder,
    watch: &mut dyn FnMut(Progress),
    inputs: &[(f64, crate::engine::Input)],
) -> Summary {
    let mut dev = VirtualDevice::new(config, recorder);
    for (t, i) in inputs {
        dev.sim.input_at((t * f64::from(config.tick_hz)) as u64, *i);
    }
    // The power-up banner went out before the sender connected.
    let _ = dev.take_output();
    let (host, mut pipe) = MemPipe::pair();
    let mut client = Client::new(host);
    client.set_resync_after(None);
    let mut errors = Vec::new();
    let lines: Vec<&str> = source.lines().collect();
    let total = lines.len() as u32;
    if client.begin().is_err() {
        errors.push(stream_error(0, "could not open the framed session"));
    }
    let step = ((IDLE_STEP_S * f64::from(config.tick_hz)) as u64).max(1);
    // File line of each sequence number (in order: seq numbers grow by one).
    let mut seq_lines: Vec<(u32, u32)> = Vec::with_capacity(lines.len());
    let mut sent = 0usize;
    let mut msg = String::new();
    let mut alarm = false;
    let mut wire = Wire::new(config);
    let mut idle_rounds = 0u32;
    let mut buf = [0u8; 4096];
    loop {
        while !alarm && sent < lines.len() && client.can_send() {
            match client.send_line(lines[sent].as_bytes()) {
                Ok(seq) => seq_lines.push((seq, sent as u32 + 1)),
                Err(e) => errors.push(stream_error(sent as u32 + 1, &e.to_string())),
            }
            sent += 1;
        }
        while let Ok(n @ 1..) = pipe.read(&mut buf) {
            wire.send(&buf[..n], dev.sim.now());
        }
        wire.deliver(&mut dev);
        dev.sim.input_pending = sent < lines.len() || client.in_flight() > 0;
        let until = wire.next_arrival().unwrap_or(u64::MAX);
        let spoke = advance(&mut dev, step, until);
        let out = dev.take_output();
        if !out.is_empty() {
            let _ = pipe.write_all(&out);
        }
        while let Ok(Some(ev)) = client.poll() {
            match ev {
                ClientEvent::Device(DeviceMsg::Msg(m)) => {
                    // A full frame's text continues in the next one;
                    // otherwise an error belongs to the latest message.
                    if msg.len() != msg_cap() {
                        msg.clear();
                    }
                    msg.push_str(&m);
                }
                ClientEvent::Device(DeviceMsg::Error { seq, code, .. }) => {
                    let line = seq.map_or(0, |s| file_line(&seq_lines, s));
                    let text = std::mem::take(&mut msg);
                    errors.push(RunError {
                        line,
                        code,
                        message: clean(&text, code),
                    });
                }
                ClientEvent::Device(DeviceMsg::Alarm { code }) => {
                    alarm = true;
                    let text = std::mem::take(&mut msg);
                    errors.push(RunError {
                        line: file_line(&seq_lines, dev.sim.stepper.line()),
                        code,
                        message: format!("ALARM:{code} {}", clean(&text, code)),
                    });
                }
                _ => {}
            }
        }
        let seq = dev.sim.rt.running().1;
        watch(Progress {
            tick: dev.sim.now(),
            line: if seq == 0 {
                0
            } else {
                file_line(&seq_lines, seq)
            },
            running: !dev.sim.rt.stepper_idle(),
            steps: dev.sim.rt.position(),
        });
        // The operator presses cycle start at a program pause.
        if paused(&dev) {
            let _ = client.realtime(Rt::CycleStart);
        }
        let done = (alarm || sent == lines.len()) && client.in_flight() == 0 && dev.idle();
        if done {
            break;
        }
        // Progress: a reply, or the step timer running (moves and dwells
        // of any length); a board that does neither for this long is stuck.
        idle_rounds = if spoke || dev.sim.rt.stepping() {
            0
        } else {
            idle_rounds + 1
        };
        if idle_rounds > STUCK_ROUNDS {
            errors.push(stream_error(
                sent as u32,
                "the device stopped answering (stuck)",
            ));
            break;
        }
    }
    let wco = dev.controller.session.interp.wco();
    let mut summary = dev.sim.summary(total, wco);
    // The executor's errors reached the sender as replies (with their
    // lines); the engine's own copies would count them twice.
    errors.sort_by_key(|e| e.line);
    summary.errors = errors;
    let _ = dev.sim.finish(&summary);
    summary
}

/// Run the board until it has something to say, `step` of virtual time
/// has passed, or `until` (the next bytes arrive); returns whether it said
/// something.
fn advance(dev: &mut VirtualDevice, step: u64, until: u64) -> bool {
    let until = (dev.sim.now() + step).min(until.max(dev.sim.now()));
    loop {
        dev.poll();
        if !dev.tx.0.is_empty() {
            return true;
        }
        dev.sim.run_until(until);
        if !dev.sim.task_wanted() {
            dev.poll();
            return !dev.tx.0.is_empty();
        }
    }
}

/// The wire from the sender to the board: at the host model's byte rate
/// (`link_bytes_per_s`, 0: instant), bytes arrive one after the other; the
/// board takes them as its receive ring has room.
struct Wire {
    /// Ticks per byte ×2^16.
    byte_ticks_q16: u64,
    /// When the last byte sent so far is in.
    free_at: u64,
    /// Bytes on the wire with the tick their last byte arrives.
    wire: std::collections::VecDeque<(u64, Vec<u8>)>,
    /// Arrived, waiting for room in the board's ring.
    arrived: Vec<u8>,
}

impl Wire {
    fn new(cfg: &MachineConfig) -> Self {
        let rate = u64::from(cfg.host.link_bytes_per_s);
        Wire {
            byte_ticks_q16: (u64::from(cfg.tick_hz) << 16)
                .checked_div(rate)
                .unwrap_or(0),
            free_at: 0,
            wire: Default::default(),
            arrived: Vec::new(),
        }
    }

    fn send(&mut self, bytes: &[u8], now: u64) {
        if self.byte_ticks_q16 == 0 {
            self.arrived.extend_from_slice(bytes);
            return;
        }
        // One chunk per line, so each line arrives as its last byte does.
        for chunk in bytes.split_inclusive(|&b| b == 0 || b == b'\n') {
            let start = self.free_at.max(now);
            self.free_at = start + ((chunk.len() as u64 * self.byte_ticks_q16) >> 16);
            self.wire.push_back((self.free_at, chunk.to_vec()));
        }
    }

    fn deliver(&mut self, dev: &mut VirtualDevice) {
        let now = dev.sim.now();
        while self.wire.front().is_some_and(|(t, _)| *t <= now) {
            if let Some((_, b)) = self.wire.pop_front() {
                self.arrived.extend_from_slice(&b);
            }
        }
        let n = dev.receive(&self.arrived);
        self.arrived.drain(..n);
    }

    fn next_arrival(&self) -> Option<u64> {
        self.wire.front().map(|(t, _)| *t)
    }
}

/// Held at a program pause (or any hold) with the stepper stopped.
fn paused(dev: &VirtualDevice) -> bool {
    dev.sim.machine.state(&dev.sim.rt) == burin::executor::State::Hold && dev.sim.rt.stepper_idle()
}

/// Characters one `DeviceMsg::Msg` frame holds.
fn msg_cap() -> usize {
    protocol::msg::MsgText::new().capacity()
}

fn file_line(map: &[(u32, u32)], seq: u32) -> u32 {
    match map.binary_search_by_key(&seq, |&(s, _)| s) {
        Ok(i) => map[i].1,
        Err(_) => 0,
    }
}

fn clean(text: &str, code: u16) -> String {
    let t = text
        .trim()
        .trim_start_matches("[MSG:")
        .trim_end_matches(']')
        .trim();
    if t.is_empty() {
        format!("error {code}")
    } else {
        t.to_string()
    }
}

fn stream_error(line: u32, message: &str) -> RunError {
    RunError {
        line,
        code: 0,
        message: message.to_string(),
    }
}
