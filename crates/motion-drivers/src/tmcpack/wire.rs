//! The host side of the half-duplex line: one request in flight, the pack's switch-over
//! time on both sides of its answer (manual 6.1), and finding the answer in the byte stream.
//!
//! Timing of one query at 19200 baud with a 2 ms switch-over: the request takes 4.7 ms on
//! the wire; the pack answers after the switch-over delay; the answer takes 4.7 ms; the pack
//! then keeps driving the line for the switch-over time again, and bytes sent to it then
//! are lost. So after an answer the whole bus stays quiet for the switch-over time (the
//! driver reports [`awaiting_reply`](crate::Driver::awaiting_reply) until then, which holds
//! every other driver on the bus too).

use core::time::Duration;

use tmcpack::{Command, FRAME_LEN, Reply, ReplyFrame};

/// What a query waits for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Expect {
    pub command: Command,
    /// The motor a $20 or $21 answer must name, the channel a $30 answer must name.
    pub motor: Option<u8>,
    /// Which query this is.
    pub purpose: Purpose,
}

/// Why a query was sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Purpose {
    /// $43 of the start-up sequence.
    Startup,
    /// $43 checking the reset flag while online.
    ResetCheck,
    /// $20 of the polling plan.
    Poll,
    /// $28 of the start-up survey: which motors are active.
    Survey,
    /// $21 while stopping motors found active at start-up.
    Quiesce,
    /// $30 of the polling plan (inputs).
    Io,
}

/// Who may use the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Wire {
    /// Free.
    Idle,
    /// A request without an answer is still on the wire.
    Sending { until: Duration },
    /// Waiting for the answer to a query.
    Awaiting {
        expect: Expect,
        sent_at: Duration,
        deadline: Duration,
    },
    /// The pack still drives the line after its answer, or the line is kept silent after
    /// a timeout so that the pack's packet timeout ($41) resynchronises it.
    Quiet { until: Duration },
}

impl Wire {
    /// When the line state changes by itself.
    pub fn deadline(&self) -> Option<Duration> {
        match *self {
            Self::Idle => None,
            Self::Sending { until } | Self::Quiet { until } => Some(until),
            Self::Awaiting { deadline, .. } => Some(deadline),
        }
    }
}

/// Capacity of the hunting window: a reply plus garbage before it.
const WINDOW: usize = 4 * FRAME_LEN;

/// Finds the expected answer in the received bytes. The line has no start byte and no
/// checksum (6.1), but the host knows what it waits for: a word that starts with its
/// response address and the query's command and decodes. Anything else before it is
/// garbage and is skipped byte by byte, so a reply is found even right after a burst of
/// noise (the pack's own resynchronisation, the packet timeout, needs a silent gap).
#[derive(Debug, Clone)]
pub(crate) struct ReplyHunter {
    buf: [u8; WINDOW],
    len: usize,
    /// Bytes skipped since the last [`reset`](Self::reset).
    pub skipped: u32,
}

impl ReplyHunter {
    pub const fn new() -> Self {
        Self {
            buf: [0; WINDOW],
            len: 0,
            skipped: 0,
        }
    }

    /// Forgets everything (a new request was sent).
    pub fn reset(&mut self) {
        self.len = 0;
        self.skipped = 0;
    }

    /// Takes `bytes`; returns the expected answer once it is complete. Bytes after it are
    /// left in the window (and dropped by the next reset).
    pub fn push(&mut self, reply_address: u8, expect: Expect, bytes: &[u8]) -> Option<Reply> {
        for &byte in bytes {
            if self.len == WINDOW {
                self.shift(1);
            }
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = byte;
                self.len += 1;
            }
            if let Some(reply) = self.scan(reply_address, expect) {
                return Some(reply);
            }
        }
        None
    }

    fn scan(&mut self, reply_address: u8, expect: Expect) -> Option<Reply> {
        loop {
            let head = self.buf.get(..self.len)?;
            match head {
                [] => return None,
                [first, ..] if *first != reply_address => {}
                [_, command, ..] if *command != expect.command.code() => {}
                _ if self.len < FRAME_LEN => return None,
                _ => {
                    if let Some(reply) = self
                        .buf
                        .get(..FRAME_LEN)
                        .and_then(|word| ReplyFrame::decode(word).ok())
                        .map(|frame| frame.reply)
                        .filter(|reply| matches(reply, expect))
                    {
                        self.shift(FRAME_LEN);
                        return Some(reply);
                    }
                }
            }
            self.shift(1);
            self.skipped += 1;
        }
    }

    fn shift(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }
}

fn matches(reply: &Reply, expect: Expect) -> bool {
    match (reply, expect.motor) {
        (Reply::Position { motor, .. } | Reply::Velocity { motor, .. }, Some(want)) => {
            *motor == want
        }
        (Reply::Input { channel, .. }, Some(want)) => *channel == want,
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const POLL: Expect = Expect {
        command: Command::QueryPosition,
        motor: Some(1),
        purpose: Purpose::Poll,
    };

    // Manual 8.4 $20 response: CMD $20, P0 motnr, P1..4 posact LSB first, P5 action, P6 stop.
    const ANSWER: [u8; 9] = [0xFE, 0x20, 0x01, 0xD0, 0x07, 0x00, 0x00, 0x05, 0x00];

    #[test]
    fn finds_the_answer_in_any_chunking() {
        for chunk in 1..=FRAME_LEN {
            let mut hunter = ReplyHunter::new();
            let mut found = None;
            for part in ANSWER.chunks(chunk) {
                if let Some(reply) = hunter.push(0xFE, POLL, part) {
                    found = Some(reply);
                }
            }
            assert!(matches!(
                found,
                Some(Reply::Position {
                    motor: 1,
                    position: 2000,
                    ..
                })
            ));
        }
    }

    #[test]
    fn skips_garbage_before_the_answer_even_if_it_looks_like_a_header() {
        let mut hunter = ReplyHunter::new();
        let mut bytes = vec![0x13, 0xFE, 0x20, 0x07, 0xFE, 0xFE];
        bytes.extend_from_slice(&ANSWER);
        let reply = hunter.push(0xFE, POLL, &bytes);
        assert!(matches!(
            reply,
            Some(Reply::Position { position: 2000, .. })
        ));
        assert_eq!(hunter.skipped, 6);
    }

    #[test]
    fn ignores_another_motor_and_another_address() {
        let mut hunter = ReplyHunter::new();
        let mut other_motor = ANSWER;
        other_motor[2] = 2;
        let mut other_address = ANSWER;
        other_address[0] = 0x01;
        assert_eq!(hunter.push(0xFE, POLL, &other_motor), None);
        assert_eq!(hunter.push(0xFE, POLL, &other_address), None);
        assert!(hunter.push(0xFE, POLL, &ANSWER).is_some());
    }

    #[test]
    fn endless_noise_never_overflows() {
        let mut hunter = ReplyHunter::new();
        let noise: Vec<u8> = (0..1000u32).map(|i| (i * 37 % 251) as u8).collect();
        assert_eq!(hunter.push(0xFE, POLL, &noise), None);
        assert!(hunter.push(0xFE, POLL, &ANSWER).is_some());
    }
}
