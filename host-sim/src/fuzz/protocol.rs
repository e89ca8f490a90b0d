//! `protocol_frames`: the frame decoder, message decoding and the encode /
//! decode round trip, the device's sequence and credit rules
//! (`protocol::session::Session`) against a model, and the host client fed
//! arbitrary device frames. The first byte picks the part.

use protocol::client::mem::MemPipe;
use protocol::client::Client;
use protocol::frame::{self, FrameDecoder, MAX_WIRE};
use protocol::msg::{DeviceInfo, DeviceMsg, HostMsg, LineText};
use protocol::session::{seq_distance, LineVerdict, Session};
use protocol::{Code, Rt};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::HashMap;
use std::io::{Read, Write};

use super::Bytes;

pub fn protocol_frames(data: &[u8]) {
    let mut b = Bytes::new(data);
    match b.u8() % 4 {
        0 => frames(b.rest()),
        1 => built(&mut b),
        2 => session(&mut b),
        _ => client(&mut b),
    }
}

/// A decoded message encodes, decodes and encodes again to the same bytes.
fn round_trip<T: Serialize + DeserializeOwned + core::fmt::Debug>(msg: &T) {
    let mut a = [0u8; MAX_WIRE];
    let Ok(n) = frame::encode(msg, &mut a) else {
        return; // too long to send: refused, never truncated
    };
    assert!(n >= 2 && a[n - 1] == 0, "frame not delimited: {msg:?}");
    assert!(!a[..n - 1].contains(&0), "0x00 inside a frame: {msg:?}");
    let mut c = a;
    let back: T =
        frame::decode(&mut c[..n - 1]).unwrap_or_else(|e| panic!("{msg:?} does not decode: {e:?}"));
    let mut d = [0u8; MAX_WIRE];
    let m = frame::encode(&back, &mut d).expect("re-encode");
    assert_eq!(a[..n], d[..m], "{msg:?} came back as {back:?}");
}

/// Raw bytes through both decoders.
fn frames(bytes: &[u8]) {
    let mut host = FrameDecoder::new();
    let mut dev = FrameDecoder::new();
    for &x in bytes {
        if let Some(Ok(m)) = host.push::<HostMsg>(x) {
            round_trip(&m);
        }
        if let Some(Ok(m)) = dev.push::<DeviceMsg>(x) {
            round_trip(&m);
        }
    }
}

const RTS: &[Rt] = &[
    Rt::SoftReset,
    Rt::StatusQuery,
    Rt::FeedHold,
    Rt::CycleStart,
    Rt::JogCancel,
];

fn line_text(b: &mut Bytes) -> LineText {
    LineText::from_slice(b.take(usize::MAX)).unwrap_or_default()
}

fn host_msg(b: &mut Bytes) -> HostMsg {
    match b.u8() % 7 {
        0 => HostMsg::Hello { version: b.u16() },
        1 => HostMsg::Line {
            seq: b.u32(),
            text: line_text(b),
        },
        2 => HostMsg::Realtime(b.pick(RTS)),
        3 => HostMsg::GetSetting { n: b.u16() },
        4 => HostMsg::SetSetting {
            n: b.u16(),
            value: f32::from_bits(b.u32()),
        },
        5 => HostMsg::ListSettings,
        _ => HostMsg::Bye,
    }
}

fn device_msg(b: &mut Bytes) -> DeviceMsg {
    match b.u8() % 4 {
        0 => DeviceMsg::Welcome(DeviceInfo {
            protocol: protocol::PROTOCOL_VERSION,
            firmware: Default::default(),
            board: Default::default(),
            axes: 4,
            line_slots: u16::from(b.u8() % 16),
            planner_blocks: 64,
            rx_bytes: 128,
            caps: 0,
            next_seq: b.u32(),
            credits: u16::from(b.u8() % 16),
        }),
        1 => DeviceMsg::Ack {
            seq: b.u32(),
            next: b.u32(),
            credits: u16::from(b.u8() % 16),
        },
        2 => DeviceMsg::Nak {
            expected: b.u32(),
            code: b.u16(),
        },
        _ => DeviceMsg::Error {
            seq: Some(b.u32()),
            line: None,
            code: b.u16(),
        },
    }
}

/// Messages built from the input: encode/decode, then with one byte hit.
fn built(b: &mut Bytes) {
    while !b.is_empty() {
        let m = host_msg(b);
        round_trip(&m);
        let mut w = [0u8; MAX_WIRE];
        if let Ok(n) = frame::encode(&m, &mut w) {
            let i = usize::from(b.u8()) % n;
            w[i] ^= b.u8() | 1;
            let mut dec = FrameDecoder::new();
            for &x in &w[..n] {
                if let Some(Ok(got)) = dec.push::<HostMsg>(x) {
                    round_trip(&got);
                }
            }
        }
    }
}

