//! Property tests of the link under real senders and abuse (issue 15):
//! a job streamed in random USB-sized chunks, by a character-counting
//! sender or as a flood, with realtime bytes (single-byte and UTF-8 forms,
//! plus bytes that are no commands) injected at random positions, inside
//! lines too. Whatever the stream:
//!
//! * every line is acknowledged (`ok`, never `error`), and every
//!   acknowledged line runs exactly once, in order (the executor's log of
//!   accepted line numbers);
//! * no realtime byte waits behind text: a `?` is answered in the same 2 ms
//!   round of virtual time in which its chunk arrived, however much text is
//!   queued ahead of it (the bound);
//! * the machine ends where the job says.

use host_sim::config::MachineConfig;
use host_sim::device_sim::VirtualDevice;
use host_sim::record::Discard;
use proptest::prelude::*;

const LINES: usize = 24;
/// The exhaustive test's shorter job.
const SHORT: usize = 3;
const STEP_MM: f32 = 0.5;

fn cfg() -> MachineConfig {
    MachineConfig {
        start_position_mm: [0.0; burin::AXES],
        ..MachineConfig::default()
    }
}

/// Realtime bytes that leave the job's path alone, in their text forms;
/// 0x98 and a UTF-8 character are no commands and must vanish.
fn injections() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = vec![
        b"?".to_vec(),
        b"!".to_vec(),
        b"~".to_vec(),
        vec![0x98],
        "é".as_bytes().to_vec(),
    ];
    for b in [0x84u8, 0x90, 0x91, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97] {
        v.push(vec![b]);
        v.push(vec![0xC2, b]);
    }
    for b in 0x99u8..=0x9D {
        v.push(vec![b]);
        v.push(vec![0xC2, b]);
    }
    v
}

fn job(moves: usize) -> Vec<Vec<u8>> {
    let mut lines = vec![b"G91 F3000".to_vec()];
    for _ in 0..moves {
        lines.push(format!("G1 X-{STEP_MM} Y{STEP_MM}").into_bytes());
    }
    lines
}

struct Run {
    moves: usize,
    acks: usize,
    errors: Vec<String>,
    log: Vec<u32>,
    pos: [f32; 2],
    late_queries: usize,
}

