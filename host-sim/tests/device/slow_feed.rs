//! Extreme feeds through the whole virtual device: `G1 X-1 F0.0001` once
//! sent the segment preparer into an endless loop inside `Machine::poll`,
//! and from then on nothing was answered, not even `?` or a soft reset.
//!
//! Bound: every reply arrives within [`ANSWER_ROUNDS`] rounds of 2 ms of
//! virtual time (20 ms). The device runs on its own thread; if a round does
//! not come back within [`WALL_S`] of wall time the test fails instead of
//! hanging.

use std::sync::mpsc;
use std::time::Duration;

use host_sim::config::MachineConfig;
use host_sim::device_sim::VirtualDevice;
use host_sim::record::Discard;
use protocol::client::grbl::parse_status;

/// Rounds of 2 ms virtual time a reply may take.
const ANSWER_ROUNDS: usize = 10;
/// Wall time the whole session may take before it counts as hung.
const WALL_S: u64 = 30;

struct Rig<'r> {
    dev: VirtualDevice<'r>,
    step: u64,
}

impl<'r> Rig<'r> {
    fn new(cfg: &MachineConfig, rec: &'r mut Discard) -> Self {
        let dev = VirtualDevice::new(cfg, rec);
        let mut r = Rig {
            dev,
            step: u64::from(cfg.tick_hz) / 500,
        };
        r.answer(|l| l.starts_with("Grbl 1.1h"));
        r
    }

    /// Sends `bytes`, then runs 2 ms rounds until a line satisfies `done`;
    /// fails after `ANSWER_ROUNDS`. Returns every line received.
    fn send_until(&mut self, bytes: &[u8], done: impl Fn(&str) -> bool) -> Vec<String> {
        assert_eq!(self.dev.receive(bytes), bytes.len(), "link full");
        self.answer(done)
    }

    fn answer(&mut self, done: impl Fn(&str) -> bool) -> Vec<String> {
        let mut text = String::new();
        for _ in 0..ANSWER_ROUNDS {
            let t = self.dev.sim.now() + self.step;
            self.dev.advance_to(t);
            text.push_str(&String::from_utf8_lossy(&self.dev.take_output()));
            if text.split("\r\n").any(&done) {
                return text.split("\r\n").map(str::to_string).collect();
            }
        }
        panic!("no answer within {ANSWER_ROUNDS} rounds of 2 ms: {text:?}");
    }

    fn state(&mut self) -> String {
        let lines = self.send_until(b"?", |l| parse_status(l).is_some());
        let st = lines.iter().find_map(|l| parse_status(l));
        st.map(|s| s.state).unwrap_or_default()
    }
}

/// Runs `f` on a thread; a hang becomes a failure after `WALL_S`.
fn within(f: impl FnOnce() + Send + 'static) {
    let (tx, rx) = mpsc::channel();
    let h = std::thread::spawn(move || {
        f();
        let _ = tx.send(());
    });
    match rx.recv_timeout(Duration::from_secs(WALL_S)) {
        Ok(()) => {}
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            if let Err(p) = h.join() {
                std::panic::resume_unwind(p);
            }
        }
        Err(mpsc::RecvTimeoutError::Timeout) => {
            panic!("the device did not come back within {WALL_S} s: Machine::poll loops")
        }
    }
}

fn origin() -> MachineConfig {
    MachineConfig {
        start_position_mm: [0.0; burin::AXES],
        ..MachineConfig::default()
    }
}

/// The line: one step would be 7 500 s away, beyond the step
/// driver's 11.2 s (`seams::MAX_PERIOD`), so the move is refused (error 412) and nothing moves;
/// found after the line's `ok`, it stops the job as alarm 21 (issue 35);
/// `?`, `!` and a soft reset are all answered, and `$X` unlocks.
#[test]
fn feed_0_0001_is_refused_and_the_device_keeps_answering() {
    within(|| {
        let mut rec = Discard;
        let mut r = Rig::new(&origin(), &mut rec);
        let out = r.send_until(b"G1 X-1 F0.0001\n", |l| l == "ALARM:21");
        assert!(out.iter().any(|l| l == "ok"), "{out:?}");
        assert!(out.iter().any(|l| l.contains("error 412")), "{out:?}");
        assert_eq!(r.state(), "Alarm");
        r.send_until(b"!", |_| true);
        assert_eq!(r.state(), "Alarm");
        let out = r.send_until(&[0x18], |l| l.starts_with("Grbl 1.1h"));
        assert!(!out.iter().any(|l| l.starts_with("ALARM")), "{out:?}");
        assert_eq!(r.state(), "Alarm");
        r.send_until(b"$X\n", |l| l == "ok");
        assert_eq!(r.state(), "Idle");
        assert_eq!(r.dev.position_steps(), [0; burin::AXES]);
    });
}

/// The slowest feeds that are accepted (a step every 9.4 s at F0.08 on
/// 80 steps/mm) run as steps plus waits: the device answers `?` while the
/// move runs, holds on `!`, and a soft reset stops it with alarm 3.
#[test]
fn slowest_accepted_feed_runs_and_the_device_keeps_answering() {
    within(|| {
        let mut rec = Discard;
        let mut r = Rig::new(&origin(), &mut rec);
        let out = r.send_until(b"G1 X-1 F0.08\n", |l| l == "ok");
        assert!(!out.iter().any(|l| l.contains("error")), "{out:?}");
        assert_eq!(r.state(), "Run");
        r.send_until(b"!", |_| true);
        let st = r.state();
        assert!(st.starts_with("Hold"), "{st}");
        let out = r.send_until(&[0x18], |l| l.starts_with("Grbl 1.1h"));
        assert!(out.iter().any(|l| l == "ALARM:3"), "{out:?}");
        assert_eq!(r.state(), "Alarm");
    });
}
