//! Realtime commands: they act at once, ahead of anything queued.
//!
//! In text mode each is a single byte (GRBL 1.1 values, so existing senders
//! work); in framed mode each is a [`crate::HostMsg::Realtime`] frame.

use serde::{Deserialize, Serialize};

/// One realtime command. The discriminant is also its bit in a flag word
/// (see [`Rt::bit`]), which is how the receive interrupt hands them over.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[repr(u8)]
pub enum Rt {
    /// Soft reset (0x18). Listed first: it wins over everything else.
    SoftReset = 0,
    /// Status report request (`?`).
    StatusQuery,
    /// Feed hold (`!`).
    FeedHold,
    /// Cycle start / resume (`~`).
    CycleStart,
    /// Safety door (0x84).
    SafetyDoor,
    /// Jog cancel (0x85).
    JogCancel,
    /// Feed override back to 100 % (0x90).
    FeedOv100,
    /// Feed override +10 % (0x91).
    FeedOvPlus10,
    /// Feed override -10 % (0x92).
    FeedOvMinus10,
    /// Feed override +1 % (0x93).
    FeedOvPlus1,
    /// Feed override -1 % (0x94).
    FeedOvMinus1,
    /// Rapid override 100 % (0x95).
    RapidOv100,
    /// Rapid override 50 % (0x96).
    RapidOv50,
    /// Rapid override 25 % (0x97).
    RapidOv25,
    /// Spindle override back to 100 % (0x99).
    SpindleOv100,
    /// Spindle override +10 % (0x9A).
    SpindleOvPlus10,
    /// Spindle override -10 % (0x9B).
    SpindleOvMinus10,
    /// Spindle override +1 % (0x9C).
    SpindleOvPlus1,
    /// Spindle override -1 % (0x9D).
    SpindleOvMinus1,
    /// Spindle stop toggle, only during hold (0x9E).
    SpindleStopToggle,
    /// Flood coolant toggle (0xA0).
    FloodToggle,
    /// Mist coolant toggle (0xA1).
    MistToggle,
}

/// `(command, GRBL byte)` for every realtime command, in priority order.
const TABLE: [(Rt, u8); 22] = [
    (Rt::SoftReset, 0x18),
    (Rt::StatusQuery, b'?'),
    (Rt::FeedHold, b'!'),
    (Rt::CycleStart, b'~'),
    (Rt::SafetyDoor, 0x84),
    (Rt::JogCancel, 0x85),
    (Rt::FeedOv100, 0x90),
    (Rt::FeedOvPlus10, 0x91),
    (Rt::FeedOvMinus10, 0x92),
    (Rt::FeedOvPlus1, 0x93),
    (Rt::FeedOvMinus1, 0x94),
    (Rt::RapidOv100, 0x95),
    (Rt::RapidOv50, 0x96),
    (Rt::RapidOv25, 0x97),
    (Rt::SpindleOv100, 0x99),
    (Rt::SpindleOvPlus10, 0x9A),
    (Rt::SpindleOvMinus10, 0x9B),
    (Rt::SpindleOvPlus1, 0x9C),
    (Rt::SpindleOvMinus1, 0x9D),
    (Rt::SpindleStopToggle, 0x9E),
    (Rt::FloodToggle, 0xA0),
    (Rt::MistToggle, 0xA1),
];

impl Rt {
    /// Every realtime command, highest priority first.
    pub const ALL: [Rt; 22] = {
        let mut all = [Rt::SoftReset; 22];
        let mut i = 0;
        while i < TABLE.len() {
            all[i] = TABLE[i].0;
            i += 1;
        }
        all
    };

    /// The text-mode byte for `b`, if it is a realtime byte.
    pub const fn from_byte(b: u8) -> Option<Rt> {
        let mut i = 0;
        while i < TABLE.len() {
            if TABLE[i].1 == b {
                return Some(TABLE[i].0);
            }
            i += 1;
        }
        None
    }

    /// The GRBL byte that sends this command in text mode.
    pub const fn byte(self) -> u8 {
        TABLE[self as usize].1
    }

    /// This command's bit in a pending-flags word.
    pub const fn bit(self) -> u32 {
        1 << (self as u32)
    }

    /// The commands whose bits are set in `flags`, highest priority first.
    /// Visits only the set bits (lowest first, which is `ALL`'s order: the
    /// bit of each command is its index there), so an empty set costs
    /// nothing: the parse task asks at every pass.
    pub fn iter_bits(flags: u32) -> impl Iterator<Item = Rt> {
        let mut left = flags & ((1u32 << Rt::ALL.len()) - 1);
        core::iter::from_fn(move || {
            let i = left.trailing_zeros() as usize;
            left &= left.wrapping_sub(1);
            Rt::ALL.get(i).copied()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iter_bits_visits_the_set_commands_in_priority_order() {
        let all: u32 = Rt::ALL.iter().fold(0, |a, r| a | r.bit());
        assert!(Rt::iter_bits(all).eq(Rt::ALL));
        assert_eq!(Rt::iter_bits(0).count(), 0);
        let some = Rt::FeedHold.bit() | Rt::SoftReset.bit() | Rt::MistToggle.bit();
        let want = [Rt::SoftReset, Rt::FeedHold, Rt::MistToggle];
        assert!(Rt::iter_bits(some | 1 << 31).eq(want));
    }

    #[test]
    fn table_is_in_discriminant_order_and_bytes_round_trip() {
        for (i, (rt, b)) in TABLE.iter().enumerate() {
            assert_eq!(*rt as usize, i);
            assert_eq!(Rt::from_byte(*b), Some(*rt));
            assert_eq!(rt.byte(), *b);
        }
        assert_eq!(Rt::from_byte(b'G'), None);
        assert_eq!(Rt::from_byte(0x98), None);
        assert_eq!(Rt::from_byte(0x00), None);
    }
}
