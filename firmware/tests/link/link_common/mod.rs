//! Shared helpers for the link tests: owned copies of events, a seeded PRNG.
#![allow(dead_code)]

use burin::link::{Link, LinkEvent, LinkMode, SysCmd};
use protocol::{Code, FrameError, HostMsg, Rt};

/// An owned [`LinkEvent`], so runs can be compared.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Ev {
    Line(Vec<u8>),
    System(String),
    Error(Code),
    Frame(HostMsg),
    BadFrame(FrameError),
    Mode(LinkMode),
}

pub fn own(ev: LinkEvent<'_>) -> Ev {
    match ev {
        LinkEvent::Line(l) => Ev::Line(l.to_vec()),
        LinkEvent::System(SysCmd::Jog(body)) => {
            Ev::System(format!("Jog({})", String::from_utf8_lossy(body)))
        }
        LinkEvent::System(c) => Ev::System(format!("{c:?}")),
        LinkEvent::Error(c) => Ev::Error(c),
        LinkEvent::Frame(m) => Ev::Frame(m),
        LinkEvent::BadFrame(e) => Ev::BadFrame(e),
        LinkEvent::Mode(m) => Ev::Mode(m),
    }
}

/// Everything one run produced: events in order, and every realtime
/// command raised (as a set: repeats within one poll coalesce by design).
#[derive(Debug, Default, PartialEq)]
pub struct Outcome {
    pub events: Vec<Ev>,
    pub realtime: std::collections::BTreeSet<u8>,
}

/// Feed `bytes` in the given chunk sizes, polling after each chunk like the
/// task would after each USB packet. Like the USB endpoint (which NAKs
/// until the ring has room), a chunk is held back while the link is full.
pub fn run_chunks(bytes: &[u8], sizes: impl IntoIterator<Item = usize>) -> Outcome {
    let mut link = Link::new();
    let mut out = Outcome::default();
    let mut rest = bytes;
    let mut sizes = sizes.into_iter();
    while !rest.is_empty() {
        let n = sizes.next().unwrap_or(rest.len()).clamp(1, rest.len());
        let (chunk, tail) = rest.split_at(n);
        rest = tail;
        let mut chunk = chunk;
        while !chunk.is_empty() {
            let (now, later) = chunk.split_at(link.room().min(chunk.len()));
            link.feed(now);
            drain(&mut link, &mut out);
            chunk = later;
        }
    }
    drain(&mut link, &mut out);
    out
}

pub fn drain(link: &mut Link, out: &mut Outcome) {
    while let Some(ev) = link.poll() {
        out.events.push(own(ev));
    }
    for rt in link.take_realtime().iter() {
        out.realtime.insert(rt.byte());
    }
}

pub fn rts(list: &[Rt]) -> std::collections::BTreeSet<u8> {
    list.iter().map(|r| r.byte()).collect()
}

/// The protocol tests' PRNG (one copy for both crates).
#[path = "../../../../protocol/tests/wire/common/rng.rs"]
mod rng;
pub use rng::Rng;
