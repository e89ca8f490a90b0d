//! Framed mode through the firmware link, and the whole path host client ->
//! noisy wire -> link (random 1..64-byte chunks) -> Session -> queue: every
//! acknowledged line executes exactly once, in order.

use crate::link_common;

use burin::link::{encode_reply, FramedAction, FramedPort, Link, LinkMode};
use link_common::{drain, own, rts, run_chunks, Ev, Outcome, Rng};
use proptest::prelude::*;
use protocol::client::mem::MemPipe;
use protocol::client::Client;
use protocol::frame::{self, MAX_WIRE};
use protocol::{DeviceInfo, DeviceMsg, FrameError, HostMsg, LineText, Rt, ShortText};
use std::collections::VecDeque;
use std::io::{Read, Write};

fn enc(m: &HostMsg) -> Vec<u8> {
    let mut b = [0u8; MAX_WIRE];
    let n = frame::encode(m, &mut b).expect("encode");
    b[..n].to_vec()
}

fn line(seq: u32, t: &[u8]) -> HostMsg {
    HostMsg::Line {
        seq,
        text: LineText::from_slice(t).expect("short"),
    }
}

fn sample() -> (Vec<u8>, Outcome) {
    let mut s = b"G0 X1\n\0".to_vec();
    let mut events = vec![Ev::Line(b"G0 X1".to_vec()), Ev::Mode(LinkMode::Framed)];
    let msgs = [
        HostMsg::Hello { version: 1 },
        line(
            1,
            b"G1 X5 ? ! ~ \x18 \x85 \x91 (realtime bytes are data here)",
        ),
        line(2, &[0u8, 1, 2, 0, 0xFF]),
        HostMsg::ListSettings,
    ];
    for m in &msgs {
        s.extend(enc(m));
        events.push(Ev::Frame(m.clone()));
    }
    s.extend(enc(&HostMsg::Realtime(Rt::FeedHold)));
    let mut bad = enc(&line(3, b"G1 X6"));
    bad[4] ^= 0x10;
    s.extend(bad);
    events.push(Ev::BadFrame(FrameError::Crc));
    s.extend(enc(&HostMsg::Realtime(Rt::StatusQuery)));
    s.extend(enc(&HostMsg::Bye));
    events.push(Ev::Frame(HostMsg::Bye));
    s.extend_from_slice(b"?G0 X0\n");
    events.push(Ev::Line(b"G0 X0".to_vec()));
    (
        s,
        Outcome {
            events,
            realtime: rts(&[Rt::FeedHold, Rt::StatusQuery]),
        },
    )
}

#[test]
fn framed_sample_in_every_chunking() {
    let (bytes, want) = sample();
    assert_eq!(run_chunks(&bytes, [usize::MAX]), want);
    let mut runs = 0;
    for size in 1..=64 {
        for first in 1..=size {
            let sizes = std::iter::once(first).chain(std::iter::repeat(size));
            assert_eq!(run_chunks(&bytes, sizes), want, "size {size} first {first}");
            runs += 1;
        }
    }
    for cut in 1..bytes.len() {
        assert_eq!(run_chunks(&bytes, [cut, usize::MAX]), want, "cut {cut}");
        runs += 1;
    }
    println!(
        "framed split runs: {runs} over a {}-byte stream",
        bytes.len()
    );
}

#[test]
fn every_bit_flip_of_line_and_realtime_frames_is_refused() {
    let mut count = 0;
    for m in [line(9, b"G1 X1 Y2 F3000"), HostMsg::Realtime(Rt::SoftReset)] {
        let good = enc(&m);
        for i in 0..good.len() {
            for bit in 0..8 {
                let mut bytes = vec![0u8];
                bytes.extend(&good);
                bytes[1 + i] ^= 1 << bit;
                bytes.push(0);
                let out = run_chunks(&bytes, [7; 100]);
                assert!(out.realtime.is_empty(), "no realtime from a damaged frame");
                assert!(
                    out.events.iter().all(|e| !matches!(e, Ev::Frame(_))),
                    "damaged frame decoded: byte {i} bit {bit}"
                );
                assert!(out.events.iter().any(|e| matches!(e, Ev::BadFrame(_))));
                count += 1;
            }
        }
    }
    println!("framed bit flips through the link: {count}, all refused");
}

