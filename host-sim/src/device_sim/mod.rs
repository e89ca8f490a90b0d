//! The virtual device: the firmware's link decoder, device session and motion
//! core around the discrete-event engine. Bytes in, bytes out, virtual time
//! advanced by the caller, so the same device serves the pty
//! (`cargo xtask sim --pty`, paced to the wall clock) and the deterministic
//! end-to-end tests (driven tick by tick over an in-memory pipe).
//!
//! Settings and offsets persist in a [`SimFlash`]: a RAM copy of the
//! boards' two 16 KiB sectors under the same record log as the boards. A
//! fresh device starts erased; [`VirtualDevice::flash`] hands the contents
//! to [`VirtualDevice::with_flash`] to "reboot" with what was saved.

use burin::command::{Command, Pos};
use burin::device::{Device, Identity, MotionPort, Tx};
use burin::link::Link;
use burin::machine::{self, Machine, MachineError};
use burin::persist::{FlashMap, Persist, RamFlash};
use burin::realtime::Realtime;
use burin::settings::table::SettingError;
use burin::settings::Settings;
use burin::stepper::Stepper;

use crate::config::MachineConfig;
use crate::engine::{Sim, PLANNER_BLOCKS};
use crate::record::Recorder;

/// Board name the virtual device reports in `$I` and the handshake.
pub const BOARD: &str = "host-sim";

/// The virtual board's settings flash: two 16 KiB sectors, as on the F411.
pub type SimFlash = RamFlash<{ 2 * 16384 }, 16384>;

/// The engine seen through the device's [`MotionPort`] seam.
struct SimPort<'a, 'r> {
    sim: &'a mut Sim<'r>,
    log: Option<&'a mut Vec<u32>>,
}

impl MotionPort for SimPort<'_, '_> {
    fn rt(&self) -> &Realtime {
        &self.sim.rt
    }
    fn ready(&self) -> bool {
        self.sim.machine.ready()
    }
    fn submit(&mut self, cmd: &Command, line: u32) -> Result<(), MachineError> {
        let Sim { machine, rt, .. } = &mut *self.sim;
        machine.submit(rt, cmd, line, &mut |_| {})?;
        if let Some(log) = self.log.as_deref_mut() {
            log.push(line);
        }
        Ok(())
    }
    fn state(&self) -> machine::State {
        self.sim.machine.state(&self.sim.rt)
    }
    fn alarm(&self) -> Option<MachineError> {
        self.sim.machine.alarm()
    }
    fn motion_idle(&self) -> bool {
        self.sim.idle()
    }
    fn commanded_position(&self) -> Pos {
        self.sim.machine.commanded_position()
    }
    fn probe_result(&self) -> Option<(Pos, bool)> {
        self.sim.machine.probe_result
    }
    fn feed_and_line(&self) -> (f32, u32) {
        let st = &self.sim.stepper;
        (st.speed_mm_min(), st.line())
    }
    fn planner_free(&self) -> u16 {
        (PLANNER_BLOCKS - self.sim.machine.planner.len()) as u16
    }
    fn planner_blocks(&self) -> u16 {
        PLANNER_BLOCKS as u16
    }
    fn settings(&self) -> &Settings {
        self.sim.machine.settings()
    }
    /// Rebuilds the executor and stepper with the new settings (only ever
    /// called while idle), keeping the position in millimetres.
    fn set_setting(&mut self, n: u16, value: f32) -> Result<(), SettingError> {
        let mut s = *self.sim.machine.settings();
        s.set(n, value)?;
        let pos = self.sim.machine.commanded_position();
        let tick_hz = self.sim.tick_hz();
        let sim = &mut *self.sim;
        sim.machine = Machine::new(s, tick_hz);
        if sim.machine.set_position(&sim.rt, &pos).is_err() {
            let _ = sim.machine.set_position(&sim.rt, &[0.0; burin::AXES]);
        }
        sim.stepper = Stepper::new(sim.machine.step_config());
        sim.stepper.set_position(&sim.rt, sim.rt.position());
        Ok(())
    }
}

/// Output bytes collected for the transport.
#[derive(Debug, Default)]
pub struct TxBuf(pub Vec<u8>);

impl Tx for TxBuf {
    fn send(&mut self, bytes: &[u8]) {
        self.0.extend_from_slice(bytes);
    }
}

/// A whole virtual board.
pub struct VirtualDevice<'r> {
    pub sim: Sim<'r>,
    pub link: Link,
    pub device: Device<FlashMap<SimFlash>>,
    pub tx: TxBuf,
    /// When set, the machine line number of every command the executor
    /// accepted, in order (tests check exactly-once delivery with it).
    pub log: Option<Vec<u32>>,
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
        let mut sim = Sim::new(cfg, rec);
        // An operator (the host) resumes holds and M0 pauses with `~`.
        sim.auto_resume = false;
        let mut persist = Persist::new(FlashMap::new(flash), *sim.machine.settings());
        let boot = persist.load();
        SimPort {
            sim: &mut sim,
            log: None,
        }
        .replace_settings(&boot.settings);
        let ident = Identity {
            board: BOARD,
            caps: protocol::msg::caps::CHECK_MODE | protocol::msg::caps::HOMING,
        };
        let mut device = Device::with_storage(ident, persist, Some(&boot));
        let mut tx = TxBuf::default();
        device.hello(&mut tx);
        VirtualDevice {
            sim,
            link: Link::new(),
            device,
            tx,
            log: None,
        }
    }

    /// The settings flash as it is now (to power up another device with).
    pub fn flash(&mut self) -> SimFlash {
        self.device
            .persist()
            .storage()
            .flash()
            .cloned()
            .unwrap_or_default()
    }

    /// Bytes the device can take now (like the USB endpoint, hold the rest).
    pub fn room(&self) -> usize {
        self.link.room()
    }

    /// Receive bytes; returns how many were taken (at most [`Self::room`]).
    pub fn receive(&mut self, bytes: &[u8]) -> usize {
        let n = bytes.len().min(self.room());
        if let Some(b) = bytes.get(..n) {
            self.link.feed(b);
        }
        n
    }

    /// The host closed the port: the link goes back to text mode (see
    /// [`Device::port_reset`] for what happens to a running job).
    pub fn port_closed(&mut self) {
        let VirtualDevice {
            sim,
            link,
            device,
            log,
            ..
        } = self;
        device.port_reset(
            link,
            &SimPort {
                sim,
                log: log.as_mut(),
            },
        );
    }

    /// Run the parse/plan task, then virtual time up to `tick`, then the
    /// task again (it reacts to what the machine did).
    pub fn advance_to(&mut self, tick: u64) {
        self.poll();
        self.sim.run_until(tick);
        self.poll();
    }

    /// One pass of the device session.
    pub fn poll(&mut self) {
        let VirtualDevice {
            sim,
            link,
            device,
            tx,
            log,
        } = self;
        device.poll(
            link,
            &mut SimPort {
                sim,
                log: log.as_mut(),
            },
            tx,
        );
    }

    /// Take the bytes the device wants to send.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.tx.0)
    }

    /// Nothing queued anywhere and the machine stopped.
    pub fn idle(&self) -> bool {
        self.device.drained() && self.sim.idle() && self.link.rx_pending() == 0
    }

    /// Machine position in steps.
    pub fn position_steps(&self) -> [i32; burin::AXES] {
        self.sim.rt.position()
    }
}
