//! What the board sends: the transmit queue (whole lines released when their processing
//! is done; the link charges the wire time) and a model of the UART's backlog, used to
//! drop stream samples the line cannot carry and to time a baud-rate change.

use core::time::Duration;
use std::collections::VecDeque;

use qsb::{Eor, MAX_RESPONSE_LEN, Response};

#[derive(Debug, Clone)]
pub(crate) struct Output {
    /// Bytes with the instant their line may start.
    queue: VecDeque<(Duration, u8)>,
    capacity: usize,
    /// When the UART has sent everything queued so far.
    pub uart_free: Duration,
    pub dropped_lines: u64,
    pub lines: u64,
}

/// Time one 8N1 byte takes at `baud`.
pub(crate) fn byte_time(baud: u32) -> Duration {
    Duration::from_nanos(10_000_000_000 / u64::from(baud.max(1)))
}

impl Output {
    pub(crate) fn new(capacity: usize) -> Self {
        Self {
            queue: VecDeque::with_capacity(capacity),
            capacity,
            uart_free: Duration::ZERO,
            dropped_lines: 0,
            lines: 0,
        }
    }

    /// Queues `response` formatted by `eor`, to start at `ready`. Returns when its last
    /// byte will have left the UART, or `None` when the queue is full (the line is lost).
    pub(crate) fn send(
        &mut self,
        response: Response,
        eor: Eor,
        ready: Duration,
        baud: u32,
    ) -> Option<Duration> {
        let mut buf = [0u8; MAX_RESPONSE_LEN];
        let Ok(n) = response.encode(eor, &mut buf) else {
            self.dropped_lines += 1;
            return None;
        };
        if self.queue.len() + n > self.capacity {
            self.dropped_lines += 1;
            return None;
        }
        self.queue.extend(buf.iter().take(n).map(|b| (ready, *b)));
        let start = self.uart_free.max(ready);
        self.uart_free = start.saturating_add(byte_time(baud) * n as u32);
        self.lines += 1;
        Some(self.uart_free)
    }

    /// Moves into `out` the bytes whose line has started by `now`.
    pub(crate) fn take(&mut self, now: Duration, out: &mut [u8]) -> usize {
        let mut n = 0;
        for slot in out.iter_mut() {
            match self.queue.front() {
                Some(&(ready, b)) if ready <= now => {
                    *slot = b;
                    self.queue.pop_front();
                    n += 1;
                }
                _ => break,
            }
        }
        n
    }

    /// When the next queued byte may start.
    pub(crate) fn next_ready(&self) -> Option<Duration> {
        self.queue.front().map(|(t, _)| *t)
    }

    pub(crate) fn clear(&mut self, now: Duration) {
        self.queue.clear();
        self.uart_free = now;
    }
}
