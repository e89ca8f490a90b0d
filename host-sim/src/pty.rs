//! `cargo xtask sim --pty`: the virtual device on a pseudo-terminal, so
//! outside programs (our streamer, GRBL senders, a terminal) connect to it
//! like to the board's USB-CDC port.
//!
//! Contract: the slave path (`/dev/pts/N`) is the first line on stdout;
//! then the device runs until killed, paced to the wall clock (`speed` 1)
//! or `speed` times faster.
//!
//! Connecting and disconnecting: the simulator keeps only the master side
//! open, so the kernel reports a hangup whenever no client has the slave
//! open. On a hangup the device still takes what the client wrote before
//! it left (a last soft reset, its `Bye`), then both directions are
//! flushed (the next client must not receive stale replies glued to its
//! first frame) and the link resets to text mode, as DTR dropping or a USB
//! reset does on the board. What happens to a running job is the device
//! session's rule (`burin::session::Device::port_reset`): a framed job is
//! held and the next client is told; a text-mode job keeps running, as
//! GRBL does when its sender goes away.
//!
//! When a client connects the device prints the `Grbl` banner at once,
//! before it reads anything the client wrote (an Arduino GRBL resets when
//! the port opens; a sender that writes at once never sees an `ok` before
//! the banner). A framed client's 0x00 makes the device send a 0x00 too,
//! so the banner ends as one frame the client ignores before its
//! `Welcome`. `BURIN_PTY_DEBUG=1` logs connections and received bytes to
//! stderr; `BURIN_PTY_TRACE=FILE` records every call into the device
//! (bytes taken, virtual times, hangups) so that [`replay`] runs the same
//! session again, tick for tick, without the wall clock.

use std::fs::File;
use std::io::{self, ErrorKind, Read, Write};
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
use nix::sys::termios::{cfmakeraw, tcflush, tcgetattr, tcsetattr, FlushArg, SetArg};

use crate::config::MachineConfig;
use crate::device_sim::VirtualDevice;
use crate::record::Discard;

/// Virtual time one device pass may cover: the parse/plan task runs at
/// least this often in virtual time, so the planner never starves because
/// of the pacing.
const CHUNK_S: f64 = 0.002;

/// A pseudo-terminal's master side.
pub struct Pty {
    master: File,
    path: String,
}

impl Pty {
    /// Open a pty in raw mode; the slave is closed again (clients open it).
    pub fn open() -> io::Result<Pty> {
        let p = nix::pty::openpty(None, None).map_err(io::Error::from)?;
        let mut t = tcgetattr(p.slave.as_fd()).map_err(io::Error::from)?;
        cfmakeraw(&mut t);
        tcsetattr(p.slave.as_fd(), SetArg::TCSANOW, &t).map_err(io::Error::from)?;
        let path = nix::unistd::ttyname(p.slave.as_fd())
            .map_err(io::Error::from)?
            .display()
            .to_string();
        let flags = fcntl(p.master.as_fd(), FcntlArg::F_GETFL).map_err(io::Error::from)?;
        let flags = OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK;
        fcntl(p.master.as_fd(), FcntlArg::F_SETFL(flags)).map_err(io::Error::from)?;
        drop(p.slave);
        Ok(Pty {
            master: File::from(p.master),
            path,
        })
    }

    /// The device path clients open.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Forget bytes in flight both ways: the departed client's unread input
    /// (its `Bye`, say) and replies it never read, which the next client
    /// would otherwise receive glued to the front of its first frame. The
    /// latter sit in the slave's queue, so the slave is opened for a moment.
    fn flush_stale(&self) {
        use std::os::unix::fs::OpenOptionsExt;
        let _ = tcflush(self.master.as_fd(), FlushArg::TCIOFLUSH);
        let slave = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags((OFlag::O_NOCTTY | OFlag::O_NONBLOCK).bits())
            .open(&self.path);
        if let Ok(f) = slave {
            let _ = tcflush(f.as_fd(), FlushArg::TCIOFLUSH);
        }
    }

