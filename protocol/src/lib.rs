//! burin's native wire format, shared by the firmware and host tools.
#![cfg_attr(not(feature = "std"), no_std)]

/// Protocol version exchanged in the handshake.
pub const PROTOCOL_VERSION: u16 = 1;
