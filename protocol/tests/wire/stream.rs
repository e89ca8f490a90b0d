//! End-to-end reliability of the framed job stream: client <-> (noisy relay)
//! <-> model device. The one property checked everywhere: the device
//! executes exactly the job's lines, each once, in order.

use crate::common;

use common::{job, FakeDevice, Relay, Rng};
use protocol::client::mem::MemPipe;
use protocol::client::{Client, ClientEvent};
use protocol::frame::{self, MAX_WIRE};
use protocol::{Code, DeviceMsg, HostMsg, LineText, Session};

struct Run {
    client: Client<MemPipe>,
    relay: Option<Relay>,
    dev: FakeDevice,
}

impl Run {
    fn clean(capacity: usize) -> Self {
        let (host, dev) = MemPipe::pair();
        Self::build(host, dev, None, capacity, Session::new())
    }

    fn noisy(capacity: usize, seed: u64, flip_ppm: u64, drop_ppm: u64, s: Session) -> Self {
        let (host, relay_h) = MemPipe::pair();
        let (relay_d, dev) = MemPipe::pair();
        let relay = Relay {
            host_side: relay_h,
            device_side: relay_d,
            rng: Rng(seed),
            flip_ppm,
            drop_ppm,
            damaged: 0,
        };
        Self::build(host, dev, Some(relay), capacity, s)
    }

    fn build(host: MemPipe, dev: MemPipe, relay: Option<Relay>, cap: usize, s: Session) -> Self {
        let mut client = Client::new(host);
        client.set_resync_after(None);
        client.begin().expect("hello");
        Run {
            client,
            relay,
            dev: FakeDevice::with_session(dev, cap, s),
        }
    }

    fn tick(&mut self, exec: usize) -> Vec<ClientEvent> {
        if let Some(r) = &mut self.relay {
            r.pump();
        }
        self.dev.pump();
        self.dev.execute(exec);
        if let Some(r) = &mut self.relay {
            r.pump();
        }
        let mut events = Vec::new();
        while let Some(ev) = self.client.poll().expect("client poll") {
            events.push(ev);
        }
        events
    }

    /// Stream `lines[from..]`; a virtual retransmission timer resyncs after
    /// 20 ticks without progress. Returns the ticks used.
    fn stream(&mut self, lines: &[Vec<u8>], from: usize, exec: usize, max_ticks: usize) -> usize {
        let (mut next, mut idle, mut last) = (from, 0, (0, 0));
        for t in 0..max_ticks {
            while next < lines.len() && self.client.can_send() {
                self.client.send_line(&lines[next]).expect("send");
                next += 1;
            }
            self.tick(exec);
            assert!(
                lines.starts_with(&self.dev.executed),
                "executed lines are not a prefix of the job (duplicate or reordering)"
            );
            if next == lines.len() && self.client.in_flight() == 0 && self.dev.queue.is_empty() {
                return t;
            }
            let now = (self.dev.executed.len(), self.client.in_flight());
            idle = if now == last { idle + 1 } else { 0 };
            last = now;
            if idle > 20 {
                self.client.resync().expect("resync");
                idle = 0;
            }
        }
        panic!(
            "job did not finish: executed {}/{}, in flight {}",
            self.dev.executed.len(),
            lines.len(),
            self.client.in_flight()
        );
    }
}

#[test]
fn clean_stream_executes_every_line_once_in_order() {
    let lines = job(2000);
    let mut run = Run::clean(8);
    run.stream(&lines, 0, 3, 100_000);
    assert_eq!(run.dev.executed, lines);
    assert_eq!(run.dev.duplicates, 0);
    assert_eq!(run.dev.rejected, 0);
    let s = run.client.stats();
    assert_eq!(s.lines_sent, 2000, "no resends on a clean link");
    println!("clean: 2000 lines, {} acks", s.acks);
}

#[test]
fn noisy_links_lose_and_duplicate_nothing() {
    let lines = job(600);
    let mut total_damage = 0;
    let mut seeds = 0;
    for seed in 1..=40u64 {
        // 0.2 % of bytes flipped, 0.1 % dropped, both directions.
        let mut run = Run::noisy(6, seed * 7919, 2000, 1000, Session::new());
        run.stream(&lines, 0, 2, 200_000);
        assert_eq!(run.dev.executed, lines, "seed {seed}");
        total_damage += run.relay.as_ref().map_or(0, |r| r.damaged);
        seeds += 1;
    }
    assert!(total_damage > 100, "the relay must actually damage bytes");
    println!("noisy: {seeds} seeds x 600 lines, {total_damage} bytes damaged, all exact");
}

#[test]
fn sequence_numbers_wrap_around() {
    let lines = job(100);
    let mut run = Run::noisy(4, 99, 3000, 0, Session::starting_at(u32::MAX - 10));
    run.stream(&lines, 0, 1, 100_000);
    assert_eq!(run.dev.executed, lines);
    assert!(run.dev.session.next_seq() < 100, "wrapped past u32::MAX");
}

