//! GRBL text mode through the link: chunking anywhere gives the same result,
//! realtime bytes act at once wherever they are, long lines are refused
//! whole, the 128-byte window holds, and noise never panics.

use crate::link_common;

use burin::link::{Link, LinkMode, RX_RING};
use link_common::{drain, rts, run_chunks, Ev, Outcome, Rng};
use proptest::prelude::*;
use protocol::{Code, Rt, MAX_LINE, RX_WINDOW};

fn sample() -> Vec<u8> {
    let mut s = Vec::new();
    s.extend_from_slice(b"\r\n\r\n$$\n");
    s.extend_from_slice(b"G21 G90 (why? because) X1\n");
    s.extend_from_slice(b"G1 X10.5!Y2 F300\r\n~\n");
    s.extend_from_slice(b"$J=G91 X1 F100\n$110 = 5000.5\n$Z\n");
    s.extend_from_slice(b"G0 ");
    for i in 0..100 {
        s.extend_from_slice(b"X1 ");
        if i == 90 {
            s.push(0x85); // jog cancel inside an over-long line
        }
    }
    s.extend_from_slice(b"\n\x91\x92\x93G4 P0\rG0 X0\n");
    s.extend((0x90u8..=0x9D).filter(|b| *b != 0x98));
    s.extend_from_slice(b"\xA0\xA1\x9E\x84$X\n$H\n$#\n$G\n$I\n$C\n\x18");
    s
}

fn expected() -> Outcome {
    let line = |t: &[u8]| Ev::Line(t.to_vec());
    let sys = |t: &str| Ev::System(t.to_string());
    Outcome {
        events: vec![
            line(b""),
            line(b""),
            sys("ListSettings"),
            line(b"G21 G90 (why because) X1"),
            line(b"G1 X10.5Y2 F300"),
            line(b""),
            sys("Jog(G91 X1 F100)"),
            sys("SetSetting { n: 110, value: 5000.5 }"),
            Ev::Error(Code::InvalidStatement),
            Ev::Error(Code::LineOverflow),
            line(b"G4 P0"),
            line(b"G0 X0"),
            sys("Unlock"),
            sys("Home(0)"),
            sys("Params"),
            sys("ParserState"),
            sys("BuildInfo"),
            sys("CheckMode"),
        ],
        realtime: Rt::ALL.iter().map(|r| r.byte()).collect(),
    }
}

#[test]
fn sample_stream_decodes_as_expected() {
    let got = run_chunks(&sample(), [usize::MAX]);
    assert_eq!(got, expected());
}

#[test]
fn every_split_point_of_every_chunk_size_gives_the_same_result() {
    let bytes = sample();
    let want = expected();
    let mut runs = 0;
    for size in 1..=64 {
        for first in 1..=size {
            let sizes = std::iter::once(first).chain(std::iter::repeat(size));
            assert_eq!(run_chunks(&bytes, sizes), want, "size {size} first {first}");
            runs += 1;
        }
    }
    // And two-piece splits at every byte boundary.
    for cut in 1..bytes.len() {
        assert_eq!(run_chunks(&bytes, [cut, usize::MAX]), want, "cut {cut}");
        runs += 1;
    }
    println!("text split runs: {runs} over a {}-byte stream", bytes.len());
}

#[test]
fn realtime_acts_mid_line_before_the_line_ends() {
    let mut link = Link::new();
    link.feed(b"G1 X1 ? Y2 !");
    assert!(link.poll().is_none(), "no line yet");
    let rt = link.take_realtime();
    assert!(rt.contains(Rt::StatusQuery) && rt.contains(Rt::FeedHold));
    link.feed(b"\n");
    let mut out = Outcome::default();
    drain(&mut link, &mut out);
    assert_eq!(out.events, vec![Ev::Line(b"G1 X1  Y2 ".to_vec())]);
}

#[test]
fn realtime_acts_while_the_ring_is_full_and_nobody_reads() {
    let mut link = Link::new();
    // The task is busy: nobody polls. Fill the ring and then some.
    let flood = vec![b'X'; RX_RING + 100];
    link.feed(&flood);
    link.feed(b"!\x85");
    let rt = link.take_realtime();
    assert!(rt.contains(Rt::FeedHold) && rt.contains(Rt::JogCancel));
    assert!(link.flags().take_overflow(), "dropped input is flagged");
    // The task catches up; the damaged line is reported, never executed,
    // and the next one is fine.
    let mut out = Outcome::default();
    drain(&mut link, &mut out);
    assert!(out.events.is_empty());
    link.feed(b"\n");
    drain(&mut link, &mut out);
    link.feed(b"G0 X1\n");
    drain(&mut link, &mut out);
    assert_eq!(
        out.events,
        vec![Ev::Error(Code::RxOverflow), Ev::Line(b"G0 X1".to_vec())]
    );
}

