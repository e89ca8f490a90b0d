//! Frame layer: damaged, truncated, oversized and noisy input is rejected
//! with a typed error, never decoded as something else, and the decoder is
//! back in step at the next delimiter.

use proptest::prelude::*;
use protocol::frame::{self, FrameError, MAX_FRAME, MAX_WIRE};
use protocol::msg::{DeviceInfo, MachineState, MsgText, Overrides, Status};
use protocol::{DeviceMsg, FrameDecoder, HostMsg, LineText, Rt, ShortText};
use std::sync::atomic::{AtomicU64, Ordering};

fn samples() -> Vec<HostMsg> {
    let line = |s: &str| LineText::from_slice(s.as_bytes()).expect("short");
    vec![
        HostMsg::Hello { version: 1 },
        HostMsg::Line {
            seq: 7,
            text: line("G1 X10.5 Y-3 F1200"),
        },
        HostMsg::Line {
            seq: u32::MAX,
            text: LineText::from_slice(&[0u8; 256]).expect("fits"),
        },
        HostMsg::Realtime(Rt::FeedHold),
        HostMsg::SetSetting {
            n: 110,
            value: 5000.0,
        },
        HostMsg::ListSettings,
        HostMsg::Bye,
    ]
}

fn device_samples() -> Vec<DeviceMsg> {
    let status = Status {
        state: MachineState::Run,
        mpos: {
            let mut p = [0.0; protocol::AXES];
            p[..4].copy_from_slice(&[1.0, -2.5, 3.25, 90.0]);
            p
        },
        line: Some(42),
        overrides: Overrides {
            feed: 120,
            rapid: 50,
            spindle: 100,
        },
        ..Status::default()
    };
    vec![
        DeviceMsg::Ack {
            seq: 1,
            next: 2,
            credits: 15,
        },
        DeviceMsg::Nak {
            expected: 9,
            code: 101,
        },
        DeviceMsg::Status(status),
        DeviceMsg::Error {
            seq: Some(3),
            line: Some(30),
            code: 22,
        },
        DeviceMsg::Alarm { code: 1 },
        DeviceMsg::Msg(MsgText::try_from("Pgm End").expect("short")),
        DeviceMsg::Welcome(DeviceInfo {
            protocol: 1,
            firmware: ShortText::try_from("0.1.0").expect("short"),
            board: ShortText::try_from("blackpill-f411").expect("short"),
            axes: 4,
            line_slots: 32,
            planner_blocks: 32,
            rx_bytes: 128,
            caps: 3,
            next_seq: 1,
            credits: 32,
        }),
    ]
}

fn encode(m: &impl serde::Serialize) -> Vec<u8> {
    let mut buf = [0u8; MAX_WIRE];
    let n = frame::encode(m, &mut buf).expect("encode");
    buf[..n].to_vec()
}

/// Feed `bytes` and collect every result.
fn decode_all<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Vec<Result<T, FrameError>> {
    let mut d = FrameDecoder::new();
    bytes.iter().filter_map(|b| d.push::<T>(*b)).collect()
}

#[test]
fn round_trip_every_message() {
    for m in samples() {
        assert_eq!(decode_all::<HostMsg>(&encode(&m)), vec![Ok(m)]);
    }
    for m in device_samples() {
        assert_eq!(decode_all::<DeviceMsg>(&encode(&m)), vec![Ok(m)]);
    }
}

#[test]
fn every_single_bit_flip_is_rejected() {
    let mut flips = 0;
    for m in samples() {
        let good = encode(&m);
        for i in 0..good.len() {
            for bit in 0..8 {
                let mut bad = good.clone();
                bad[i] ^= 1 << bit;
                // Then a delimiter (in case the flip hit ours) and a good
                // frame: the decoder must be back in step for it.
                bad.push(0);
                bad.extend_from_slice(&good);
                let out = decode_all::<HostMsg>(&bad);
                let oks: Vec<_> = out.iter().filter(|r| r.is_ok()).collect();
                assert_eq!(oks, vec![&Ok(m.clone())], "flip byte {i} bit {bit}");
                assert!(out.len() >= 2, "the damaged frame is reported");
                assert!(out[..out.len() - 1].iter().all(|r| r.is_err()));
                flips += 1;
            }
        }
    }
    println!("bit flips: {flips} damaged frames, all rejected with a typed error");
    assert!(flips > 2000);
}

