//! The one error type of the G-code language half of the core.
//!
//! Every kind has a stable number ([`ErrorKind::code`]) that check mode and
//! the native protocol print, and the nearest GRBL 1.1 error number
//! ([`ErrorKind::grbl_code`]) for the `error:N` text protocol, because
//! senders (UGS, CNCjs, bCNC) show GRBL's own text for that number.
//!
//! Stable code table (never renumber; add new kinds at the end of a range):
//!
//! | range | what |
//! |---|---|
//! | 100–119 | lexing: line length, characters, numbers, comments, checksum, N |
//! | 200–219 | parameters and expressions |
//! | 300–309 | words that are recognised but not supported (named) |
//! | 310–339 | block semantics: modal groups, missing/unused words, arcs, tools |
//! | 340–359 | dialect rules: several commands on a line, BeagleG's M list |
//! | 360–379 | O-words: subroutines and flow control (`crate::flow`) |
//! | 380–399 | cutter radius compensation (`crate::comp`) |

use core::fmt;

/// A feature we know by name and refuse on purpose, so that the operator
/// reads what is missing instead of "bad word".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unsupported {
    /// A G or M code: letter plus the number in tenths (G59.1 is 591).
    Code { letter: u8, tenths: u16 },
    /// A word letter with no meaning here (E, B, C, U, V, W, D, H, ...).
    Letter(u8),
    /// An `O` word the flow stage did not take (not first on its line,
    /// or the interpreter used alone).
    OWord,
    /// A keyword such as `WHILE` or `IF` outside an expression.
    ControlFlow,
    /// LinuxCNC's `#<_hal[…]>` / `#<_ini[…]>` system parameters.
    SystemParam,
}

/// Why an O-word line (or a line inside its block) was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OWord {
    /// Not `O<number or <name>> keyword [args]`, or words after it.
    Syntax,
    /// A closer, `else` or `elseif` without its opening line.
    Unmatched,
    /// The block does not fit the capture buffer: none of it runs.
    TooLarge,
    /// Calls or loops nested deeper than the flow stage holds.
    TooDeep,
    /// `call` of a subroutine not defined (or no longer held).
    UndefinedSub,
    /// A line inside a refused block: it is not run.
    InRefusedBlock,
    /// `break`/`continue` outside a loop, `return`/`endsub` outside a call.
    Outside,
    /// `sub` inside another block.
    NestedSub,
    /// A block inside a replayed body has no end.
    Unclosed,
}

