//! The controller: everything the parse/plan task decides, written once and
//! driven by both shells.
//!
//! One [`Controller::pass`] is one wake-up of the board's lowest-priority
//! task and one task slot of host-sim's virtual board: the device session
//! (both protocols) reads the link and feeds the executor, the executor
//! fills the segment queue, and the outputs (spindle, coolant, stepper
//! enable with `$1`) follow what was executed. The shells only move bytes
//! (token ring in, reply bytes out), pin levels ([`Pins`] out, switch
//! levels in) and time (`now_ms`); the RTIC app writes the result to
//! registers, host-sim to its recorder. So nothing that decides what the
//! machine does can drift between the board and the simulator.
//!
//! The session meets the rest of the core through two small ports
//! (`session::LinkPort`, `session::MotionPort`), implemented here and only
//! here (`controller_ports.rs`).

use crate::executor::{Machine, Note, State};
use crate::link::{LineAssembler, LinkMode, RtFlags, TokenSource};
use crate::outputs::{Enable, LaserQueue, Motion, Outputs, Spindle};
use crate::realtime::Realtime;
use crate::seams::{Storage, Switches};
use crate::session::{Device, Tx};
use crate::settings::Settings;
use crate::stepper::prep::SegmentSink;
use crate::suspend::Suspend;

#[path = "controller_ports.rs"]
mod ports;
use ports::{Core, TaskLink};

pub use crate::link::{RX_BACKLOG, RX_RING};
pub use crate::session::TX_HEADROOM;

/// Planner ring size (blocks of look-ahead), the same in both shells.
pub const PLANNER_BLOCKS: usize = 64;
/// Prepared segments between the parse task and the step interrupt
/// (`heapless::spsc` keeps one slot free), the same in both shells.
pub const SEGMENT_SLOTS: usize = 16;
/// Reply bytes waiting for the link interrupt: the board's TX ring, and
/// the room host-sim's tests give their reply buffer to see a full ring.
/// A pass reads new input only with [`TX_HEADROOM`] of it free.
pub const TX_RING: usize = 1024;
const _: () = assert!(TX_HEADROOM < TX_RING);

/// What the shell reports at the start of a pass.
#[derive(Clone, Copy, Debug, Default)]
pub struct Inputs {
    /// Milliseconds since power-up (wrapping; the board's heartbeat clock).
    pub now_ms: u32,
    /// Limit and probe levels as read now.
    pub switches: Switches,
    /// Debounced inputs for the status report (`protocol::msg::pins` bits).
    pub pins: u16,
    /// The port was closed or reopened since the last pass (the receive
    /// side already put its mode-reset marker into the ring).
    pub port_closed: bool,
    /// A client opened the port since the last pass (after any close):
    /// the session decides whether that is a reset with a banner
    /// (`session::Device::port_opened`).
    pub port_opened: bool,
}

/// Output pin levels after a pass, in hardware-free terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pins {
    /// Stepper drivers powered (before the `$4` polarity).
    pub enable: bool,
    /// `$4` as it is now: the polarity the shell writes `enable` with (a
    /// change rewrites the pin at once).
    pub enable_invert: bool,
    pub spindle: Spindle,
    pub flood: bool,
    pub mist: bool,
}

/// What the shell does after a pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pass {
    pub pins: Pins,
    /// Enter the step interrupt now (the board pends it): segments wait,
    /// the drivers are awake and the step timer is stopped (start it),
    /// motion was flushed while it runs (stop it without waiting for its
    /// next slot), or a `$n=` published a step configuration the step
    /// interrupt has not taken (stopped, it takes it and sets the idle pin
    /// levels under it at once; in the slot after its last event it stops
    /// as soon as the last pulse is over, and takes it then).
    pub kick: bool,
}

/// What a pass lets its shell watch (host-sim records paths and checks
/// exactly-once delivery with these; the board ignores them).
#[derive(Clone, Copy, Debug)]
pub enum Event<'n, 'c> {
    /// The executor reported something.
    Note(&'n Note<'c>),
    /// The executor accepted a command of this machine line number
    /// (`motion`: it moves the machine).
    Accepted { line: u32, motion: bool },
}

/// The queues and flags a pass works on, owned by the shell because the
/// interrupts hold their other ends.
#[derive(Debug)]
pub struct Io<'a, Q, R, T> {
    pub rt: &'a Realtime,
    pub flags: &'a RtFlags,
    /// Consumer end of the receive token ring.
    pub rx: &'a mut R,
    /// Producer end of the segment queue.
    pub segments: &'a mut Q,
    pub tx: &'a mut T,
}

/// The parse/plan task's state besides the executor.
#[derive(Debug)]
pub struct Controller<S: Storage> {
    pub session: Device<S>,
    asm: LineAssembler,
    outputs: Outputs,
    suspend: Suspend,
    laser: LaserQueue,
    enable: Enable,
    resets: u32,
    /// The segment generation the last pass saw, and whether a flush since
    /// then still has the step timer running (see [`Pass::kick`]).
    generation: u32,
    halting: bool,
}