#[test]
fn host_disconnect_mid_job_then_reconnect_executes_nothing_twice() {
    let lines = job(300);
    let mut run = Run::clean(8);
    // Stream part of the job, then pull the cable with lines in flight.
    let mut next = 0;
    while run.dev.executed.len() < 100 {
        while next < lines.len() && run.client.can_send() {
            run.client.send_line(&lines[next]).expect("send");
            next += 1;
        }
        run.tick(1);
    }
    let (h, d) = (run.client.get_mut().clone(), run.dev.io.clone());
    // Unsent bytes on the wire are lost with the cable.
    let mut sink = [0u8; 4096];
    let _ = std::io::Read::read(&mut d.clone(), &mut sink);
    h.close();
    let queued = run.dev.queue.len();
    for _ in 0..50 {
        run.dev.pump();
        run.dev.execute(1);
    }
    assert!(run.dev.held, "device notices the host is gone");
    assert_eq!(
        run.dev.queue.len(),
        queued,
        "device holds: runs nothing while held"
    );
    let noticed = (0..100).any(|_| run.client.poll().is_err());
    assert!(noticed, "client notices the disconnect");

    // Reconnect on a new port; the client keeps its unacknowledged lines.
    let (host2, dev2) = MemPipe::pair();
    run.dev.io = dev2;
    run.client.reconnect(host2).expect("reconnect");
    run.stream(&lines, next, 1, 100_000);
    assert_eq!(run.dev.executed, lines, "every line exactly once, in order");
}

#[test]
fn overrunning_the_credits_is_refused_and_loses_nothing() {
    let lines = job(20);
    let (mut host, dev) = MemPipe::pair();
    let mut dev = FakeDevice::new(dev, 4);
    // A rogue host: 20 lines at once, ignoring credits.
    let mut buf = [0u8; MAX_WIRE];
    std::io::Write::write_all(&mut host, &[0]).expect("write");
    for (i, l) in lines.iter().enumerate() {
        let text = LineText::from_slice(l).expect("short line");
        let msg = HostMsg::Line {
            seq: i as u32 + 1,
            text,
        };
        let n = frame::encode(&msg, &mut buf).expect("encode");
        std::io::Write::write_all(&mut host, &buf[..n]).expect("write");
    }
    dev.pump();
    assert_eq!(dev.queue.len(), 4, "exactly the free slots were taken");
    assert_eq!(dev.rejected, 16);
    // Replies: 4 acks and one typed refusal (the rest of the burst is dropped).
    let mut replies = Vec::new();
    let mut dec = protocol::FrameDecoder::new();
    let mut rx = [0u8; 4096];
    let n = std::io::Read::read(&mut host, &mut rx).expect("replies");
    for &b in &rx[..n] {
        if let Some(m) = dec.push::<DeviceMsg>(b) {
            replies.push(m.expect("clean reply"));
        }
    }
    let naks: Vec<_> = replies
        .iter()
        .filter(|m| matches!(m, DeviceMsg::Nak { .. }))
        .collect();
    assert_eq!(replies.len(), 5);
    assert_eq!(
        naks,
        [&DeviceMsg::Nak {
            expected: 5,
            code: Code::FlowOverrun.code()
        }]
    );
    // A well-behaved client finishes the job from where the device is.
    dev.execute(4);
    let mut client = Client::new(host);
    client.set_resync_after(None);
    client.begin().expect("hello");
    let mut run = Run {
        client,
        relay: None,
        dev,
    };
    run.tick(0);
    assert_eq!(run.client.next_seq(), 5);
    run.stream(&lines, 4, 1, 10_000);
    assert_eq!(run.dev.executed, lines);
}

#[test]
fn reconnecting_to_a_rebooted_device_is_reported_not_guessed() {
    let lines = job(50);
    let mut run = Run::clean(8);
    let mut next = 0;
    while run.dev.executed.len() < 20 {
        while next < lines.len() && run.client.can_send() {
            run.client.send_line(&lines[next]).expect("send");
            next += 1;
        }
        run.tick(1);
    }
    while next < lines.len() && run.client.can_send() {
        run.client.send_line(&lines[next]).expect("send");
        next += 1;
    }
    assert!(run.client.in_flight() > 0);
    // The device reboots: its sequence starts again at 1.
    let (host2, dev2) = MemPipe::pair();
    run.dev = FakeDevice::new(dev2, 8);
    run.client.reconnect(host2).expect("hello");
    run.dev.pump();
    let err = (0..10).find_map(|_| run.client.poll().err());
    assert!(
        matches!(
            err,
            Some(protocol::client::ClientError::SessionLost { device_next: 1 })
        ),
        "{err:?}"
    );
}
