//! An in-memory byte pipe pair, so the client (and anything else speaking
//! the protocol) can be tested without a serial port or pty.

use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::sync::{Arc, Mutex};

type Buf = Arc<Mutex<VecDeque<u8>>>;

/// One end of a duplex pipe. Reads never block: an empty pipe gives
/// `WouldBlock`, like a serial port with a zero timeout. A closed peer gives
/// end-of-file once its bytes are drained.
#[derive(Debug, Clone)]
pub struct MemPipe {
    rx: Buf,
    tx: Buf,
    closed: Arc<Mutex<bool>>,
}

impl MemPipe {
    /// Two connected ends.
    pub fn pair() -> (MemPipe, MemPipe) {
        let a: Buf = Arc::default();
        let b: Buf = Arc::default();
        let closed = Arc::new(Mutex::new(false));
        (
            MemPipe {
                rx: a.clone(),
                tx: b.clone(),
                closed: closed.clone(),
            },
            MemPipe {
                rx: b,
                tx: a,
                closed,
            },
        )
    }

    /// Bytes waiting to be read at this end.
    pub fn available(&self) -> usize {
        self.rx.lock().map(|q| q.len()).unwrap_or(0)
    }

    /// Close both directions (a cable pull): later reads see end-of-file.
    pub fn close(&self) {
        if let Ok(mut c) = self.closed.lock() {
            *c = true;
        }
    }

    fn is_closed(&self) -> bool {
        self.closed.lock().map(|c| *c).unwrap_or(true)
    }
}

impl Read for MemPipe {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let mut q = self
            .rx
            .lock()
            .map_err(|_| io::Error::other("pipe poisoned"))?;
        if q.is_empty() {
            return if self.is_closed() {
                Ok(0)
            } else {
                Err(io::ErrorKind::WouldBlock.into())
            };
        }
        let n = buf.len().min(q.len());
        for (dst, src) in buf.iter_mut().zip(q.drain(..n)) {
            *dst = src;
        }
        Ok(n)
    }
}

impl Write for MemPipe {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.is_closed() {
            return Err(io::ErrorKind::BrokenPipe.into());
        }
        let mut q = self
            .tx
            .lock()
            .map_err(|_| io::Error::other("pipe poisoned"))?;
        q.extend(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}
