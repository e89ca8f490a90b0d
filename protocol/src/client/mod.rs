//! Host side of the framed protocol, over any byte transport.
//!
//! The client never blocks waiting for the device except in [`Client::connect`]:
//! everything else is driven by [`Client::poll`], which reads what is there,
//! updates acknowledgements and credits, resends after a `Nak`, and hands
//! back one event. That keeps it usable from a streamer's main loop, a test
//! that runs a fake device in the same thread, and a Ctrl-C handler alike.
//!
//! Reliability rules (see the crate docs): lines are kept until the device
//! acknowledges them; `Nak{expected}` rewinds sending to `expected`
//! (go-back-N); a lost `Ack` or credit refresh is recovered by re-sending
//! `Hello` after [`Client::set_resync_after`] of silence, whose `Welcome`
//! carries the device's `next_seq` and free slots.

pub mod grbl;
pub mod mem;

use crate::frame::{self, FrameDecoder, FrameError, MAX_WIRE};
use crate::msg::{DeviceInfo, DeviceMsg, HostMsg, LineText};
use crate::rt::Rt;
use crate::session::seq_distance;
use crate::{MAX_LINE, PROTOCOL_VERSION};
use std::collections::VecDeque;
use std::io::{self, ErrorKind, Read, Write};
use std::time::{Duration, Instant};

/// What went wrong on the host side.
#[derive(Debug)]
pub enum ClientError {
    /// The transport failed.
    Io(io::Error),
    /// The transport reached end-of-file: the device went away.
    Disconnected,
    /// No `Welcome` within the timeout.
    Timeout,
    /// `send_line` without a credit; poll and retry.
    NoCredit,
    /// The line is longer than [`MAX_LINE`] bytes.
    LineTooLong,
    /// Device speaks another protocol version.
    Version { device: u16 },
    /// After a reconnect the device's `next_seq` does not match the lines we
    /// still hold (it rebooted?): delivery can no longer be guaranteed.
    SessionLost { device_next: u32 },
}

impl From<io::Error> for ClientError {
    fn from(e: io::Error) -> Self {
        ClientError::Io(e)
    }
}

impl std::fmt::Display for ClientError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ClientError::Io(e) => write!(f, "link I/O error: {e}"),
            ClientError::Disconnected => write!(f, "device disconnected"),
            ClientError::Timeout => write!(f, "no answer to the handshake"),
            ClientError::NoCredit => write!(f, "no credit to send a line"),
            ClientError::LineTooLong => write!(f, "line longer than {MAX_LINE} bytes"),
            ClientError::Version { device } => write!(
                f,
                "device speaks protocol {device}, this host {PROTOCOL_VERSION}"
            ),
            ClientError::SessionLost { device_next } => write!(
                f,
                "device restarted its sequence at {device_next}: lines may be lost"
            ),
        }
    }
}

impl std::error::Error for ClientError {}

/// One thing the device said. `Ack`/`Nak`/`Welcome` are passed on after the
/// client has applied them, so a UI can show progress.
#[derive(Debug, Clone, PartialEq)]
pub enum ClientEvent {
    Device(DeviceMsg),
    /// A frame from the device was damaged and dropped.
    BadFrame(FrameError),
}

/// Counters for reports and tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClientStats {
    pub lines_sent: u64,
    pub lines_resent: u64,
    pub acks: u64,
    pub naks: u64,
    pub bad_frames: u64,
    pub resyncs: u64,
}

/// The host end of a framed session over transport `T`.
#[derive(Debug)]
pub struct Client<T> {
    io: T,
    dec: FrameDecoder,
    inbox: VecDeque<ClientEvent>,
    info: Option<DeviceInfo>,
    /// Lines not yet acknowledged, oldest first, with their sequence numbers.
    unacked: VecDeque<(u32, LineText)>,
    /// Index into `unacked` of the next line to put on the wire.
    send_idx: usize,
    /// Sequence number the next new line gets.
    next_seq: u32,
    /// Lines with `seq < window_end` (serially) may be on the wire.
    window_end: u32,
    last_progress: Instant,
    resync_after: Option<Duration>,
    stats: ClientStats,
}

impl<T: Read + Write> Client<T> {
    /// Wrap a transport. Nothing is sent until [`Client::begin`] / [`Client::connect`].
    pub fn new(io: T) -> Self {
        Client {
            io,
            dec: FrameDecoder::new(),
            inbox: VecDeque::new(),
            info: None,
            unacked: VecDeque::new(),
            send_idx: 0,
            next_seq: 0,
            window_end: 0,
            last_progress: Instant::now(),
            resync_after: Some(Duration::from_millis(1000)),
            stats: ClientStats::default(),
        }
    }

