//! The virtual board: the firmware's receive splitter, controller
//! (`burin::controller`: device session, executor, outputs) and stepper
//! around the discrete-event engine. Bytes in, bytes out, virtual time
//! advanced by the caller, so the same device serves the pty (`cargo xtask
//! sim --pty`, paced to the wall clock), offline runs (`cargo xtask sim
//! FILE`) and the deterministic end-to-end tests (driven tick by tick over
//! an in-memory pipe).
//!
//! This shell only moves bytes, pin levels and time, as the RTIC app
//! does: [`VirtualDevice::receive`] is the USB interrupt (splitter into the
//! token ring, realtime bytes flagged at once), the engine's task slot is
//! the parse task (one [`Controller::pass`] each), and the pass's [`Pins`]
//! are recorded where the board writes registers.
//!
//! Settings and offsets persist in a [`SimFlash`]: a RAM copy of the
//! boards' two 16 KiB sectors under the same record log as the boards. A
//! fresh device starts erased; [`VirtualDevice::flash`] hands the contents
//! to [`VirtualDevice::with_flash`] to "reboot" with what was saved.

use burin::controller::{Controller, Pins};
use burin::link::{LinkMode, RtFlags, RxBacklog, RxSplitter, RxToken, RX_RING_HOLDS};
use burin::persist::{FlashMap, Persist, RamFlash};
use burin::session::{Device, Identity, Tx};
use heapless::Deque;

use crate::config::MachineConfig;
use crate::engine::{DeviceTask, Sim};
use crate::record::Recorder;

mod panel;
pub use panel::Panel;

/// Board name the virtual device reports in `$I` and the handshake.
pub const BOARD: &str = "host-sim";

/// The virtual board's settings flash: two 16 KiB sectors, as on the F411.
pub type SimFlash = RamFlash<{ 2 * 16384 }, 16384>;

/// Received tokens the virtual board holds while its ring is full: the
/// board's size (the pty keeps whatever does not fit in the kernel's
/// buffer, as the host's USB stack does while the board NAKs).
pub use burin::link::RX_BACKLOG as BACKLOG;

/// Driver wake-up between enable and the first step, ms (the board's
/// `WAKE_MS`).
const WAKE_MS: u16 = 0;

/// Output bytes collected for the transport; with a capacity (`.1`, the
/// board's TX ring size) it reports its room as the ring does, so tests
/// can leave replies unread and see what the board does with a full ring.
#[derive(Debug, Default)]
pub struct TxBuf(pub Vec<u8>, pub Option<usize>);

impl Tx for TxBuf {
    fn send(&mut self, bytes: &[u8]) {
        self.0.extend_from_slice(bytes);
    }
    fn room(&self) -> usize {
        self.1
            .map_or(usize::MAX, |cap| cap.saturating_sub(self.0.len()))
    }
}

/// A whole virtual board.
pub struct VirtualDevice<'r> {
    pub sim: Sim<'r>,
    /// The receive interrupt's half of the link and the ring it fills.
    splitter: RxSplitter,
    ring: Deque<RxToken, RX_RING_HOLDS>,
    backlog: Box<RxBacklog<BACKLOG>>,
    flags: RtFlags,
    pub controller: Controller<FlashMap<SimFlash>>,
    pub tx: TxBuf,
    /// When set, the machine line number of every command the executor
    /// accepted, in order (tests check exactly-once delivery with it).
    pub log: Option<Vec<u32>>,
    /// Output pin levels after the last pass, and every change with its tick.
    pins: Option<Pins>,
    pub pin_log: Vec<(u64, Pins)>,
    port_closed: bool,
    port_opened: bool,
    /// Switch inputs a test sets ([`VirtualDevice::set_input`]).
    panel: Panel,
}

impl<'r> VirtualDevice<'r> {
    /// Power-up with erased settings flash: prints the banner, as the
    /// board does.
    pub fn new(cfg: &MachineConfig, rec: &'r mut dyn Recorder) -> Self {
        Self::with_flash(cfg, rec, SimFlash::new())
    }

    /// Power-up with `flash` as it was left: loads settings (the machine
    /// file's are the defaults) and offsets from it, as the board's init
    /// does before it builds the machine.
    pub fn with_flash(cfg: &MachineConfig, rec: &'r mut dyn Recorder, flash: SimFlash) -> Self {
        let mut persist = Persist::new(FlashMap::new(flash), cfg.settings);
        let boot = persist.load();
        // The board builds its machine and stepper on the loaded settings.
        let mut booted = cfg.clone();
        booted.settings = boot.settings;
        let mut sim = Sim::new(&booted, rec);
        sim.set_device_mode();
        // The board's boot check of its pulse-end path, on the DMA model.
        if sim.hw.hardware_fall() {
            let (path, chip) = booted.interrupts.pulse_dma;
            if let Err(f) = burin::chip::check_pulse_end(&path, chip, &mut sim.hw.dma) {
                sim.rt.set_hw_fault(f);
            }
        }
        let ident = Identity {
            board: BOARD,
            caps: protocol::msg::caps::CHECK_MODE | protocol::msg::caps::HOMING,
        };
        let settings = *sim.machine.settings();
        let session = Device::with_storage(ident, persist, Some(&boot));
        let mut controller = Controller::new(session, &settings, WAKE_MS);
        let mut tx = TxBuf::default();
        controller.hello(&mut tx);
        VirtualDevice {
            sim,
            splitter: RxSplitter::new(),
            ring: Deque::new(),
            backlog: Box::default(),
            flags: RtFlags::new(),
            controller,
            tx,
            log: None,
            pins: None,
            pin_log: Vec::new(),
            port_closed: false,
            port_opened: false,
            panel: Panel::default(),
        }
    }

