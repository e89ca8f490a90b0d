//! The two seams of the device session: the link decoder and the motion
//! core. Each is implemented once, in `controller.rs`, which both shells
//! drive; as traits they name exactly what the session may ask of the
//! rest, and `session` needs none of the controller's types.

use crate::command::{Command, Pos};
use crate::executor::{self, MachineError};
use crate::link::{LinkEvent, RtSet};
use crate::realtime::Realtime;
use crate::settings::table::SettingError;
use crate::settings::Settings;

/// The link decoder as the device sees it (implemented once, by the
/// controller, over the assembler and the receive ring).
pub trait LinkPort {
    fn poll(&mut self) -> Option<LinkEvent<'_>>;
    /// Take the pending realtime commands in `mask` (bits of
    /// `protocol::Rt::bit`); the others stay pending.
    fn take_realtime(&mut self, mask: u32) -> RtSet;
    /// Received bytes not yet turned into events.
    fn rx_pending(&self) -> usize;
    /// The receive side's mode right now (the splitter's, which runs
    /// ahead of the events): replies to realtime commands and unprompted
    /// reports (alarms) use it. Replies to an event use the event's mode.
    fn framed(&self) -> bool;
    /// Mode of the next event (the assembler's): framed events are always
    /// taken (the session refuses lines without a slot), text lines only
    /// with room for their commands.
    fn events_framed(&self) -> bool;
}

/// The motion core as the device sees it (implemented once, by the
/// controller).
pub trait MotionPort {
    fn rt(&self) -> &Realtime;
    /// The executor takes a command now.
    fn ready(&self) -> bool;
    /// `ready`, and the planner may take more before the segment queue is
    /// filled again (`Machine::may_plan`).
    fn may_plan(&self) -> bool;
    fn submit(&mut self, cmd: &Command, line: u32) -> Result<(), MachineError>;
    /// `e` was found after line `line` was acknowledged: stop the job
    /// (`executor::Machine::fault`).
    fn fault(&mut self, e: MachineError, line: u32);
    /// A fault to report (the session's or the executor's own), once.
    fn take_fault(&mut self) -> Option<(MachineError, u32)>;
    /// `end` is inside the soft limits (or they are off).
    fn check_soft(&self, end: &Pos) -> Result<(), MachineError>;
    fn state(&self) -> executor::State;
    fn alarm(&self) -> Option<MachineError>;
    /// Nothing queued, planned or moving.
    fn motion_idle(&self) -> bool;
    /// Where the next command starts, machine mm.
    fn commanded_position(&self) -> Pos;
    /// Last probe result (machine mm, contact).
    fn probe_result(&self) -> Option<(Pos, bool)>;
    /// M6 reached its hold, or the tool setter measured the new tool.
    fn take_tool_event(&mut self) -> Option<executor::ToolEvent>;
    /// Current feed, mm/min, and the machine line number executing.
    fn feed_and_line(&self) -> (f32, u32);
    /// Spindle speed as executed (0 after M5), rpm.
    fn spindle_speed(&self) -> f32;
    fn planner_free(&self) -> u16;
    fn planner_blocks(&self) -> u16;
    fn settings(&self) -> &Settings;
    /// Change a setting (the device calls this only while idle).
    fn set_setting(&mut self, n: u16, value: f32) -> Result<(), SettingError>;
    /// Replace every setting (M501, `$RST=$`; idle only): one
    /// [`MotionPort::set_setting`] per value that differs, so each is
    /// validated as `$n=` would validate it. Two passes: a value checked
    /// against one not yet replaced (`$0` against the old `$201`) gets a
    /// second try. `Err`: the first setting still refused after both, which
    /// keeps its old value; the caller tells the user.
    fn replace_settings(&mut self, s: &Settings) -> Result<(), (u16, SettingError)> {
        let mut refused = None;
        for _pass in 0..2 {
            refused = None;
            for n in crate::settings::table::numbers() {
                let (Some(new), old) = (s.get(n), self.settings().get(n)) else {
                    continue;
                };
                if old.map(f32::to_bits) != Some(new.to_bits()) {
                    if let Err(e) = self.set_setting(n, new) {
                        refused = refused.or(Some((n, e)));
                    }
                }
            }
            if refused.is_none() {
                break;
            }
        }
        refused.map_or(Ok(()), Err)
    }
    /// Active input pins, `protocol::msg::pins` bits.
    fn pins(&self) -> u16 {
        0
    }
    /// Put the machine in alarm at rest (`$SLP` woken by a reset).
    fn lock(&mut self, e: MachineError);
    /// The safety door opened (`suspend::Suspend::door`).
    fn door(&mut self);
    /// 0x9E in a hold; true when it turns the spindle back on.
    fn spindle_stop(&mut self) -> bool;
    /// Cycle start through the suspend rules.
    fn resume(&mut self) -> crate::suspend::Resume;
    /// 0xA0 (`flood`) or 0xA1: toggle the coolant now; returns the new
    /// (mist, flood).
    fn toggle_coolant(&mut self, flood: bool) -> (bool, bool);
    /// `Door:n` while a door is dealt with.
    fn door_substate(&self) -> Option<u8>;
    /// The `A:` bits (`outputs::accessory`).
    fn accessories(&self) -> u8;
    /// The spindle override, percent.
    fn set_spindle_override(&mut self, percent: u8);
}
