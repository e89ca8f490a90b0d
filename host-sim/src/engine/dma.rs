//! The pulse-end DMA stream as the chip runs it, for the paths the board
//! code programs (`burin::chip::dma::DmaPath`): a request on a path whose
//! ports reach both addresses copies the step-off word to the step port;
//! on any other path the chip raises the stream's transfer-error flag and
//! disables it, and no pin changes (RM0383 §9.3.16). The verdict is
//! `DmaPath::check`, the same table the board code is checked against, so
//! the model cannot be kinder to a path than the library is.

use burin::chip::dma::{DmaPath, PathFault, StreamFlags};
use burin::chip::{Chip, PulseEndHw};

/// One DMA stream in circular mode with one item, as the board sets it up.
#[derive(Clone, Copy, Debug)]
pub struct PulseDma {
    path: DmaPath,
    chip: Chip,
    flags: StreamFlags,
}

impl PulseDma {
    /// The stream enabled on `path` (as the board's init leaves it).
    pub fn new(path: DmaPath, chip: Chip) -> Self {
        PulseDma {
            path,
            chip,
            flags: StreamFlags {
                enabled: true,
                ..StreamFlags::default()
            },
        }
    }

    /// One request from the timer: true when the word reached the pins.
    /// A request that is not wired to the stream does nothing at all; a
    /// path with an unreachable port errors and disables the stream.
    pub fn request(&mut self) -> bool {
        if !self.flags.enabled {
            return false;
        }
        match self.path.check(self.chip) {
            Ok(()) => {
                self.flags.complete = true;
                true
            }
            Err(PathFault::NotMapped) => false,
            Err(_) => {
                self.flags.transfer_error = true;
                self.flags.enabled = false;
                false
            }
        }
    }

    pub fn flags(&self) -> StreamFlags {
        self.flags
    }
}

impl PulseEndHw for PulseDma {
    fn request_once(&mut self) {
        self.request();
    }
    fn flags(&self) -> StreamFlags {
        self.flags
    }
    fn clear_flags(&mut self) {
        self.flags.complete = false;
        self.flags.transfer_error = false;
        self.flags.direct_error = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use burin::chip::bus::addr::*;

    #[test]
    fn the_16ae6d1_path_errors_and_disables_the_stream() {
        let mut old = PulseDma::new(DmaPath::before_16ae6d1(), Chip::F411);
        assert!(!old.request(), "no write reaches GPIOB");
        let f = old.flags();
        assert!(f.transfer_error && !f.enabled);
        assert!(!old.request(), "a disabled stream stays silent");
        assert_eq!(
            burin::chip::self_test(&mut PulseDma::new(DmaPath::before_16ae6d1(), Chip::F411)),
            Err(burin::chip::HwFault::PulseEndSelfTest)
        );
    }

    #[test]
    fn the_boards_path_writes_every_time() {
        let path = DmaPath::pulse_end(GPIOB + GPIO_BSRR, SRAM + 0x100);
        let mut dma = PulseDma::new(path, Chip::F401);
        assert!(dma.request() && dma.request());
        assert!(!dma.flags().failed());
        assert_eq!(burin::chip::self_test(&mut dma), Ok(()));
    }
}
