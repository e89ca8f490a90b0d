//! DMA paths as data: which request drives which stream and channel
//! (RM0383 §9.3.3, tables 27 and 28; RM0368 §9.3.3, the same tables), and
//! whether a stream's two ports reach the addresses it is given
//! ([`super::bus`]). The board programs its streams from a [`DmaPath`]
//! built here, host-sim's DMA model runs the same value, and
//! [`DmaPath::check`] says what the chip would do with it.

use super::bus::{Port, Region};
use super::Chip;

/// The controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dma {
    Dma1,
    Dma2,
}

/// Transfer direction (DMA_SxCR.DIR). Memory-to-memory is left out: it
/// cannot be triggered by a peripheral request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    /// Reads at PAR through the peripheral port, writes at M0AR through
    /// the memory port.
    PeripheralToMemory,
    /// Reads at M0AR through the memory port, writes at PAR through the
    /// peripheral port.
    MemoryToPeripheral,
}

/// Peripheral requests the board code uses (and the one it used to).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    /// TIM1 compare 2: its match ends the step pulse.
    Tim1Ch2,
    /// TIM5 compare 2 (burin up to 16ae6d1; its stream is on DMA1).
    Tim5Ch2,
}

/// `(controller, stream, channel, request)`: the entries of tables 27 and
/// 28 for the requests in [`Request`].
const MAP: [(Dma, u8, u8, Request); 2] = [
    (Dma::Dma1, 4, 6, Request::Tim5Ch2),
    (Dma::Dma2, 2, 6, Request::Tim1Ch2),
];

/// One stream's configuration: what the board writes to DMA_SxCR (channel,
/// direction), DMA_SxPAR and DMA_SxM0AR.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DmaPath {
    pub dma: Dma,
    pub stream: u8,
    pub channel: u8,
    pub request: Request,
    pub dir: Dir,
    pub par: u32,
    pub m0ar: u32,
}

/// Why a path cannot work on the chip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathFault {
    /// The request is not wired to this stream and channel: the stream
    /// never sees it.
    NotMapped,
    /// The port that reads (`Port`) cannot reach the source address: a
    /// transfer error at the first request.
    ReadUnreachable(Port, Region),
    /// The port that writes cannot reach the destination.
    WriteUnreachable(Port, Region),
}

impl DmaPath {
    /// The step pulse's end on the boards: TIM1's compare 2 requests DMA2
    /// stream 2, channel 6, which copies the step-off word from SRAM
    /// (`word`, read through DMA2's memory port) to the step port's BSRR
    /// (`bsrr`, written through DMA2's peripheral port, bus matrix S5 ->
    /// AHB1).
    pub const fn pulse_end(bsrr: u32, word: u32) -> DmaPath {
        DmaPath {
            dma: Dma::Dma2,
            stream: 2,
            channel: 6,
            request: Request::Tim1Ch2,
            dir: Dir::MemoryToPeripheral,
            par: bsrr,
            m0ar: word,
        }
    }

    /// The path burin used up to 16ae6d1: TIM5's compare 2 on DMA1 stream
    /// 4, channel 6, reading the step-off word from TIM5's CCR3 and writing
    /// GPIOB's BSRR through DMA1's memory port, which cannot reach it.
    pub const fn before_16ae6d1() -> DmaPath {
        use super::bus::addr::*;
        DmaPath {
            dma: Dma::Dma1,
            stream: 4,
            channel: 6,
            request: Request::Tim5Ch2,
            dir: Dir::PeripheralToMemory,
            par: TIM5 + TIM_CCR3,
            m0ar: GPIOB + GPIO_BSRR,
        }
    }

    /// The ports that read and write, in that order.
    pub const fn ports(&self) -> (Port, Port) {
        let (mem, periph) = match self.dma {
            Dma::Dma1 => (Port::Dma1Memory, Port::Dma1Peripheral),
            Dma::Dma2 => (Port::Dma2Memory, Port::Dma2Peripheral),
        };
        match self.dir {
            Dir::PeripheralToMemory => (periph, mem),
            Dir::MemoryToPeripheral => (mem, periph),
        }
    }

    /// The source and destination addresses.
    pub const fn ends(&self) -> (u32, u32) {
        match self.dir {
            Dir::PeripheralToMemory => (self.par, self.m0ar),
            Dir::MemoryToPeripheral => (self.m0ar, self.par),
        }
    }

