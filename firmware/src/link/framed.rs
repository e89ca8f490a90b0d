//! The device's rules for framed mode in one place, so the RTIC app and
//! host-sim answer frames identically: handshake, sequence checks and
//! acknowledgements, credit refreshes. The caller only executes what comes
//! out and sends the reply frames it is handed.

use protocol::frame::{self, MAX_WIRE};
use protocol::{DeviceInfo, DeviceMsg, FrameError, HostMsg, LineText, LineVerdict, Rt, Session};

/// What the device must do after a frame (replies are already sent).
/// The line is carried inline: no heap on the device.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum FramedAction {
    /// Queue this job line; it has been acknowledged, so it must run (or
    /// fail with `DeviceMsg::Error { seq: Some(seq), .. }`). A `$` command
    /// travels here too: check it with [`super::syscmd::parse`].
    Execute {
        seq: u32,
        text: LineText,
    },
    /// A realtime command the interrupt did not catch (host-sim without a
    /// splitter): act on it like the flag.
    Realtime(Rt),
    /// Answer with `DeviceMsg::Setting` or `DeviceMsg::Error`.
    GetSetting(u16),
    SetSetting {
        n: u16,
        value: f32,
    },
    /// Answer with one `Setting` per number, then `SettingsEnd`.
    ListSettings,
    /// The host said `Bye`: the port is in text mode again.
    Closed,
}

/// Device side of a framed session.
#[derive(Clone, Copy, Debug, Default)]
pub struct FramedPort {
    session: Session,
}

impl FramedPort {
    pub const fn new() -> Self {
        FramedPort {
            session: Session::new(),
        }
    }

    /// The sequence state (the expected number survives soft resets and
    /// reconnects: keep this value for the device's whole uptime).
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// Handle one decoded frame. `free` is the number of free line slots
    /// now; `info` is what the handshake reports (its `next_seq` and
    /// `credits` are filled in here). Replies go to `reply`.
    pub fn on_frame(
        &mut self,
        msg: HostMsg,
        free: u16,
        info: &DeviceInfo,
        reply: &mut impl FnMut(&DeviceMsg),
    ) -> Option<FramedAction> {
        match msg {
            HostMsg::Hello { .. } => {
                // Always answer with our version; the host decides if it
                // can talk to us.
                self.session.advertise(free);
                let mut info = info.clone();
                info.next_seq = self.session.next_seq();
                info.credits = free;
                reply(&DeviceMsg::Welcome(info));
                None
            }
            HostMsg::Line { seq, text } => {
                let (verdict, msg) = self.session.on_line(seq, free);
                if let Some(m) = msg {
                    reply(&m);
                }
                (verdict == LineVerdict::Execute).then_some(FramedAction::Execute { seq, text })
            }
            HostMsg::Realtime(rt) => Some(FramedAction::Realtime(rt)),
            HostMsg::GetSetting { n } => Some(FramedAction::GetSetting(n)),
            HostMsg::SetSetting { n, value } => Some(FramedAction::SetSetting { n, value }),
            HostMsg::ListSettings => Some(FramedAction::ListSettings),
            HostMsg::Bye => Some(FramedAction::Closed),
        }
    }

    /// A frame failed to decode: ask for a resend.
    pub fn on_bad_frame(&mut self, err: FrameError, reply: &mut impl FnMut(&DeviceMsg)) {
        reply(&self.session.on_bad_frame(err));
    }

    /// Call whenever line slots free up: tells a starved host it may send.
    pub fn refresh(&mut self, free: u16, reply: &mut impl FnMut(&DeviceMsg)) {
        if let Some(m) = self.session.refresh(free) {
            reply(&m);
        }
    }
}

/// Encode a reply as one frame into `buf`; returns the bytes to send. Every
/// `DeviceMsg` fits [`MAX_WIRE`]; should one not, nothing is sent rather
/// than a truncated frame.
pub fn encode_reply<'b>(msg: &DeviceMsg, buf: &'b mut [u8; MAX_WIRE]) -> &'b [u8] {
    let n = frame::encode(msg, buf).unwrap_or(0);
    buf.get(..n).unwrap_or(&[])
}
