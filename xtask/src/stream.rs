//! `cargo xtask stream`: send a job to a board (or to `cargo xtask sim
//! --pty`) over the native protocol, with a progress bar.
//!
//! One file line is one job line, so a device error's sequence number maps
//! straight back to `FILE:LINE`. The board is found by its USB VID/PID
//! through sysfs, not libudev, so the tool needs no system libraries.
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use protocol::client::{Client, ClientEvent};
use protocol::{DeviceMsg, MachineState, Rt};
use std::collections::HashMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct StreamArgs {
    /// G-code job to stream.
    pub file: PathBuf,
    /// Serial port (e.g. /dev/ttyACM0, or the path `cargo xtask sim --pty`
    /// prints). Default: the board with burin's USB VID/PID.
    #[arg(long)]
    pub port: Option<String>,
    /// Run the job in the device's check mode ($C): interpret, no motion.
    #[arg(long)]
    pub check: bool,
}

/// How often the live status is polled.
const STATUS_EVERY: Duration = Duration::from_millis(250);

/// The first tty whose USB device has burin's VID/PID.
fn find_board() -> Result<String> {
    let want = (burin::usb_ids::USB_VID, burin::usb_ids::USB_PID);
    let mut found = Vec::new();
    for e in std::fs::read_dir("/sys/class/tty").context("listing /sys/class/tty")? {
        let e = e?;
        let Ok(dev) = std::fs::canonicalize(e.path().join("device")) else {
            continue;
        };
        let mut dir: Option<&Path> = Some(&dev);
        while let Some(d) = dir {
            let id = |f: &str| {
                std::fs::read_to_string(d.join(f))
                    .ok()
                    .and_then(|s| u16::from_str_radix(s.trim(), 16).ok())
            };
            if let (Some(v), Some(p)) = (id("idVendor"), id("idProduct")) {
                if (v, p) == want {
                    found.push(format!("/dev/{}", e.file_name().to_string_lossy()));
                }
                break;
            }
            dir = d.parent();
        }
    }
    found.sort();
    found.into_iter().next().with_context(|| {
        format!(
            "no board with USB id {:04x}:{:04x} found; give --port",
            want.0, want.1
        )
    })
}

fn status_text(st: &protocol::Status) -> String {
    let w = st.wpos();
    format!(
        "{:<5} X{:.3} Y{:.3} Z{:.3} F{:.0}",
        st.state.name(),
        w[0],
        w[1],
        w[2],
        st.feed
    )
}

