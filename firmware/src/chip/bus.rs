//! Which bus master can reach which address: the memory map (RM0383 §2.3,
//! table 1; RM0368 §2.3, table 1) and the bus matrix (RM0383 §2.1,
//! figure 1; RM0368 §2.1, figure 1). The two chips share both except the
//! sizes of flash and SRAM.
//!
//! Why this is data and not a comment: a DMA stream programmed with an
//! address its port cannot reach does not write anything. The chip raises
//! the stream's transfer-error flag and disables it (RM0383 §9.3.16), and
//! nothing else tells. The board code before this module made exactly that
//! mistake (DMA1's memory port writing GPIOB); `DmaPath::check` now refuses
//! such a path in the library, host-sim's DMA model follows the same
//! table, and the board's boot check catches what the table could not.

use super::Chip;

/// An address range of the memory map, as the bus matrix sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Region {
    /// Main flash memory (0x0800_0000).
    Flash,
    /// SRAM1 (0x2000_0000; 128 KiB on the F411, 64 KiB on the F401CC).
    Sram,
    /// APB1 peripherals, 0x4000_0000..0x4000_8000: TIM2-TIM5, USART2, I2C,
    /// SPI2/3, PWR, IWDG.
    Apb1,
    /// APB2 peripherals, 0x4001_0000..0x4001_5800: TIM1, USART1/6, ADC1,
    /// SPI1/4/5, SYSCFG, EXTI, TIM9-11.
    Apb2,
    /// AHB1 peripherals, 0x4002_0000..0x4002_6800: GPIOA-H, CRC, RCC, the
    /// flash interface, DMA1, DMA2.
    Ahb1,
    /// AHB2, 0x5000_0000..0x5004_0000: USB OTG FS.
    Ahb2,
    /// Anything else: reserved space, system memory, the Cortex-M4's own
    /// peripherals (0xE000_0000..; only the CPU reaches those).
    Other,
}

/// The base of each register block the board code addresses directly.
pub mod addr {
    /// TIM5 (RM0383 table 1).
    pub const TIM5: u32 = 0x4000_0C00;
    /// TIM1.
    pub const TIM1: u32 = 0x4001_0000;
    /// GPIOA, GPIOB.
    pub const GPIOA: u32 = 0x4002_0000;
    pub const GPIOB: u32 = 0x4002_0400;
    /// DMA1, DMA2.
    pub const DMA1: u32 = 0x4002_6000;
    pub const DMA2: u32 = 0x4002_6400;
    /// Offsets inside a block (RM0383 §8.4 GPIO, §12.4 TIM1, §13.4 TIM2-5).
    pub const GPIO_BSRR: u32 = 0x18;
    pub const TIM_CCR2: u32 = 0x38;
    pub const TIM_CCR3: u32 = 0x3C;
    /// Start of SRAM.
    pub const SRAM: u32 = 0x2000_0000;
}

impl Chip {
    /// Where `a` lies in this chip's memory map.
    pub const fn region(self, a: u32) -> Region {
        let (flash, sram) = self.memory();
        if a >= 0x0800_0000 && a - 0x0800_0000 < flash {
            Region::Flash
        } else if a >= addr::SRAM && a - addr::SRAM < sram {
            Region::Sram
        } else if a >= 0x4000_0000 && a < 0x4000_8000 {
            Region::Apb1
        } else if a >= 0x4001_0000 && a < 0x4001_5800 {
            Region::Apb2
        } else if a >= 0x4002_0000 && a < 0x4002_6800 {
            Region::Ahb1
        } else if a >= 0x5000_0000 && a < 0x5004_0000 {
            Region::Ahb2
        } else {
            Region::Other
        }
    }

    /// Flash and SRAM sizes in bytes (RM0383 §2.3 / §3.3; RM0368 §2.3 /
    /// §3.3; the CC/CE suffix fixes the flash size).
    pub const fn memory(self) -> (u32, u32) {
        match self {
            Chip::F411 => (512 * 1024, 128 * 1024),
            Chip::F401 => (256 * 1024, 64 * 1024),
        }
    }
}

/// The two ports of each DMA controller (RM0383 §9.2, figure 24): a
/// stream reads through one and writes through the other, which one by the
/// transfer direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Port {
    /// DMA1's memory port: bus matrix master S3.
    Dma1Memory,
    /// DMA1's peripheral port: not on the bus matrix; it is wired to the
    /// AHB-APB1 bridge alone (figure 1: `DMA_PI` -> APB1).
    Dma1Peripheral,
    /// DMA2's memory port: bus matrix master S4.
    Dma2Memory,
    /// DMA2's peripheral port: bus matrix master S5.
    Dma2Peripheral,
}

impl Port {
    /// Whether this port reaches `region` (RM0383 §2.1.4 "S3, S4: DMA
    /// memory bus": its targets are the data memories, flash and SRAM;
    /// §2.1.5 "S5: DMA peripheral bus": the AHB and APB peripherals plus
    /// the data memories; figure 1 for DMA1's peripheral port, APB1 only).
    ///
    /// The reading is the conservative one: some readings of figure 1
    /// give DMA2's memory port the AHB peripherals as well. burin's paths
    /// never rely on that; the table refuses it, so a path it accepts
    /// works under either reading.
    pub const fn reaches(self, region: Region) -> bool {
        use Region::*;
        match self {
            Port::Dma1Memory | Port::Dma2Memory => matches!(region, Flash | Sram),
            Port::Dma1Peripheral => matches!(region, Apb1),
            Port::Dma2Peripheral => matches!(region, Flash | Sram | Apb1 | Apb2 | Ahb1 | Ahb2),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_of_the_registers_the_board_uses() {
        let c = Chip::F411;
        assert_eq!(c.region(addr::TIM5 + addr::TIM_CCR3), Region::Apb1);
        assert_eq!(c.region(addr::TIM1 + addr::TIM_CCR2), Region::Apb2);
        assert_eq!(c.region(addr::GPIOB + addr::GPIO_BSRR), Region::Ahb1);
        assert_eq!(c.region(0x2001_FFFC), Region::Sram);
        // The F401CC's SRAM ends at 64 KiB: the F411's upper half is not there.
        assert_eq!(Chip::F401.region(0x2001_FFFC), Region::Other);
        assert_eq!(c.region(0xE000_E010), Region::Other);
    }

    #[test]
    fn only_dma2s_peripheral_port_reaches_gpio() {
        let bsrr = Chip::F411.region(addr::GPIOB + addr::GPIO_BSRR);
        assert!(!Port::Dma1Memory.reaches(bsrr));
        assert!(!Port::Dma1Peripheral.reaches(bsrr));
        assert!(!Port::Dma2Memory.reaches(bsrr));
        assert!(Port::Dma2Peripheral.reaches(bsrr));
        assert!(Port::Dma1Peripheral.reaches(Region::Apb1));
        assert!(!Port::Dma1Peripheral.reaches(Region::Apb2));
    }
}