#[test]
fn longest_line_passes_and_one_more_byte_is_refused_whole() {
    let mut ok = vec![b'G'; MAX_LINE];
    ok.push(b'\n');
    let mut long = vec![b'G'; MAX_LINE + 1];
    long.push(b'\n');
    let got = run_chunks(&[ok.clone(), long, b"M2\n".to_vec()].concat(), [64; 100]);
    assert_eq!(
        got.events,
        vec![
            Ev::Line(ok[..MAX_LINE].to_vec()),
            Ev::Error(Code::LineOverflow),
            Ev::Line(b"M2".to_vec())
        ]
    );
}

#[test]
fn rx_window_holds_128_unread_bytes_for_character_counting() {
    let mut link = Link::new();
    assert!(
        link.room() >= RX_WINDOW + 64,
        "room for the window plus a USB packet"
    );
    // A character-counting sender: at most RX_WINDOW bytes unacknowledged;
    // the device handles one line per tick.
    let lines: Vec<Vec<u8>> = (0..500)
        .map(|i| format!("G1 X{} Y{} F{}\n", i, i * 3 % 71, 100 + i).into_bytes())
        .collect();
    let (mut next, mut unacked, mut done) = (0, std::collections::VecDeque::new(), Vec::new());
    let mut in_window = 0usize;
    while done.len() < lines.len() {
        while next < lines.len() && in_window + lines[next].len() <= RX_WINDOW {
            link.feed(&lines[next]);
            in_window += lines[next].len();
            unacked.push_back(lines[next].len());
            next += 1;
        }
        assert!(link.rx_pending() <= RX_WINDOW);
        if let Some(ev) = link.poll() {
            done.push(link_common::own(ev));
            in_window -= unacked.pop_front().expect("an ok answers a sent line");
        }
    }
    assert!(!link.flags().take_overflow());
    let want: Vec<Ev> = lines
        .iter()
        .map(|l| Ev::Line(l[..l.len() - 1].to_vec()))
        .collect();
    assert_eq!(done, want);
}

#[test]
fn nul_switches_to_framed_and_drops_the_partial_line() {
    let got = run_chunks(b"G1 X1\nhalf a li\0", [3; 10]);
    assert_eq!(
        got.events,
        vec![Ev::Line(b"G1 X1".to_vec()), Ev::Mode(LinkMode::Framed)]
    );
    assert_eq!(got.realtime, rts(&[]));
}

static NOISE_CASES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

proptest! {
    #![proptest_config(ProptestConfig { cases: 5_000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Binary noise in any chunking: no panic, no line longer than the
    /// limit, and the link still works afterwards (after a port reset).
    #[test]
    fn noise_never_panics_and_link_recovers(
        bytes in proptest::collection::vec(any::<u8>(), 0..3000),
        seed in any::<u64>(),
    ) {
        let mut rng = Rng(seed | 1);
        let mut link = Link::new();
        let mut rest = &bytes[..];
        while !rest.is_empty() {
            let n = (1 + rng.below(64)).min(rest.len());
            let (chunk, tail) = rest.split_at(n);
            rest = tail;
            link.feed(chunk);
            while let Some(ev) = link.poll() {
                if let burin::link::LinkEvent::Line(l) = ev {
                    prop_assert!(l.len() <= MAX_LINE);
                }
            }
            let _ = link.take_realtime();
        }
        link.reset();
        link.feed(b"\nG0 X1\n");
        let mut out = Outcome::default();
        drain(&mut link, &mut out);
        prop_assert_eq!(out.events.last(), Some(&Ev::Line(b"G0 X1".to_vec())));
        let n = NOISE_CASES.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if n == 5_000 { println!("text/binary noise: {n} cases"); }
    }
}

#[test]
fn soft_reset_discards_input_received_before_it_and_keeps_what_follows() {
    let mut link = Link::new();
    // The task is busy; two lines and half a line wait in the ring.
    link.feed(b"G1 X1\nG1 X2\nG1 X");
    link.feed(b"\x18");
    link.feed(b"3\n$I\n");
    let rt = link.take_realtime();
    assert!(rt.contains(Rt::SoftReset));
    let mut out = Outcome::default();
    drain(&mut link, &mut out);
    assert_eq!(
        out.events,
        vec![Ev::Line(b"3".to_vec()), Ev::System("BuildInfo".into())]
    );
    // Two resets before the task looks: input up to the second one goes.
    link.feed(b"G0 X1\n\x18G0 X2\n\x18G0 X3\n");
    let _ = link.take_realtime();
    let mut out = Outcome::default();
    drain(&mut link, &mut out);
    assert_eq!(out.events, vec![Ev::Line(b"G0 X3".to_vec())]);
}