/// The device side: the firmware link + FramedPort + a queue of `cap` slots.
struct Dev {
    io: MemPipe,
    link: Link,
    port: FramedPort,
    queue: VecDeque<Vec<u8>>,
    cap: usize,
    executed: Vec<Vec<u8>>,
    rng: Rng,
}

impl Dev {
    fn send(&mut self, m: &DeviceMsg) {
        let mut b = [0u8; MAX_WIRE];
        let bytes = encode_reply(m, &mut b);
        assert!(!bytes.is_empty());
        let _ = self.io.write_all(bytes);
    }

    fn pump(&mut self) {
        let mut buf = [0u8; 64];
        loop {
            let want = (1 + self.rng.below(64)).min(self.link.room());
            match self.io.read(&mut buf[..want]) {
                Ok(n) if n > 0 => self.link.feed(&buf[..n]),
                _ => break,
            }
            if self.link.take_realtime().contains(Rt::SoftReset) {
                // Abort: the queue goes; the link already dropped the input
                // that came before the reset.
                self.queue.clear();
            }
            while let Some(ev) = self.link.poll().map(own) {
                self.handle(ev);
            }
        }
    }

    fn handle(&mut self, ev: Ev) {
        let free = (self.cap - self.queue.len()) as u16;
        let info = DeviceInfo {
            protocol: protocol::PROTOCOL_VERSION,
            firmware: ShortText::try_from(burin::VERSION).unwrap_or_default(),
            board: ShortText::try_from("test").unwrap_or_default(),
            axes: 4,
            line_slots: self.cap as u16,
            planner_blocks: 16,
            rx_bytes: 128,
            caps: 0,
            next_seq: 0,
            credits: 0,
        };
        let mut replies = Vec::new();
        let mut out = |m: &DeviceMsg| replies.push(m.clone());
        match ev {
            Ev::Frame(msg) => {
                if let Some(FramedAction::Execute { text, .. }) =
                    self.port.on_frame(msg, free, &info, &mut out)
                {
                    self.queue.push_back(text.to_vec());
                }
            }
            Ev::BadFrame(e) => self.port.on_bad_frame(e, &mut out),
            _ => {}
        }
        for r in &replies {
            self.send(r);
        }
    }

    fn execute(&mut self) {
        if let Some(l) = self.queue.pop_front() {
            self.executed.push(l);
        }
        let mut replies = Vec::new();
        self.port
            .refresh((self.cap - self.queue.len()) as u16, &mut |m| {
                replies.push(m.clone())
            });
        for r in &replies {
            self.send(r);
        }
    }
}

/// Copy bytes between pipes, flipping one bit in about 1 of `one_in` bytes.
fn relay(from: &mut MemPipe, to: &mut MemPipe, rng: &mut Rng, one_in: usize) -> usize {
    let mut buf = [0u8; 256];
    let mut damaged = 0;
    while let Ok(n @ 1..) = from.read(&mut buf) {
        for b in &mut buf[..n] {
            if one_in > 0 && rng.below(one_in) == 0 {
                *b ^= 1 << rng.below(8);
                damaged += 1;
            }
        }
        let _ = to.write_all(&buf[..n]);
    }
    damaged
}

