//! Realtime commands, the status report, soft reset and port open: GRBL
//! 1.1's realtime state machine (the safety door and the spindle stop
//! themselves are `crate::suspend`, in the controller, which owns the
//! outputs and the clock).

use super::sys::{report_alarm, RT_REPLY_ROOM};
use super::{Device, LinkPort, MotionPort, Out, Tx};
use crate::executor::{self, MachineError};
use crate::link::reply::{self, Format};
use protocol::{DeviceMsg, MachineState, Overrides, Rt, Status, WIRE_AXES};

impl<S: crate::seams::Storage> Device<S> {
    /// The realtime half of [`Device::poll`], which the shell runs on its
    /// own while the reply ring is too full to read new input: hold, cycle
    /// start, jog cancel and the overrides write nothing and act at once;
    /// a status query or a soft reset waits until its reply fits
    /// ([`RT_REPLY_ROOM`]), so no reply is ever cut.
    pub fn poll_realtime(
        &mut self,
        link: &mut impl LinkPort,
        m: &mut impl MotionPort,
        tx: &mut impl Tx,
    ) {
        let replying = Rt::SoftReset.bit() | Rt::StatusQuery.bit();
        let mask = if tx.room() >= RT_REPLY_ROOM {
            u32::MAX
        } else {
            !replying
        };
        for r in link.take_realtime(mask).iter() {
            let framed = link.framed();
            let rx_free = protocol::RX_WINDOW.saturating_sub(link.rx_pending()) as u16;
            self.realtime(r, rx_free, m, &mut Out::new(tx, framed));
        }
    }

    /// A client opened the port. A USB port's open resets nothing by
    /// itself, but GRBL senders expect what an Arduino's DTR reset gives
    /// them: a banner, check mode off, the modal state at its defaults.
    /// So when nothing runs the open IS a soft reset (the banner tells the
    /// truth, an alarm shows its unlock hint); while a job runs, is queued
    /// or held (a text job goes on when its sender leaves) the open resets
    /// nothing and sends no banner: `?` shows the state. A framed client
    /// has its own handshake.
    pub fn port_opened(
        &mut self,
        link: &mut impl LinkPort,
        m: &mut impl MotionPort,
        tx: &mut impl Tx,
    ) {
        if link.framed() || link.events_framed() {
            return;
        }
        let busy = !m.motion_idle()
            || !m.ready()
            || !self.cmds.is_empty()
            || !self.slots.is_empty()
            || m.door_substate().is_some();
        if !busy {
            self.soft_reset(m, &mut Out::new(tx, false));
        }
    }

    /// 0x18 (and a port open at rest, and `$C` turning check mode off).
    pub(super) fn soft_reset(&mut self, m: &mut impl MotionPort, o: &mut Out<'_, impl Tx>) {
        // A reset loses position only where something moves (GRBL's
        // rule): a finished hold, a dwell, a machine waiting for its
        // drivers are exact. The executor judges the same way.
        let moving = !m.rt().at_rest();
        let asleep = self.sleep;
        m.rt().request_reset();
        self.cmds.clear();
        self.slots.clear();
        self.flow.reset(&mut self.interp);
        self.interp.reset();
        self.check = false;
        self.sleep = false;
        self.jogging = false;
        self.jog_cancel = false;
        self.sync = true;
        self.pending.cancel_queued();
        self.stats.resets += 1;
        // The e-stop's reset: its own alarm (the executor latches it).
        let estop = m.rt().estop();
        if (moving || estop) && m.alarm().is_none() {
            // Reported now so that it comes before the banner.
            let e = if estop {
                MachineError::EStop
            } else {
                MachineError::ResetDuringMotion
            };
            self.seen_alarm = Some(e);
            report_alarm(e, o);
        } else if asleep && m.alarm().is_none() {
            // GRBL wakes from sleep into alarm with no alarm code: the
            // drivers were off, the position is not to be trusted.
            m.lock(MachineError::Slept);
            self.seen_alarm = Some(MachineError::Slept);
        }
        if !o.framed() {
            let _ = reply::banner(o);
            if moving || estop || asleep || m.alarm().is_some() {
                let _ = reply::msg(o, "'$H'|'$X' to unlock");
            }
        }
    }

    pub(super) fn status(&mut self, rx_free: u16, m: &impl MotionPort) -> Status {
        let s = m.settings();
        let pos = m.rt().position();
        let mut mpos = [0.0; WIRE_AXES];
        for (i, p) in mpos.iter_mut().enumerate().take(crate::AXES) {
            *p = pos[i] as f32 / s.axes[i].steps_per_mm;
        }
        let mut wco = [0.0; WIRE_AXES];
        for (w, v) in wco.iter_mut().zip(self.interp.wco()) {
            *w = v;
        }
        let door = m.door_substate();
        let state = match m.state() {
            _ if self.sleep => MachineState::Sleep,
            _ if self.check => MachineState::Check,
            executor::State::Alarm => MachineState::Alarm,
            executor::State::Homing => MachineState::Home,
            _ if door.is_some() => MachineState::Door,
            executor::State::Hold => MachineState::Hold,
            _ if self.jogging => MachineState::Jog,
            executor::State::Idle if self.cmds.is_empty() && self.slots.is_empty() => {
                MachineState::Idle
            }
            _ => MachineState::Run,
        };
        let (feed, line) = m.feed_and_line();
        Status {
            state,
            // GRBL 1.1: `Hold:0` complete, ready to resume; `Hold:1` still
            // decelerating (a reset then alarms). A dwell is at rest.
            substate: door.unwrap_or(u8::from(!m.rt().at_rest())),
            mpos,
            wco,
            feed,
            spindle: m.spindle_speed(),
            planner_free: m.planner_free(),
            rx_free,
            line: (line != 0 && state != MachineState::Idle).then_some(line),
            overrides: Overrides {
                feed: m.rt().feed_override(),
                rapid: m.rt().rapid_override(),
                spindle: self.spindle_ov,
            },
            pins: m.pins(),
            accessories: m.accessories(),
        }
    }

