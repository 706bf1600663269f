//! The pack's UART side: receiving words and scheduling replies on a half-duplex pair.
//!
//! Timing rules (manual 6.1): a reply starts only after the transmitter switch-over time
//! ($40, 6 ms by default) "has passed", measured from the end of the request; "the PACK
//! continues to drive the line for a pre-set time after transmitting a message". While the
//! pack drives the pair its receiver is off (RS-485 half duplex with the driver enable and
//! receiver enable tied, our reading), so bytes sent to it then are lost.

use core::time::Duration;
use std::collections::VecDeque;

use tmcpack::{FRAME_LEN, Word};

/// Why something is on the transmit queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// The answer to the request just received.
    Immediate,
    /// A delayed $28 answer.
    Delayed,
    /// The 0 byte a reset puts on the line.
    Glitch,
}

#[derive(Debug, Clone)]
struct Outgoing {
    start: Duration,
    bytes: Word,
    len: usize,
    sent: usize,
    byte_time: Duration,
    hold: Duration,
    kind: Kind,
}

impl Outgoing {
    fn byte_start(&self, i: usize) -> Duration {
        self.start
            .saturating_add(self.byte_time.saturating_mul(i as u32))
    }

    fn end(&self) -> Duration {
        self.byte_start(self.len)
    }

    fn window_end(&self) -> Duration {
        self.end().saturating_add(self.hold)
    }
}

/// The transmit side.
#[derive(Debug, Clone, Default)]
pub(crate) struct Transmitter {
    queue: VecDeque<Outgoing>,
    last_window: Option<(Duration, Duration)>,
}

impl Transmitter {
    /// `true` while the pack drives the pair at `t`.
    pub fn driving(&self, t: Duration) -> bool {
        let inside = |s: Duration, e: Duration| s <= t && t < e;
        self.last_window.is_some_and(|(s, e)| inside(s, e))
            || self.queue.iter().any(|o| inside(o.start, o.window_end()))
    }

    /// `true` while an answer to a request is still due at `t` — queued for after its
    /// switch-over delay, on the line, or in the hold after it — or the pack drives the
    /// pair with any other message: a request that begins then is interlaced (manual 7.1
    /// "Requests must not be interlaced. Each request should wait for the response of the
    /// PACK before transmitting a new command."). A delayed `$28` answer that has not
    /// started is not due ("a delayed response with RS 232 may be outstanding in
    /// parallel").
    pub fn answer_due(&self, t: Duration) -> bool {
        self.driving(t)
            || self
                .queue
                .iter()
                .any(|o| o.kind == Kind::Immediate && t < o.window_end())
    }

    /// Queues `bytes` to start at `ready` (or after what is already queued). An immediate
    /// answer replaces one that has not started yet; returns `true` if it did.
    pub fn schedule(
        &mut self,
        ready: Duration,
        bytes: &[u8],
        byte_time: Duration,
        hold: Duration,
        kind: Kind,
    ) -> bool {
        let mut replaced = false;
        if kind == Kind::Immediate {
            let before = self.queue.len();
            self.queue
                .retain(|o| !(o.kind == Kind::Immediate && o.sent == 0));
            replaced = self.queue.len() != before;
        }
        let start = self
            .queue
            .iter()
            .map(Outgoing::end)
            .fold(ready, Duration::max);
        let mut word = [0u8; FRAME_LEN];
        let len = bytes.len().min(FRAME_LEN);
        word.get_mut(..len)
            .unwrap_or_default()
            .copy_from_slice(bytes.get(..len).unwrap_or_default());
        self.queue.push_back(Outgoing {
            start,
            bytes: word,
            len,
            sent: 0,
            byte_time,
            hold,
            kind,
        });
        replaced
    }

    /// Moves into `out` the bytes whose transmission started at or before `now`.
    pub fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        let mut n = 0;
        for o in &mut self.queue {
            while o.sent < o.len && o.byte_start(o.sent) <= now {
                let Some(slot) = out.get_mut(n) else { return n };
                *slot = o.bytes.get(o.sent).copied().unwrap_or(0);
                o.sent += 1;
                n += 1;
            }
            if o.sent < o.len {
                break;
            }
        }
        while self
            .queue
            .front()
            .is_some_and(|o| o.sent == o.len && o.window_end() <= now)
        {
            if let Some(o) = self.queue.pop_front() {
                self.last_window = Some((o.start, o.window_end()));
            }
        }
        n
    }

    /// When the next byte starts.
    pub fn next_byte(&self) -> Option<Duration> {
        self.queue
            .iter()
            .find(|o| o.sent < o.len)
            .map(|o| o.byte_start(o.sent))
    }

    /// Forgets everything queued (reset).
    pub fn clear(&mut self) {
        self.queue.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BT: Duration = Duration::from_micros(500);
    const HOLD: Duration = Duration::from_millis(6);

    #[test]
    fn bytes_start_on_time_and_the_line_is_held_after() {
        let mut tx = Transmitter::default();
        let t = Duration::from_millis(10);
        assert!(!tx.schedule(t, &[1, 2, 3], BT, HOLD, Kind::Immediate));
        let mut out = [0u8; 8];
        assert_eq!(tx.transmit(t - Duration::from_nanos(1), &mut out), 0);
        assert_eq!(tx.next_byte(), Some(t));
        assert_eq!(tx.transmit(t + BT, &mut out), 2);
        assert_eq!(out[..2], [1, 2]);
        assert_eq!(tx.transmit(t + BT * 2, &mut out), 1);
        assert!(tx.driving(t + BT * 3 + HOLD - Duration::from_nanos(1)));
        assert!(!tx.driving(t + BT * 3 + HOLD));
        assert!(!tx.driving(t - Duration::from_nanos(1)));
        assert_eq!(tx.transmit(t + BT * 4 + HOLD, &mut out), 0);
        assert!(tx.driving(t + BT), "remembered after it left the queue");
    }

    #[test]
    fn an_answer_is_due_from_its_request_to_the_end_of_its_hold() {
        let mut tx = Transmitter::default();
        let t = Duration::from_millis(10);
        assert!(!tx.answer_due(t));
        tx.schedule(t + HOLD, &[1; 9], BT, HOLD, Kind::Immediate);
        assert!(tx.answer_due(t), "waiting for its switch-over");
        let end = t + HOLD + BT * 9 + HOLD;
        assert!(tx.answer_due(end - Duration::from_nanos(1)));
        assert!(!tx.answer_due(end));
        let mut out = [0u8; 16];
        tx.transmit(end, &mut out);
        assert!(!tx.answer_due(end));
        // A delayed $28 answer may be outstanding: not due until it goes out.
        let later = end + HOLD;
        tx.schedule(later, &[2; 9], BT, HOLD, Kind::Delayed);
        assert!(!tx.answer_due(later - Duration::from_nanos(1)));
        assert!(tx.answer_due(later));
    }

    #[test]
    fn a_waiting_answer_is_replaced_and_others_queue_behind() {
        let mut tx = Transmitter::default();
        let t = Duration::from_millis(10);
        tx.schedule(t, &[1; 9], BT, HOLD, Kind::Delayed);
        assert!(!tx.schedule(t, &[2; 9], BT, HOLD, Kind::Immediate));
        assert!(tx.schedule(t, &[3; 9], BT, HOLD, Kind::Immediate));
        let mut out = [0u8; 32];
        let n = tx.transmit(t + BT * 17, &mut out);
        assert_eq!(n, 18);
        assert_eq!(out[..9], [1; 9]);
        assert_eq!(
            out[9..18],
            [3; 9],
            "the later answer replaced the waiting one"
        );
    }
}