/// What went wrong. The column of the fault travels in [`GcodeError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    // --- lexing (100..) ---
    /// The line has more than [`crate::gcode::MAX_LINE`] bytes.
    LineTooLong,
    /// A character that cannot start a word.
    ExpectedLetter(u8),
    /// A word letter without a valid number after it.
    BadNumber,
    /// `(` without `)`.
    UnclosedComment,
    /// `(` inside a comment.
    NestedComment,
    /// RepRap `*nn` checksum does not match the XOR of the bytes before it.
    ChecksumMismatch {
        expected: u8,
        computed: u8,
    },
    /// `*` not followed by a 0-255 number at the end of the line.
    BadChecksum,
    /// `N` after other words.
    LineNumberMisplaced,
    /// `N` value negative, fractional or above 99999999.
    InvalidLineNumber,
    /// A byte that is not ASCII.
    NonAscii,
    // --- parameters and expressions (200..) ---
    UnbalancedBrackets,
    DivisionByZero,
    /// ACOS/ASIN outside [-1, 1], SQRT/LN of a negative, negative ** fraction.
    DomainError,
    UnknownOperation,
    /// Brackets nested deeper than the evaluator's fixed stack allows.
    ExpressionTooDeep,
    /// Parameter number outside 1..=5399 (or 0 for reading).
    ParamOutOfRange,
    /// Assignment to `#0` or a computed parameter such as #5420.
    ParamReadOnly,
    /// A named parameter read before it was set.
    UndefinedParam,
    /// No room for another numbered or named parameter.
    ParamTableFull,
    ParamNameTooLong,
    /// More parameter assignments in one line than the undo log holds.
    TooManyAssignments,
    /// A value overflowed to infinity or became NaN.
    NotFinite,
    // --- unsupported (300..) ---
    Unsupported(Unsupported),
    // --- block semantics (310..) ---
    /// Two words of one modal group in one command.
    ModalGroupViolation,
    /// A feed move without a feed rate (or G93 without F on the line).
    UndefinedFeed,
    /// A value that must be an integer is not (G/M numbers, P counts, T).
    NotInteger(u8),
    /// Two commands in one block both want the axis words.
    AxisCommandConflict,
    RepeatedWord(u8),
    /// The command needs at least one axis word.
    NoAxisWords,
    InvalidLineNumberRange,
    /// A word the command requires is missing.
    ValueWordMissing(u8),
    /// G53 with a motion other than G0/G1, or in G91.
    G53Invalid,
    /// Axis words with nothing to use them (G80 active).
    AxisWordsUnused,
    /// Target equals start where that is meaningless (probe, R full circle).
    InvalidTarget,
    /// Arc radius mismatch or R too small for the chord.
    ArcRadius,
    /// G2/G3 centre format without an offset in the arc plane.
    NoOffsetsInPlane,
    /// A word that no command in the block uses.
    UnusedWord(u8),
    /// A value outside its allowed range (negative dwell, pin number, ...).
    ValueOutOfRange(u8),
    /// G5/G5.1 outside G17, or with axes other than X/Y.
    SplinePlane,
    /// More commands on one line than the line buffer holds.
    TooManyCommands,
    /// A word that only the first command of a line may carry.
    WordAfterSplit(u8),
    /// G10 L2/L20, G28.1, G30.1 or M500 with the spindle or coolant on: a
    /// flash write stalls the CPU (and the e-stop handler) for up to 0.8 s.
    FlashWriteOutputsOn,
    // --- dialect rules (340..) ---
    /// Mode words (G20, G91, F, ...) after the last command of a line that
    /// holds several: RS274NGC would apply them to that command, BeagleG
    /// only to the lines after, so the line is refused.
    AmbiguousOrder,
    /// M104/M105/M109/M116: a 3D printer's heater commands.
    NoHeaters,
    /// An arc offset (I/J/K) off the active plane: `I` in G19, `J` in G18, `K` in G17.
    ArcWordOffPlane(u8),
    /// G86/G88 with the spindle stopped (LinuxCNC refuses them too).
    SpindleStopped,
    // --- tools and arcs, issue 30 (329..) ---
    /// G2/G3 with both R and I/J/K (LinuxCNC: "mixed radius ijk format").
    MixedArcFormat,
    /// T, M6, M61, G43 H or G43.2 H names a tool the table does not hold
    /// (LinuxCNC refuses the line: an unknown tool has no known length).
    ToolNotInTable,
    /// G10 L1 with no value to write (LinuxCNC: "has no effect").
    NoToolValues,
    /// G43.2 with both H and axis words.
    MixedToolOffset,
    // --- O-words (360..) ---
    OWord(OWord),
    // --- cutter radius compensation (380..) ---
    /// The entry move (or entry arc) is not longer than the tool radius.
    CompEntryTooShort,
    /// The tool does not fit inside an arc it cuts from the inside.
    CompToolTooBig,
    /// An inside corner the compensated tool cannot reach without cutting
    /// into the part (a move or arc would run backwards).
    CompGouge,
    /// The move right after G40 must be straight.
    CompArcAfterG40,
    /// More commands wait behind a held compensated move than fit.
    CompQueueFull,
    /// Compensation in G19, an arc outside its plane, or `L` outside G18.
    CompPlane,
    /// G41/G42 while compensation is already on.
    CompAlreadyOn,
    /// Something compensation cannot carry on through (tool change, canned
    /// cycle, G28/G30, probe, G53, G92, a coordinate system or tool offset
    /// change, a plane change, a spline): the letter and number in tenths.
    CompForbidden {
        letter: u8,
        tenths: u16,
    },
}

