//! The USART side of the link, for boards without a USB device (QEMU's
//! netduinoplus2 has no OTG model). Same contract as `usb.rs`: received
//! bytes go to the parse task as packets through a channel, replies come back
//! through another, and everything runs in the link interrupt (USART1 here,
//! OTG_FS there) at the same priority, so the app's tasks are the same.
use rtic_sync::channel::{Receiver, Sender};
use stm32f4xx_hal::{
    nb, pac,
    prelude::*,
    serial::{Event, Serial},
};

/// Packets moved between tasks; 64 bytes like a USB full-speed packet.
pub type Packet = heapless::Vec<u8, 64>;
/// Packets the parse task may lag behind reception.
pub const RX_PACKETS: usize = 8;
/// Reply packets waiting for the transmitter.
pub const TX_PACKETS: usize = 4;

pub type RxSender = Sender<'static, Packet, RX_PACKETS>;
pub type RxReceiver = Receiver<'static, Packet, RX_PACKETS>;
pub type TxSender = Sender<'static, Packet, TX_PACKETS>;
pub type TxReceiver = Receiver<'static, Packet, TX_PACKETS>;

/// The link's interrupt: the parse task pends it after queueing a reply.
pub const IRQ: pac::Interrupt = pac::Interrupt::USART1;

/// Line rate; QEMU ignores it, a real USART-to-USB bridge would not.
pub const BAUD: u32 = 115_200;

pub struct UsartLink {
    serial: Serial<pac::USART1>,
    rx: RxSender,
    tx: TxReceiver,
    /// Reply being written and how much of it has gone out.
    pending: Packet,
    sent: usize,
    overruns: u32,
}

impl UsartLink {
    /// Takes a USART already set up for `BAUD` 8N1 and starts listening for
    /// received bytes.
    pub fn new(mut serial: Serial<pac::USART1>, rx: RxSender, tx: TxReceiver) -> Self {
        serial.listen(Event::RxNotEmpty);
        UsartLink {
            serial,
            rx,
            tx,
            pending: Packet::new(),
            sent: 0,
            overruns: 0,
        }
    }

    /// Everything the USART interrupt does: drain the receiver into one
    /// packet, then feed the transmitter while it has room. TXE is listened
    /// to only while a reply is in flight, or it would fire forever.
    pub fn service(&mut self) {
        self.receive();
        self.transmit();
    }

    fn receive(&mut self) {
        let mut packet = Packet::new();
        loop {
            match _embedded_hal_serial_nb_Read::read(&mut self.serial) {
                Ok(byte) => {
                    if packet.push(byte).is_err() {
                        self.forward(core::mem::take(&mut packet));
                        // The new packet is empty: this push cannot fail.
                        let _ = packet.push(byte);
                    }
                }
                // WouldBlock: nothing more; an overrun or framing error has
                // been cleared by the read, and the bytes are lost either way.
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => {
                    self.overruns = self.overruns.wrapping_add(1);
                }
            }
        }
        if !packet.is_empty() {
            self.forward(packet);
        }
    }

    fn forward(&mut self, packet: Packet) {
        let n = packet.len();
        if self.rx.try_send(packet).is_err() {
            self.overruns = self.overruns.wrapping_add(1);
            defmt::warn!("usart rx overrun #{}: {} bytes dropped", self.overruns, n);
        }
    }

    fn transmit(&mut self) {
        loop {
            if self.sent >= self.pending.len() {
                match self.tx.try_recv() {
                    Ok(packet) => (self.pending, self.sent) = (packet, 0),
                    Err(_) => {
                        self.serial.unlisten(Event::TxEmpty);
                        return;
                    }
                }
            }
            let Some(&byte) = self.pending.get(self.sent) else {
                continue;
            };
            match _embedded_hal_serial_nb_Write::write(&mut self.serial, byte) {
                Ok(()) => self.sent += 1,
                Err(_) => {
                    // Data register full: TXE calls us again when it empties.
                    self.serial.listen(Event::TxEmpty);
                    return;
                }
            }
        }
    }
}