    /// Wait up to `timeout` for input; `Ok(false)` when no client has the
    /// slave open (hangup).
    fn wait(&self, timeout: Duration) -> io::Result<bool> {
        let ms = u16::try_from(timeout.as_millis()).unwrap_or(u16::MAX);
        let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLIN)];
        match poll(&mut fds, PollTimeout::from(ms)) {
            Ok(_) => {}
            Err(nix::errno::Errno::EINTR) => return Ok(true),
            Err(e) => return Err(e.into()),
        }
        let rev = fds[0].revents().unwrap_or(PollFlags::empty());
        Ok(!rev.contains(PollFlags::POLLHUP))
    }
}

/// Run the virtual device on a new pty until killed. `announce` gets the
/// slave path first thing.
pub fn run(cfg: &MachineConfig, speed: f64, announce: impl FnOnce(&str)) -> io::Result<()> {
    let mut pty = Pty::open()?;
    announce(pty.path());
    let mut rec = Discard;
    let mut dev = VirtualDevice::new(cfg, &mut rec);
    // The power-up banner is for a client that is there; see the module docs.
    let _ = dev.take_output();
    let speed = if speed.is_finite() && speed > 0.0 {
        speed
    } else {
        1.0
    };
    let hz = f64::from(cfg.tick_hz);
    let chunk = ((CHUNK_S * hz) as u64).max(1);
    let mut connected = false;
    let mut closing = false;
    let mut inbox: Vec<u8> = Vec::new();
    let mut outbox: Vec<u8> = Vec::new();
    let mut base = (Instant::now(), dev.sim.now());
    let mut buf = [0u8; 4096];
    let debug = std::env::var_os("BURIN_PTY_DEBUG").is_some();
    let mut trace = Trace::open();
    loop {
        let up = pty.wait(Duration::from_millis(1))?;
        if up != connected {
            connected = up;
            if debug {
                eprintln!("pty: {}", if up { "client connected" } else { "hangup" });
            }
            if up {
                // Replies made while no client had the port (a line the
                // last one left running answers when it completes) are for
                // nobody: a USB host that reopens the port gets none either.
                outbox.clear();
                let _ = dev.take_output();
                // The session hears of the open before anything the client
                // writes is read: a banner (when it resets) comes first.
                dev.port_opened();
                trace.note(format_args!("H"));
            } else {
                // What the client wrote before it left (a last soft reset,
                // its `Bye`) still counts: the device takes what it has
                // room for (realtime bytes act), then the session closes
                // (below) and the rest is void.
                closing = true;
                while let Ok(n @ 1..) = pty.master.read(&mut buf) {
                    inbox.extend_from_slice(&buf[..n]);
                }
            }
        }
        if closing {
            take_now(&mut dev, &mut inbox, &mut trace);
            inbox.clear();
            closing = false;
            // Replies the departed client never read must not reach the next.
            pty.flush_stale();
            dev.port_closed();
            trace.note(format_args!("C"));
            outbox.clear();
        }
        // Virtual time follows the wall clock; while idle it waits.
        if dev.sim.idle() {
            base = (Instant::now(), dev.sim.now());
        }
        let wall = base.0.elapsed().as_secs_f64();
        let target = base.1 + (wall * speed * hz) as u64;
        let limit = dev.sim.now() + chunk * 64;
        let target = target.min(limit);
        loop {
            take(&mut dev, &mut inbox, &mut trace);
            let (before, t) = (dev.sim.now(), (dev.sim.now() + chunk).min(target));
            dev.advance_to(t);
            trace.note(format_args!("A {t}"));
            // Idle or held: no events to run, virtual time stands still.
            if dev.sim.now() >= target || dev.sim.now() == before {
                break;
            }
        }
        if dev.sim.now() >= limit || dev.sim.now() < target {
            // Falling behind the wall clock: do not try to catch up later.
            base = (Instant::now(), dev.sim.now());
        }
        // New input, once virtual time has caught up with the wall clock:
        // a `?` is answered with the state of now, as the board answers,
        // not of the previous pass (a pass is up to a poll interval old).
        // Flow control: read only what the device can take now (its ring
        // and backlog); the rest waits in the kernel and the writer blocks,
        // as the board NAKs. Realtime bytes among what is read act at once.
        let want = dev.room().min(buf.len());
        if connected && inbox.is_empty() && want > 0 {
            match pty.master.read(&mut buf[..want]) {
                Ok(n) => {
                    if debug && n > 0 {
                        eprintln!("pty: rx {:?}", String::from_utf8_lossy(&buf[..n.min(40)]));
                    }
                    inbox.extend_from_slice(&buf[..n])
                }
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => {}
                // EIO: the client closed between poll and read.
                Err(e) => {
                    if debug {
                        eprintln!("pty: read: {e}");
                    }
                }
            }
        }
        if !inbox.is_empty() {
            take_now(&mut dev, &mut inbox, &mut trace);
        }
        outbox.extend(dev.take_output());
        if connected && !closing && !outbox.is_empty() {
            match pty.master.write(&outbox) {
                Ok(n) => {
                    outbox.drain(..n);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {}
                Err(_) => outbox.clear(),
            }
        }
    }
}

/// The device takes what it has room for from `inbox` (realtime bytes act).
fn take(dev: &mut VirtualDevice, inbox: &mut Vec<u8>, trace: &mut Trace) {
    let n = dev.receive(inbox);
    trace.bytes(&inbox[..n]);
    inbox.drain(..n);
}

/// [`take`], then a pass of the task at the current instant, so what was
/// taken is answered before virtual time moves on.
fn take_now(dev: &mut VirtualDevice, inbox: &mut Vec<u8>, trace: &mut Trace) {
    take(dev, inbox, trace);
    dev.advance_to(dev.sim.now());
    trace.note(format_args!("A {}", dev.sim.now()));
}

/// The record `BURIN_PTY_TRACE` asks for: one line per call into the
/// device, `R <hex>` (bytes taken), `A <tick>` (advance to), `H` (banner),
/// `C` (port closed). [`replay`] skips `#` lines (a test's notes). A run of
/// `A` lines may be cut to its first and last: the device is polled at
/// each, but between inputs only the first and last poll matter as long
/// as the run stays deterministic (the replay test checks its outcome).
/// Each line is written at once, so a session killed mid-run keeps its
/// record.
struct Trace(Option<File>);

impl Trace {
    fn open() -> Trace {
        Trace(std::env::var_os("BURIN_PTY_TRACE").and_then(|p| File::create(p).ok()))
    }
    /// Formats nothing unless a trace was asked for: the pacing loop
    /// calls this on every pass.
    fn note(&mut self, line: std::fmt::Arguments) {
        if let Some(w) = self.0.as_mut() {
            let _ = writeln!(w, "{line}");
        }
    }
    fn bytes(&mut self, b: &[u8]) {
        if !b.is_empty() && self.0.is_some() {
            let hex: String = b.iter().map(|x| format!("{x:02x}")).collect();
            self.note(format_args!("R {hex}"));
        }
    }
}

/// Run a session recorded with `BURIN_PTY_TRACE` again on a fresh device;
/// returns it as the recording left it, and everything it sent.
pub fn replay<'r>(
    cfg: &MachineConfig,
    rec: &'r mut Discard,
    trace: &str,
) -> io::Result<(VirtualDevice<'r>, Vec<u8>)> {
    let bad = |l: &str| io::Error::new(ErrorKind::InvalidData, format!("trace line {l:?}"));
    let mut dev = VirtualDevice::new(cfg, rec);
    let _ = dev.take_output();
    let mut out = Vec::new();
    for line in trace
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
    {
        let (op, arg) = line.split_once(' ').unwrap_or((line, ""));
        match op {
            "H" => dev.port_opened(),
            "C" => dev.port_closed(),
            "A" => dev.advance_to(arg.parse().map_err(|_| bad(line))?),
            "R" => {
                let bytes: Vec<u8> = (0..arg.len() / 2)
                    .map(|i| u8::from_str_radix(arg.get(2 * i..2 * i + 2).unwrap_or("zz"), 16))
                    .collect::<Result<_, _>>()
                    .map_err(|_| bad(line))?;
                if dev.receive(&bytes) != bytes.len() {
                    return Err(bad(line));
                }
            }
            _ => return Err(bad(line)),
        }
        out.extend(dev.take_output());
    }
    Ok((dev, out))
}