/// The device's sequence rules against a model.
fn session(b: &mut Bytes) {
    let start = b.u32();
    let mut s = Session::starting_at(start);
    let mut next = start;
    let mut executed: u32 = 0;
    while !b.is_empty() {
        let op = b.u8();
        let free = u16::from(b.u8() % 5);
        if op % 8 == 7 {
            if let Some(DeviceMsg::Ack {
                seq,
                next: n,
                credits,
            }) = s.refresh(free)
            {
                assert_eq!((seq, n, credits), (next.wrapping_sub(1), next, free));
            }
            continue;
        }
        let seq = match op % 4 {
            0 => next,
            1 => next.wrapping_sub(u32::from(b.u8())),
            2 => next.wrapping_add(u32::from(b.u8())),
            _ => b.u32(),
        };
        let (verdict, reply) = s.on_line(seq, free);
        let d = seq_distance(next, seq);
        match verdict {
            LineVerdict::Execute => {
                assert!(
                    d == 0 && free > 0,
                    "executed {seq} with next {next}, free {free}"
                );
                next = next.wrapping_add(1);
                executed += 1;
                assert!(
                    matches!(reply, Some(DeviceMsg::Ack { seq: a, next: n, credits })
                        if a == seq && n == next && credits == free - 1),
                    "{reply:?}"
                );
            }
            LineVerdict::Duplicate => {
                assert!(d < 0, "duplicate {seq} with next {next}");
                assert!(
                    matches!(reply, Some(DeviceMsg::Ack { seq: a, next: n, .. }) if a == seq && n == next)
                );
            }
            LineVerdict::Reject(_) => {
                assert!(
                    d > 0 || free == 0,
                    "refused {seq} with next {next}, free {free}"
                );
                match reply {
                    None => {}
                    Some(DeviceMsg::Nak { expected, .. }) => assert_eq!(expected, next),
                    Some(r) => panic!("refused line answered {r:?}"),
                }
            }
        }
        assert_eq!(s.next_seq(), next);
        assert_eq!(next.wrapping_sub(start), executed);
    }
}

/// The window a client must keep to once it applied `m`.
fn window_of(m: &DeviceMsg) -> Option<u32> {
    match m {
        DeviceMsg::Welcome(i) => Some(i.next_seq.wrapping_add(u32::from(i.credits))),
        DeviceMsg::Ack { next, credits, .. } => Some(next.wrapping_add(u32::from(*credits))),
        DeviceMsg::Nak { expected, code } if *code == Code::FlowOverrun.code() => Some(*expected),
        _ => None,
    }
}

/// Frames out of `pipe` (what the client put on the wire).
fn drain_host_frames(pipe: &mut MemPipe, dec: &mut FrameDecoder, out: &mut Vec<HostMsg>) {
    let mut buf = [0u8; 512];
    while let Ok(n @ 1..) = pipe.read(&mut buf) {
        for &x in &buf[..n] {
            if let Some(Ok(m)) = dec.push::<HostMsg>(x) {
                out.push(m);
            }
        }
    }
}

/// The host client against a device that says arbitrary things: every
/// line it puts on the wire is one it was given, under its number, and
/// inside a window some device message opened.
fn client(b: &mut Bytes) {
    let (host, mut dev) = MemPipe::pair();
    let mut c = Client::new(host);
    c.set_resync_after(None);
    c.begin().expect("begin");
    let mut sent: HashMap<u32, Vec<u8>> = HashMap::new();
    let mut limit: Option<u32> = None;
    let mut dec = FrameDecoder::new();
    let mut wire = Vec::new();
    let mut broken = false;
    while !b.is_empty() {
        match b.u8() % 3 {
            0 => {
                let m = device_msg(b);
                if let Some(l) = window_of(&m) {
                    limit = Some(l);
                }
                let mut w = [0u8; MAX_WIRE];
                let n = frame::encode(&m, &mut w).expect("encode");
                dev.write_all(&w[..n]).expect("write");
            }
            1 => {
                // Raw bytes, then a delimiter so the next frame stays whole;
                // a valid frame among them counts as sent.
                let raw = b.take(64);
                let mut d = FrameDecoder::new();
                for &x in raw.iter().chain(&[0]) {
                    if let Some(Ok(m)) = d.push::<DeviceMsg>(x) {
                        if let Some(l) = window_of(&m) {
                            limit = Some(l);
                        }
                    }
                }
                let _ = dev.write_all(raw);
                let _ = dev.write_all(&[0]);
            }
            _ => {
                if c.can_send() {
                    let text = b.take(40).to_vec();
                    let seq = c.send_line(&text).expect("send_line");
                    sent.insert(seq, text);
                }
            }
        }
        loop {
            match c.poll() {
                Ok(Some(_)) => {}
                Ok(None) => break,
                // It refused the device's state (version, lost session):
                // what it applied of that read is unknown from here.
                Err(_) => {
                    broken = true;
                    break;
                }
            }
        }
        drain_host_frames(&mut dev, &mut dec, &mut wire);
        for m in wire.drain(..) {
            if let HostMsg::Line { seq, text } = m {
                let given = sent.get(&seq);
                assert!(
                    given.is_some_and(|g| g[..] == text[..]),
                    "line {seq} was not given as sent"
                );
                let l = limit.expect("a line went out before any window");
                assert!(
                    broken || seq_distance(seq, l) > 0,
                    "line {seq} outside every window (end {l})"
                );
            }
        }
    }
}
