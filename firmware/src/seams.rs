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

/// Persistent settings: a small key/value store (flash sectors on the MCU,
/// a file or memory on the host).
pub trait Storage {
    type Error: core::fmt::Debug;
    /// Read the record for `key` into `buf`, returning its length, or `None`.
    fn load(&mut self, key: u16, buf: &mut [u8]) -> Result<Option<usize>, Self::Error>;
    /// Write the record for `key`.
    fn store(&mut self, key: u16, data: &[u8]) -> Result<(), Self::Error>;
}

/// Byte link to the PC (USB-CDC on the MCU; a pty or pipe on the host).
pub trait Serial {
    /// Queue bytes for transmission; returns how many were accepted.
    fn write(&mut self, bytes: &[u8]) -> usize;
}