fn stream_job(seed: u64, one_in: usize, lines: &[Vec<u8>]) -> usize {
    let (host, mut wire_h) = MemPipe::pair();
    let (mut wire_d, dev_io) = MemPipe::pair();
    let mut rng = Rng(seed);
    let mut dev = Dev {
        io: dev_io,
        link: Link::new(),
        port: FramedPort::new(),
        queue: VecDeque::new(),
        cap: 5,
        executed: Vec::new(),
        rng: Rng(seed ^ 0xABCD),
    };
    let mut client = Client::new(host);
    client.set_resync_after(None);
    client.begin().expect("hello");
    let (mut next, mut idle, mut last, mut damaged) = (0, 0, (0, 0), 0);
    for _ in 0..400_000 {
        while next < lines.len() && client.can_send() {
            client.send_line(&lines[next]).expect("send");
            next += 1;
        }
        damaged += relay(&mut wire_h, &mut wire_d, &mut rng, one_in);
        dev.pump();
        dev.execute();
        damaged += relay(&mut wire_d, &mut wire_h, &mut rng, one_in);
        while client.poll().expect("poll").is_some() {}
        assert!(
            lines.starts_with(&dev.executed),
            "duplicate or reordered line"
        );
        if next == lines.len() && client.in_flight() == 0 && dev.queue.is_empty() {
            assert_eq!(dev.executed, lines);
            return damaged;
        }
        let now = (dev.executed.len(), client.in_flight());
        idle = if now == last { idle + 1 } else { 0 };
        last = now;
        if idle > 30 {
            client.resync().expect("resync");
            idle = 0;
        }
    }
    panic!(
        "seed {seed}: executed {}/{}",
        dev.executed.len(),
        lines.len()
    );
}

#[test]
fn client_to_firmware_link_exactly_once_clean_and_noisy() {
    let lines: Vec<Vec<u8>> = (0..400)
        .map(|i| format!("G1 X{} Y{} F{}", i % 50, i, 500 + i).into_bytes())
        .collect();
    assert_eq!(stream_job(1, 0, &lines), 0);
    let mut damaged = 0;
    for seed in 2..22 {
        damaged += stream_job(seed * 104_729, 700, &lines);
    }
    assert!(damaged > 100);
    println!("client->link: 20 noisy runs x 400 lines, {damaged} bytes damaged, all exact");
}

static CASES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

proptest! {
    #![proptest_config(ProptestConfig { cases: 5_000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Noise in framed mode: no panic, nothing but typed results, and after
    /// a delimiter a good frame still decodes.
    #[test]
    fn framed_noise_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let mut all = vec![0u8];
        all.extend(&bytes);
        all.push(0);
        let good = line(1, b"G0 X1");
        all.extend(enc(&good));
        let mut link = Link::new();
        let mut out = Outcome::default();
        for chunk in all.chunks(61) {
            link.feed(chunk);
            drain(&mut link, &mut out);
        }
        // Noise may contain a `Bye`-looking frame only with a valid CRC;
        // otherwise the final frame arrives intact.
        if link.mode() == LinkMode::Framed {
            prop_assert_eq!(out.events.last(), Some(&Ev::Frame(good)));
        }
        let n = CASES.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if n == 5_000 { println!("framed noise: {n} cases"); }
    }
}

#[test]
fn port_closed_mid_job_then_reopened_executes_nothing_twice() {
    let lines: Vec<Vec<u8>> = (0..200)
        .map(|i| format!("G1 X{i} F900").into_bytes())
        .collect();
    let (host, dev_io) = MemPipe::pair();
    let mut dev = Dev {
        io: dev_io,
        link: Link::new(),
        port: FramedPort::new(),
        queue: VecDeque::new(),
        cap: 6,
        executed: Vec::new(),
        rng: Rng(77),
    };
    let mut client = Client::new(host);
    client.set_resync_after(None);
    client.begin().expect("hello");
    let mut next = 0;
    let send = |client: &mut Client<MemPipe>, next: &mut usize| {
        while *next < lines.len() && client.can_send() {
            client.send_line(&lines[*next]).expect("send");
            *next += 1;
        }
    };
    while dev.executed.len() < 70 {
        send(&mut client, &mut next);
        dev.pump();
        dev.execute();
        while client.poll().expect("poll").is_some() {}
    }
    assert!(dev.link.flags().is_framed());
    // Cable pulled with frames in flight: whatever is on the wire is lost.
    send(&mut client, &mut next);
    let mut lost = [0u8; 4096];
    let _ = dev.io.read(&mut lost);
    dev.io.close();
    let held = dev.queue.len();
    // The glue sees the port close: the link goes back to text mode and
    // the machine holds (here: executes nothing) until the host is back.
    dev.link.reset();
    assert!(!dev.link.flags().is_framed());
    assert_eq!(dev.queue.len(), held);

    let (host2, dev2) = MemPipe::pair();
    dev.io = dev2;
    client.reconnect(host2).expect("reconnect");
    for _ in 0..10_000 {
        send(&mut client, &mut next);
        dev.pump();
        dev.execute();
        while client.poll().expect("poll").is_some() {}
        assert!(lines.starts_with(&dev.executed));
        if next == lines.len() && client.in_flight() == 0 && dev.queue.is_empty() {
            break;
        }
    }
    assert_eq!(
        dev.executed, lines,
        "every line once, in order, across the reconnect"
    );
}

