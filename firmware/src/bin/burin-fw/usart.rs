//! The USART side of the link, for boards without a USB device (QEMU's
//! netduinoplus2 has no OTG model). Same contract as `usb.rs`: received
//! bytes go through the link's [`RxSplitter`] into the token ring (realtime
//! bytes become flags at once), replies come from the TX byte ring, and
//! everything runs in the link interrupt at the same priority.
use burin::link::{RtFlags, RxSplitter, RxToken};
use heapless::spsc::{Consumer, Producer};
use stm32f4xx_hal::{
    nb, pac,
    prelude::*,
    serial::{Event, Serial},
};

/// The link's interrupt: the parse task pends it after queueing a reply.
pub const IRQ: pac::Interrupt = pac::Interrupt::USART1;

/// Line rate; QEMU ignores it, a real USART-to-USB bridge would not.
pub const BAUD: u32 = 115_200;

pub struct UsartLink {
    serial: Serial<pac::USART1>,
    splitter: RxSplitter,
    rx: Producer<'static, RxToken>,
    tx: Consumer<'static, u8>,
    errors: u32,
}

impl UsartLink {
    /// Takes a USART already set up for `BAUD` 8N1 and starts listening for
    /// received bytes.
    pub fn new(
        mut serial: Serial<pac::USART1>,
        rx: Producer<'static, RxToken>,
        tx: Consumer<'static, u8>,
    ) -> Self {
        serial.listen(Event::RxNotEmpty);
        UsartLink {
            serial,
            splitter: RxSplitter::new(),
            rx,
            tx,
            errors: 0,
        }
    }

    /// Everything the USART interrupt does: drain the receiver through the
    /// splitter, then feed the transmitter while it has room. TXE is
    /// listened to only while replies wait, or it would fire forever.
    /// Returns true when the parse task has something new to do.
    pub fn service(&mut self, flags: &RtFlags) -> bool {
        let got = self.receive(flags);
        got | self.transmit()
    }

    fn receive(&mut self, flags: &RtFlags) -> bool {
        let mut buf = [0u8; 64];
        let mut n = 0;
        let mut any = false;
        loop {
            match _embedded_hal_serial_nb_Read::read(&mut self.serial) {
                Ok(byte) => {
                    if let Some(slot) = buf.get_mut(n) {
                        *slot = byte;
                        n += 1;
                    }
                    if n == buf.len() {
                        self.splitter.feed(&buf, &mut self.rx, flags);
                        (n, any) = (0, true);
                    }
                }
                // WouldBlock: nothing more; an overrun or framing error has
                // been cleared by the read, and the bytes are lost either way
                // (a character-counting sender never overruns the window).
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => self.errors = self.errors.wrapping_add(1),
            }
        }
        if let Some(rest) = buf.get(..n).filter(|b| !b.is_empty()) {
            self.splitter.feed(rest, &mut self.rx, flags);
            any = true;
        }
        any
    }

    /// Returns true when the TX ring ran empty (a blocked parse task may go on).
    fn transmit(&mut self) -> bool {
        let mut sent = false;
        while let Some(&byte) = self.tx.peek() {
            match _embedded_hal_serial_nb_Write::write(&mut self.serial, byte) {
                Ok(()) => {
                    self.tx.dequeue();
                    sent = true;
                }
                Err(_) => {
                    // Data register full: TXE calls us again when it empties.
                    self.serial.listen(Event::TxEmpty);
                    return false;
                }
            }
        }
        self.serial.unlisten(Event::TxEmpty);
        sent
    }
}
