//! The person at the machine: the progress bar with a key help under it,
//! lines printed above it, and keys read in raw mode (crossterm). Without
//! a terminal there are no keys and no bar: lines go plainly to stderr.

use crossterm::event::{self, Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver};

/// What a key asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// `!`: feed hold.
    Hold,
    /// `~`, Enter: cycle start.
    Resume,
    /// Space: hold when running, resume when held.
    Toggle,
    /// `x`, Ctrl-X: soft reset (asks first).
    Reset,
    FeedUp,
    FeedDown,
    Feed100,
    /// `s`, `?`: one detailed status line.
    Status,
    /// Ctrl-C: hold and ask what to do.
    Interrupt,
    /// Anything else (answers to a question).
    Other(char),
}

/// The key help under the bar (fits 80 columns).
pub const HELP: &str =
    "space/! hold  ~/Enter resume  +/- feed ±10%  0 100%  s status  x reset  ^C menu";

/// Ctrl-C without a terminal (a signal; in raw mode it is a key).
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

pub struct Ui {
    pub bar: ProgressBar,
    keys: Option<Receiver<Key>>,
    raw: bool,
}

impl Ui {
    /// `interactive`: keys and a bar (stdin and stderr are terminals).
    pub fn new(total: usize, interactive: bool) -> Ui {
        let bar = if interactive {
            let b = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template(&format!(
                "{{bar:30}} line {{pos}}/{{len}} {{percent:>3}}% {{prefix}} | {{msg}}\n{HELP}"
            )) {
                b.set_style(style);
            }
            b
        } else {
            ProgressBar::hidden()
        };
        let mut ui = Ui {
            bar,
            keys: None,
            raw: false,
        };
        // Signals stay on for the first job of a process only: ctrlc
        // installs one handler per process.
        let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
        if interactive && crossterm::terminal::enable_raw_mode().is_ok() {
            ui.raw = true;
            keep_output_processing();
            let (tx, rx) = channel();
            std::thread::spawn(move || loop {
                match event::read() {
                    Ok(Event::Key(k)) => {
                        if let Some(key) = map_key(k) {
                            if tx.send(key).is_err() {
                                return;
                            }
                        }
                    }
                    Ok(_) => {}
                    Err(_) => return,
                }
            });
            ui.keys = Some(rx);
        }
        ui
    }

    pub fn interactive(&self) -> bool {
        self.keys.is_some()
    }

    /// A line above the bar.
    pub fn say(&self, line: impl AsRef<str>) {
        if self.bar.is_hidden() {
            eprintln!("{}", line.as_ref());
        } else {
            self.bar.println(line.as_ref());
        }
    }

    /// The next key pressed, if any (Ctrl-C as a signal counts too).
    pub fn key(&self) -> Option<Key> {
        if INTERRUPTED.swap(false, Ordering::SeqCst) {
            return Some(Key::Interrupt);
        }
        self.keys.as_ref()?.try_recv().ok()
    }
}

impl Drop for Ui {
    fn drop(&mut self) {
        if self.raw {
            let _ = crossterm::terminal::disable_raw_mode();
        }
    }
}

/// Raw mode turns off output processing too; put `\n` -> `\r\n` back so
/// the bar and the lines above it print as usual.
fn keep_output_processing() {
    use nix::sys::termios::{tcgetattr, tcsetattr, OutputFlags, SetArg};
    let out = std::io::stderr();
    if !out.is_terminal() {
        return;
    }
    if let Ok(mut t) = tcgetattr(&out) {
        t.output_flags |= OutputFlags::OPOST | OutputFlags::ONLCR;
        let _ = tcsetattr(&out, SetArg::TCSANOW, &t);
    }
}

fn map_key(k: KeyEvent) -> Option<Key> {
    if k.kind == KeyEventKind::Release {
        return None;
    }
    let ctrl = k.modifiers.contains(KeyModifiers::CONTROL);
    Some(match k.code {
        KeyCode::Char('c') if ctrl => Key::Interrupt,
        KeyCode::Char('x') if ctrl => Key::Reset,
        KeyCode::Char(' ') => Key::Toggle,
        KeyCode::Char('!') => Key::Hold,
        KeyCode::Char('~') | KeyCode::Enter => Key::Resume,
        KeyCode::Char('x') => Key::Reset,
        KeyCode::Char('+') | KeyCode::Char('=') => Key::FeedUp,
        KeyCode::Char('-') => Key::FeedDown,
        KeyCode::Char('0') => Key::Feed100,
        KeyCode::Char('s') | KeyCode::Char('?') => Key::Status,
        KeyCode::Char(c) => Key::Other(c),
        _ => return None,
    })
}
