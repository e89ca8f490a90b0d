//! Why the machine stopped, in words: the board only says `Hold`, `Door`
//! or `Alarm`; the job file, the board's input pins and the messages seen
//! so far say which stop it is and what the person has to do.

use super::job::PauseKind;
use protocol::msg::pins;
use protocol::{MachineState, Status};

/// Why the machine is paused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reason {
    /// M0 / M1 / M6 at a file line.
    Program { line: usize, kind: PauseKind },
    /// The safety door input.
    Door,
    /// The board's feed-hold input.
    HoldInput,
    /// A hold asked from this keyboard.
    Keyboard,
    /// A hold from elsewhere (another sender, a `!` typed on the port).
    Other,
}

/// The machine is stopped and waits for cycle start (not an alarm).
pub fn is_pause(st: &Status) -> bool {
    // `Tool` is the state a manual tool change may report.
    matches!(st.state, MachineState::Hold | MachineState::Door) || st.state.name() == "Tool"
}

impl Reason {
    pub fn from_status(st: &Status, program: Option<(usize, PauseKind)>, ours: bool) -> Reason {
        if st.state == MachineState::Door || st.pins & pins::DOOR != 0 {
            Reason::Door
        } else if st.pins & pins::HOLD != 0 {
            Reason::HoldInput
        } else if ours {
            Reason::Keyboard
        } else if let Some((line, kind)) = program {
            Reason::Program { line, kind }
        } else if st.state.name() == "Tool" {
            Reason::Program {
                line: 0,
                kind: PauseKind::Tool(None),
            }
        } else {
            Reason::Other
        }
    }

    /// What stopped the machine; `last_msg` may name the tool.
    pub fn describe(&self, last_msg: Option<&str>) -> String {
        match self {
            Reason::Program { kind, .. } => match kind {
                PauseKind::Stop => "program pause (M0)".into(),
                PauseKind::Optional => "optional stop (M1)".into(),
                PauseKind::Tool(t) => {
                    let named = last_msg.filter(|m| m.to_ascii_lowercase().contains("tool"));
                    match (named, t) {
                        (Some(m), _) => format!("tool change (M6): {m}"),
                        (None, Some(t)) => format!("tool change (M6): insert tool T{t}"),
                        (None, None) => "tool change (M6)".into(),
                    }
                }
            },
            Reason::Door => "safety door open (board input); close it first".into(),
            Reason::HoldInput => "feed hold from the board's hold input".into(),
            Reason::Keyboard => "held from the keyboard".into(),
            Reason::Other => "feed hold (from the board or another program)".into(),
        }
    }
}

/// An alarm in words, with what clears it.
pub fn alarm_text(code: u16) -> String {
    use protocol::codes::alarm;
    let what = match code {
        alarm::HARD_LIMIT => "hard limit switch hit; position lost",
        alarm::SOFT_LIMIT => "target outside the soft limits; the move was not started",
        alarm::ABORT_CYCLE => "reset while moving; position may be lost",
        alarm::PROBE_FAIL_INITIAL => "probe not in the expected state before probing",
        alarm::PROBE_FAIL_CONTACT => "probe did not touch within the move",
        alarm::HOMING_FAIL_RESET => "homing: reset during the cycle",
        alarm::HOMING_FAIL_DOOR => "homing: door opened during the cycle",
        alarm::HOMING_FAIL_PULLOFF => "homing: pull-off did not clear the switch",
        alarm::HOMING_FAIL_APPROACH => "homing: switch not found",
        alarm::ESTOP => "e-stop pressed; release it",
        alarm::LINK_LOST => "host link lost while running",
        alarm::LATE_ERROR => {
            "a line was refused after its ok (the error above); nothing after it ran"
        }
        _ => "alarm",
    };
    format!("{what}; the job stopped: unlock with $X or home with $H before moving again")
}

/// `X1.000 Y2.000 Z3.000` (work position).
pub fn wpos_text(st: &Status) -> String {
    let w = st.wpos();
    format!("X{:.3} Y{:.3} Z{:.3}", w[0], w[1], w[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reasons_in_words() {
        let held = Status {
            state: MachineState::Hold,
            ..Status::default()
        };
        let m6 = Some((12, PauseKind::Tool(Some(3))));
        let r = Reason::from_status(&held, m6, false);
        assert_eq!(r.describe(None), "tool change (M6): insert tool T3");
        // The board's own message naming the tool wins over the file's T.
        assert_eq!(
            r.describe(Some("Change to tool 4 (6 mm end mill)")),
            "tool change (M6): Change to tool 4 (6 mm end mill)"
        );
        assert_eq!(
            Reason::from_status(&held, Some((4, PauseKind::Stop)), false).describe(None),
            "program pause (M0)"
        );
        // A hold from the keyboard is not the M0 further down the file.
        assert_eq!(Reason::from_status(&held, m6, true), Reason::Keyboard);
        let door = Status {
            pins: pins::DOOR,
            ..held
        };
        assert_eq!(Reason::from_status(&door, m6, true), Reason::Door);
        let input = Status {
            pins: pins::HOLD,
            ..held
        };
        assert_eq!(Reason::from_status(&input, None, false), Reason::HoldInput);
        assert!(alarm_text(protocol::codes::alarm::HARD_LIMIT).contains("$X"));
    }
}
