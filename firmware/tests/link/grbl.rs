//! A GRBL sender (protocol's `GrblClient`) against a text-mode device model
//! built from the firmware link, the reply formatter and the settings table:
//! reset and banner, `$I`, `$$`, `$n=v`, `$G`, `?`, and a job streamed both
//! send-response and character-counting, with a slow device so the
//! 128-byte window is actually exercised.

use crate::link_common;

use burin::link::reply::{self, BuildInfo, Cadence, Format, ReplyBuf};
use burin::link::{Link, LinkEvent, SysCmd};
use burin::settings::Settings;
use link_common::Rng;
use protocol::client::grbl::{GrblClient, Pacing, TextEvent};
use protocol::client::mem::MemPipe;
use protocol::{Rt, Status, RX_WINDOW};
use std::collections::VecDeque;
use std::io::{Read, Write};

struct TextDev {
    io: MemPipe,
    link: Link,
    settings: Settings,
    queue: VecDeque<Vec<u8>>,
    cap: usize,
    executed: Vec<Vec<u8>>,
    cadence: Cadence,
    rng: Rng,
    max_pending: usize,
}

impl TextDev {
    fn new(io: MemPipe, seed: u64) -> Self {
        TextDev {
            io,
            link: Link::new(),
            settings: Settings::default(),
            queue: VecDeque::new(),
            cap: 4,
            executed: Vec::new(),
            cadence: Cadence::default(),
            rng: Rng(seed),
            max_pending: 0,
        }
    }

    fn out(&mut self, f: impl FnOnce(&mut String) -> core::fmt::Result) {
        let mut s = String::new();
        f(&mut s).expect("format");
        self.io.write_all(s.as_bytes()).expect("write");
    }

    fn pump(&mut self) {
        let mut buf = [0u8; 64];
        let want = (1 + self.rng.below(64)).min(self.link.room());
        if let Ok(n @ 1..) = self.io.read(&mut buf[..want]) {
            self.link.feed(&buf[..n]);
        }
        self.max_pending = self.max_pending.max(self.link.rx_pending());
        for rt in self.link.take_realtime().iter() {
            match rt {
                Rt::SoftReset => {
                    self.queue.clear();
                    self.out(reply::banner);
                }
                Rt::StatusQuery => {
                    let st = Status {
                        planner_free: (self.cap - self.queue.len()) as u16,
                        rx_free: RX_WINDOW.saturating_sub(self.link.rx_pending()) as u16,
                        ..Status::default()
                    };
                    let extras = self.cadence.next(&st);
                    let mut b = ReplyBuf::new();
                    let f = Format::from_settings(&self.settings);
                    reply::status(&mut b, &st, self.settings.status_mask | 2, f, extras)
                        .expect("fits");
                    self.io.write_all(b.as_bytes()).expect("write");
                }
                _ => {}
            }
        }
        // Backpressure: take a line only when a slot is free.
        while self.queue.len() < self.cap {
            let Some(ev) = self.link.poll() else { break };
            let mut s = String::new();
            match ev {
                LinkEvent::Line(l) => {
                    self.queue.push_back(l.to_vec());
                    reply::ok(&mut s).expect("fmt");
                }
                LinkEvent::System(cmd) => system(&mut self.settings, cmd, &mut s),
                LinkEvent::Error(code) => reply::error(&mut s, code.code()).expect("fmt"),
                _ => {}
            }
            self.io.write_all(s.as_bytes()).expect("write");
        }
    }

    fn execute(&mut self) {
        if let Some(l) = self.queue.pop_front() {
            self.executed.push(l);
        }
    }
}

fn system(settings: &mut Settings, cmd: SysCmd<'_>, s: &mut String) {
    let r = match cmd {
        SysCmd::ListSettings => reply::settings(s, settings),
        SysCmd::SetSetting { n, value } => match settings.set(n, value) {
            Ok(()) => Ok(()),
            Err(e) => return reply::error(s, e.code().code()).expect("fmt"),
        },
        SysCmd::BuildInfo => {
            let info = BuildInfo {
                firmware: burin::VERSION,
                board: "model",
                options: "VNMH",
                planner_blocks: 16,
                axes: 4,
            };
            reply::build_info(s, &info)
        }
        SysCmd::ParserState => reply::gc(s, "G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0"),
        _ => Ok(()),
    };
    r.and_then(|()| reply::ok(s)).expect("fmt");
}

