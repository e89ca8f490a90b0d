//! Where the device's replies go, in whichever protocol the port speaks.
//!
//! Every reply is written once, as GRBL text, through [`Out`]'s
//! `core::fmt::Write`: in text mode the bytes go out as they are; in framed
//! mode each text line becomes one `DeviceMsg::Msg` frame. So `$#`, `$G`,
//! `$I` and messages need one implementation for both protocols, and
//! nothing needs a buffer bigger than one message.

use crate::link::encode_reply;
use core::fmt::{self, Write};
use protocol::frame::MAX_WIRE;
use protocol::msg::MsgText;
use protocol::DeviceMsg;

pub use crate::seams::Tx;

/// A reply writer for one protocol.
pub struct Out<'a, T: Tx> {
    tx: &'a mut T,
    framed: bool,
    line: MsgText,
}

impl<T: Tx> core::fmt::Debug for Out<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Out").field("framed", &self.framed).finish()
    }
}

impl<'a, T: Tx> Out<'a, T> {
    pub fn new(tx: &'a mut T, framed: bool) -> Self {
        Out {
            tx,
            framed,
            line: MsgText::new(),
        }
    }

    pub fn framed(&self) -> bool {
        self.framed
    }

    /// Reply bytes the sink takes now.
    pub fn room(&self) -> usize {
        self.tx.room()
    }

    /// Send one frame (framed mode only; text mode ignores it).
    pub fn frame(&mut self, msg: &DeviceMsg) {
        if self.framed {
            let mut buf = [0u8; MAX_WIRE];
            self.tx.send(encode_reply(msg, &mut buf));
        }
    }

    /// Bytes as they are, in either mode (a frame delimiter).
    pub fn raw(&mut self, bytes: &[u8]) {
        self.tx.send(bytes);
    }

    /// Text mode: write `s` as it is. Framed mode: nothing.
    pub fn text(&mut self, s: &str) {
        if !self.framed {
            self.tx.send(s.as_bytes());
        }
    }

    fn flush_line(&mut self) {
        let line = core::mem::take(&mut self.line);
        let trimmed = line.trim_end_matches(['\r', '\n']);
        if !trimmed.is_empty() {
            let mut m = MsgText::new();
            let _ = m.push_str(trimmed);
            self.frame(&DeviceMsg::Msg(m));
        }
    }
}

impl<T: Tx> Write for Out<'_, T> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        if !self.framed {
            self.tx.send(s.as_bytes());
            return Ok(());
        }
        for c in s.chars() {
            if c == '\n' {
                self.flush_line();
            } else if self.line.push(c).is_err() {
                // A line longer than one message continues in the next.
                self.flush_line();
                let _ = self.line.push(c);
            }
        }
        Ok(())
    }
}

impl<T: Tx> Drop for Out<'_, T> {
    fn drop(&mut self) {
        if self.framed && !self.line.is_empty() {
            self.flush_line();
        }
    }
}