    /// The settings flash as it is now (to power up another device with).
    pub fn flash(&mut self) -> SimFlash {
        self.controller
            .session
            .persist()
            .storage()
            .flash()
            .cloned()
            .unwrap_or_default()
    }

    /// Bytes the device can take now (like the USB endpoint, hold the
    /// rest): the ring's room plus the backlog's.
    pub fn room(&self) -> usize {
        self.backlog.room(&self.ring)
    }

    /// Receive bytes, as the board's USB interrupt does; returns how many
    /// were taken (at most [`Self::room`]). Realtime commands among them
    /// act at once, however much text waits in the backlog.
    pub fn receive(&mut self, bytes: &[u8]) -> usize {
        let n = bytes.len().min(self.room());
        if let Some(b) = bytes.get(..n) {
            self.backlog
                .feed(&mut self.splitter, b, &mut self.ring, &self.flags);
        }
        n
    }

    /// The host closed the port: unread input is void, the receive side
    /// goes back to text mode at once, the session hears of it at its next
    /// pass (see `burin::session::Device::port_reset` for a running job).
    pub fn port_closed(&mut self) {
        self.backlog
            .port_reset(&mut self.splitter, &mut self.ring, &self.flags);
        self.port_closed = true;
    }

    /// A client opened the port: the next pass tells the session, which
    /// resets (banner) when nothing runs (`burin::session::Device::port_opened`),
    /// before it reads any of the client's input.
    pub fn port_opened(&mut self) {
        self.port_opened = true;
    }

    /// Run the parse/plan task, then virtual time up to `tick` (the task
    /// runs again whenever the engine says it is due, as the step
    /// interrupt wakes it on the board), then the task again.
    pub fn advance_to(&mut self, tick: u64) {
        // A masked input's heartbeat comes between (`panel`).
        while let Some(at) = self.beat_due(tick) {
            self.run_to(at);
            self.beat(at);
        }
        self.run_to(tick);
    }

    fn run_to(&mut self, tick: u64) {
        loop {
            self.poll();
            self.sim.run_until(tick);
            if !self.sim.task_wanted() {
                break;
            }
        }
        self.poll();
    }

    /// One pass of the parse/plan task (skipped while it is still busy).
    pub fn poll(&mut self) {
        self.backlog.pump(&mut self.ring);
        let VirtualDevice {
            sim,
            ring,
            flags,
            controller,
            tx,
            log,
            port_closed,
            port_opened,
            panel,
            ..
        } = self;
        let task = DeviceTask {
            controller,
            flags,
            rx: ring,
            tx,
            pins: panel.report_pins(),
            port_closed: *port_closed,
            port_opened: *port_opened,
            log: log.as_mut(),
        };
        if let Some(pass) = sim.controller_pass(task) {
            self.sim.task_syncing = self.controller.session.syncing();
            self.port_closed = false;
            self.port_opened = false;
            if self.pins != Some(pass.pins) {
                self.pins = Some(pass.pins);
                self.pin_log.push((self.sim.now(), pass.pins));
            }
        }
    }

    /// Output pin levels as the last pass left them.
    pub fn pins(&self) -> Option<Pins> {
        self.pins
    }

    /// Take the bytes the device wants to send.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.tx.0)
    }

    /// Print the banner as at power-up (a port open is [`Self::port_opened`]).
    pub fn hello(&mut self) {
        self.controller.hello(&mut self.tx);
    }

    /// The receive side is in framed mode.
    pub fn framed(&self) -> bool {
        self.flags.is_framed()
    }

    /// Mode of the next link event.
    pub fn link_mode(&self) -> LinkMode {
        self.controller.link_mode()
    }

    /// Received bytes not yet turned into events (the `Bf:` figure's
    /// complement).
    pub fn rx_pending(&self) -> usize {
        self.backlog.len() + self.ring.len() + self.controller.rx_partial()
    }

    /// Nothing queued anywhere and the machine stopped.
    pub fn idle(&self) -> bool {
        self.controller.session.drained() && self.sim.idle() && self.rx_pending() == 0
    }

    /// Machine position in steps.
    pub fn position_steps(&self) -> [i32; burin::AXES] {
        self.sim.rt.position()
    }
}
