//! Cost of the native protocol itself, without any machine behind it: frame
//! encode/decode per line, and whole lines per second from `Client` through
//! an in-memory pipe into a model device (`Session` + queue) and back.
//! The goal is 10,000 lines/s end to end through the virtual device;
//! this is the ceiling the protocol layer sets.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use protocol::client::mem::MemPipe;
use protocol::client::Client;
use protocol::frame::{self, MAX_WIRE};
use protocol::{FrameDecoder, HostMsg, LineText};
use std::hint::black_box;

#[path = "../tests/wire/common/mod.rs"]
mod common;

fn line() -> HostMsg {
    let text = LineText::from_slice(b"G1 X123.456 Y-78.9 Z1.5 F1500").unwrap_or_default();
    HostMsg::Line { seq: 123_456, text }
}

fn frames(c: &mut Criterion) {
    let msg = line();
    let mut buf = [0u8; MAX_WIRE];
    let n = frame::encode(&msg, &mut buf).unwrap_or(0);
    let wire = buf[..n].to_vec();
    let mut g = c.benchmark_group("frame");
    g.throughput(Throughput::Elements(1));
    g.bench_function("encode_line", |b| {
        b.iter(|| frame::encode(black_box(&msg), &mut buf).unwrap_or(0))
    });
    g.bench_function("decode_line", |b| {
        let mut d = FrameDecoder::new();
        b.iter(|| {
            let mut out = None;
            for &x in black_box(&wire) {
                if let Some(r) = d.push::<HostMsg>(x) {
                    out = Some(r);
                }
            }
            out
        })
    });
    g.finish();
}

fn stream(c: &mut Criterion) {
    const LINES: usize = 1000;
    let job = common::job(LINES);
    let mut g = c.benchmark_group("client_to_model_device");
    g.throughput(Throughput::Elements(LINES as u64));
    g.bench_function("1000_lines_16_slots", |b| {
        b.iter(|| {
            let (host, dev) = MemPipe::pair();
            let mut dev = common::FakeDevice::new(dev, 16);
            let mut client = Client::new(host);
            client.set_resync_after(None);
            let _ = client.begin();
            let mut next = 0;
            while dev.executed.len() < LINES {
                while next < LINES && client.can_send() {
                    let _ = client.send_line(&job[next]);
                    next += 1;
                }
                dev.pump();
                dev.execute(16);
                while let Ok(Some(_)) = client.poll() {}
            }
            dev.executed.len()
        })
    });
    g.finish();
}

criterion_group!(benches, frames, stream);
criterion_main!(benches);