    /// Switch the port to framed mode and say hello (non-blocking).
    pub fn begin(&mut self) -> Result<(), ClientError> {
        self.io.write_all(&[0])?;
        self.send(&HostMsg::Hello {
            version: PROTOCOL_VERSION,
        })
    }

    /// [`Client::begin`], then poll until the `Welcome` (other events that
    /// arrive meanwhile stay queued for [`Client::poll`]).
    pub fn connect(&mut self, timeout: Duration) -> Result<DeviceInfo, ClientError> {
        self.begin()?;
        let start = Instant::now();
        loop {
            self.read_available()?;
            if let Some(info) = &self.info {
                return Ok(info.clone());
            }
            if start.elapsed() > timeout {
                return Err(ClientError::Timeout);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// After this long without progress while lines are outstanding (or no
    /// credits are left), re-send `Hello` to learn the device's state.
    /// `None` turns it off (deterministic tests).
    pub fn set_resync_after(&mut self, after: Option<Duration>) {
        self.resync_after = after;
    }

    /// The handshake answer, once it arrived.
    pub fn info(&self) -> Option<&DeviceInfo> {
        self.info.as_ref()
    }

    /// True when a new line may be sent now.
    pub fn can_send(&self) -> bool {
        self.info.is_some() && seq_distance(self.next_seq, self.window_end) > 0
    }

    /// Send one job line; returns its sequence number. The line is kept
    /// until acknowledged and resent as needed.
    pub fn send_line(&mut self, text: &[u8]) -> Result<u32, ClientError> {
        let text = LineText::from_slice(text).map_err(|_| ClientError::LineTooLong)?;
        if !self.can_send() {
            return Err(ClientError::NoCredit);
        }
        let seq = self.next_seq;
        self.next_seq = seq.wrapping_add(1);
        self.unacked.push_back((seq, text));
        self.pump()?;
        Ok(seq)
    }

    /// Send a realtime command (no sequence number, no queueing).
    ///
    /// A soft reset voids every line the device has not yet queued and
    /// empties its queue, so the client forgets its unacknowledged lines and
    /// asks for a fresh `Welcome` to learn the sequence number to go on with.
    pub fn realtime(&mut self, rt: Rt) -> Result<(), ClientError> {
        self.send(&HostMsg::Realtime(rt))?;
        if rt == Rt::SoftReset {
            self.unacked.clear();
            self.send_idx = 0;
            self.window_end = self.next_seq;
            self.resync()?;
        }
        Ok(())
    }

    /// Send any non-line message (settings requests, `Bye`).
    pub fn request(&mut self, msg: &HostMsg) -> Result<(), ClientError> {
        self.send(msg)
    }

    /// Ask the device for its state again (also done automatically, see
    /// [`Client::set_resync_after`]); use after a reconnect.
    pub fn resync(&mut self) -> Result<(), ClientError> {
        self.stats.resyncs += 1;
        self.last_progress = Instant::now();
        self.begin()
    }

    /// Lines sent (or waiting to be resent) but not acknowledged.
    pub fn in_flight(&self) -> usize {
        self.unacked.len()
    }

    /// Sequence number the next line will get.
    pub fn next_seq(&self) -> u32 {
        self.next_seq
    }

    pub fn stats(&self) -> ClientStats {
        self.stats
    }

    pub fn get_mut(&mut self) -> &mut T {
        &mut self.io
    }

    /// Swap in a new transport after the old one failed (port reopened),
    /// keep every unacknowledged line, and say hello again: the `Welcome`
    /// tells which of them the device already has. Returns the old one.
    pub fn reconnect(&mut self, io: T) -> Result<T, ClientError> {
        let old = std::mem::replace(&mut self.io, io);
        self.dec.reset();
        self.inbox.clear();
        self.send_idx = 0;
        self.window_end = self.unacked.front().map_or(self.next_seq, |(s, _)| *s);
        self.resync()?;
        Ok(old)
    }

    /// Give the transport back, e.g. to reconnect it and build a new client.
    pub fn into_inner(self) -> T {
        self.io
    }

    /// Read what is available, apply it, resend what may be resent, and
    /// return the next event if there is one.
    pub fn poll(&mut self) -> Result<Option<ClientEvent>, ClientError> {
        if self.inbox.is_empty() {
            self.read_available()?;
        }
        let stalled = !self.unacked.is_empty() || (self.info.is_some() && !self.can_send());
        if let Some(after) = self.resync_after {
            if stalled && self.last_progress.elapsed() > after {
                self.resync()?;
            }
        }
        self.pump()?;
        Ok(self.inbox.pop_front())
    }

    fn send(&mut self, msg: &HostMsg) -> Result<(), ClientError> {
        let mut buf = [0u8; MAX_WIRE];
        let n = frame::encode(msg, &mut buf).map_err(|_| ClientError::LineTooLong)?;
        self.io.write_all(&buf[..n])?;
        Ok(())
    }

    /// Put every line the window allows on the wire, oldest first.
    fn pump(&mut self) -> Result<(), ClientError> {
        while let Some((seq, text)) = self.unacked.get(self.send_idx) {
            if seq_distance(*seq, self.window_end) <= 0 {
                break;
            }
            let msg = HostMsg::Line {
                seq: *seq,
                text: text.clone(),
            };
            self.send(&msg)?;
            self.send_idx += 1;
            self.stats.lines_sent += 1;
        }
        Ok(())
    }

    fn read_available(&mut self) -> Result<(), ClientError> {
        let mut buf = [0u8; 512];
        let n = match self.io.read(&mut buf) {
            Ok(0) => return Err(ClientError::Disconnected),
            Ok(n) => n,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => 0,
            Err(e) if e.kind() == ErrorKind::Interrupted => 0,
            Err(e) => return Err(e.into()),
        };
        for &b in &buf[..n] {
            match self.dec.push::<DeviceMsg>(b) {
                Some(Ok(msg)) => {
                    self.apply(&msg)?;
                    self.inbox.push_back(ClientEvent::Device(msg));
                }
                // Text before the handshake (a `Grbl` banner printed as the
                // port opened) ends as one bad frame: not an error.
                Some(Err(_)) if self.info.is_none() => {}
                Some(Err(e)) => {
                    self.stats.bad_frames += 1;
                    self.inbox.push_back(ClientEvent::BadFrame(e));
                }
                None => {}
            }
        }
        Ok(())
    }

    /// Drop lines older than `next` (the device has them all) and note progress.
    fn retire_before(&mut self, next: u32) {
        let mut removed = 0;
        while let Some((seq, _)) = self.unacked.front() {
            if seq_distance(next, *seq) >= 0 {
                break;
            }
            self.unacked.pop_front();
            removed += 1;
        }
        if removed > 0 {
            self.send_idx = self.send_idx.saturating_sub(removed);
            self.last_progress = Instant::now();
        }
    }

    fn apply(&mut self, msg: &DeviceMsg) -> Result<(), ClientError> {
        match msg {
            DeviceMsg::Welcome(info) => {
                if info.protocol != PROTOCOL_VERSION {
                    return Err(ClientError::Version {
                        device: info.protocol,
                    });
                }
                match self.unacked.front() {
                    None => self.next_seq = info.next_seq,
                    Some((oldest, _)) => {
                        let ahead = seq_distance(*oldest, info.next_seq);
                        if ahead < 0 || ahead > self.unacked.len() as i64 {
                            return Err(ClientError::SessionLost {
                                device_next: info.next_seq,
                            });
                        }
                    }
                }
                self.retire_before(info.next_seq);
                self.send_idx = 0;
                self.window_end = info.next_seq.wrapping_add(u32::from(info.credits));
                self.last_progress = Instant::now();
                self.info = Some(info.clone());
            }
            DeviceMsg::Ack { next, credits, .. } => {
                self.stats.acks += 1;
                self.retire_before(*next);
                self.window_end = next.wrapping_add(u32::from(*credits));
                if *credits > 0 {
                    self.last_progress = Instant::now();
                }
            }
            DeviceMsg::Nak { expected, code } => {
                self.stats.naks += 1;
                self.retire_before(*expected);
                if *code == crate::Code::FlowOverrun.code() {
                    // Our credit count was wrong: wait for a refresh.
                    self.window_end = *expected;
                }
                // The device drops the rest of a broken burst silently, so
                // every Nak is news: resend everything not yet acknowledged.
                self.stats.lines_resent += self.send_idx as u64;
                self.send_idx = 0;
            }
            _ => {}
        }
        Ok(())
    }
}
