//! A minimal GRBL 1.1 text-mode sender, the way UGS, CNCjs or bCNC talk:
//! soft reset and wait for the `Grbl ` banner, `$` commands, `?` status, and
//! job streaming either send-response (one line in flight) or character
//! counting (up to [`RX_WINDOW`] bytes in flight). Used to test the board
//! and the virtual device as an outside sender would, and to benchmark the
//! text protocol against the native one.
//!
//! Like [`super::Client`] it is poll-driven: [`GrblClient::poll`] never
//! blocks, so a test can run a device model in the same thread;
//! [`GrblClient::wait`] is the blocking convenience for real ports.

use crate::RX_WINDOW;
use std::collections::VecDeque;
use std::io::{self, ErrorKind, Read, Write};
use std::time::{Duration, Instant};

/// How lines are paced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pacing {
    /// Send a line, wait for its `ok`/`error`.
    SendResponse,
    /// Keep up to [`RX_WINDOW`] bytes unacknowledged.
    CharCounting,
}

/// One line from the device, classified.
#[derive(Clone, Debug, PartialEq)]
pub enum TextEvent {
    /// `Grbl 1.1h ['$' for help]`.
    Banner(String),
    Ok,
    Error(u16),
    Alarm(u16),
    Status(TextStatus),
    /// Anything else: `[MSG:…]`, `[GC:…]`, `$n=v`, `[VER:…]`.
    Info(String),
}

/// A parsed `<…>` status report. Fields absent from a report are `None`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TextStatus {
    /// `Idle`, `Run`, `Hold:0`, …
    pub state: String,
    pub mpos: Option<Vec<f32>>,
    pub wpos: Option<Vec<f32>>,
    pub wco: Option<Vec<f32>>,
    pub bf: Option<(u32, u32)>,
    pub line: Option<u32>,
    pub feed: Option<f32>,
    pub spindle: Option<f32>,
    pub pins: Option<String>,
    pub ov: Option<(u32, u32, u32)>,
    /// `A:` letters (spindle `S`/`C`, flood `F`, mist `M`).
    pub accessories: Option<String>,
}

fn floats(s: &str) -> Option<Vec<f32>> {
    s.split(',').map(|v| v.parse().ok()).collect()
}

/// Parse one `<…>` line; `None` if it is not a status report.
pub fn parse_status(line: &str) -> Option<TextStatus> {
    let body = line.trim().strip_prefix('<')?.strip_suffix('>')?;
    let mut fields = body.split('|');
    let mut st = TextStatus {
        state: fields.next()?.to_string(),
        ..TextStatus::default()
    };
    for f in fields {
        let (key, val) = f.split_once(':')?;
        let nums = || -> Option<Vec<u32>> { val.split(',').map(|v| v.parse().ok()).collect() };
        match key {
            "MPos" => st.mpos = Some(floats(val)?),
            "WPos" => st.wpos = Some(floats(val)?),
            "WCO" => st.wco = Some(floats(val)?),
            "Bf" => st.bf = nums().and_then(|n| Some((*n.first()?, *n.get(1)?))),
            "Ln" => st.line = val.parse().ok(),
            "FS" | "F" => {
                let v = floats(val)?;
                st.feed = v.first().copied();
                st.spindle = v.get(1).copied();
            }
            "Pn" => st.pins = Some(val.to_string()),
            "A" => st.accessories = Some(val.to_string()),
            "Ov" => st.ov = nums().and_then(|n| Some((*n.first()?, *n.get(1)?, *n.get(2)?))),
            _ => {}
        }
    }
    Some(st)
}

/// Classify one received line (without its line ending).
pub fn classify(line: &str) -> TextEvent {
    if let Some(st) = parse_status(line) {
        return TextEvent::Status(st);
    }
    let code = |p: &str| line.strip_prefix(p).and_then(|n| n.trim().parse().ok());
    if line == "ok" {
        TextEvent::Ok
    } else if let Some(n) = code("error:") {
        TextEvent::Error(n)
    } else if let Some(n) = code("ALARM:") {
        TextEvent::Alarm(n)
    } else if line.starts_with("Grbl ") {
        TextEvent::Banner(line.to_string())
    } else {
        TextEvent::Info(line.to_string())
    }
}

/// The sender.
#[derive(Debug)]
pub struct GrblClient<T> {
    io: T,
    rx: Vec<u8>,
    events: VecDeque<TextEvent>,
    /// Byte lengths (with `\n`) of lines sent and not yet answered.
    in_flight: VecDeque<usize>,
    pacing: Pacing,
}