/// Run device ticks until the client yields an event matching `want`.
fn until(
    c: &mut GrblClient<MemPipe>,
    d: &mut TextDev,
    mut want: impl FnMut(&TextEvent) -> bool,
) -> Vec<TextEvent> {
    let mut seen = Vec::new();
    for _ in 0..100_000 {
        d.pump();
        d.execute();
        while let Some(ev) = c.poll().expect("poll") {
            let done = want(&ev);
            seen.push(ev);
            if done {
                return seen;
            }
        }
    }
    panic!("no matching event; saw {seen:?}");
}

fn session(pacing: Pacing, seed: u64) {
    let (host, dev_io) = MemPipe::pair();
    let mut d = TextDev::new(dev_io, seed);
    let mut c = GrblClient::new(host, pacing);

    c.realtime(0x18).expect("reset");
    until(
        &mut c,
        &mut d,
        |e| matches!(e, TextEvent::Banner(b) if b.starts_with("Grbl 1.1h")),
    );

    c.send_line("$I").expect("send");
    let seen = until(&mut c, &mut d, |e| *e == TextEvent::Ok);
    assert!(
        seen.contains(&TextEvent::Info("[OPT:VNMH,16,128]".into())),
        "{seen:?}"
    );

    c.send_line("$$").expect("send");
    let seen = until(&mut c, &mut d, |e| *e == TextEvent::Ok);
    assert_eq!(
        seen.len(),
        burin::persist::SETTINGS + 1,
        "every setting then ok"
    );
    assert_eq!(seen[0], TextEvent::Info("$0=2.000".into()));

    c.send_line("$110=6000").expect("send");
    until(&mut c, &mut d, |e| *e == TextEvent::Ok);
    assert_eq!(d.settings.axes[0].max_rate, 6000.0);
    c.send_line("$110=-1").expect("send");
    until(&mut c, &mut d, |e| *e == TextEvent::Error(4));

    c.send_line("$G").expect("send");
    let seen = until(&mut c, &mut d, |e| *e == TextEvent::Ok);
    assert!(matches!(&seen[0], TextEvent::Info(g) if g.starts_with("[GC:G0 G54")));

    c.realtime(b'?').expect("?");
    let seen = until(&mut c, &mut d, |e| matches!(e, TextEvent::Status(_)));
    let Some(TextEvent::Status(st)) = seen.last() else {
        unreachable!()
    };
    assert_eq!(st.state, "Idle");
    // `$208`'s default number of axes.
    let shown = usize::from(burin::settings::DEFAULT_REPORT_AXES);
    assert_eq!(st.mpos, Some(vec![0.0; shown]));

    // The job: lines of varied length, a status query every 50 lines.
    let job: Vec<String> = (0..600)
        .map(|i| {
            format!(
                "G1 X{}.{} Y{} Z-{} F{}",
                i % 83,
                i % 7,
                i * 13 % 997,
                i % 3,
                200 + i
            )
        })
        .collect();
    let (mut next, mut oks) = (0, 0);
    while oks < job.len() {
        while next < job.len() && c.can_send(&job[next]) {
            c.send_line(&job[next]).expect("send");
            next += 1;
            if next % 50 == 0 {
                c.realtime(b'?').expect("?");
            }
        }
        d.pump();
        if d.rng.below(3) == 0 {
            d.execute(); // a slow machine: the window fills up
        }
        while let Some(ev) = c.poll().expect("poll") {
            match ev {
                TextEvent::Ok => oks += 1,
                TextEvent::Status(_) => {}
                other => panic!("unexpected {other:?}"),
            }
        }
    }
    while !d.queue.is_empty() {
        d.execute();
    }
    let want: Vec<Vec<u8>> = job.iter().map(|l| l.as_bytes().to_vec()).collect();
    assert_eq!(d.executed, want, "every line once, in order");
    assert!(
        d.max_pending <= RX_WINDOW,
        "sender never overran the window"
    );
    assert!(!d.link.flags().take_overflow());
    if pacing == Pacing::CharCounting {
        assert!(
            d.max_pending > 64,
            "character counting keeps the buffer busy"
        );
    }
}

#[test]
fn grbl_sender_send_response() {
    session(Pacing::SendResponse, 5);
}

#[test]
fn grbl_sender_character_counting() {
    for seed in 1..=5 {
        session(Pacing::CharCounting, seed);
    }
}
