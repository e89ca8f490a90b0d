//! The parse task's side of the seams: the device session (`burin::device`)
//! sees the RTIC app through [`AppLink`] (assembler + token ring consumer),
//! [`AppMotion`] (executor + segment producer) and [`TxRing`] (reply bytes
//! to the link interrupt), exactly as host-sim's virtual device does.
use burin::command::{Command, Pos};
use burin::device::{LinkPort, MotionPort, Tx};
use burin::link::{LineAssembler, LinkEvent, LinkMode, RtFlags, RtSet, RxToken};
use burin::machine::{self, Machine, MachineError, Note};
use burin::outputs::Outputs;
use burin::realtime::Realtime;
use burin::settings::table::SettingError;
use burin::settings::Settings;
use burin::stepper::{Segment, Switches};
use heapless::spsc::{Consumer, Producer};

/// Planner ring size (blocks of look-ahead).
pub const PLANNER_BLOCKS: usize = 64;
/// Prepared segments between the parse task and the step interrupt
/// (`heapless::spsc` keeps one slot free).
pub const SEGMENT_SLOTS: usize = 16;
/// Reply bytes waiting for the link interrupt.
pub const TX_RING: usize = 1024;
/// The session runs only with this much TX room, which holds the longest
/// burst one pass writes (a `$$` listing is about 600 bytes): replies are
/// never dropped, reading the link just pauses while the host is slow.
pub const TX_HEADROOM: usize = 768;

/// The link decoder's task half.
pub struct AppLink<'a> {
    pub asm: &'a mut LineAssembler,
    pub rx: &'a mut Consumer<'static, RxToken>,
    pub flags: &'static RtFlags,
}

impl LinkPort for AppLink<'_> {
    fn poll(&mut self) -> Option<LinkEvent<'_>> {
        self.asm.poll(self.rx)
    }
    fn take_realtime(&mut self) -> RtSet {
        let set = self.flags.take();
        if set.contains(protocol::Rt::SoftReset) {
            // Input from before the reset is void.
            self.asm.flush_reset(self.rx, self.flags);
        }
        set
    }
    fn rx_pending(&self) -> usize {
        self.rx.len() + self.asm.pending()
    }
    fn framed(&self) -> bool {
        self.flags.is_framed()
    }
    /// The link interrupt already reset its splitter (it saw the port
    /// close first); the marker it queued resets the assembler in order.
    fn reset(&mut self) {}
    fn events_framed(&self) -> bool {
        self.asm.mode() == LinkMode::Framed
    }
}

/// The executor and the producer end of the segment queue.
pub struct AppMotion<'a> {
    pub machine: &'a mut Machine<PLANNER_BLOCKS>,
    pub segments: &'a mut Producer<'static, Segment>,
    pub rt: &'static Realtime,
    /// Spindle and coolant as the executed commands left them.
    pub outputs: &'a mut Outputs,
}

/// Spindle and coolant commands reach the outputs as the executor runs
/// them: in program order, synced with motion.
fn record(outputs: &mut Outputs, note: &Note) {
    if let Note::Executed { command, .. } = note {
        outputs.apply(command);
    }
}

impl AppMotion<'_> {
    /// Background work of the executor: fill the segment queue.
    pub fn poll(&mut self, sw: Switches) {
        let outputs = &mut *self.outputs;
        self.machine
            .poll(self.rt, self.segments, sw, &mut |n| record(outputs, &n));
    }
    /// Segments are waiting for the step interrupt.
    pub fn queued(&self) -> bool {
        !self.segments.is_empty()
    }
}

impl MotionPort for AppMotion<'_> {
    fn rt(&self) -> &Realtime {
        self.rt
    }
    fn ready(&self) -> bool {
        self.machine.ready()
    }
    fn submit(&mut self, cmd: &Command, line: u32) -> Result<(), MachineError> {
        let outputs = &mut *self.outputs;
        self.machine
            .submit(self.rt, cmd, line, &mut |n| record(outputs, &n))
    }
    fn state(&self) -> machine::State {
        self.machine.state(self.rt)
    }
    fn alarm(&self) -> Option<MachineError> {
        self.machine.alarm()
    }
    fn motion_idle(&self) -> bool {
        self.machine.ready()
            && self.machine.planner.is_empty()
            && self.machine.prep.is_idle()
            && self.segments.is_empty()
            && self.rt.stepper_idle()
    }
    fn commanded_position(&self) -> Pos {
        self.machine.commanded_position()
    }
    fn probe_result(&self) -> Option<(Pos, bool)> {
        self.machine.probe_result
    }
    /// The stepper's running figures live in the step interrupt; the
    /// status report shows 0 until the stepper publishes them in `Realtime`.
    fn feed_and_line(&self) -> (f32, u32) {
        (0.0, 0)
    }
    fn planner_free(&self) -> u16 {
        (PLANNER_BLOCKS - self.machine.planner.len()) as u16
    }
    fn planner_blocks(&self) -> u16 {
        PLANNER_BLOCKS as u16
    }
    fn settings(&self) -> &Settings {
        self.machine.settings()
    }
    fn pins(&self) -> u16 {
        crate::inputs::report_pins()
    }
    /// Rebuilds the executor with the new settings (only ever called while
    /// idle), keeping the position. The step interrupt keeps the pin timing
    /// and inverts it was started with until the next reset.
    fn set_setting(&mut self, n: u16, value: f32) -> Result<(), SettingError> {
        let mut s = *self.machine.settings();
        s.set(n, value)?;
        let pos = self.machine.commanded_position();
        let tick_hz = self.machine.step_config().tick_hz;
        *self.machine = Machine::new(s, tick_hz);
        if self.machine.set_position(self.rt, &pos).is_err() {
            let _ = self.machine.set_position(self.rt, &[0.0; burin::AXES]);
        }
        Ok(())
    }
}

/// Reply bytes towards the link interrupt.
pub struct TxRing<'a> {
    pub ring: &'a mut Producer<'static, u8>,
    /// Bytes that found the ring full (never expected: see [`TX_HEADROOM`]).
    pub dropped: u32,
}

impl TxRing<'_> {
    /// Room for one whole pass of the session.
    pub fn has_room(&self) -> bool {
        self.ring.capacity() - self.ring.len() >= TX_HEADROOM
    }
}

impl Tx for TxRing<'_> {
    fn send(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.ring.enqueue(b).is_err() {
                self.dropped = self.dropped.wrapping_add(1);
            }
        }
    }
}
