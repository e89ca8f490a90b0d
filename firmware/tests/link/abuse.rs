//! The link under abuse (issue 15): realtime bytes in their UTF-8 form,
//! other bytes above 0x7F, a soft reset behind a full ring, and text held
//! back while realtime bytes behind it still act at once.

use crate::link_common;

use burin::link::{LineAssembler, Link, LinkEvent, RtFlags, RxBacklog, RxSplitter, RxToken};
use heapless::Deque;
use link_common::{drain, rts, Ev, Outcome};
use protocol::Rt;

fn lines(out: &Outcome) -> Vec<String> {
    out.events
        .iter()
        .filter_map(|e| match e {
            Ev::Line(l) => Some(String::from_utf8_lossy(l).into_owned()),
            _ => None,
        })
        .collect()
}

#[test]
fn utf8_realtime_bytes_act_and_other_high_bytes_vanish() {
    let mut link = Link::new();
    let mut out = Outcome::default();
    // bCNC / cncjs: 0x92 (feed -10 %) sent as UTF-8, right before a line.
    link.feed(b"\xC2\x92G0 X1\n");
    // A lone 0x98 is no realtime command: dropped, not an error.
    link.feed(b"\x98G0 X2\n");
    // UTF-8 text in a comment: its continuation bytes are no commands
    // (U+029A is CA 9A; 0x9A alone would be spindle +10 %).
    link.feed(b"(caf\xC3\xA9 \xCA\x9A \xE2\x80\x99)G0 X3\n");
    // Each realtime form, single byte and UTF-8, split across feeds.
    link.feed(b"G0 X4\xC2");
    link.feed(b"\x85\n\x84");
    drain(&mut link, &mut out);
    assert_eq!(
        lines(&out),
        ["G0 X1", "G0 X2", "(caf  )G0 X3", "G0 X4"],
        "{out:?}"
    );
    assert_eq!(
        out.realtime,
        rts(&[Rt::FeedOvMinus10, Rt::JogCancel, Rt::SafetyDoor])
    );
    assert!(
        out.events.iter().all(|e| matches!(e, Ev::Line(_))),
        "{out:?}"
    );
}

/// Every realtime byte, in both forms, anywhere in a line: the line is
/// intact and the command is raised.
#[test]
fn every_realtime_byte_in_both_forms() {
    for rt in Rt::ALL {
        let b = rt.byte();
        if b < 0x80 && rt == Rt::SoftReset {
            continue;
        }
        for utf8 in [false, true] {
            if utf8 && b < 0x80 {
                continue;
            }
            let mut bytes = b"G1 X".to_vec();
            if utf8 {
                bytes.push(0xC2);
            }
            bytes.push(b);
            bytes.extend_from_slice(b"5 F100\n");
            let mut link = Link::new();
            let mut out = Outcome::default();
            link.feed(&bytes);
            drain(&mut link, &mut out);
            assert_eq!(lines(&out), ["G1 X5 F100"], "{rt:?} utf8 {utf8}");
            assert_eq!(out.realtime, rts(&[rt]), "{rt:?} utf8 {utf8}");
        }
    }
}

/// Fed as the board's USB interrupt fed it (no room check): a soft reset
/// behind a full ring still voids everything before it, and what follows
/// the reset is read.
#[test]
fn reset_behind_a_full_ring_voids_the_input_before_it() {
    let mut ring: Deque<RxToken, 64> = Deque::new();
    let (mut split, mut asm, flags) = (RxSplitter::new(), LineAssembler::new(), RtFlags::new());
    let mut job = Vec::new();
    for _ in 0..150 {
        job.extend_from_slice(b"G91 G1 Y-1 F1000\n");
    }
    split.feed(&job, &mut ring, &flags);
    split.feed(b"\x18", &mut ring, &flags);
    let set = flags.take();
    assert!(set.contains(Rt::SoftReset));
    asm.flush_reset(&mut ring, &flags);
    assert_eq!(asm.poll(&mut ring), None);
    split.feed(b"G0 X9\n", &mut ring, &flags);
    let mut got = Vec::new();
    while let Some(ev) = asm.poll(&mut ring) {
        if let LinkEvent::Line(l) = ev {
            got.push(String::from_utf8_lossy(l).into_owned());
        }
    }
    assert_eq!(got, ["G0 X9"]);
}

