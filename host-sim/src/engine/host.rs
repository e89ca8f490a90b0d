//! The host side of the simulation: job lines arriving over a link of
//! finite rate (the sender keeps at most the receive window in flight or
//! unparsed, like GRBL character counting), and the parse/plan task's own
//! run time.

use std::collections::VecDeque;

use burin::command::Command;

use crate::config::HostModel;

/// One G-code line on its way to (and through) the parser.
pub(super) struct Line {
    pub line: u32,
    /// Length on the link with its newline; 0: not sent over the link.
    pub bytes: u32,
    pub cmds: VecDeque<Command>,
    /// The sender started it; `arrival` is when its last byte is in.
    pub sent: bool,
    pub arrival: u64,
    /// The parser took it (its bytes left the receive window).
    pub taken: bool,
}

impl Line {
    pub fn new(line: u32, bytes: u32, cmds: Vec<Command>) -> Self {
        Line {
            line,
            bytes,
            cmds: cmds.into(),
            sent: false,
            arrival: 0,
            taken: false,
        }
    }
}

/// Link and task state, all in timer ticks.
pub(super) struct Task {
    /// Ticks per byte ×2^16 (0: instant link).
    byte_ticks_q16: u64,
    window: u32,
    line_ticks: u64,
    block_ticks: u64,
    scurve_visit_ticks: u64,
    /// Bytes sent and not yet taken by the parser.
    in_window: u32,
    /// Lines at the front of the queue already sent.
    sent: usize,
    link_free: u64,
    pub busy_until: u64,
    /// The task was asked to run while busy: run it then.
    pub wake: Option<u64>,
}

impl Task {
    pub fn new(h: &HostModel, tick_hz: u32) -> Self {
        let ns = |v: u32| (u64::from(v) * u64::from(tick_hz) + 500_000_000) / 1_000_000_000;
        let byte_ticks_q16 = if h.link_bytes_per_s == 0 {
            0
        } else {
            (u64::from(tick_hz) << 16) / u64::from(h.link_bytes_per_s)
        };
        Task {
            byte_ticks_q16,
            window: h.rx_window_bytes.max(1),
            line_ticks: ns(h.line_ns),
            block_ticks: ns(h.block_ns),
            scurve_visit_ticks: ns(h.scurve_visit_ns),
            in_window: 0,
            sent: 0,
            link_free: 0,
            busy_until: 0,
            wake: None,
        }
    }

    /// The task takes virtual time.
    pub fn costed(&self) -> bool {
        self.line_ticks > 0 || self.block_ticks > 0 || self.scurve_visit_ticks > 0
    }

    /// `visits`: blocks the planner's passes visited in S-curve mode
    /// (`Planner::work`; 0 in trapezoid mode).
    pub fn cost(&self, lines: u64, blocks: u64, visits: u64) -> u64 {
        lines * self.line_ticks + blocks * self.block_ticks + visits * self.scurve_visit_ticks
    }

    /// Start sending every line the receive window has room for.
    pub fn send(&mut self, lines: &mut VecDeque<Line>, now: u64) {
        while let Some(l) = lines.get_mut(self.sent) {
            if l.bytes == 0 || self.byte_ticks_q16 == 0 {
                l.arrival = now;
            } else {
                if self.in_window > 0 && self.in_window + l.bytes > self.window {
                    return;
                }
                let start = self.link_free.max(now);
                l.arrival = start + ((u64::from(l.bytes) * self.byte_ticks_q16) >> 16);
                self.link_free = l.arrival;
                self.in_window += l.bytes;
            }
            l.sent = true;
            self.sent += 1;
        }
    }

    /// The parser took a line of `bytes` (they leave the receive window).
    pub fn consumed(&mut self, bytes: u32) {
        if self.byte_ticks_q16 != 0 {
            self.in_window = self.in_window.saturating_sub(bytes);
        }
    }

    /// The front line left the queue.
    pub fn popped(&mut self) {
        self.sent = self.sent.saturating_sub(1);
    }
}