fn run(moves: usize, inject: &[(usize, usize)], chunks: &[usize], flood: bool) -> Run {
    let cfg = cfg();
    let mut rec = Discard;
    let mut dev = VirtualDevice::new(&cfg, &mut rec);
    dev.log = Some(Vec::new());
    let _ = dev.take_output();
    let kinds = injections();
    // The byte stream: job text with injections at byte positions; each
    // byte remembers which line it belongs to (for character counting).
    let lines = job(moves);
    let mut stream: Vec<(u8, Option<usize>)> = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        for &b in l.iter().chain(b"\n") {
            stream.push((b, Some(i)));
        }
    }
    let mut marks: Vec<(usize, usize)> = inject
        .iter()
        .map(|&(p, k)| (p % (stream.len() + 1), k % kinds.len()))
        .collect();
    marks.sort();
    for &(p, k) in marks.iter().rev() {
        for &b in kinds[k].iter().rev() {
            stream.insert(p, (b, None));
        }
    }
    let round = u64::from(cfg.tick_hz) / 500;
    let mut out = String::new();
    let (mut sent, mut acked_lines, mut late) = (0usize, 0usize, 0usize);
    let mut in_flight: std::collections::VecDeque<usize> = Default::default();
    let mut chunk_i = 0;
    for _ in 0..20_000 {
        if sent < stream.len() {
            let size = chunks
                .get(chunk_i % chunks.len().max(1))
                .copied()
                .unwrap_or(64);
            chunk_i += 1;
            // A character-counting sender keeps at most 128 bytes of text
            // unacknowledged; a flood sends whatever the device takes.
            let window: usize = in_flight.iter().sum();
            let mut chunk = Vec::new();
            let mut text = 0;
            while sent < stream.len() && chunk.len() < size {
                let (b, line) = stream[sent];
                if line.is_some() && !flood && window + text >= 128 {
                    break;
                }
                chunk.push(b);
                if let Some(l) = line {
                    text += 1;
                    if b == b'\n' {
                        in_flight.push_back(lines[l].len() + 1);
                    }
                }
                sent += 1;
            }
            let n = dev.receive(&chunk);
            assert_eq!(n, chunk.len(), "the device refused bytes it had room for");
            let query = chunk.contains(&b'?');
            let t = dev.sim.now() + round;
            dev.advance_to(t);
            let got = String::from_utf8_lossy(&dev.take_output()).into_owned();
            if query && !got.contains('<') {
                late += 1;
            }
            out.push_str(&got);
        } else {
            // Job sent: resume any hold, then run out.
            let _ = dev.receive(b"~");
            let t = dev.sim.now() + round * 10;
            dev.advance_to(t);
            out.push_str(&String::from_utf8_lossy(&dev.take_output()));
        }
        let acks = out.matches("ok\r\n").count();
        while acked_lines < acks {
            in_flight.pop_front();
            acked_lines += 1;
        }
        if sent == stream.len() && acked_lines == lines.len() && dev.idle() {
            break;
        }
    }
    let steps = dev.position_steps();
    let spm = [
        cfg.settings.axes[0].steps_per_mm,
        cfg.settings.axes[1].steps_per_mm,
    ];
    Run {
        moves,
        acks: acked_lines,
        errors: out
            .lines()
            .filter(|l| l.starts_with("error") || l.starts_with("ALARM"))
            .map(str::to_string)
            .collect(),
        log: dev.log.take().unwrap_or_default(),
        pos: [steps[0] as f32 / spm[0], steps[1] as f32 / spm[1]],
        late_queries: late,
    }
}

fn check(r: &Run) -> Result<(), TestCaseError> {
    prop_assert!(r.errors.is_empty(), "{:?}", r.errors);
    prop_assert_eq!(r.acks, r.moves + 1);
    // Line 1 (G91 F3000) queues no command; lines 2.. one move each.
    let want: Vec<u32> = (2..=(r.moves as u32 + 1)).collect();
    prop_assert_eq!(&r.log, &want);
    let d = STEP_MM * r.moves as f32;
    prop_assert!(
        (r.pos[0] + d).abs() < 1e-3 && (r.pos[1] - d).abs() < 1e-3,
        "{:?}",
        r.pos
    );
    prop_assert_eq!(r.late_queries, 0, "a `?` waited behind text");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Realtime bytes anywhere, a character-counting sender.
    #[test]
    fn counted_stream_with_realtime_anywhere(
        inject in prop::collection::vec((0usize..4096, 0usize..64), 0..24),
        chunks in prop::collection::vec(1usize..=64, 1..8),
    ) {
        check(&run(LINES, &inject, &chunks, false))?;
    }

    /// The same as a flood: text far beyond the ring, realtime behind it.
    #[test]
    fn flood_with_realtime_anywhere(
        inject in prop::collection::vec((0usize..4096, 0usize..64), 0..24),
        chunks in prop::collection::vec(1usize..=64, 1..8),
    ) {
        check(&run(LINES, &inject, &chunks, true))?;
    }
}

/// Every injection kind at every byte position of a short job, one at a
/// time (exhaustive, not sampled), streamed as one flood.
#[test]
fn every_injection_at_every_position() {
    let n = job(SHORT).iter().map(|l| l.len() + 1).sum::<usize>();
    let kinds = injections().len();
    let mut cases = 0;
    for k in 0..kinds {
        for p in 0..=n {
            let r = run(SHORT, &[(p, k)], &[64], true);
            if let Err(e) = check(&r) {
                panic!("kind {k} at {p}: {e}");
            }
            cases += 1;
        }
    }
    assert_eq!(cases, kinds * (n + 1));
    println!(
        "every injection at every position: {kinds} kinds x {} positions = {cases} cases",
        n + 1
    );
}
