//! Whole files at once, for host tools (check mode, comparisons).

use super::{err, Flow, Intake, Step};
use crate::gcode::{GcodeError, OWord};
use crate::interp::Interpreter;

/// What [`Flow::feed_line`] calls for each line to interpret.
pub type RunLine<'a> = dyn FnMut(&mut Interpreter, &[u8], u32) -> Result<(), GcodeError> + 'a;

impl Flow {
    /// Feeds one line and runs all it releases at once: `run` interprets
    /// each line to execute (text, source line). For tools that take a
    /// whole file (check mode, comparisons); the device's session steps
    /// instead, a bounded number per pass. A replay longer than
    /// `max_steps` steps ends with [`OWord::TooDeep`].
    pub fn feed_line(
        &mut self,
        text: &[u8],
        n: u32,
        interp: &mut Interpreter,
        max_steps: u64,
        run: &mut RunLine<'_>,
    ) -> Result<(), (u32, GcodeError)> {
        match self.intake(text, n, interp) {
            Intake::Run => run(interp, text, n).map_err(|e| (n, e)),
            Intake::Reply(r) => r.map_err(|e| (n, e)),
            Intake::Replay => {
                let mut buf = [0u8; crate::gcode::MAX_LINE];
                let mut steps = 0u64;
                loop {
                    steps += 1;
                    if steps > max_steps {
                        self.abort(interp);
                        return Err((n, err(OWord::TooDeep)));
                    }
                    match self.step(interp, &mut buf) {
                        Step::Run { n: ln, len } => {
                            let line = buf.get(..len).unwrap_or(&[]);
                            if let Err(e) = run(interp, line, ln) {
                                self.abort(interp);
                                return Err((ln, e));
                            }
                        }
                        Step::Busy => {}
                        Step::Done { result, .. } => return result,
                        Step::Idle => return Ok(()),
                    }
                }
            }
        }
    }
}
