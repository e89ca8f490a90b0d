//! Numbered (`#1`–`#5399`) and named (`#<name>`) parameters.
//!
//! RS274NGC describes 5400 numbered parameters; 5400 `f32`s would take a third
//! of the F401's RAM, and real programs touch a handful. So the table is
//! sparse: a sorted list of the numbers that were ever written (unset reads
//! give 0, as in LinuxCNC) plus a short list of names. A full table is a typed
//! error, never a silent drop.
//!
//! Assignments take effect at once (BeagleG semantics: `G1 #1=10 X#1` moves
//! to X10). Because a failed line must leave no trace, every write of a line
//! is logged and [`Params::rollback`] undoes them in reverse order.

use super::error::ErrorKind;

/// Numbered parameters that can be held at once.
pub const NUMBERED_CAP: usize = 128;
/// Named parameters that can be held at once.
pub const NAMED_CAP: usize = 32;
/// Longest parameter name in bytes (after lowercasing, spaces removed).
pub const NAME_MAX: usize = 23;
/// Parameter writes one line may make (the undo log's size).
pub const UNDO_CAP: usize = 16;
/// Highest parameter number.
pub const PARAM_MAX: u16 = 5399;
/// The highest number a `#n` may name: #5400-#5410 are the current tool's,
/// computed by the interpreter (read-only, not in the table).
pub const PARAM_READ_MAX: u16 = 5410;

/// A parameter name, lowercased, without spaces (LinuxCNC's rules).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Name {
    bytes: [u8; NAME_MAX],
    len: u8,
}

impl Name {
    pub const fn empty() -> Self {
        Name {
            bytes: [0; NAME_MAX],
            len: 0,
        }
    }
    /// Appends one byte, lowercased.
    pub fn push(&mut self, b: u8) -> Result<(), ErrorKind> {
        let slot = self
            .bytes
            .get_mut(self.len as usize)
            .ok_or(ErrorKind::ParamNameTooLong)?;
        *slot = b.to_ascii_lowercase();
        self.len += 1;
        Ok(())
    }
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..self.len as usize).unwrap_or(&[])
    }
}

/// Where the lexer reads and writes parameters. The interpreter implements
/// it so that #5161.. #5399 map onto its typed offset state.
pub trait ParamStore {
    fn get(&self, n: u16) -> Result<f32, ErrorKind>;
    fn set(&mut self, n: u16, v: f32) -> Result<(), ErrorKind>;
    fn get_named(&self, name: &Name) -> Result<f32, ErrorKind>;
    fn set_named(&mut self, name: &Name, v: f32) -> Result<(), ErrorKind>;
}

/// Highest local numbered parameter: a call's arguments `#1`-`#30`.
pub const LOCALS: u16 = 30;

/// One local parameter with its value (see [`Params::locals`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Local {
    Num(u16, f32),
    Named(Name, f32),
}

/// Names without a leading `_` belong to the call level that set them.
fn is_local(n: &Name) -> bool {
    n.as_bytes().first() != Some(&b'_')
}

#[derive(Clone, Copy, Debug)]
enum Undo {
    /// Numbered parameter `n` had `Some(old)` or did not exist.
    Num(u16, Option<f32>),
    /// Named parameter at `index` had `Some(old)`, or was appended (`None`).
    Named(u8, Option<f32>),
}

/// The sparse parameter tables plus the per-line undo log.
#[derive(Clone, Debug)]
pub struct Params {
    numbered: heapless::Vec<(u16, f32), NUMBERED_CAP>,
    named: heapless::Vec<(Name, f32), NAMED_CAP>,
    undo: heapless::Vec<Undo, UNDO_CAP>,
}

impl Default for Params {
    fn default() -> Self {
        Self::new()
    }
}

impl Params {
    pub const fn new() -> Self {
        Params {
            numbered: heapless::Vec::new(),
            named: heapless::Vec::new(),
            undo: heapless::Vec::new(),
        }
    }

    /// Starts a line: forget the previous line's undo log (it committed).
    pub fn begin_line(&mut self) {
        self.undo.clear();
    }

    /// Undoes every write since [`Params::begin_line`], newest first.
    pub fn rollback(&mut self) {
        while let Some(u) = self.undo.pop() {
            match u {
                Undo::Num(n, old) => {
                    if let Ok(i) = self.numbered.binary_search_by_key(&n, |e| e.0) {
                        match old {
                            Some(v) => {
                                if let Some(e) = self.numbered.get_mut(i) {
                                    e.1 = v;
                                }
                            }
                            None => {
                                self.numbered.remove(i);
                            }
                        }
                    }
                }
                Undo::Named(i, Some(v)) => {
                    if let Some(e) = self.named.get_mut(i as usize) {
                        e.1 = v;
                    }
                }
                Undo::Named(_, None) => {
                    self.named.pop();
                }
            }
        }
    }

    /// Same stored values as `other`, bit for bit (the undo log aside):
    /// what a failed line must leave behind (checked by the fuzz targets).
    pub fn same_values(&self, other: &Params) -> bool {
        let num = |a: &(u16, f32), b: &(u16, f32)| a.0 == b.0 && a.1.to_bits() == b.1.to_bits();
        let named = |a: &(Name, f32), b: &(Name, f32)| a.0 == b.0 && a.1.to_bits() == b.1.to_bits();
        self.numbered.len() == other.numbered.len()
            && self.named.len() == other.named.len()
            && self
                .numbered
                .iter()
                .zip(&other.numbered)
                .all(|(a, b)| num(a, b))
            && self
                .named
                .iter()
                .zip(&other.named)
                .all(|(a, b)| named(a, b))
    }

