//! USB identity of the board, shared by the firmware and the host tools (the
//! streamer finds the board's serial port by these numbers).

/// pid.codes' vendor ID, which it shares with open-source hardware projects.
pub const USB_VID: u16 = 0x1209;

/// pid.codes' "Test PID" (1209:0001). pid.codes keeps PIDs 0x0000-0x0FFF of
/// its VID for common uses such as testing; a released burin should request its
/// own PID there and change only this line.
pub const USB_PID: u16 = 0x0001;

/// Manufacturer string descriptor.
pub const USB_MANUFACTURER: &str = "burin project";

/// Product string descriptor; host tools match on it as well as on VID/PID,
/// because the test PID is shared with other people's test devices.
pub const USB_PRODUCT: &str = "burin CNC controller";

/// Length of the serial-number string: the chip's 96-bit unique ID in hex.
pub const USB_SERIAL_LEN: usize = 24;

/// Formats the three unique-ID words (as read from 0x1FFF_7A10, lowest
/// address first) as 24 upper-case hex digits, most significant nibble of
/// each word first, the way ST's own tools print the UID.
pub fn serial_from_uid(words: [u32; 3], out: &mut [u8; USB_SERIAL_LEN]) -> &str {
    const HEX: &[u8; 16] = b"0123456789ABCDEF";
    for (chunk, word) in out.chunks_exact_mut(8).zip(words) {
        for (i, digit) in chunk.iter_mut().enumerate() {
            // i < 8 so the shift stays below 32; the mask keeps the index < 16.
            *digit = HEX[((word >> (28 - 4 * i)) & 0xF) as usize];
        }
    }
    // Every byte is an ASCII hex digit, so this never fails; the fallback
    // keeps the function total without a panic path.
    core::str::from_utf8(out).unwrap_or("0")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serial_is_24_hex_digits_word_by_word() {
        let mut buf = [0; USB_SERIAL_LEN];
        let s = serial_from_uid([0x0034_0021, 0x3235_5105, 0xDEAD_BEEF], &mut buf);
        assert_eq!(s, "0034002132355105DEADBEEF");
    }

    #[test]
    fn distinct_ids_give_distinct_serials() {
        let (mut a, mut b) = ([0; USB_SERIAL_LEN], [0; USB_SERIAL_LEN]);
        let sa = serial_from_uid([1, 2, 3], &mut a).to_owned();
        let sb = serial_from_uid([1, 2, 4], &mut b);
        assert_ne!(sa, sb);
        assert_eq!(sb.len(), USB_SERIAL_LEN);
    }
}