impl ErrorKind {
    /// Stable number for check mode and the native protocol.
    pub const fn code(&self) -> u16 {
        use ErrorKind::*;
        match self {
            LineTooLong => 100,
            ExpectedLetter(_) => 101,
            BadNumber => 102,
            UnclosedComment => 103,
            NestedComment => 104,
            ChecksumMismatch { .. } => 105,
            BadChecksum => 106,
            LineNumberMisplaced => 107,
            InvalidLineNumber => 108,
            NonAscii => 109,
            UnbalancedBrackets => 200,
            DivisionByZero => 201,
            DomainError => 202,
            UnknownOperation => 203,
            ExpressionTooDeep => 204,
            ParamOutOfRange => 205,
            ParamReadOnly => 206,
            UndefinedParam => 207,
            ParamTableFull => 208,
            ParamNameTooLong => 209,
            TooManyAssignments => 210,
            NotFinite => 211,
            Unsupported(self::Unsupported::Code { .. }) => 300,
            Unsupported(self::Unsupported::Letter(_)) => 301,
            Unsupported(self::Unsupported::OWord) => 302,
            Unsupported(self::Unsupported::ControlFlow) => 303,
            Unsupported(self::Unsupported::SystemParam) => 304,
            ModalGroupViolation => 310,
            UndefinedFeed => 311,
            NotInteger(_) => 312,
            AxisCommandConflict => 313,
            RepeatedWord(_) => 314,
            NoAxisWords => 315,
            InvalidLineNumberRange => 316,
            ValueWordMissing(_) => 317,
            G53Invalid => 318,
            AxisWordsUnused => 319,
            InvalidTarget => 320,
            ArcRadius => 321,
            NoOffsetsInPlane => 322,
            UnusedWord(_) => 323,
            ValueOutOfRange(_) => 324,
            SplinePlane => 325,
            TooManyCommands => 326,
            WordAfterSplit(_) => 327,
            FlashWriteOutputsOn => 328,
            AmbiguousOrder => 340,
            NoHeaters => 341,
            ArcWordOffPlane(_) => 342,
            SpindleStopped => 343,
            MixedArcFormat => 329,
            ToolNotInTable => 330,
            NoToolValues => 331,
            MixedToolOffset => 332,
            OWord(self::OWord::Syntax) => 360,
            OWord(self::OWord::Unmatched) => 361,
            OWord(self::OWord::TooLarge) => 362,
            OWord(self::OWord::TooDeep) => 363,
            OWord(self::OWord::UndefinedSub) => 364,
            OWord(self::OWord::InRefusedBlock) => 365,
            OWord(self::OWord::Outside) => 366,
            OWord(self::OWord::NestedSub) => 367,
            OWord(self::OWord::Unclosed) => 368,
            CompEntryTooShort => 380,
            CompToolTooBig => 381,
            CompGouge => 382,
            CompArcAfterG40 => 383,
            CompQueueFull => 384,
            CompPlane => 385,
            CompAlreadyOn => 386,
            CompForbidden { .. } => 387,
        }
    }

    /// GRBL 1.1 `error:N` number; kinds GRBL lacks map to its nearest meaning
    /// (syntax faults to 1/2, parameter faults to 2, ranges to 4 or 38).
    pub const fn grbl_code(&self) -> u8 {
        use ErrorKind::*;
        match self {
            LineTooLong => 11,
            ExpectedLetter(_) | NonAscii | UnclosedComment | NestedComment => 1,
            BadNumber | BadChecksum | ChecksumMismatch { .. } => 2,
            UnbalancedBrackets | DivisionByZero | DomainError | UnknownOperation
            | ExpressionTooDeep | NotFinite => 2,
            ParamOutOfRange | ParamReadOnly | UndefinedParam | ParamTableFull
            | ParamNameTooLong | TooManyAssignments => 2,
            LineNumberMisplaced | InvalidLineNumber | InvalidLineNumberRange => 27,
            Unsupported(_) => 20,
            ModalGroupViolation => 21,
            UndefinedFeed => 22,
            NotInteger(_) => 23,
            AxisCommandConflict | WordAfterSplit(_) | AmbiguousOrder => 24,
            NoHeaters => 20,
            ArcWordOffPlane(_) => 36,
            RepeatedWord(_) => 25,
            NoAxisWords => 26,
            ValueWordMissing(_) => 28,
            G53Invalid => 30,
            AxisWordsUnused => 31,
            InvalidTarget => 33,
            ArcRadius => 34,
            NoOffsetsInPlane => 35,
            SpindleStopped | OWord(_) => 20,
            MixedArcFormat => 34,
            ToolNotInTable | NoToolValues => 4,
            MixedToolOffset => 24,
            CompEntryTooShort | CompToolTooBig | CompGouge => 33,
            CompArcAfterG40 | CompAlreadyOn | CompForbidden { .. } => 20,
            CompQueueFull => 11,
            CompPlane => 20,
            UnusedWord(_) | SplinePlane => 36,
            ValueOutOfRange(_) => 4,
            TooManyCommands => 11,
            FlashWriteOutputsOn => 8,
        }
    }

