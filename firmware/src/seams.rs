//! The only places the motion core touches hardware. The RTIC binary
//! implements these with registers; host-sim with a virtual clock, a
//! recorder and files.

/// Step and direction outputs. Bit n of each mask is axis n (X, Y, Z, A).
/// Implementations write all set bits at once (one BSRR write on STM32), so
/// the axes of one event pulse together.
pub trait StepPins {
    /// Set the direction pins: bit set means negative direction
    /// (before the invert mask, which implementations apply).
    fn set_dirs(&mut self, dir_mask: u8);
    /// Raise the step pins in `step_mask`.
    fn step_high(&mut self, step_mask: u8);
    /// Lower all step pins (end of pulse).
    fn step_low(&mut self);
    /// Stepper drivers on/off.
    fn set_enabled(&mut self, on: bool);
}

/// The step timer: a free-running tick counter with one pending compare.
pub trait StepTimer {
    /// Tick rate in Hz (96 MHz TIM5 on the F411; whatever host-sim chooses).
    fn tick_hz(&self) -> u32;
    /// Fire the next step event `ticks` after the current one.
    fn schedule_in(&mut self, ticks: u32);
    /// Stop firing events (idle, hold complete, alarm).
    fn stop(&mut self);
}

/// Persistent records: a small key/value store (a record log
/// in flash on the MCU, RAM on QEMU and in host-sim; see `persist`). It is
/// blocking on purpose: a flash write stalls the CPU anyway (code runs from
/// flash), so the device calls it only while no motion runs.
pub trait Storage {
    type Error: core::fmt::Debug;
    /// Read the newest record for `key` into `buf`, returning its length,
    /// or `None` when there is none (a torn last write leaves the one before).
    fn load(&mut self, key: u16, buf: &mut [u8]) -> Result<Option<usize>, Self::Error>;
    /// Write the record for `key`; it replaces the previous one only once
    /// it is complete.
    fn store(&mut self, key: u16, data: &[u8]) -> Result<(), Self::Error>;
}

/// No storage: nothing is ever found, writes vanish. Devices built with
/// `Device::new` (tests, tools) use it.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStorage;

impl Storage for NoStorage {
    type Error = core::convert::Infallible;
    fn load(&mut self, _key: u16, _buf: &mut [u8]) -> Result<Option<usize>, Self::Error> {
        Ok(None)
    }
    fn store(&mut self, _key: u16, _data: &[u8]) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Reply bytes towards the host: the TX ring the USB (or USART)
/// interrupt drains on the board, a buffer host-sim hands to its pty or
/// pipe. It must take every byte: the session writes whole replies only,
/// and runs only while [`Tx::room`] holds its longest burst.
pub trait Tx {
    fn send(&mut self, bytes: &[u8]);
    /// Bytes it can take now (a ring's free space; unbounded sinks say so).
    fn room(&self) -> usize {
        usize::MAX
    }
}

impl<T: Tx + ?Sized> Tx for &mut T {
    fn send(&mut self, bytes: &[u8]) {
        (**self).send(bytes)
    }
    fn room(&self) -> usize {
        (**self).room()
    }
}
