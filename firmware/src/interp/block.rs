//! Collecting one command's words and checking RS274NGC's modal groups.
//!
//! A line may hold several commands (BeagleG): a motion G word (G0-G3, G5,
//! G38.x, G80) that arrives after axis words starts a new block, so
//! `G1 X10 Y100 G1 X0 Y0` is two moves. Any other second word of one group
//! is a modal group violation, as RS274NGC says.

use crate::gcode::{ErrorKind, GcodeError, Unsupported, Word};
use crate::AXES;

/// G-word modal groups (index into [`Block::g`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum GGroup {
    NonModal = 0,
    Motion,
    Plane,
    Distance,
    ArcDistance,
    FeedMode,
    Units,
    Cutter,
    ToolLength,
    Wcs,
    Path,
    /// G98/G99: where canned cycles retract to.
    Retract,
}
const G_GROUPS: usize = 12;

/// The groups that only set a mode ([`Block::gmask`] bits).
pub(crate) const MODE_GROUPS: u16 = 1 << GGroup::Plane as u16
    | 1 << GGroup::Distance as u16
    | 1 << GGroup::ArcDistance as u16
    | 1 << GGroup::FeedMode as u16
    | 1 << GGroup::Units as u16
    | 1 << GGroup::Wcs as u16
    | 1 << GGroup::Path as u16
    | 1 << GGroup::Retract as u16;

/// M-word groups (index into [`Block::m`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MGroup {
    Stop = 0,
    Spindle,
    Coolant,
    Misc,
    /// M6, M61: tool change, set the current tool.
    Tool,
}
const M_GROUPS: usize = 5;

fn g_group(tenths: u16) -> Option<GGroup> {
    use GGroup::*;
    Some(match tenths {
        80 | 40 | 100 | 270 | 280 | 281 | 300 | 301 | 530 | 920..=923 => NonModal,
        0
        | 10
        | 20
        | 30
        | 50
        | 51
        | 382..=385
        | 800
        | 730
        | 810
        | 820
        | 830
        | 850
        | 860
        | 880
        | 890 => Motion,
        170 | 180 | 190 => Plane,
        900 | 910 => Distance,
        901 | 911 => ArcDistance,
        930 | 940 => FeedMode,
        200 | 210 | 700 | 710 => Units,
        400 | 410 | 411 | 420 | 421 => Cutter,
        430..=432 | 490 => ToolLength,
        540 | 550 | 560 | 570 | 580 | 590..=593 => Wcs,
        610 | 611 | 640 => Path,
        980 | 990 => Retract,
        _ => return None,
    })
}

fn m_group(n: u16) -> Option<MGroup> {
    use MGroup::*;
    Some(match n {
        0 | 1 | 2 | 30 => Stop,
        3..=5 => Spindle,
        7..=9 => Coolant,
        10 | 11 | 24 | 80..=83 | 104 | 105 | 109 | 111 | 116 | 120 | 121 | 245 | 246 | 355 => Misc,
        6 | 61 => Tool,
        17
        | 18
        | 84
        | 42
        | 62..=65
        | 106
        | 107
        | 114
        | 115
        | 117
        | 119
        | 220
        | 400
        | 500
        | 501
        | 999 => Misc,
        _ => return None,
    })
}

/// The axes' letters, in array order ([`crate::AXIS_NAMES`] as bytes).
pub(crate) const AXIS_LETTERS: [u8; AXES] = {
    let mut l = [0; AXES];
    let mut i = 0;
    while i < AXES {
        l[i] = crate::AXIS_NAMES[i] as u8;
        i += 1;
    }
    l
};

/// The axes' letters as [`bit`]s.
pub(crate) const AXIS_BITS: u32 = {
    let mut m = 0;
    let mut i = 0;
    while i < AXES {
        m |= bit(AXIS_LETTERS[i]);
        i += 1;
    }
    m
};

/// The axes after X, Y and Z (A, B, C): no plane, cycle or spline uses them.
pub(crate) const EXTRA_AXIS_BITS: u32 = AXIS_BITS & !(bit(b'X') | bit(b'Y') | bit(b'Z'));