    /// What the chip makes of this path: `Ok` when the request reaches the
    /// stream and both ports reach their addresses.
    pub fn check(&self, chip: Chip) -> Result<(), PathFault> {
        let mapped = MAP.iter().any(|&(d, s, c, r)| {
            d == self.dma && s == self.stream && c == self.channel && r == self.request
        });
        if !mapped {
            return Err(PathFault::NotMapped);
        }
        let (read, write) = self.ports();
        let (src, dst) = self.ends();
        let (rs, rd) = (chip.region(src), chip.region(dst));
        if !read.reaches(rs) {
            return Err(PathFault::ReadUnreachable(read, rs));
        }
        if !write.reaches(rd) {
            return Err(PathFault::WriteUnreachable(write, rd));
        }
        Ok(())
    }
}

/// A stream's status flags as DMA_LISR/HISR hold them (RM0383 §9.5.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamFlags {
    /// TCIFx: a transfer completed.
    pub complete: bool,
    /// TEIFx: a bus error; the hardware cleared EN.
    pub transfer_error: bool,
    /// DMEIFx: a direct-mode error.
    pub direct_error: bool,
    /// DMA_SxCR.EN as read back: a circular stream stays enabled.
    pub enabled: bool,
}

impl StreamFlags {
    /// DMA_LISR/HISR bit positions of stream `n` (0..8): FEIF at the
    /// base, DMEIF +2, TEIF +3, HTIF +4, TCIF +5; bases 0, 6, 16, 22 for
    /// streams 0-3 in LISR and 4-7 in HISR.
    pub const fn base_bit(stream: u8) -> u32 {
        [0, 6, 16, 22][(stream & 3) as usize]
    }

    /// From the raw LISR (streams 0-3) or HISR (4-7) word and EN.
    pub const fn from_isr(word: u32, stream: u8, enabled: bool) -> StreamFlags {
        let b = Self::base_bit(stream);
        StreamFlags {
            complete: word >> (b + 5) & 1 != 0,
            transfer_error: word >> (b + 3) & 1 != 0,
            direct_error: word >> (b + 2) & 1 != 0,
            enabled,
        }
    }

    /// The stream is broken: an error flag, or a circular stream that the
    /// hardware disabled.
    pub const fn failed(&self) -> bool {
        self.transfer_error || self.direct_error || !self.enabled
    }
}

#[cfg(test)]
mod tests {
    use super::super::bus::addr::*;
    use super::*;

    #[test]
    fn the_boards_pulse_end_path_works_on_both_chips() {
        let p = DmaPath::pulse_end(GPIOB + GPIO_BSRR, 0x2000_0100);
        assert_eq!(p.check(Chip::F411), Ok(()));
        assert_eq!(p.check(Chip::F401), Ok(()));
    }

    #[test]
    fn the_path_of_16ae6d1_cannot_write_gpio() {
        let p = DmaPath::before_16ae6d1();
        assert_eq!(
            p.check(Chip::F411),
            Err(PathFault::WriteUnreachable(Port::Dma1Memory, Region::Ahb1))
        );
    }

    #[test]
    fn a_request_on_the_wrong_stream_is_refused() {
        let mut p = DmaPath::pulse_end(GPIOB + GPIO_BSRR, 0x2000_0100);
        p.stream = 1;
        assert_eq!(p.check(Chip::F411), Err(PathFault::NotMapped));
        // DMA2 memory-to-peripheral with the source on a peripheral: the
        // memory port cannot read it.
        let mut q = DmaPath::pulse_end(GPIOB + GPIO_BSRR, TIM1 + TIM_CCR3);
        q.dir = Dir::MemoryToPeripheral;
        assert_eq!(
            q.check(Chip::F411),
            Err(PathFault::ReadUnreachable(Port::Dma2Memory, Region::Apb2))
        );
    }

    #[test]
    fn flags_from_the_status_words() {
        // Stream 2: TEIF2 is bit 19, TCIF2 bit 21.
        let f = StreamFlags::from_isr(1 << 19, 2, false);
        assert!(f.transfer_error && !f.complete && f.failed());
        let ok = StreamFlags::from_isr(1 << 21, 2, true);
        assert!(ok.complete && !ok.failed());
        // Stream 4 in HISR: TEIF4 is bit 3.
        assert!(StreamFlags::from_isr(1 << 3, 4, true).transfer_error);
    }
}