    /// A jog stops as a hold and is then flushed (`watch`).
    fn cancel_jog(&mut self, m: &impl MotionPort) {
        self.jog_cancel = true;
        m.rt().feed_hold();
    }

    pub(super) fn realtime(
        &mut self,
        r: Rt,
        rx_free: u16,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) {
        let rt = m.rt();
        let feed = u16::from(rt.feed_override());
        let state = m.state();
        match r {
            Rt::SoftReset => self.soft_reset(m, o),
            Rt::StatusQuery => {
                let st = self.status(rx_free, m);
                if o.framed() {
                    o.frame(&DeviceMsg::Status(st));
                } else {
                    let mask = m.settings().status_mask;
                    let f = Format::from_settings(m.settings());
                    let extras = self.cadence.next(&st);
                    let _ = reply::status(o, &st, mask, f, extras);
                }
            }
            // GRBL's commands document: a feed hold cancels a jog.
            Rt::FeedHold if self.jogging => self.cancel_jog(m),
            Rt::FeedHold => rt.feed_hold(),
            // In alarm and check mode GRBL ignores the door.
            Rt::SafetyDoor if self.check || m.alarm().is_some() => {}
            Rt::SafetyDoor => {
                // The door acts at once; its message only if it fits whole.
                if o.room() >= 32 {
                    let _ = reply::msg(o, "Check Door");
                }
                if state == executor::State::Homing {
                    // GRBL's alarm 7: the cycle stops unfinished.
                    m.fault(MachineError::HomingDoor, 0);
                } else if !self.sleep {
                    // A jog is cancelled first; the door then holds.
                    if self.jogging {
                        self.cancel_jog(m);
                    }
                    m.door();
                }
            }
            // Asleep, nothing resumes (the drivers are off): reset first.
            Rt::CycleStart if self.sleep => {}
            Rt::CycleStart => {
                if m.resume() == (crate::suspend::Resume::Restoring { door: false }) {
                    let _ = reply::msg(o, "Restoring spindle");
                }
            }
            Rt::JogCancel => {
                if self.jogging {
                    self.cancel_jog(m);
                }
            }
            Rt::FeedOv100 => rt.set_feed_override(100),
            Rt::FeedOvPlus10 => rt.set_feed_override(feed + 10),
            Rt::FeedOvMinus10 => rt.set_feed_override(feed.saturating_sub(10)),
            Rt::FeedOvPlus1 => rt.set_feed_override(feed + 1),
            Rt::FeedOvMinus1 => rt.set_feed_override(feed.saturating_sub(1)),
            Rt::RapidOv100 => rt.set_rapid_override(100),
            Rt::RapidOv50 => rt.set_rapid_override(50),
            Rt::RapidOv25 => rt.set_rapid_override(25),
            Rt::SpindleOv100
            | Rt::SpindleOvPlus10
            | Rt::SpindleOvMinus10
            | Rt::SpindleOvPlus1
            | Rt::SpindleOvMinus1 => {
                let ov = self.spindle_ov;
                self.spindle_ov = match r {
                    Rt::SpindleOvPlus10 => ov.saturating_add(10).min(200),
                    Rt::SpindleOvMinus10 => ov.saturating_sub(10).max(10),
                    Rt::SpindleOvPlus1 => ov.saturating_add(1).min(200),
                    Rt::SpindleOvMinus1 => ov.saturating_sub(1).max(10),
                    _ => 100,
                };
                m.set_spindle_override(self.spindle_ov);
            }
            // Only in a plain hold (GRBL's): a door stops the spindle anyway.
            Rt::SpindleStopToggle => {
                if state == executor::State::Hold
                    && m.door_substate().is_none()
                    && !self.jogging
                    && m.spindle_stop()
                {
                    let _ = reply::msg(o, "Restoring spindle");
                }
            }
            // GRBL: in Idle, Run and Hold; the modal state follows.
            Rt::FloodToggle | Rt::MistToggle => {
                let allowed = matches!(
                    state,
                    executor::State::Idle | executor::State::Run | executor::State::Hold
                ) && !(self.sleep || self.check || self.jogging)
                    && m.door_substate().is_none();
                if allowed {
                    let (mist, flood) = m.toggle_coolant(r == Rt::FloodToggle);
                    self.interp.set_coolant(mist, flood);
                }
            }
        }
    }
}
