//! The G-code language: one line in, words out.
//!
//! [`Lexer`] turns a line into [`Word`]s, evaluating parameters and
//! `[expressions]` as it goes, so nothing downstream ever sees text. It
//! allocates nothing: all state is on the stack or in [`Params`].
//! The interpreter (`crate::interp`) gives the words meaning.

pub mod error;
mod expr;
pub mod lexer;
pub mod params;

pub use error::{ErrorKind, GcodeError, OWord, Unsupported};
pub use expr::MAX_DEPTH;
pub use lexer::{Lexer, Token};
pub use params::{Local, Name, ParamStore, Params};

/// Longest accepted line in bytes, not counting the line terminator. Longer
/// lines are an error, never truncated: a cut-off `X1000` would be `X10`.
pub const MAX_LINE: usize = 256;

/// One word: an upper-case letter and its evaluated value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Word {
    pub letter: u8,
    pub value: f32,
    /// 1-based column of the letter.
    pub col: u16,
    /// An axis letter with no number (`G28 X Y`, `M18 Z`: RepRap style).
    /// Only homing and motor commands accept it; `value` is then 0.
    pub bare: bool,
}

impl Word {
    /// The number in tenths (G59.1 -> 591) when it has at most one decimal,
    /// as G and M numbers must.
    pub fn tenths(&self) -> Option<u16> {
        let t10 = self.value * 10.0;
        if !(0.0..=65535.0).contains(&t10) {
            return None;
        }
        // Non-negative here, so the cast after +0.5 rounds to nearest.
        let t = (t10 + 0.5) as u16;
        if (t10 - f32::from(t)).abs() < 1e-3 {
            Some(t)
        } else {
            None
        }
    }
}