/// The words of one command.
#[derive(Clone, Debug, Default)]
pub(crate) struct Block<'a> {
    /// Per group: the G number in tenths and its column.
    pub g: [Option<(u16, u16)>; G_GROUPS],
    /// Per group: the M number and its column. Coolant keeps M7+M8 as a mask in `coolant`.
    pub m: [Option<(u16, u16)>; M_GROUPS],
    /// Which G groups (bit = [`GGroup`] index) and M groups hold a word,
    /// so the executor can skip absent groups wholesale.
    pub gmask: u16,
    pub mmask: u8,
    /// Bit 0: M7 seen, bit 1: M8 seen, bit 2: M9 seen.
    pub coolant: u8,
    /// Value words by letter (A=0 .. Z=25); `present` says which are set.
    pub val: [f32; 26],
    pub col: [u16; 26],
    pub present: u32,
    /// `(MSG, …)` text, and M117's text.
    pub msg: Option<(&'a [u8], u16)>,
    pub text: Option<&'a [u8]>,
    /// Column of the first word, for faults of the block as a whole.
    pub first_col: u16,
    /// Column of the first axis letter given without a number, if any.
    pub bare_col: u16,
    /// The source line: a tool number past `f32`'s exact integers is read
    /// again from its digits ([`super::exec::Ctx::tool`]).
    pub line: &'a [u8],
}

/// Letters that carry values: the axes and F H I J K L P Q R S T.
const VALUE_LETTERS: u32 = AXIS_BITS
    | bit(b'H')
    | bit(b'F')
    | bit(b'I')
    | bit(b'J')
    | bit(b'K')
    | bit(b'L')
    | bit(b'P')
    | bit(b'Q')
    | bit(b'R')
    | bit(b'S')
    | bit(b'T')
    | bit(b'D');

pub(crate) const fn bit(letter: u8) -> u32 {
    1u32 << (letter.wrapping_sub(b'A') % 26)
}

impl<'a> Block<'a> {
    pub fn is_empty(&self) -> bool {
        self.present == 0 && self.gmask == 0 && self.mmask == 0 && self.msg.is_none()
    }

    pub fn has(&self, letter: u8) -> bool {
        self.present & bit(letter) != 0
    }

    pub fn get(&self, letter: u8) -> Option<f32> {
        if self.has(letter) {
            self.val
                .get(usize::from(letter.wrapping_sub(b'A')))
                .copied()
        } else {
            None
        }
    }

    pub fn col_of(&self, letter: u8) -> u16 {
        self.col
            .get(usize::from(letter.wrapping_sub(b'A')))
            .copied()
            .unwrap_or(0)
    }

    /// The axis words present, bit `i` for axis `i`. X Y Z are letters
    /// 23-25 of `present` and A B C letters 0-2, so two shifts and masks
    /// do it (the size-optimised build keeps a loop over the letters, and
    /// this runs several times a line).
    pub fn axis_mask(&self) -> u8 {
        const _: () = assert!(AXES >= 3 && AXES <= 6);
        let p = self.present;
        let xyz = (p >> (b'X' - b'A')) & 0b111;
        let rest = p & ((1 << (AXES - 3)) - 1);
        (xyz | rest << 3) as u8
    }

    /// The first axis letter (in array order) among `letters` that the
    /// block holds.
    pub fn first_axis_of(&self, letters: u32) -> Option<u8> {
        // X Y Z (letters 23-25) come first in array order, then A B C.
        let m = self.present & letters & AXIS_BITS;
        let xyz = m & !((1 << (b'X' - b'A')) - 1);
        let pick = if xyz != 0 { xyz } else { m };
        (pick != 0).then(|| b'A' + pick.trailing_zeros() as u8)
    }

    pub fn g_of(&self, grp: GGroup) -> Option<(u16, u16)> {
        self.g.get(grp as usize).copied().flatten()
    }

    pub fn m_of(&self, grp: MGroup) -> Option<(u16, u16)> {
        self.m.get(grp as usize).copied().flatten()
    }

    fn note_col(&mut self, col: u16) {
        if self.first_col == 0 {
            self.first_col = col;
        }
    }

