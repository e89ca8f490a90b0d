//! A model device speaking the framed protocol (the same `Session` rules the
//! firmware uses) and a noisy relay, for deterministic reliability tests.
#![allow(dead_code)]

use protocol::client::mem::MemPipe;
use protocol::frame::{self, MAX_WIRE};
use protocol::{
    DeviceInfo, DeviceMsg, FrameDecoder, HostMsg, LineVerdict, Rt, Session, ShortText,
    PROTOCOL_VERSION,
};
use std::collections::VecDeque;
use std::io::{Read, Write};

mod rng;
pub use rng::Rng;

/// The device model: receives frames, judges lines with `Session`, queues
/// them in `capacity` slots, and "executes" them when told to.
#[derive(Debug)]
pub struct FakeDevice {
    pub io: MemPipe,
    dec: FrameDecoder,
    pub session: Session,
    pub queue: VecDeque<Vec<u8>>,
    pub capacity: usize,
    pub executed: Vec<Vec<u8>>,
    pub duplicates: usize,
    pub rejected: usize,
    pub bad_frames: usize,
    pub realtime: Vec<Rt>,
    /// Holding after the host vanished.
    pub held: bool,
}

impl FakeDevice {
    pub fn new(io: MemPipe, capacity: usize) -> Self {
        Self::with_session(io, capacity, Session::new())
    }

    pub fn with_session(io: MemPipe, capacity: usize, session: Session) -> Self {
        FakeDevice {
            io,
            dec: FrameDecoder::new(),
            session,
            queue: VecDeque::new(),
            capacity,
            executed: Vec::new(),
            duplicates: 0,
            rejected: 0,
            bad_frames: 0,
            realtime: Vec::new(),
            held: false,
        }
    }

    pub fn free(&self) -> u16 {
        (self.capacity - self.queue.len()) as u16
    }

    fn send(&mut self, msg: &DeviceMsg) {
        let mut buf = [0u8; MAX_WIRE];
        let n = frame::encode(msg, &mut buf).expect("device message fits");
        // A vanished host: the bytes go nowhere.
        let _ = self.io.write_all(&buf[..n]);
    }

    /// Handle everything received so far.
    pub fn pump(&mut self) {
        let mut buf = [0u8; 256];
        loop {
            let n = match self.io.read(&mut buf) {
                Ok(0) => {
                    // The host is gone: hold, keep the queue, wait.
                    self.held = true;
                    return;
                }
                Ok(n) => n,
                Err(_) => return,
            };
            for &b in &buf[..n] {
                match self.dec.push::<HostMsg>(b) {
                    Some(Ok(msg)) => self.handle(msg),
                    Some(Err(e)) => {
                        self.bad_frames += 1;
                        let m = self.session.on_bad_frame(e);
                        self.send(&m);
                    }
                    None => {}
                }
            }
        }
    }

    fn handle(&mut self, msg: HostMsg) {
        match msg {
            HostMsg::Hello { .. } => {
                let free = self.free();
                self.session.advertise(free);
                let info = DeviceInfo {
                    protocol: PROTOCOL_VERSION,
                    firmware: ShortText::try_from("0.1.0").unwrap_or_default(),
                    board: ShortText::try_from("model").unwrap_or_default(),
                    axes: 4,
                    line_slots: self.capacity as u16,
                    planner_blocks: 16,
                    rx_bytes: 128,
                    caps: 0,
                    next_seq: self.session.next_seq(),
                    credits: free,
                };
                self.held = false;
                self.send(&DeviceMsg::Welcome(info));
            }
            HostMsg::Line { seq, text } => {
                let (verdict, reply) = self.session.on_line(seq, self.free());
                match verdict {
                    LineVerdict::Execute => self.queue.push_back(text.to_vec()),
                    LineVerdict::Duplicate => self.duplicates += 1,
                    LineVerdict::Reject(_) => self.rejected += 1,
                }
                if let Some(r) = reply {
                    self.send(&r);
                }
            }
            HostMsg::Realtime(rt) => self.realtime.push(rt),
            _ => {}
        }
    }

    /// Run up to `n` queued lines, then tell the host about freed slots.
    pub fn execute(&mut self, n: usize) {
        if self.held {
            return;
        }
        for _ in 0..n {
            match self.queue.pop_front() {
                Some(l) => self.executed.push(l),
                None => break,
            }
        }
        if let Some(m) = self.session.refresh(self.free()) {
            self.send(&m);
        }
    }
}

/// Moves bytes between two pipes, flipping bits and dropping bytes at the
/// given rates (per million bytes) in each direction.
#[derive(Debug)]
pub struct Relay {
    pub host_side: MemPipe,
    pub device_side: MemPipe,
    pub rng: Rng,
    pub flip_ppm: u64,
    pub drop_ppm: u64,
    pub damaged: usize,
}

impl Relay {
    pub fn pump(&mut self) {
        let mut buf = [0u8; 97];
        for dir in 0..2 {
            loop {
                let (from, to) = if dir == 0 {
                    (&mut self.host_side, &mut self.device_side)
                } else {
                    (&mut self.device_side, &mut self.host_side)
                };
                let n = match from.read(&mut buf) {
                    Ok(n) if n > 0 => n,
                    _ => break,
                };
                let mut out = Vec::with_capacity(n);
                for &b in &buf[..n] {
                    if self.rng.chance(self.drop_ppm) {
                        self.damaged += 1;
                        continue;
                    }
                    if self.rng.chance(self.flip_ppm) {
                        self.damaged += 1;
                        out.push(b ^ (1 << self.rng.below(8)));
                    } else {
                        out.push(b);
                    }
                }
                let _ = to.write_all(&out);
            }
        }
    }
}

/// A job of `n` distinct G-code lines.
pub fn job(n: usize) -> Vec<Vec<u8>> {
    (0..n)
        .map(|i| format!("G1 X{}.{} Y{} F{}", i % 97, i % 10, i, 100 + i % 900).into_bytes())
        .collect()
}
