//! The USB side of the link: a CDC-ACM port serviced entirely from the
//! OTG_FS interrupt. Received packets go through the link's [`RxSplitter`]
//! into the token ring (realtime bytes become flags at once); replies come
//! from the TX byte ring and are fed to the port whenever it can take them.
use burin::link::{RtFlags, RxBacklog, RxSplitter, RxToken};
use core::sync::atomic::{AtomicBool, Ordering};
use heapless::spsc::{Consumer, Producer};
use protocol::usb_ids::{USB_MANUFACTURER, USB_PID, USB_PRODUCT, USB_VID};
use stm32f4xx_hal::otg_fs::UsbBusType;
use usb_device::{bus::UsbBusAllocator, prelude::*};
use usbd_serial::SerialPort;

/// Set when the host closed the port (DTR dropped) or the bus was reset;
/// the parse task tells the device session (`Device::port_reset`).
pub static PORT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Set when the host opened the port (DTR raised): the parse task tells
/// the session (`Device::port_opened`, which decides on a reset and its
/// banner) before it handles anything the new client sent.
pub static PORT_OPENED: AtomicBool = AtomicBool::new(false);

/// Received tokens held while the ring is full: the board's
/// `RX_BACKLOG` (`burin::link::RX_BACKLOG`, 8 KiB, on the F411; half on
/// the F401, see `f401.rs`). A static of init's, lent to the link: inside
/// it, the link was 8 KB that init built on the stack and moved twice
/// (init's frame was 20.7 KB on the F401).
pub use super::board::RX_BACKLOG as BACKLOG;

/// One full-speed OUT packet.
const PACKET: usize = 64;

pub struct UsbLink {
    dev: UsbDevice<'static, UsbBusType>,
    serial: SerialPort<'static, UsbBusType>,
    splitter: RxSplitter,
    backlog: &'static mut RxBacklog<BACKLOG>,
    rx: Producer<'static, RxToken>,
    tx: Consumer<'static, u8>,
    /// Reply bytes taken from the ring and how many the port has taken.
    pending: [u8; 64],
    len: usize,
    sent: usize,
    /// The port was open (DTR high, configured) at the last interrupt.
    open: bool,
}

impl UsbLink {
    pub fn new(
        bus: &'static UsbBusAllocator<UsbBusType>,
        serial_number: &'static str,
        rx: Producer<'static, RxToken>,
        tx: Consumer<'static, u8>,
        backlog: &'static mut RxBacklog<BACKLOG>,
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
            splitter: RxSplitter::new(),
            backlog,
            rx,
            tx,
            pending: [0; 64],
            len: 0,
            sent: 0,
            open: false,
        }
    }

    /// Everything the OTG_FS interrupt does (also pended by the parse task
    /// after each pass). A packet is read only while the ring and the
    /// backlog have room for it; otherwise it stays in the core's FIFO, the
    /// endpoint NAKs and the host holds further input (flow control: text
    /// is never dropped). An unread packet keeps the RX-level interrupt
    /// asserted, which would starve the parse task that frees the room, so
    /// that interrupt is masked until the task's next pass pends us.
    /// Returns true when the parse task has something new to do.
    pub fn service(&mut self, flags: &RtFlags) -> bool {
        let mut news = self.backlog.pump(&mut self.rx);
        // Also without a poll event: a packet may wait for room since a
        // pass (its interrupt masked).
        let _ = self.dev.poll(&mut [&mut self.serial]);
        news |= self.receive(flags);
        let open = self.dev.state() == UsbDeviceState::Configured && self.serial.dtr();
        if self.open && !open {
            // Port closed or bus reset: back to text mode at this point of
            // the stream, unread input void; replies still queued have no
            // reader.
            self.backlog
                .port_reset(&mut self.splitter, &mut self.rx, flags);
            self.drop_replies();
            PORT_CLOSED.store(true, Ordering::Release);
            news = true;
        }
        if open && !self.open {
            // Replies made while the port was closed (a line the last
            // client left running answers when it completes) are for
            // nobody: the new client's first bytes are the banner.
            self.drop_replies();
            PORT_OPENED.store(true, Ordering::Release);
            news = true;
        }
        self.open = open;
        news | self.transmit()
    }

    fn receive(&mut self, flags: &RtFlags) -> bool {
        let mut buf = [0u8; PACKET];
        let mut any = false;
        loop {
            if self.backlog.room(&self.rx) < PACKET {
                // Full: the next packet stays in the FIFO (NAK) until a
                // pass frees room and pends this interrupt.
                rx_level_irq(false);
                return any;
            }
            let Ok(n @ 1..) = self.serial.read(&mut buf) else {
                rx_level_irq(true);
                return any;
            };
            let bytes = buf.get(..n).unwrap_or(&[]);
            self.backlog
                .feed(&mut self.splitter, bytes, &mut self.rx, flags);
            any = true;
        }
    }

    /// Returns true when reply bytes left the ring (room for the parse task).
    /// Forget every reply not yet handed to the USB stack.
    fn drop_replies(&mut self) {
        while self.tx.dequeue().is_some() {}
        (self.len, self.sent) = (0, 0);
    }

    fn transmit(&mut self) -> bool {
        let mut freed = false;
        loop {
            if self.sent >= self.len {
                (self.len, self.sent) = (0, 0);
                for slot in self.pending.iter_mut() {
                    let Some(b) = self.tx.dequeue() else { break };
                    *slot = b;
                    self.len += 1;
                }
                if self.len == 0 {
                    return freed;
                }
                freed = true;
            }
            let rest = self.pending.get(self.sent..self.len).unwrap_or(&[]);
            match self.serial.write(rest) {
                Ok(n) if n > 0 => self.sent += n,
                // Port buffer full: the IN-complete interrupt calls us again.
                _ => return freed,
            }
        }
    }
}

/// Unmask or mask the OTG core's RX-FIFO-level interrupt (GINTMSK.RXFLVLM).
fn rx_level_irq(on: bool) {
    // SAFETY: a single read-modify-write of one mask bit of the OTG core,
    // done only from the OTG_FS interrupt (the USB driver touches GINTMSK
    // only from the same interrupt: poll and bus reset).
    #[allow(unsafe_code)]
    let otg = unsafe { &*stm32f4xx_hal::pac::OTG_FS_GLOBAL::ptr() };
    otg.gintmsk().modify(|_, w| w.rxflvlm().bit(on));
}