    /// Whether `w` starts the next command on the line (BeagleG reads a
    /// line left to right): any G word once this block's command has its
    /// axis words (`G0 X10 G91 G0 X5` is two blocks, so G91 never reaches
    /// X10), and a motion word after G27/G28/G30 (`G28 G1 X100`: home,
    /// then move). M and value words never split: RS274NGC's order (spindle
    /// and coolant before motion) keeps holding for them.
    pub fn splits_on(&self, w: &Word) -> bool {
        if w.letter != b'G' {
            return false;
        }
        let grp = w.tenths().and_then(g_group);
        // `G0 X1 G80`: LinuxCNC lets G80 share the block with the motion
        // it follows, which wins; no second command.
        let g80_beside_motion = w.tenths() == Some(800) && self.g_of(GGroup::Motion).is_some();
        grp.is_some() && self.axis_mask() != 0 && !g80_beside_motion
            || grp == Some(GGroup::Motion)
                && w.tenths() != Some(800)
                && matches!(self.g_of(GGroup::NonModal), Some((270 | 280 | 300, _)))
    }

    /// A block that would only set modes (G20, G91, F, G80, ...): after a
    /// split it is ambiguous, since RS274NGC would apply those words to the
    /// earlier command and BeagleG only to later lines.
    pub fn is_mode_only(&self) -> bool {
        let axes_ijk = self.axis_mask() != 0
            || self.present & (bit(b'I') | bit(b'J') | bit(b'K') | bit(b'R')) != 0;
        !axes_ijk
            && self.mmask == 0
            && self.msg.is_none()
            && self.g_of(GGroup::NonModal).is_none()
            && matches!(self.g_of(GGroup::Motion), None | Some((800, _)))
    }

    /// Adds a word; [`Block::splits_on`] must have been asked first.
    #[inline(always)]
    pub fn add(&mut self, w: &Word) -> Result<(), GcodeError> {
        let err = |k| Err(GcodeError::new(k, w.col));
        match w.letter {
            b'G' => {
                let Some(t) = w.tenths() else {
                    return err(ErrorKind::NotInteger(b'G'));
                };
                let Some(grp) = g_group(t) else {
                    return err(ErrorKind::Unsupported(Unsupported::Code {
                        letter: b'G',
                        tenths: t,
                    }));
                };
                let slot = self
                    .g
                    .get_mut(grp as usize)
                    .ok_or(GcodeError::new(ErrorKind::ModalGroupViolation, w.col))?;
                match *slot {
                    // LinuxCNC lets G80 share a block with another motion code
                    // (CAM preambles write `G0 ... G80`); the other one wins.
                    Some((800, _)) if grp == GGroup::Motion => *slot = Some((t, w.col)),
                    Some(_) if grp == GGroup::Motion && t == 800 => {}
                    Some(_) => return err(ErrorKind::ModalGroupViolation),
                    None => *slot = Some((t, w.col)),
                }
                self.gmask |= 1 << grp as u16;
            }
            b'M' => {
                let t = match w.tenths().map(|t| (t, t % 10)) {
                    Some((t, 0)) => t / 10,
                    Some((t, _)) => {
                        return err(ErrorKind::Unsupported(Unsupported::Code {
                            letter: b'M',
                            tenths: t,
                        }))
                    }
                    None => return err(ErrorKind::NotInteger(b'M')),
                };
                let Some(grp) = m_group(t) else {
                    return err(ErrorKind::Unsupported(Unsupported::Code {
                        letter: b'M',
                        tenths: t * 10,
                    }));
                };
                let slot = self
                    .m
                    .get_mut(grp as usize)
                    .ok_or(GcodeError::new(ErrorKind::ModalGroupViolation, w.col))?;
                // One M code per group and line, as in LinuxCNC: `M7 M8`
                // is refused (write them on two lines for both coolants).
                if slot.is_some() {
                    return err(ErrorKind::ModalGroupViolation);
                }
                if grp == MGroup::Coolant {
                    self.coolant = match t {
                        7 => 1,
                        8 => 2,
                        _ => 4,
                    };
                }
                *slot = Some((t, w.col));
                self.mmask |= 1 << grp as u8;
            }
            l if l.is_ascii_uppercase() && VALUE_LETTERS & bit(l) != 0 => {
                let b = bit(l);
                if self.present & b != 0 {
                    return err(ErrorKind::RepeatedWord(l));
                }
                let i = usize::from(l.wrapping_sub(b'A') % 26);
                if let (Some(v), Some(c)) = (self.val.get_mut(i), self.col.get_mut(i)) {
                    *v = w.value;
                    *c = w.col;
                }
                self.present |= b;
                if w.bare && self.bare_col == 0 {
                    self.bare_col = w.col;
                }
            }
            l => return err(ErrorKind::Unsupported(Unsupported::Letter(l))),
        }
        self.note_col(w.col);
        Ok(())
    }
}