    /// True for the faults that name a feature we refuse on purpose
    /// (the corpus conformance test accepts exactly these).
    pub const fn is_unsupported(&self) -> bool {
        matches!(self, ErrorKind::Unsupported(_))
    }
}

/// An error with the 1-based byte column in the line where the fault is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GcodeError {
    pub kind: ErrorKind,
    /// 1-based byte offset of the offending word or character (0: whole line).
    pub col: u16,
}

impl GcodeError {
    pub const fn new(kind: ErrorKind, col: u16) -> Self {
        GcodeError { kind, col }
    }
    pub const fn code(&self) -> u16 {
        self.kind.code()
    }
    pub const fn grbl_code(&self) -> u8 {
        self.kind.grbl_code()
    }
}

fn letter(c: u8) -> char {
    c.to_ascii_uppercase() as char
}

/// Writes `G59.1` / `M3` from a letter and a number in tenths.
pub(crate) fn write_code(f: &mut dyn fmt::Write, l: u8, tenths: u16) -> fmt::Result {
    match tenths % 10 {
        0 => write!(f, "{}{}", letter(l), tenths / 10),
        d => write!(f, "{}{}.{}", letter(l), tenths / 10, d),
    }
}

fn family(l: u8, tenths: u16) -> &'static str {
    match (l, tenths) {
        (b'G', 410 | 411 | 420 | 421) => " (cutter radius compensation)",
        (b'G', 430..=439) => " (tool length offset)",
        (b'G', 730 | 760 | 810..=899) => " (canned cycle)",
        (b'G', 330..=339) => " (spindle-synchronised motion)",
        (b'G', 520..=529) => " (NURBS spline)",
        (b'G', 100 | 110) => " (tool table)",
        (b'M', 60) => " (tool change)",
        (b'G', 70) => " (lathe diameter mode)",
        _ => "",
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use ErrorKind::*;
        match *self {
            LineTooLong => write!(f, "line longer than {} bytes", super::MAX_LINE),
            ExpectedLetter(c) if c.is_ascii_graphic() => {
                write!(f, "expected a word letter, found '{}'", c as char)
            }
            ExpectedLetter(c) => write!(f, "expected a word letter, found byte 0x{c:02x}"),
            BadNumber => f.write_str("bad number format"),
            UnclosedComment => f.write_str("comment not closed with ')'"),
            NestedComment => f.write_str("'(' inside a comment"),
            ChecksumMismatch { expected, computed } => {
                write!(
                    f,
                    "checksum mismatch: line says {expected}, bytes give {computed}"
                )
            }
            BadChecksum => f.write_str("'*' checksum must be 0-255 at the end of the line"),
            LineNumberMisplaced => f.write_str("N word must come first on the line"),
            InvalidLineNumber | InvalidLineNumberRange => {
                f.write_str("line number must be an integer 0-99999999")
            }
            NonAscii => f.write_str("non-ASCII byte outside a comment"),
            UnbalancedBrackets => f.write_str("unbalanced '[' ']' in expression"),
            DivisionByZero => f.write_str("division by zero"),
            DomainError => f.write_str("argument outside the function's domain"),
            UnknownOperation => f.write_str("unknown operation in expression"),
            ExpressionTooDeep => f.write_str("expression nested too deeply"),
            ParamOutOfRange => f.write_str("parameter number outside 1-5399 (5400-5410 read-only)"),
            ParamReadOnly => f.write_str("parameter is read-only"),
            UndefinedParam => f.write_str("named parameter used before it was set"),
            ParamTableFull => f.write_str("parameter table full"),
            ParamNameTooLong => f.write_str("parameter name too long"),
            TooManyAssignments => f.write_str("too many parameter assignments on one line"),
            NotFinite => f.write_str("value is not a finite number"),
            Unsupported(self::Unsupported::Code { letter: l, tenths }) => {
                f.write_str("unsupported command ")?;
                write_code(f, l, tenths)?;
                f.write_str(family(l, tenths))
            }
            Unsupported(self::Unsupported::Letter(b'E')) => {
                f.write_str("unsupported word E (extruder axis)")
            }
            Unsupported(self::Unsupported::Letter(c)) => {
                write!(f, "unsupported word {}", letter(c))
            }
            Unsupported(self::Unsupported::OWord) => {
                // The flow stage (`crate::flow`) takes O-word lines; one
                // reaches the interpreter only when the O is not first.
                f.write_str("O-word not at the start of its line (or no flow stage)")
            }
            Unsupported(self::Unsupported::ControlFlow) => {
                f.write_str("unsupported control flow (keyword or compound assignment)")
            }
            Unsupported(self::Unsupported::SystemParam) => {
                f.write_str("unsupported LinuxCNC system parameter (#<_hal[..]>, #<_ini[..]>)")
            }
            ModalGroupViolation => f.write_str("two words of one modal group in one command"),
            UndefinedFeed => f.write_str("feed rate undefined"),
            NotInteger(c) => write!(f, "{} value must be an integer", letter(c)),
            AxisCommandConflict => f.write_str("two commands in the block use the axis words"),
            RepeatedWord(c) => write!(f, "word {} repeated", letter(c)),
            NoAxisWords => f.write_str("command needs axis words"),
            ValueWordMissing(c) => write!(f, "{} word missing", letter(c)),
            G53Invalid => f.write_str("G53 needs G0 or G1 in absolute mode"),
            AxisWordsUnused => f.write_str("axis words with no command to use them"),
            InvalidTarget => f.write_str("invalid target for this command"),
            ArcRadius => f.write_str("arc radius error"),
            NoOffsetsInPlane => f.write_str("arc centre offsets missing in the active plane"),
            UnusedWord(c) => write!(f, "word {} not used by any command", letter(c)),
            ValueOutOfRange(c) => write!(f, "{} value out of range", letter(c)),
            SplinePlane => f.write_str("G5/G5.1 need G17 and only X/Y axis words"),
            TooManyCommands => f.write_str("too many commands on one line"),
            WordAfterSplit(c) => write!(f, "word {} after a second command on the line", letter(c)),
            FlashWriteOutputsOn => {
                f.write_str("no flash write with spindle or coolant on (M5 M9 first)")
            }
            AmbiguousOrder => f.write_str(
                "mode words after the last command of a line with several commands are ambiguous: move them before a command or to their own line",
            ),
            NoHeaters => f.write_str("this controller has no heaters (M104/M105/M109/M116)"),
            ArcWordOffPlane(c) => write!(f, "arc offset {} is not in the active plane", letter(c)),
            SpindleStopped => f.write_str("G86/G88 need the spindle turning"),
            MixedArcFormat => f.write_str("arc with both R and I/J/K"),
            ToolNotInTable => f.write_str("tool not in the tool table (G10 L1 P<tool> first)"),
            NoToolValues => f.write_str("G10 L1 without offsets has no effect"),
            MixedToolOffset => f.write_str("G43.2 with both H and axis words"),
            OWord(k) => f.write_str(match k {
                self::OWord::Syntax => "bad O-word line (O<number> or O<name>, a keyword, [args])",
                self::OWord::Unmatched => "O-word closer, else or elseif without its opening line",
                self::OWord::TooLarge => {
                    "O-word block too large for the capture buffer: refused, none of it runs"
                }
                self::OWord::TooDeep => "O-word calls or loops nested too deeply",
                self::OWord::UndefinedSub => "call of a subroutine that is not defined",
                self::OWord::InRefusedBlock => "line inside a refused O-word block: not run",
                self::OWord::Outside => {
                    "break/continue outside a loop, or return/endsub outside a call"
                }
                self::OWord::NestedSub => "sub defined inside another O-word block",
                self::OWord::Unclosed => "O-word block without its end",
            }),
            CompEntryTooShort => f.write_str(
                "cutter compensation entry move is not longer than the tool radius",
            ),
            CompToolTooBig => f.write_str("tool radius not less than the arc radius it cuts inside"),
            CompGouge => f.write_str(
                "inside corner the compensated tool cannot reach without gouging",
            ),
            CompArcAfterG40 => f.write_str("the move after G40 must be straight, not an arc"),
            CompQueueFull => f.write_str(
                "too many commands between two compensated moves",
            ),
            CompPlane => f.write_str("cutter compensation only in G17 or G18 (L only in G18)"),
            CompAlreadyOn => f.write_str("cutter compensation is already on (G40 first)"),
            CompForbidden { letter: l, tenths } => {
                f.write_str("cannot use ")?;
                write_code(f, l, tenths)?;
                f.write_str(" with cutter compensation on (G40 first)")
            }
        }
    }
}

impl fmt::Display for GcodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.kind, f)
    }
}