impl<S: Storage> Controller<S> {
    /// `wake_ms`: how long the drivers need between enable and a first step.
    #[inline(always)]
    pub fn new(session: Device<S>, settings: &Settings, wake_ms: u16) -> Self {
        let resets = session.stats.resets;
        Controller {
            session,
            asm: LineAssembler::new(),
            outputs: Outputs::new(settings),
            suspend: Suspend::new(),
            laser: LaserQueue::new(),
            enable: Enable::new(settings.idle_delay_ms, wake_ms),
            resets,
            generation: 0,
            halting: false,
        }
    }

    /// The banner, as after power-up (a port open is `Inputs::port_opened`).
    pub fn hello(&mut self, tx: &mut impl Tx) {
        self.session.hello(tx);
    }

    /// Mode of the next link event (the assembler's).
    pub fn link_mode(&self) -> LinkMode {
        self.asm.mode()
    }

    /// Received bytes not yet turned into events, besides those in `rx`.
    pub fn rx_partial(&self) -> usize {
        self.asm.pending()
    }

    /// Spindle and coolant as the executed commands left them.
    pub fn outputs(&self) -> &Outputs {
        &self.outputs
    }

    /// One pass: session, executor, session again (it reacts to what the
    /// executor did, sync points and alarms, in the same wake-up), then
    /// the outputs. `obs` sees what the executor did ([`Event`]).
    pub fn pass<const N: usize>(
        &mut self,
        machine: &mut Machine<N>,
        io: Io<'_, impl SegmentSink, impl TokenSource, impl Tx>,
        input: Inputs,
        obs: &mut dyn FnMut(Event),
    ) -> Pass {
        let Io {
            rt,
            flags,
            rx,
            segments,
            tx,
        } = io;
        let mut link = TaskLink {
            asm: &mut self.asm,
            rx,
            flags,
        };
        let mut core = Core {
            machine,
            segments,
            rt,
            outputs: &mut self.outputs,
            suspend: &mut self.suspend,
            laser: &mut self.laser,
            pins: input.pins,
            now_ms: input.now_ms,
            obs,
        };
        if input.port_closed {
            self.session.port_reset(&mut link, &core);
            // What the departed client sent and the task did not read is
            // void (the splitter counted the port reset as a discard point).
            link.asm.flush_reset(link.rx, link.flags);
        }
        if input.port_opened {
            self.session.port_opened(&mut link, &mut core, tx);
        }
        for _ in 0..2 {
            // Realtime commands act whatever the link does; only the
            // reading of new input waits for reply room.
            if tx.room() >= TX_HEADROOM {
                self.session.poll(&mut link, &mut core, tx);
            } else {
                self.session.poll_realtime(&mut link, &mut core, tx);
            }
            // A soft reset (0x18, e-stop) stops spindle and coolant.
            if self.session.stats.resets != self.resets {
                self.resets = self.session.stats.resets;
                core.outputs.all_off();
                core.suspend.clear(core.outputs);
                core.laser.clear();
            }
            core.poll(input.switches);
            let delay_ms = (core.machine.settings().spindle_delay_s * 1000.0) as u32;
            core.suspend
                .update(rt, core.outputs, input.now_ms, delay_ms);
        }
        let queued = !core.segments.is_empty();
        let state = core.machine.state(rt);
        let settings = core.machine.settings();
        let enable_invert = settings.enable_invert;
        let stepping = rt.stepping();
        let busy = queued || stepping || !rt.stepper_idle();
        // A flush (reset, alarm, e-stop, hard limit) while the timer runs:
        // the step interrupt stops at its next entry, which a slow move may
        // not reach for many seconds, so it gets one now, every pass until
        // it has stopped.
        let generation = rt.generation();
        self.halting = stepping && (self.halting || generation != self.generation);
        self.generation = generation;
        core.outputs.configure(settings);
        self.enable.set_idle_ms(settings.idle_delay_ms);
        // `$SLP` powers everything down as an alarm does.
        let alarm = state == State::Alarm || self.session.sleeping();
        if alarm {
            core.outputs.all_off();
            core.suspend.clear(core.outputs);
            core.laser.clear();
        }
        // Laser mode: spindle commands apply as their line starts to run,
        // all of them once the motion has stopped.
        let running = (busy && !core.laser.is_empty()).then(|| rt.running().1);
        core.laser.release(core.outputs, running);
        let enable = self
            .enable
            .update(input.now_ms, busy, state == State::Hold, alarm);
        // Laser mode: the beam follows the segment the step interrupt runs
        // (`Segment::cut`): dark on rapids, waits and dwells, in a hold and
        // when stopped; M4 scales with that segment's speed.
        let cut = rt.running_cut();
        let motion = if !stepping || state == State::Hold {
            Motion::Stopped
        } else if cut > 0.0 {
            Motion::Feed { ratio: cut }
        } else {
            Motion::Rapid
        };
        Pass {
            pins: Pins {
                enable,
                enable_invert,
                spindle: self.outputs.spindle(motion),
                flood: self.outputs.flood_on(),
                mist: self.outputs.mist_on(),
            },
            kick: (queued && !stepping && self.enable.may_step())
                || self.halting
                || rt.step_config().pending(),
        }
    }
}
