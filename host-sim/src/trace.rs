//! `--trace FILE`: every step event as a CSV row, for tools that check
//! rates, accelerations and path error offline.
//!
//! Format (a contract, other tools read it): header `tick,X,Y,Z,A`, then one
//! row per timer event that raised at least one step pin, giving the event's
//! tick and the machine position in steps after it.
//!
//! A long job is tens of millions of rows, so rows are formatted with `itoa`
//! into one reused buffer and handed to the writer in large blocks.

use std::io::{self, Write};

use burin::AXIS_NAMES;

use crate::record::{PinEvent, Recorder, Summary};

/// Bytes gathered before one `write_all`; big enough that the syscall cost
/// per row vanishes, small enough to stay in cache.
const BLOCK: usize = 1 << 16;

pub struct TraceCsv<W: Write> {
    out: Option<W>,
    buf: Vec<u8>,
    rows: u64,
    /// The first write error; later rows are dropped and `finish` reports it.
    error: Option<io::Error>,
}

impl<W: Write> TraceCsv<W> {
    /// Starts a trace; the header is written at once.
    pub fn new(out: W) -> Self {
        let mut buf = Vec::with_capacity(BLOCK + 128);
        buf.extend_from_slice(b"tick");
        for n in AXIS_NAMES {
            buf.push(b',');
            buf.push(n as u8);
        }
        buf.push(b'\n');
        TraceCsv {
            out: Some(out),
            buf,
            rows: 0,
            error: None,
        }
    }

    /// Rows written so far (the header not counted).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Appends one row; no-op for events that raised no step pin.
    #[inline]
    pub fn push(&mut self, ev: &PinEvent) {
        if ev.step_mask == 0 {
            return;
        }
        let mut fmt = itoa::Buffer::new();
        self.buf.extend_from_slice(fmt.format(ev.tick).as_bytes());
        for p in ev.pos {
            self.buf.push(b',');
            self.buf.extend_from_slice(fmt.format(p).as_bytes());
        }
        self.buf.push(b'\n');
        self.rows += 1;
        if self.buf.len() >= BLOCK {
            self.drain();
        }
    }

    fn drain(&mut self) {
        if let (Some(out), None) = (self.out.as_mut(), self.error.as_ref()) {
            if let Err(e) = out.write_all(&self.buf) {
                self.error = Some(e);
            }
        }
        self.buf.clear();
    }

    /// Writes out what is buffered and flushes the writer.
    pub fn flush(&mut self) -> io::Result<()> {
        self.drain();
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        match self.out.as_mut() {
            Some(out) => out.flush(),
            None => Ok(()),
        }
    }

    /// Flushes and gives the writer back (tests read a `Vec<u8>` this way).
    pub fn into_inner(mut self) -> io::Result<W> {
        self.flush()?;
        self.out
            .take()
            .ok_or_else(|| io::Error::other("trace writer already taken"))
    }
}

impl<W: Write> Recorder for TraceCsv<W> {
    fn step_event(&mut self, ev: &PinEvent) {
        self.push(ev);
    }

    fn finish(&mut self, _summary: &Summary) -> io::Result<()> {
        self.flush()
    }
}

impl<W: Write> Drop for TraceCsv<W> {
    /// A run that ends without `finish` (an early error) still leaves a
    /// readable file; errors here have nowhere to go.
    fn drop(&mut self) {
        let _ = self.flush();
    }
}