impl<T: Read + Write> GrblClient<T> {
    pub fn new(io: T, pacing: Pacing) -> Self {
        GrblClient {
            io,
            rx: Vec::new(),
            events: VecDeque::new(),
            in_flight: VecDeque::new(),
            pacing,
        }
    }

    pub fn get_mut(&mut self) -> &mut T {
        &mut self.io
    }

    /// Send one realtime byte (`?`, `!`, `~`, 0x18, overrides).
    pub fn realtime(&mut self, byte: u8) -> io::Result<()> {
        if byte == 0x18 {
            // A reset forgets everything the device had buffered.
            self.in_flight.clear();
        }
        self.io.write_all(&[byte])
    }

    /// Whether `line` may be sent now under the pacing rule.
    pub fn can_send(&self, line: &str) -> bool {
        match self.pacing {
            Pacing::SendResponse => self.in_flight.is_empty(),
            Pacing::CharCounting => {
                // The line goes out with its `\n`.
                let used: usize = self.in_flight.iter().sum::<usize>() + 1;
                used + line.len() <= RX_WINDOW
            }
        }
    }

    /// Send a line (a `\n` is appended); the caller checks [`Self::can_send`].
    pub fn send_line(&mut self, line: &str) -> io::Result<()> {
        self.io.write_all(line.as_bytes())?;
        self.io.write_all(b"\n")?;
        self.in_flight.push_back(line.len() + 1);
        Ok(())
    }

    /// Lines sent but not yet answered.
    pub fn in_flight(&self) -> usize {
        self.in_flight.len()
    }

    /// Read what is there and return the next event, if any. `ok` and
    /// `error:N` retire the oldest line in flight.
    pub fn poll(&mut self) -> io::Result<Option<TextEvent>> {
        if self.events.is_empty() {
            let mut buf = [0u8; 512];
            match self.io.read(&mut buf) {
                Ok(0) => return Err(ErrorKind::UnexpectedEof.into()),
                Ok(n) => self.rx.extend_from_slice(&buf[..n]),
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
            while let Some(end) = self.rx.iter().position(|b| *b == b'\n') {
                let raw: Vec<u8> = self.rx.drain(..=end).collect();
                let line = String::from_utf8_lossy(&raw);
                let line = line.trim_end_matches(['\r', '\n']);
                if line.is_empty() {
                    continue;
                }
                let ev = classify(line);
                match ev {
                    TextEvent::Ok | TextEvent::Error(_) => {
                        self.in_flight.pop_front();
                    }
                    TextEvent::Banner(_) => self.in_flight.clear(),
                    _ => {}
                }
                self.events.push_back(ev);
            }
        }
        Ok(self.events.pop_front())
    }

    /// Blocking: poll until `want` accepts an event (which is returned),
    /// collecting the events passed over into `seen`.
    pub fn wait(
        &mut self,
        timeout: Duration,
        seen: &mut Vec<TextEvent>,
        mut want: impl FnMut(&TextEvent) -> bool,
    ) -> io::Result<TextEvent> {
        let start = Instant::now();
        loop {
            match self.poll()? {
                Some(ev) if want(&ev) => return Ok(ev),
                Some(ev) => seen.push(ev),
                None if start.elapsed() > timeout => return Err(ErrorKind::TimedOut.into()),
                None => std::thread::sleep(Duration::from_millis(1)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_and_replies_parse() {
        let st = parse_status("<Hold:0|MPos:1.000,-2.500,3.000|Bf:15,128|Ln:7|FS:500,8000|Pn:XP|WCO:0.000,1.000,0.000|Ov:110,100,100>")
            .expect("status");
        assert_eq!(st.state, "Hold:0");
        assert_eq!(st.mpos, Some(vec![1.0, -2.5, 3.0]));
        assert_eq!(st.bf, Some((15, 128)));
        assert_eq!(st.line, Some(7));
        assert_eq!((st.feed, st.spindle), (Some(500.0), Some(8000.0)));
        assert_eq!(st.pins.as_deref(), Some("XP"));
        assert_eq!(st.ov, Some((110, 100, 100)));
        assert_eq!(classify("error:22"), TextEvent::Error(22));
        assert_eq!(classify("ALARM:1"), TextEvent::Alarm(1));
        assert_eq!(classify("ok"), TextEvent::Ok);
        assert!(matches!(
            classify("Grbl 1.1h ['$' for help]"),
            TextEvent::Banner(_)
        ));
        assert!(matches!(
            classify("[MSG:Reset to continue]"),
            TextEvent::Info(_)
        ));
        assert_eq!(parse_status("<Idle|MPos:x>"), None);
    }
}