    /// Every stored value is finite.
    pub fn all_finite(&self) -> bool {
        self.numbered.iter().all(|e| e.1.is_finite()) && self.named.iter().all(|e| e.1.is_finite())
    }

    /// Value of a stored numbered parameter; unset ones read 0.
    pub fn get_num(&self, n: u16) -> f32 {
        match self.numbered.binary_search_by_key(&n, |e| e.0) {
            Ok(i) => self.numbered.get(i).map_or(0.0, |e| e.1),
            Err(_) => 0.0,
        }
    }

    /// Stores a numbered parameter (range checks are the caller's).
    pub fn set_num(&mut self, n: u16, v: f32) -> Result<(), ErrorKind> {
        match self.numbered.binary_search_by_key(&n, |e| e.0) {
            Ok(i) => {
                let e = self.numbered.get_mut(i).ok_or(ErrorKind::ParamTableFull)?;
                let old = e.1;
                self.undo
                    .push(Undo::Num(n, Some(old)))
                    .map_err(|_| ErrorKind::TooManyAssignments)?;
                if let Some(e) = self.numbered.get_mut(i) {
                    e.1 = v;
                }
            }
            Err(i) => {
                if self.numbered.is_full() {
                    return Err(ErrorKind::ParamTableFull);
                }
                self.undo
                    .push(Undo::Num(n, None))
                    .map_err(|_| ErrorKind::TooManyAssignments)?;
                self.numbered
                    .insert(i, (n, v))
                    .map_err(|_| ErrorKind::ParamTableFull)?;
            }
        }
        Ok(())
    }

    pub fn get_name(&self, name: &Name) -> Result<f32, ErrorKind> {
        self.named
            .iter()
            .find(|e| e.0 == *name)
            .map(|e| e.1)
            .ok_or(ErrorKind::UndefinedParam)
    }

    pub fn set_name(&mut self, name: &Name, v: f32) -> Result<(), ErrorKind> {
        if let Some(i) = self.named.iter().position(|e| e.0 == *name) {
            let old = self.named.get(i).map(|e| e.1);
            self.undo
                .push(Undo::Named(i as u8, old))
                .map_err(|_| ErrorKind::TooManyAssignments)?;
            if let Some(e) = self.named.get_mut(i) {
                e.1 = v;
            }
            return Ok(());
        }
        if self.named.is_full() {
            return Err(ErrorKind::ParamTableFull);
        }
        self.undo
            .push(Undo::Named(self.named.len() as u8, None))
            .map_err(|_| ErrorKind::TooManyAssignments)?;
        self.named
            .push((*name, v))
            .map_err(|_| ErrorKind::ParamTableFull)
    }

    /// A subroutine's local parameters (LinuxCNC's scoping): `#1`-`#30` and
    /// names without a leading `_`. A call saves the caller's elsewhere and
    /// removes them; its return drops the callee's and puts them back.
    pub fn locals(&self) -> impl Iterator<Item = Local> + '_ {
        let num = self
            .numbered
            .iter()
            .take_while(|e| e.0 <= LOCALS)
            .map(|&(n, v)| Local::Num(n, v));
        let named = self
            .named
            .iter()
            .filter(|e| is_local(&e.0))
            .map(|&(n, v)| Local::Named(n, v));
        num.chain(named)
    }

    /// Drops every local parameter (see [`Params::locals`]); no undo, as
    /// it happens between lines.
    pub fn clear_locals(&mut self) {
        self.undo.clear();
        self.numbered.retain(|e| e.0 > LOCALS);
        self.named.retain(|e| !is_local(&e.0));
    }

    /// Restores one saved local, outside any line (no undo entry).
    pub fn put_local(&mut self, l: Local) -> Result<(), ErrorKind> {
        let r = match l {
            Local::Num(n, v) => self.set_num(n, v),
            Local::Named(name, v) => self.set_name(&name, v),
        };
        self.undo.clear();
        r
    }

    /// Numbered parameters currently stored (for tests and `$#`-style dumps).
    pub fn numbered_len(&self) -> usize {
        self.numbered.len()
    }
}

/// A plain store over [`Params`] alone, for lexer tests and tools that do
/// not need the interpreter's computed parameters.
impl ParamStore for Params {
    fn get(&self, n: u16) -> Result<f32, ErrorKind> {
        if n > PARAM_MAX {
            return Err(ErrorKind::ParamOutOfRange);
        }
        Ok(self.get_num(n))
    }
    fn set(&mut self, n: u16, v: f32) -> Result<(), ErrorKind> {
        match n {
            0 => Err(ErrorKind::ParamReadOnly),
            1..=PARAM_MAX => self.set_num(n, v),
            _ => Err(ErrorKind::ParamOutOfRange),
        }
    }
    fn get_named(&self, name: &Name) -> Result<f32, ErrorKind> {
        self.get_name(name)
    }
    fn set_named(&mut self, name: &Name, v: f32) -> Result<(), ErrorKind> {
        self.set_name(name, v)
    }
}
