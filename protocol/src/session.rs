//! The device's side of the framed job stream: which line to execute, which
//! to acknowledge again, which to refuse. Pure bookkeeping, no I/O, so the
//! firmware, host-sim and the reliability tests all run the same rules.
//!
//! The single invariant: a line is executed only when its sequence number is
//! exactly the next expected one and a slot is free, and `next` then moves
//! on by one. So every line executes at most once and in order, and a line is
//! acknowledged only if it was executed (queued) now or before.

use crate::codes::Code;
use crate::frame::FrameError;
use crate::msg::DeviceMsg;

/// What to do with a received job line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineVerdict {
    /// Queue it for execution (it is new and in order).
    Execute,
    /// Already queued before (a resend): acknowledge again, do not execute.
    Duplicate,
    /// Refused: not executed, not acknowledged; the host resends.
    Reject(Code),
}

/// Serial-number comparison (RFC 1982 style) for wrapping `u32` sequences.
/// Returns how far `seq` is ahead of `next` (negative: behind).
pub fn seq_distance(next: u32, seq: u32) -> i64 {
    let d = seq.wrapping_sub(next);
    if d < 0x8000_0000 {
        i64::from(d)
    } else {
        -i64::from(next.wrapping_sub(seq))
    }
}

/// Device-side sequence state of a framed session.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Session {
    next: u32,
    /// Credits last advertised, to know when a refresh is due.
    advertised: u16,
    /// `next` at the last `Nak`: later lines of the same burst are dropped
    /// silently instead of each drawing another `Nak` (the host rewinds once
    /// per `Nak`, so one is enough). Bad frames always get a `Nak`.
    nakked: Option<u32>,
}

impl Default for Session {
    fn default() -> Self {
        Self::new()
    }
}

impl Session {
    /// A fresh boot expects sequence 1.
    pub const fn new() -> Self {
        Self::starting_at(1)
    }

    /// A session expecting `next` first (tests of wrap-around use this).
    pub const fn starting_at(next: u32) -> Self {
        Session {
            next,
            advertised: 0,
            nakked: None,
        }
    }

    /// The sequence number expected next (goes into the handshake).
    pub const fn next_seq(&self) -> u32 {
        self.next
    }

    /// Judge line `seq`, given the free line slots *before* it is queued, and
    /// build the reply (if any). On `Execute` the caller must queue the line.
    pub fn on_line(&mut self, seq: u32, free: u16) -> (LineVerdict, Option<DeviceMsg>) {
        let d = seq_distance(self.next, seq);
        if d < 0 {
            let msg = self.ack(seq, free);
            return (LineVerdict::Duplicate, Some(msg));
        }
        let code = if d > 0 {
            Code::SeqGap
        } else if free == 0 {
            // The host's idea of our credits is wrong: the next freed slot
            // must be advertised, whatever we said before.
            self.advertised = 0;
            Code::FlowOverrun
        } else {
            self.next = self.next.wrapping_add(1);
            self.nakked = None;
            let msg = self.ack(seq, free - 1);
            return (LineVerdict::Execute, Some(msg));
        };
        let reply = if self.nakked == Some(self.next) {
            None
        } else {
            Some(self.nak(code))
        };
        (LineVerdict::Reject(code), reply)
    }

    /// Reply to a frame that could not be read: resend from `next`.
    pub fn on_bad_frame(&mut self, err: FrameError) -> DeviceMsg {
        self.nak(err.code())
    }

    /// A credit refresh if slots have freed since the last advertisement
    /// (call when the queue drains; the host may be waiting for credits).
    pub fn refresh(&mut self, free: u16) -> Option<DeviceMsg> {
        if free > self.advertised {
            Some(self.ack(self.next.wrapping_sub(1), free))
        } else {
            None
        }
    }

    /// Remember what the handshake advertised.
    pub fn advertise(&mut self, credits: u16) {
        self.advertised = credits;
        self.nakked = None;
    }

    fn ack(&mut self, seq: u32, credits: u16) -> DeviceMsg {
        self.advertised = credits;
        DeviceMsg::Ack {
            seq,
            next: self.next,
            credits,
        }
    }

    fn nak(&mut self, code: Code) -> DeviceMsg {
        self.nakked = Some(self.next);
        DeviceMsg::Nak {
            expected: self.next,
            code: code.code(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_wraps() {
        assert_eq!(seq_distance(5, 5), 0);
        assert_eq!(seq_distance(5, 7), 2);
        assert_eq!(seq_distance(5, 3), -2);
        assert_eq!(seq_distance(u32::MAX, 0), 1);
        assert_eq!(seq_distance(1, u32::MAX), -2);
    }

    #[test]
    fn in_order_duplicate_gap_overrun() {
        let mut s = Session::new();
        assert_eq!(s.on_line(1, 4).0, LineVerdict::Execute);
        assert_eq!(s.on_line(1, 3).0, LineVerdict::Duplicate);
        let (v, m) = s.on_line(3, 3);
        assert_eq!(v, LineVerdict::Reject(Code::SeqGap));
        assert_eq!(
            m,
            Some(DeviceMsg::Nak {
                expected: 2,
                code: 104
            })
        );
        // The rest of the burst is dropped without another Nak.
        assert_eq!(s.on_line(4, 3), (LineVerdict::Reject(Code::SeqGap), None));
        assert_eq!(s.on_line(2, 0).0, LineVerdict::Reject(Code::FlowOverrun));
        let (v, m) = s.on_line(2, 1);
        assert_eq!(v, LineVerdict::Execute);
        assert_eq!(
            m,
            Some(DeviceMsg::Ack {
                seq: 2,
                next: 3,
                credits: 0
            })
        );
        assert!(s.refresh(0).is_none());
        assert!(matches!(
            s.refresh(2),
            Some(DeviceMsg::Ack {
                seq: 2,
                next: 3,
                credits: 2
            })
        ));
    }
}