/// Text beyond the ring waits in the backlog, in order and whole; realtime
/// bytes behind it act on arrival; a reset voids the backlog too.
#[test]
fn backlog_keeps_text_and_never_delays_realtime() {
    let mut ring: Deque<RxToken, 64> = Deque::new();
    let mut backlog: RxBacklog<4096> = RxBacklog::new();
    let (mut split, mut asm, flags) = (RxSplitter::new(), LineAssembler::new(), RtFlags::new());
    let mut job = Vec::new();
    for i in 0..100 {
        job.extend_from_slice(format!("G1 X{i} F1000\n").as_bytes());
    }
    assert!(backlog.room(&ring) > job.len() + 2);
    backlog.feed(&mut split, &job, &mut ring, &flags);
    backlog.feed(&mut split, b"!?", &mut ring, &flags);
    // Nothing was read yet, and the hold and the query are already raised.
    let set = flags.take();
    assert!(set.contains(Rt::FeedHold) && set.contains(Rt::StatusQuery));
    let mut got = Vec::new();
    loop {
        backlog.pump(&mut ring);
        let Some(ev) = asm.poll(&mut ring) else { break };
        if let LinkEvent::Line(l) = ev {
            got.push(String::from_utf8_lossy(l).into_owned());
        }
    }
    let want: Vec<String> = (0..100).map(|i| format!("G1 X{i} F1000")).collect();
    assert_eq!(got, want);
    // Again, now with a reset at the end: none of the held lines is read.
    backlog.feed(&mut split, &job, &mut ring, &flags);
    backlog.feed(&mut split, b"\x18G0 Y1\n", &mut ring, &flags);
    assert!(flags.take().contains(Rt::SoftReset));
    asm.flush_reset(&mut ring, &flags);
    let mut got = Vec::new();
    loop {
        let moved = backlog.pump(&mut ring);
        match asm.poll(&mut ring) {
            Some(LinkEvent::Line(l)) => got.push(String::from_utf8_lossy(l).into_owned()),
            Some(_) => {}
            None if moved || !backlog.is_empty() => {}
            None => break,
        }
    }
    assert_eq!(got, ["G0 Y1"]);
}

/// A reset taken while the ring ends in the middle of the framed session's
/// `Bye` (the rest still in the backlog): the voided input is still decoded
/// to the marker, so both halves of the link end in text mode and a line
/// after the reset is read as text (fuzz finding, device target).
#[test]
fn reset_with_a_bye_cut_by_the_ring_keeps_the_modes_in_step() {
    use burin::link::LinkMode;
    use protocol::frame;
    use protocol::msg::HostMsg;
    let mut wire = vec![0u8];
    let mut buf = [0u8; 64];
    for _ in 0..20 {
        let n = frame::encode(&HostMsg::Bye, &mut buf).expect("encode");
        // A long frame of padding, then the `Bye`; only the last counts.
        wire.extend_from_slice(&[b'U'; 40]);
        wire.push(0);
        // (`encode` ends the frame with its 0x00.)
        wire.extend_from_slice(&buf[..n]);
        // Back to framed for the next round, except after the last one.
        wire.push(0);
    }
    wire.pop();
    // Try every cut of the ring around the final `Bye`.
    for cap in 1..wire.len() {
        let mut ring: Deque<RxToken, 2048> = Deque::new();
        let mut backlog: RxBacklog<4096> = RxBacklog::new();
        let (mut split, mut asm, flags) = (RxSplitter::new(), LineAssembler::new(), RtFlags::new());
        // The ring takes only `cap` tokens before the reset arrives.
        let mut small: Deque<RxToken, 2048> = Deque::new();
        backlog.feed(&mut split, &wire, &mut small, &flags);
        while small.len() > cap {
            let t = small.pop_back().expect("token");
            ring.push_front(t).expect("room");
        }
        assert!(!split.is_framed(), "framed before reset");
        backlog.feed(&mut split, b"\x18$I\n", &mut ring, &flags);
        assert!(flags.take().contains(Rt::SoftReset));
        assert!(!split.is_framed());
        // The task acts on the reset with only the first `cap` tokens read.
        asm.flush_reset(&mut small, &flags);
        let mut got = Vec::new();
        while let Some(t) = ring.pop_front() {
            small.push_back(t).expect("room");
        }
        while let Some(ev) = asm.poll(&mut small) {
            if let LinkEvent::System(_) = ev {
                got.push("$I");
            }
        }
        assert_eq!(asm.mode(), LinkMode::Text, "cut at {cap}");
        assert_eq!(got, ["$I"], "cut at {cap}");
    }
}
