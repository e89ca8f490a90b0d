//! The controller's two ports: the link decoder's task half and the
//! executor with the outputs, as the session sees them (`LinkPort`,
//! `MotionPort`), implemented once, here.

use super::Event;
use crate::command::{Command, Pos};
use crate::executor::{self, Machine, MachineError, Note};
use crate::link::{LineAssembler, LinkEvent, LinkMode, RtFlags, RtSet, TokenSource};
use crate::outputs::{LaserQueue, Outputs};
use crate::realtime::Realtime;
use crate::seams::Switches;
use crate::session::{LinkPort, MotionPort};
use crate::settings::table::SettingError;
use crate::settings::Settings;
use crate::stepper::prep::SegmentSink;
use crate::suspend::Suspend;

/// The link decoder's task half: the assembler on the ring's consumer end.
pub(super) struct TaskLink<'a, R> {
    pub(super) asm: &'a mut LineAssembler,
    pub(super) rx: &'a mut R,
    pub(super) flags: &'a RtFlags,
}

impl<R: TokenSource> LinkPort for TaskLink<'_, R> {
    fn poll(&mut self) -> Option<LinkEvent<'_>> {
        self.asm.poll(self.rx)
    }
    fn take_realtime(&mut self, mask: u32) -> RtSet {
        let set = self.flags.take_masked(mask);
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
    fn events_framed(&self) -> bool {
        self.asm.mode() == LinkMode::Framed
    }
}

/// The executor, the producer end of the segment queue and the outputs.
pub(super) struct Core<'a, Q, const N: usize> {
    pub(super) machine: &'a mut Machine<N>,
    pub(super) segments: &'a mut Q,
    pub(super) rt: &'a Realtime,
    pub(super) outputs: &'a mut Outputs,
    pub(super) suspend: &'a mut Suspend,
    pub(super) laser: &'a mut LaserQueue,
    pub(super) pins: u16,
    pub(super) now_ms: u32,
    pub(super) obs: &'a mut dyn FnMut(Event),
}

/// Spindle and coolant commands reach the outputs as the executor runs
/// them: in program order, synced with motion.
fn note(outputs: &mut Outputs, laser: &mut LaserQueue, obs: &mut dyn FnMut(Event), n: Note) {
    if let Note::Executed { command, line } = &n {
        if outputs.laser() {
            laser.push(outputs, *line, command);
        } else {
            outputs.apply(command);
        }
    }
    obs(Event::Note(&n));
}

impl<Q: SegmentSink, const N: usize> Core<'_, Q, N> {
    /// Background work of the executor: fill the segment queue.
    pub(super) fn poll(&mut self, sw: Switches) {
        let (outputs, laser, obs) = (&mut *self.outputs, &mut *self.laser, &mut *self.obs);
        self.machine.poll(self.rt, self.segments, sw, &mut |n| {
            note(outputs, laser, obs, n)
        });
    }
}

impl<Q: SegmentSink, const N: usize> MotionPort for Core<'_, Q, N> {
    fn rt(&self) -> &Realtime {
        self.rt
    }
    fn ready(&self) -> bool {
        self.machine.ready()
    }
    fn may_plan(&self) -> bool {
        self.machine.may_plan()
    }
    fn submit(&mut self, cmd: &Command, line: u32) -> Result<(), MachineError> {
        let (outputs, laser, obs) = (&mut *self.outputs, &mut *self.laser, &mut *self.obs);
        self.machine
            .submit(self.rt, cmd, line, &mut |n| note(outputs, laser, obs, n))?;
        (self.obs)(Event::Accepted {
            line,
            motion: cmd.end().is_some() || matches!(cmd, Command::Cycle(_)),
        });
        Ok(())
    }
    fn fault(&mut self, e: MachineError, line: u32) {
        self.machine.fault(e, line);
    }
    fn take_fault(&mut self) -> Option<(MachineError, u32)> {
        self.machine.take_fault()
    }
    fn check_soft(&self, end: &Pos) -> Result<(), MachineError> {
        self.machine.check_soft(end, end)
    }
    fn state(&self) -> executor::State {
        self.machine.state(self.rt)
    }
    fn alarm(&self) -> Option<MachineError> {
        self.machine.alarm()
    }
    fn motion_idle(&self) -> bool {
        self.machine.idle(self.rt, &*self.segments)
    }
    fn commanded_position(&self) -> Pos {
        self.machine.commanded_position()
    }
    fn probe_result(&self) -> Option<(Pos, bool)> {
        self.machine.probe_result()
    }
    fn take_tool_event(&mut self) -> Option<executor::ToolEvent> {
        self.machine.take_tool_event()
    }
    /// Published by the stepper once per segment.
    fn feed_and_line(&self) -> (f32, u32) {
        self.rt.running()
    }
    fn spindle_speed(&self) -> f32 {
        self.outputs.speed()
    }
    fn planner_free(&self) -> u16 {
        (N - self.machine.motion.planner().len()) as u16
    }
    fn planner_blocks(&self) -> u16 {
        N as u16
    }
    fn settings(&self) -> &Settings {
        self.machine.settings()
    }
    fn pins(&self) -> u16 {
        self.pins
    }
    fn lock(&mut self, e: MachineError) {
        self.machine.lock(e);
    }
    fn door(&mut self) {
        self.suspend.door(self.rt);
    }
    fn spindle_stop(&mut self) -> bool {
        self.suspend.spindle_stop(self.outputs, self.now_ms)
    }
    fn resume(&mut self) -> crate::suspend::Resume {
        self.suspend.cycle_start(self.rt, self.outputs, self.now_ms)
    }
    /// As GRBL: the coolant changes at once, out of program order.
    fn toggle_coolant(&mut self, flood: bool) -> (bool, bool) {
        let o = &mut *self.outputs;
        if flood {
            o.flood = !o.flood;
        } else {
            o.mist = !o.mist;
        }
        (o.mist, o.flood)
    }
    fn door_substate(&self) -> Option<u8> {
        self.suspend.door_substate(self.rt)
    }
    fn accessories(&self) -> u8 {
        self.outputs.accessories()
    }
    fn set_spindle_override(&mut self, percent: u8) {
        self.outputs.set_override(percent);
    }
    /// Rebuilds the executor with the new settings (only ever called while
    /// idle), keeping the position, and publishes the step interrupt's
    /// share of them (pin timing, inverts, rate ceiling), which the stopped
    /// step driver takes at this pass's kick: every setting applies at once.
    fn set_setting(&mut self, n: u16, value: f32) -> Result<(), SettingError> {
        let mut s = *self.machine.settings();
        s.set(n, value)?;
        let pos = self.machine.commanded_position();
        let tick_hz = self.machine.step_config().tick_hz;
        self.machine.rebuild(s, tick_hz);
        self.rt.step_config().publish(&self.machine.step_config());
        if self.machine.set_position(self.rt, &pos).is_err() {
            let _ = self.machine.set_position(self.rt, &[0.0; crate::AXES]);
        }
        Ok(())
    }
}
