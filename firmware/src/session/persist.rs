//! When the session writes settings and offsets to storage.
//!
//! A flash write stalls the CPU, the step interrupt included, so nothing is
//! written while motion is queued or running:
//!
//! * `$n=` is refused unless idle (GRBL's rule) and persists at once;
//!   `$RST=$`, `$RST=#` and `$RST=*` likewise.
//! * G10 L2/L20, G28.1 and G30.1 persist the offsets (GRBL does), M500
//!   writes settings and offsets, M501 reloads both as at boot. In a job
//!   these are sync points: the device takes no further line until the
//!   motion before them has finished, writes (or reads), then goes on. At
//!   idle they act before the line's `ok`.
//! * Offsets changed through their parameters (`#5221=…`) are not saved
//!   by themselves: M500 saves them, M501 (or a reset of the board)
//!   discards them. Settings have no such unsaved state: `$n=` saves.
//! * A soft reset or an alarm cancels an M500/M501 still waiting for its
//!   sync point, as it cancels the queued motion; offsets already changed
//!   are still saved when the machine next stops.
//! * Check mode (`$C`) writes nothing.
//! * Nothing is written while the spindle or coolant is on (as the lines
//!   so far leave them): a sector erase stalls every flash fetch for up
//!   to 0.8 s, the e-stop and limit interrupts included. `$n=` and `$RST=`
//!   then fail with `error:113` (`Code::OutputsOn`), and a line with G10
//!   L2/L20, G28.1, G30.1 or M500 with G-code error 328
//!   (`FlashWriteOutputsOn`, GRBL `error:8`) and leaves no trace.

use super::{Device, Identity, LinkLost, MotionPort, Out, Stats, Tx};
use crate::command::Command;
use crate::interp::{Interpreter, Offsets};
use crate::link::syscmd::Restore;
use crate::link::FramedPort;
use crate::persist::Report;
use crate::persist::{Loaded, Persist};
use crate::seams::Storage;
use crate::settings::table::SettingError;
use core::fmt::Write;
use heapless::Deque;

/// Storage work waiting for the machine to stop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Pending {
    offsets: bool,
    save: bool,
    load: bool,
}

impl Pending {
    /// M500 and M501 are the session's to do, not the executor's: noted
    /// here and kept out of the command queue. True if `c` was one.
    pub(super) fn take_command(&mut self, c: &Command) -> bool {
        match c {
            Command::SaveSettings => self.save = true,
            Command::LoadSettings => self.load = true,
            _ => return false,
        }
        true
    }

    fn any(&self) -> bool {
        self.offsets || self.save || self.load
    }

    /// Soft reset: queued M500/M501 go with the rest of the queue.
    pub(super) fn cancel_queued(&mut self) {
        self.save = false;
        self.load = false;
    }
}

/// A load's report as one `[MSG:]` line, if there is anything to say.
pub(super) fn tell(report: &Report, o: &mut Out<'_, impl Tx>) {
    if !report.is_clean() {
        let _ = write!(o, "[MSG:{report}]\r\n");
    }
}

/// A setting M501 or `$RST=$` could not apply: it keeps its old value.
fn not_applied(r: Result<(), (u16, SettingError)>, o: &mut Out<'_, impl Tx>) {
    if let Err((n, e)) = r {
        let _ = write!(o, "[MSG:${n} not applied: error {}]\r\n", e.code().code());
    }
}

fn not_saved(o: &mut Out<'_, impl Tx>) {
    let _ = o.write_str("[MSG:Not saved: settings storage error]\r\n");
}

impl<S: Storage> Device<S> {
    /// A session over `persist`. `boot` is what `persist.load()` gave
    /// before the machine was built with its settings: its offsets go to
    /// the interpreter, its report follows the first banner.
    #[inline(always)]
    pub fn with_storage(ident: Identity, persist: Persist<S>, boot: Option<&Loaded>) -> Self {
        // The interpreter (4 KB) is built in its field, not beside it on
        // the boot stack and moved in (the F401's stack headroom, issue 33).
        Device {
            interp: Interpreter::with_offsets(boot.map(|b| &b.offsets)),
            flow: crate::flow::Flow::new(),
            replay_framed: false,
            port: FramedPort::new(),
            ident,
            cmds: Deque::new(),
            slots: Deque::new(),
            cadence: Default::default(),
            check: false,
            jogging: false,
            jog_cancel: false,
            sync: true,
            probe_sync: false,
            seen_alarm: None,
            quiet_alarm: false,
            text_lines: 0,
            sleep: false,
            numbers: Default::default(),
            spindle_ov: 100,
            reset_due: false,
            link_lost: LinkLost::No,
            stats: Stats::default(),
            persist,
            pending: Pending::default(),
            boot_report: boot.map(|b| b.report).unwrap_or_default(),
        }
    }

    /// The storage layer (host-sim hands its flash to a "rebooted" device).
    pub fn persist(&mut self) -> &mut Persist<S> {
        &mut self.persist
    }

    /// After a line interpreted cleanly: note what it asks to persist, and
    /// do it now if nothing is moving, else at the sync point.
    pub(super) fn after_line(
        &mut self,
        mut line: Pending,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) {
        line.offsets = self.interp.take_offsets_changed();
        if self.check || !line.any() {
            return;
        }
        self.pending.offsets |= line.offsets;
        self.pending.save |= line.save;
        self.pending.load |= line.load;
        if m.motion_idle() && self.cmds.is_empty() {
            self.flush_storage(m, o);
        } else {
            self.sync = true;
        }
    }

    /// The sync point: the machine is idle, do what is pending.
    pub(super) fn flush_storage(&mut self, m: &mut impl MotionPort, o: &mut Out<'_, impl Tx>) {
        let p = core::mem::take(&mut self.pending);
        if p.save {
            self.save_settings(m, o);
        }
        if p.save || p.offsets {
            let offsets = self.interp.offsets();
            if self.persist.save_offsets(&offsets).is_err() {
                not_saved(o);
            }
        }
        if p.load {
            let loaded = self.persist.load();
            not_applied(m.replace_settings(&loaded.settings), o);
            self.interp.set_offsets(&loaded.offsets);
            tell(&loaded.report, o);
        }
    }

    /// Writes the settings that changed (after `$n=`, M500, `$RST=$`).
    pub(super) fn save_settings(&mut self, m: &impl MotionPort, o: &mut Out<'_, impl Tx>) {
        let s = *m.settings();
        if self.persist.save_settings(&s).is_err() {
            not_saved(o);
        }
    }

    /// `$RST=$` / `$RST=#` / `$RST=*`: defaults back, and saved. Idle only.
    pub(super) fn restore(
        &mut self,
        what: Restore,
        m: &mut impl MotionPort,
        o: &mut Out<'_, impl Tx>,
    ) -> Result<(), u16> {
        if self.check || !m.motion_idle() || !self.cmds.is_empty() {
            return Err(protocol::Code::NotIdle.code());
        }
        if self.interp.outputs_on() {
            return Err(protocol::Code::OutputsOn.code());
        }
        if matches!(what, Restore::Settings | Restore::All) {
            let d = *self.persist.defaults();
            not_applied(m.replace_settings(&d), o);
            self.save_settings(m, o);
        }
        if matches!(what, Restore::Offsets | Restore::All) {
            self.interp.set_offsets(&Offsets::default());
            if self.persist.save_offsets(&Offsets::default()).is_err() {
                not_saved(o);
            }
        }
        let _ = o.write_str("[MSG:Restoring defaults]\r\n");
        Ok(())
    }
}
