//! What the O-word stage (`crate::flow`) needs of the interpreter: a value
//! evaluated with the interpreter's parameters, and the call levels' local
//! parameters.

use super::{Env, Interpreter, Tables};
use crate::gcode::lexer::Cursor;
use crate::gcode::{GcodeError, Local, Params};

impl Interpreter {
    /// One real value (`[expr]`, a number, `#n`, a function) at byte `pos`
    /// of `line`, and the byte after it. Reads parameters, writes none.
    pub fn eval_at(&mut self, line: &[u8], pos: usize) -> Result<(f32, usize), GcodeError> {
        let mut saved = super::state::Saved::default();
        let mut tables = Tables::new(&mut self.offsets, &mut saved);
        let mut env = Env {
            state: &mut self.state,
            tables: &mut tables,
            params: &mut self.params,
        };
        let mut cur = Cursor { line, pos };
        let v = cur.real(&mut env, 0)?;
        if !v.is_finite() {
            return Err(cur.err_at(crate::gcode::ErrorKind::NotFinite, pos));
        }
        Ok((v, cur.pos))
    }

    /// The parameter table, for a call's locals (between lines only).
    pub fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }

    /// Sets one local or `#<_…>` parameter outside any line.
    pub fn put_param(&mut self, l: Local) -> Result<(), GcodeError> {
        self.params.put_local(l).map_err(|k| GcodeError::new(k, 0))
    }
}