#[test]
fn truncated_frames_are_rejected() {
    for m in samples() {
        let good = encode(&m);
        for cut in 1..good.len() - 1 {
            let mut bad = good[..cut].to_vec();
            bad.push(0);
            let out = decode_all::<HostMsg>(&bad);
            assert_eq!(out.len(), 1);
            let e = out[0].as_ref().expect_err("truncated frame must fail");
            assert!(matches!(
                e,
                FrameError::Corrupt | FrameError::Crc | FrameError::Decode
            ));
        }
    }
}

#[test]
fn oversized_frame_is_too_long_then_resync() {
    let mut bytes = vec![0x55u8; MAX_FRAME + 500];
    bytes.push(0);
    let good = encode(&HostMsg::Realtime(Rt::StatusQuery));
    bytes.extend_from_slice(&good);
    let out = decode_all::<HostMsg>(&bytes);
    assert_eq!(
        out,
        vec![
            Err(FrameError::TooLong),
            Ok(HostMsg::Realtime(Rt::StatusQuery))
        ]
    );
    assert_eq!(FrameError::TooLong.code().code(), 102);
    // A message too big to encode is refused, not truncated.
    let mut small = [0u8; 8];
    assert!(frame::encode(&samples()[2], &mut small).is_err());
}

#[test]
fn text_noise_before_a_frame_does_not_hurt_it() {
    let mut bytes = b"G1 X1\r\n?$$\n\x18garbage".to_vec();
    bytes.push(0);
    let m = samples()[1].clone();
    bytes.extend_from_slice(&encode(&m));
    let out = decode_all::<HostMsg>(&bytes);
    assert_eq!(out.last(), Some(&Ok(m)));
    assert!(out[..out.len() - 1].iter().all(|r| r.is_err()));
}

static FUZZ_CASES: AtomicU64 = AtomicU64::new(0);
static ROUNDTRIP_CASES: AtomicU64 = AtomicU64::new(0);

proptest! {
    #![proptest_config(ProptestConfig { cases: 20_000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Arbitrary bytes: never a panic; the buffer is fixed so memory is bounded.
    #[test]
    fn fuzz_decoder_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..1200)) {
        let mut d = FrameDecoder::new();
        for b in &bytes {
            let _ = d.push::<HostMsg>(*b);
            let _ = d.push::<DeviceMsg>(*b);
        }
        let n = FUZZ_CASES.fetch_add(1, Ordering::Relaxed) + 1;
        if n == 20_000 { println!("fuzz_decoder_never_panics: {n} cases"); }
    }

    /// Any line, any seq, split anywhere: decodes to itself.
    #[test]
    fn lines_round_trip_in_any_chunking(
        seq in any::<u32>(),
        text in proptest::collection::vec(any::<u8>(), 0..=256),
        cut in 1usize..64,
    ) {
        let m = HostMsg::Line { seq, text: LineText::from_slice(&text).expect("<=256") };
        let wire = encode(&m);
        let mut d = FrameDecoder::new();
        let mut got = Vec::new();
        for chunk in wire.chunks(cut) {
            got.extend(chunk.iter().filter_map(|b| d.push::<HostMsg>(*b)));
        }
        prop_assert_eq!(got, vec![Ok(m)]);
        let n = ROUNDTRIP_CASES.fetch_add(1, Ordering::Relaxed) + 1;
        if n == 20_000 { println!("lines_round_trip_in_any_chunking: {n} cases"); }
    }
}