pub fn run(a: StreamArgs) -> Result<i32> {
    let name = a.file.display().to_string();
    let source = std::fs::read_to_string(&a.file).with_context(|| format!("reading {name}"))?;
    let lines: Vec<&str> = source.lines().collect();
    let port_name = match a.port {
        Some(p) => p,
        None => find_board()?,
    };
    let port = serialport::new(&port_name, 115_200)
        .timeout(Duration::from_millis(2))
        .open_native()
        .with_context(|| format!("opening {port_name}"))?;
    let mut client = Client::new(port);
    let info = client
        .connect(Duration::from_secs(3))
        .with_context(|| format!("handshake on {port_name}"))?;
    eprintln!(
        "{port_name}: burin {} on {}, {} line slots, {} planner blocks",
        info.firmware, info.board, info.line_slots, info.planner_blocks
    );
    if let Some(st) = query_status(&mut client)? {
        if matches!(st.state, MachineState::Alarm) {
            eprintln!("{port_name}: the machine is in alarm; home ($H) or unlock ($X) it first");
            return Ok(1);
        }
    }
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
            .context("installing the Ctrl-C handler")?;
    }
    let pb = ProgressBar::new(lines.len() as u64);
    if let Ok(style) =
        ProgressStyle::with_template("{bar:30} {pos}/{len} lines {percent:>3}% ETA {eta} | {msg}")
    {
        pb.set_style(style);
    }
    // seq -> 1-based file line.
    let mut seq_line: HashMap<u32, usize> = HashMap::new();
    let check_seq = if a.check {
        Some(send_wait(&mut client, b"$C")?)
    } else {
        None
    };
    let (mut next, mut acked_to) = (0usize, 0usize);
    let (mut errors, mut alarm) = (0u32, false);
    let mut last_msg: Option<String> = None;
    let mut last_poll = Instant::now();
    let mut done_seq: Option<u32> = None;
    let mut finished = false;
    while !finished {
        if interrupted.swap(false, Ordering::SeqCst) {
            client.realtime(Rt::FeedHold)?;
            let answer = pb.suspend(|| {
                eprint!(
                    "\nfeed hold. [c]ontinue, [r]eset (abort the job), [q]uit leaving it held? "
                );
                let mut s = String::new();
                let _ = std::io::stdin().lock().read_line(&mut s);
                s.trim().to_lowercase()
            });
            match answer.as_str() {
                "r" | "reset" => {
                    client.realtime(Rt::SoftReset)?;
                    pb.abandon_with_message("reset: job aborted");
                    return Ok(130);
                }
                "q" | "quit" => {
                    pb.abandon_with_message("left in feed hold");
                    return Ok(130);
                }
                _ => client.realtime(Rt::CycleStart)?,
            }
        }
        while next < lines.len() && client.can_send() {
            let text = lines[next].as_bytes();
            let seq = match client.send_line(text) {
                Ok(s) => s,
                Err(protocol::client::ClientError::LineTooLong) => {
                    say(
                        &pb,
                        format!(
                            "{name}:{}: error: line longer than {} bytes",
                            next + 1,
                            protocol::MAX_LINE
                        ),
                    );
                    errors += 1;
                    client.send_line(b"")?
                }
                Err(e) => return Err(e.into()),
            };
            seq_line.insert(seq, next + 1);
            next += 1;
        }
        if next == lines.len() && client.in_flight() == 0 && done_seq.is_none() {
            // Everything is queued on the device. In check mode, `$C` again
            // leaves it; its "Disabled" message comes after every line's
            // errors. Otherwise wait for the machine to go idle.
            if a.check {
                done_seq = Some(client.send_line(b"$C")?);
            } else {
                done_seq = Some(client.next_seq());
            }
        }
        if last_poll.elapsed() >= STATUS_EVERY {
            last_poll = Instant::now();
            client.realtime(Rt::StatusQuery)?;
        }
        let ev = match client.poll() {
            Ok(ev) => ev,
            Err(e) => {
                pb.abandon();
                bail!("{port_name}: {e}");
            }
        };
        let Some(ev) = ev else { continue };
        match ev {
            ClientEvent::Device(DeviceMsg::Ack { next: n, .. }) => {
                let upto = seq_line
                    .get(&n.wrapping_sub(1))
                    .copied()
                    .unwrap_or(acked_to);
                acked_to = acked_to.max(upto);
                pb.set_position(acked_to as u64);
            }
            ClientEvent::Device(DeviceMsg::Msg(m)) => {
                let m = m.as_str();
                let m = m
                    .strip_prefix("[MSG:")
                    .and_then(|t| t.strip_suffix(']'))
                    .unwrap_or(m);
                if a.check && m == "Disabled" && done_seq.is_some() {
                    finished = true;
                }
                if m != "Enabled" && m != "Disabled" {
                    last_msg = Some(m.to_string());
                }
            }
            ClientEvent::Device(DeviceMsg::Error { seq, code, .. }) => {
                errors += 1;
                let at = match seq.and_then(|s| seq_line.get(&s)) {
                    Some(l) => format!("{name}:{l}"),
                    None if seq.is_some() && seq == check_seq => format!("{name}: $C"),
                    None => name.clone(),
                };
                let msg = last_msg.take().unwrap_or_else(|| {
                    protocol::Code::from_code(code)
                        .map_or("device error", |c| c.message())
                        .to_string()
                });
                say(&pb, format!("{at}: error[{code}]: {msg}"));
            }
            ClientEvent::Device(DeviceMsg::Alarm { code }) => {
                alarm = true;
                let msg = last_msg.take().unwrap_or_default();
                say(&pb, format!("{name}: ALARM:{code} {msg}"));
                finished = true;
            }
            ClientEvent::Device(DeviceMsg::Status(st)) => {
                pb.set_message(status_text(&st));
                let idle = matches!(st.state, MachineState::Idle);
                if !a.check && done_seq.is_some() && idle && client.in_flight() == 0 {
                    finished = true;
                }
                if matches!(st.state, MachineState::Alarm) && !alarm {
                    alarm = true;
                    say(&pb, format!("{name}: machine in alarm"));
                    finished = true;
                }
            }
            ClientEvent::Device(_) => {}
            ClientEvent::BadFrame(_) => {}
        }
    }
    // One last report for the final position.
    client.realtime(Rt::StatusQuery)?;
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(500) {
        if let Some(ClientEvent::Device(DeviceMsg::Status(st))) = client.poll()? {
            pb.set_message(status_text(&st));
            let m = st.mpos;
            say(
                &pb,
                format!("final MPos:{:.3},{:.3},{:.3},{:.3}", m[0], m[1], m[2], m[3]),
            );
            break;
        }
    }
    let _ = client.request(&protocol::HostMsg::Bye);
    // Let the device read the `Bye` before the port closes.
    let _ = std::io::Write::flush(client.get_mut());
    std::thread::sleep(Duration::from_millis(50));
    pb.finish();
    eprintln!(
        "{name}: {} lines, {errors} error(s){}",
        lines.len(),
        if alarm { ", alarm" } else { "" }
    );
    Ok(if errors > 0 || alarm { 1 } else { 0 })
}

/// Send one line and wait until it is acknowledged.
fn send_wait<T: std::io::Read + std::io::Write>(c: &mut Client<T>, text: &[u8]) -> Result<u32> {
    let t0 = Instant::now();
    while !c.can_send() {
        c.poll()?;
        if t0.elapsed() > Duration::from_secs(3) {
            bail!("no credit from the device");
        }
    }
    let seq = c.send_line(text)?;
    while c.in_flight() > 0 {
        c.poll()?;
        if t0.elapsed() > Duration::from_secs(3) {
            bail!(
                "device did not acknowledge {}",
                String::from_utf8_lossy(text)
            );
        }
    }
    Ok(seq)
}

/// A line above the bar (the bar hides itself, and its printing, when
/// stderr is not a terminal: then print plainly).
fn say(pb: &ProgressBar, line: String) {
    if pb.is_hidden() {
        eprintln!("{line}");
    } else {
        pb.println(line);
    }
}

/// One status report (None if the device does not answer in time).
fn query_status<T: std::io::Read + std::io::Write>(
    c: &mut Client<T>,
) -> Result<Option<protocol::Status>> {
    c.realtime(Rt::StatusQuery)?;
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(1) {
        if let Some(ClientEvent::Device(DeviceMsg::Status(st))) = c.poll()? {
            return Ok(Some(st));
        }
    }
    Ok(None)
}
