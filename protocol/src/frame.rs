//! COBS framing with a CRC-16 over the postcard bytes.
//!
//! On the wire: `COBS(payload ++ crc16_le(payload)) ++ 0x00`, where `payload`
//! is the postcard encoding of one message. The 0x00 delimiter never occurs
//! inside a frame, so a receiver that lost sync (noise, a dropped byte) is
//! back in step at the next 0x00, and a damaged frame costs exactly one
//! frame. The CRC sits *inside* the COBS so it checks the bytes postcard
//! will read, and a decoder never parses unchecked bytes.
//!
//! All buffers are fixed: [`FrameDecoder`] holds [`MAX_FRAME`] bytes and
//! discards (then reports) anything longer instead of growing.

use crate::codes::Code;
use serde::{de::DeserializeOwned, Serialize};

/// CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no xorout.
const CRC16: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);

/// CRC bytes appended to the payload.
pub const CRC_LEN: usize = 2;
/// Largest postcard payload: a [`crate::MAX_LINE`]-byte line plus its tag,
/// sequence number and length prefix fits with room to spare.
pub const MAX_PAYLOAD: usize = 280;
/// Largest encoded frame, delimiter excluded (COBS adds one byte per 254).
pub const MAX_FRAME: usize = 288;
/// Buffer size that always holds an encoded frame and its delimiter.
pub const MAX_WIRE: usize = MAX_FRAME + 1;

/// Why a frame was rejected. Each maps to a stable [`Code`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// COBS structure broken.
    Corrupt,
    /// CRC mismatch (or too short to hold a CRC).
    Crc,
    /// More than [`MAX_FRAME`] bytes before the delimiter.
    TooLong,
    /// CRC good, but not a valid message (or the message does not fit).
    Decode,
}

impl FrameError {
    /// The stable code sent back in a `Nak` and printed by tools.
    pub const fn code(self) -> Code {
        match self {
            FrameError::Corrupt => Code::FrameCorrupt,
            FrameError::Crc => Code::FrameCrc,
            FrameError::TooLong => Code::FrameTooLong,
            FrameError::Decode => Code::FrameDecode,
        }
    }
}

/// The CRC this protocol uses, for tools that want to check by hand.
pub fn crc16(bytes: &[u8]) -> u16 {
    CRC16.checksum(bytes)
}

/// Encode `msg` as one frame including its 0x00 delimiter into `out`;
/// returns the number of bytes written. `out` of [`MAX_WIRE`] bytes always
/// suffices for messages that fit [`MAX_PAYLOAD`].
pub fn encode<T: Serialize>(msg: &T, out: &mut [u8]) -> Result<usize, FrameError> {
    let mut raw = [0u8; MAX_PAYLOAD + CRC_LEN];
    let n = postcard::to_slice(msg, &mut raw[..MAX_PAYLOAD])
        .map_err(|_| FrameError::TooLong)?
        .len();
    let crc = crc16(&raw[..n]).to_le_bytes();
    raw[n..n + CRC_LEN].copy_from_slice(&crc);
    let used = cobs::try_encode(&raw[..n + CRC_LEN], out).map_err(|_| FrameError::TooLong)?;
    let delim = out.get_mut(used).ok_or(FrameError::TooLong)?;
    *delim = 0;
    Ok(used + 1)
}

/// Decode one frame given without its delimiter. Decodes in place, so the
/// buffer's contents are destroyed.
pub fn decode<T: DeserializeOwned>(encoded: &mut [u8]) -> Result<T, FrameError> {
    if encoded.len() > MAX_FRAME {
        return Err(FrameError::TooLong);
    }
    let n = cobs::decode_in_place(encoded).map_err(|_| FrameError::Corrupt)?;
    let body = encoded.get(..n).ok_or(FrameError::Corrupt)?;
    if n < CRC_LEN + 1 {
        return Err(FrameError::Crc);
    }
    let (payload, crc) = body.split_at(n - CRC_LEN);
    if crc16(payload).to_le_bytes() != [crc[0], crc[1]] {
        return Err(FrameError::Crc);
    }
    match postcard::take_from_bytes::<T>(payload) {
        Ok((msg, [])) => Ok(msg),
        _ => Err(FrameError::Decode),
    }
}

/// Byte-at-a-time frame receiver with a fixed buffer.
#[derive(Clone, Debug)]
pub struct FrameDecoder {
    buf: [u8; MAX_FRAME],
    len: usize,
    too_long: bool,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameDecoder {
    pub const fn new() -> Self {
        FrameDecoder {
            buf: [0; MAX_FRAME],
            len: 0,
            too_long: false,
        }
    }

    /// Forget a partial frame (link reset).
    pub fn reset(&mut self) {
        self.len = 0;
        self.too_long = false;
    }

    /// True between frames (nothing buffered).
    pub fn is_idle(&self) -> bool {
        self.len == 0 && !self.too_long
    }

    /// Feed one byte. Returns a result when a delimiter ends a non-empty
    /// frame; empty frames (repeated 0x00) are ignored, which lets a host
    /// send 0x00 to flush a receiver of unknown state.
    pub fn push<T: DeserializeOwned>(&mut self, byte: u8) -> Option<Result<T, FrameError>> {
        if byte != 0 {
            match self.buf.get_mut(self.len) {
                Some(slot) if !self.too_long => {
                    *slot = byte;
                    self.len += 1;
                }
                _ => self.too_long = true,
            }
            return None;
        }
        let (len, too_long) = (self.len, self.too_long);
        self.reset();
        if too_long {
            return Some(Err(FrameError::TooLong));
        }
        if len == 0 {
            return None;
        }
        Some(decode(&mut self.buf[..len]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::{HostMsg, LineText};

    #[test]
    fn longest_line_fits_the_limits() {
        let text = LineText::from_slice(&[0xFF; crate::MAX_LINE]).unwrap_or_default();
        let msg = HostMsg::Line {
            seq: u32::MAX,
            text,
        };
        let mut out = [0u8; MAX_WIRE];
        let n = encode(&msg, &mut out).expect("fits");
        assert!(n <= MAX_WIRE);
        let mut d = FrameDecoder::new();
        let got = out[..n].iter().filter_map(|b| d.push::<HostMsg>(*b)).next();
        assert_eq!(got, Some(Ok(msg)));
    }
}
