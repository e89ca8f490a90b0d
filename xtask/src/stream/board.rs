//! Finding the board and asking it things outside the job stream.

use anyhow::{bail, Context, Result};
use protocol::client::{Client, ClientEvent};
use protocol::{DeviceMsg, HostMsg, Rt};
use std::io::{Read, Write};
use std::path::Path;
use std::time::{Duration, Instant};

/// The first tty whose USB device has burin's VID/PID.
pub fn find_board() -> Result<String> {
    let want = (protocol::usb_ids::USB_VID, protocol::usb_ids::USB_PID);
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

/// Every `$n` setting of the board (the framed `$$`).
pub fn read_settings<T: Read + Write>(c: &mut Client<T>) -> Result<Vec<(u16, f32)>> {
    c.request(&HostMsg::ListSettings)?;
    let mut out = Vec::new();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(3) {
        match c.poll()? {
            Some(ClientEvent::Device(DeviceMsg::Setting { n, value })) => out.push((n, value)),
            Some(ClientEvent::Device(DeviceMsg::SettingsEnd)) => return Ok(out),
            _ => {}
        }
    }
    bail!("the board did not list its settings")
}

/// Send one line and wait until it is acknowledged.
pub fn send_wait<T: Read + Write>(c: &mut Client<T>, text: &[u8]) -> Result<u32> {
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

/// One status report (None if the device does not answer in time).
pub fn query_status<T: Read + Write>(c: &mut Client<T>) -> Result<Option<protocol::Status>> {
    c.realtime(Rt::StatusQuery)?;
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(1) {
        if let Some(ClientEvent::Device(DeviceMsg::Status(st))) = c.poll()? {
            return Ok(Some(st));
        }
    }
    Ok(None)
}