#[test]
fn mode_flag_follows_nul_bye_and_reset() {
    let mut link = Link::new();
    link.feed(b"?");
    assert!(!link.flags().is_framed());
    link.feed(&[0]);
    assert!(
        link.flags().is_framed(),
        "0x00 switches at once, for realtime replies"
    );
    link.feed(&enc(&HostMsg::Bye));
    assert!(!link.flags().is_framed());
    link.feed(&[0]);
    link.reset();
    assert!(!link.flags().is_framed());
    let mut out = Outcome::default();
    drain(&mut link, &mut out);
    assert_eq!(
        out.events,
        vec![
            Ev::Mode(LinkMode::Framed),
            Ev::Frame(HostMsg::Bye),
            Ev::Mode(LinkMode::Framed),
            Ev::Mode(LinkMode::Text)
        ]
    );
    assert_eq!(link.mode(), LinkMode::Text);
}

#[test]
fn soft_reset_mid_job_voids_the_rest_and_the_next_job_runs_exactly_once() {
    let job1: Vec<Vec<u8>> = (0..300).map(|i| format!("G1 X{i}").into_bytes()).collect();
    let job2: Vec<Vec<u8>> = (0..100).map(|i| format!("G0 Y{i}").into_bytes()).collect();
    let (host, dev_io) = MemPipe::pair();
    let mut dev = Dev {
        io: dev_io,
        link: Link::new(),
        port: FramedPort::new(),
        queue: VecDeque::new(),
        cap: 8,
        executed: Vec::new(),
        rng: Rng(5),
    };
    let mut client = Client::new(host);
    client.set_resync_after(None);
    client.begin().expect("hello");
    let mut next = 0;
    while dev.executed.len() < 50 {
        while next < job1.len() && client.can_send() {
            client.send_line(&job1[next]).expect("send");
            next += 1;
        }
        dev.pump();
        dev.execute();
        while client.poll().expect("poll").is_some() {}
    }
    // More lines in flight, then the operator resets.
    while next < job1.len() && client.can_send() {
        client.send_line(&job1[next]).expect("send");
        next += 1;
    }
    client.realtime(Rt::SoftReset).expect("reset");
    assert_eq!(client.in_flight(), 0, "the client forgets voided lines");
    let done_before = dev.executed.len();
    let mut sent2 = 0;
    for _ in 0..10_000 {
        while sent2 < job2.len() && client.can_send() {
            client.send_line(&job2[sent2]).expect("send");
            sent2 += 1;
        }
        dev.pump();
        dev.execute();
        while client.poll().expect("poll").is_some() {}
        if sent2 == job2.len() && client.in_flight() == 0 && dev.queue.is_empty() {
            break;
        }
    }
    let (old, new) = dev.executed.split_at(done_before);
    assert!(job1.starts_with(old));
    assert_eq!(
        new,
        &job2[..],
        "after the reset only the new job runs, once, in order"
    );
}
