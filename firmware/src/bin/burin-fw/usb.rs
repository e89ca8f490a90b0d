//! The USB side of the link: a CDC-ACM port serviced entirely from the
//! OTG_FS interrupt. Received packets go to the parse task through a
//! channel; the parse task's replies come back through another and are fed
//! to the port whenever the USB core can take them.
use burin::usb_ids::{USB_MANUFACTURER, USB_PID, USB_PRODUCT, USB_VID};
use rtic_sync::channel::{Receiver, Sender};
use stm32f4xx_hal::otg_fs::UsbBusType;
use usb_device::{bus::UsbBusAllocator, prelude::*};
use usbd_serial::SerialPort;

/// One full-speed bulk packet, the unit moved between tasks.
pub type Packet = heapless::Vec<u8, 64>;
/// Packets the parse task may lag behind reception (512 bytes).
pub const RX_PACKETS: usize = 8;
/// Reply packets waiting for the USB core.
pub const TX_PACKETS: usize = 4;

pub type RxSender = Sender<'static, Packet, RX_PACKETS>;
pub type RxReceiver = Receiver<'static, Packet, RX_PACKETS>;
pub type TxSender = Sender<'static, Packet, TX_PACKETS>;
pub type TxReceiver = Receiver<'static, Packet, TX_PACKETS>;

pub struct UsbLink {
    dev: UsbDevice<'static, UsbBusType>,
    serial: SerialPort<'static, UsbBusType>,
    rx: RxSender,
    tx: TxReceiver,
    /// Reply being written and how much of it the port has taken.
    pending: Packet,
    sent: usize,
    overruns: u32,
}

impl UsbLink {
    pub fn new(
        bus: &'static UsbBusAllocator<UsbBusType>,
        serial_number: &'static str,
        rx: RxSender,
        tx: TxReceiver,
    ) -> Self {
        // The class must be allocated before the device is built.
        let serial = SerialPort::new(bus);
        let strings = StringDescriptors::default()
            .manufacturer(USB_MANUFACTURER)
            .product(USB_PRODUCT)
            .serial_number(serial_number);
        let builder = UsbDeviceBuilder::new(bus, UsbVidPid(USB_VID, USB_PID));
        let builder = match builder.strings(&[strings]) {
            Ok(b) => b,
            // Only more than 16 languages is refused; there is one.
            Err(_) => defmt::panic!("USB string descriptors rejected"),
        };
        let dev = builder.device_class(usbd_serial::USB_CLASS_CDC).build();
        UsbLink {
            dev,
            serial,
            rx,
            tx,
            pending: Packet::new(),
            sent: 0,
            overruns: 0,
        }
    }

    /// Everything the OTG_FS interrupt does. Reads are never deferred: an
    /// unread OUT packet keeps the core's RX-level interrupt asserted, which
    /// would starve the lower-priority parse task that is meant to free room.
    pub fn service(&mut self) {
        if self.dev.poll(&mut [&mut self.serial]) {
            self.receive();
        }
        self.transmit();
    }

    fn receive(&mut self) {
        let mut buf = [0u8; 64];
        while let Ok(n @ 1..) = self.serial.read(&mut buf) {
            // Realtime bytes (? ! ~ 0x18) will be picked out here, before
            // queueing, so they act even when the job stream is backed up.
            let bytes = buf.get(..n).unwrap_or(&[]);
            let Ok(packet) = Packet::from_slice(bytes) else {
                continue;
            };
            if self.rx.try_send(packet).is_err() {
                // Senders pace themselves by credits / GRBL character
                // counting; landing here means the host overran the buffer
                // it was told about. Count it; the protocol layer reports it.
                self.overruns = self.overruns.wrapping_add(1);
                defmt::warn!("usb rx overrun #{}: {} bytes dropped", self.overruns, n);
            }
        }
    }

    fn transmit(&mut self) {
        loop {
            if self.sent >= self.pending.len() {
                match self.tx.try_recv() {
                    Ok(packet) => (self.pending, self.sent) = (packet, 0),
                    Err(_) => return,
                }
            }
            let rest = self.pending.get(self.sent..).unwrap_or(&[]);
            match self.serial.write(rest) {
                Ok(n) if n > 0 => self.sent += n,
                // Port buffer full: the IN-complete interrupt calls us again.
                _ => return,
            }
        }
    }
}
