//! A virtual board driven the way a GRBL text sender drives it: bytes in,
//! fixed virtual-time rounds, replies split into lines. Shared by the
//! device tests.
#![allow(dead_code)]

use host_sim::config::MachineConfig;
use host_sim::device_sim::VirtualDevice;
use host_sim::record::Recorder;
use protocol::client::grbl::parse_status;

/// The default machine, powered up at machine zero.
pub fn origin() -> MachineConfig {
    MachineConfig {
        start_position_mm: [0.0; burin::AXES],
        ..MachineConfig::default()
    }
}

pub struct Rig<'r> {
    pub dev: VirtualDevice<'r>,
    text: String,
    step: u64,
}

impl<'r> Rig<'r> {
    pub fn new(cfg: &MachineConfig, rec: &'r mut dyn Recorder) -> Self {
        let dev = VirtualDevice::new(cfg, rec);
        let mut r = Rig {
            dev,
            text: String::new(),
            step: u64::from(cfg.tick_hz) / 500,
        };
        r.run(1);
        r
    }
    pub fn send(&mut self, bytes: &[u8]) {
        let n = self.dev.receive(bytes);
        assert_eq!(n, bytes.len(), "link full");
    }
    pub fn run(&mut self, rounds: usize) {
        for _ in 0..rounds {
            let t = self.dev.sim.now() + self.step;
            self.dev.advance_to(t);
            self.text
                .push_str(&String::from_utf8_lossy(&self.dev.take_output()));
        }
    }
    /// Everything received since the last call, as lines.
    pub fn lines(&mut self) -> Vec<String> {
        let t = std::mem::take(&mut self.text);
        t.split("\r\n")
            .filter(|l| !l.is_empty())
            .map(str::to_string)
            .collect()
    }
    pub fn cmd(&mut self, line: &str) -> Vec<String> {
        self.send(line.as_bytes());
        self.send(b"\n");
        self.run(2);
        self.lines()
    }
    pub fn status(&mut self) -> protocol::client::grbl::TextStatus {
        self.status_within(1)
    }
    /// One `?`, answered within `rounds` rounds (the parse task may be
    /// busy with queued lines, as on the board, for a few ms).
    pub fn status_within(&mut self, rounds: usize) -> protocol::client::grbl::TextStatus {
        self.send(b"?");
        let mut seen = Vec::new();
        for _ in 0..rounds {
            self.run(1);
            seen.extend(self.lines());
            if let Some(st) = seen.iter().rev().find_map(|l| parse_status(l)) {
                return st;
            }
        }
        panic!("no status within {rounds} rounds: {seen:?}");
    }
    pub fn until_idle(&mut self) -> protocol::client::grbl::TextStatus {
        for _ in 0..100_000 {
            self.run(10);
            let st = self.status();
            if st.state == "Idle" {
                return st;
            }
        }
        panic!("never idle");
    }
    /// Machine X from a status report.
    pub fn x(&mut self) -> f32 {
        self.status().mpos.map_or(f32::NAN, |p| p[0])
    }
    pub fn spindle_on(&self) -> bool {
        self.dev.pins().is_some_and(|p| p.spindle.enable)
    }
    pub fn flood_on(&self) -> bool {
        self.dev.pins().is_some_and(|p| p.flood)
    }
    /// Cutting along X with the spindle and flood on (`G1 X-50 F600`,
    /// 200 ms in).
    pub fn cutting(&mut self) {
        self.lines();
        assert_eq!(self.cmd("M3 S1000"), ["ok"]);
        assert_eq!(self.cmd("M8"), ["ok"]);
        assert_eq!(self.cmd("G1 X-50 F600"), ["ok"]);
        self.run(100);
        assert_eq!(self.status().state, "Run");
        assert!(self.spindle_on() && self.flood_on());
    }
    /// In alarm, and X stays where it is for `rounds` more rounds.
    pub fn alarm_holds(&mut self, rounds: usize) {
        let st = self.status();
        assert_eq!(st.state, "Alarm");
        let x = st.mpos.as_ref().map_or(0.0, |p| p[0]);
        self.run(rounds);
        let after = self.status().mpos.as_ref().map_or(1.0, |p| p[0]);
        assert_eq!(after, x, "moved in alarm");
    }
    /// `$X` unlocks, the machine is idle, and a move to X`x` runs to the end.
    pub fn unlock_and_move_to(&mut self, x: f32) {
        assert_eq!(self.cmd("$X"), ["[MSG:Caution: Unlocked]", "ok"]);
        self.run(2);
        assert_eq!(self.status().state, "Idle");
        assert_eq!(self.cmd(&format!("G1 X{x} F1000")), ["ok"]);
        let st = self.until_idle();
        assert_eq!(st.mpos, shown([x, 0.0, 0.0, 0.0]));
    }
}

/// One host message as it goes on the wire.
pub fn frame(msg: &protocol::HostMsg) -> Vec<u8> {
    let mut out = [0u8; protocol::frame::MAX_WIRE];
    let n = protocol::frame::encode(msg, &mut out).expect("encode");
    out[..n].to_vec()
}

/// A framed job line.
pub fn line_frame(seq: u32, text: &str) -> Vec<u8> {
    let text = protocol::LineText::from_slice(text.as_bytes()).expect("line fits");
    frame(&protocol::HostMsg::Line { seq, text })
}

/// The device's frames in `bytes` (text before the first frame is skipped).
pub fn device_msgs(bytes: &[u8]) -> Vec<protocol::DeviceMsg> {
    bytes
        .split(|b| *b == 0)
        .filter(|f| !f.is_empty())
        .filter_map(|f| protocol::frame::decode(&mut f.to_vec()).ok())
        .collect()
}

impl Rig<'_> {
    /// Switch the port to frames and shake hands; returns the sequence
    /// number the device expects next.
    pub fn go_framed(&mut self) -> u32 {
        let _ = self.dev.take_output();
        self.lines();
        let mut hello = vec![0u8];
        hello.extend(frame(&protocol::HostMsg::Hello {
            version: protocol::PROTOCOL_VERSION,
        }));
        self.send(&hello);
        let msgs = self.run_framed(2);
        msgs.iter()
            .find_map(|m| match m {
                protocol::DeviceMsg::Welcome(i) => Some(i.next_seq),
                _ => None,
            })
            .unwrap_or_else(|| panic!("no Welcome in {msgs:?}"))
    }
    /// Framed mode: `rounds` rounds, and the frames the device sent.
    pub fn run_framed(&mut self, rounds: usize) -> Vec<protocol::DeviceMsg> {
        let mut out = Vec::new();
        for _ in 0..rounds {
            let t = self.dev.sim.now() + self.step;
            self.dev.advance_to(t);
            out.extend(self.dev.take_output());
        }
        device_msgs(&out)
    }
}

/// A position as the status report shows it with the default `$208`: the
/// first [`burin::settings::DEFAULT_REPORT_AXES`] values of `v` padded to
/// every axis.
pub fn shown<const N: usize>(v: [f32; N]) -> Option<Vec<f32>> {
    let n = usize::from(burin::settings::DEFAULT_REPORT_AXES);
    Some(burin::pad(v)[..n].to_vec())
}
