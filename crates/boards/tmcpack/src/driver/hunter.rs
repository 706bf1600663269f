//! Finding the answer awaited in the bytes of the line (manual 6.1: no start byte, no
//! checksum), and taking words that begin like a late answer (module `late`) out whole.

use core::time::Duration;

use tmcpack::{FRAME_LEN, Reply, ReplyFrame, Word};

use super::late::LateSet;
use super::wire::Expect;

/// Capacity of the hunting window: a reply plus garbage before it.
const WINDOW: usize = 4 * FRAME_LEN;

/// What the hunter looks for: the answer awaited (if any), and the late answers (module
/// `late`) that must not be taken for it.
pub(crate) struct Want<'a> {
    pub reply_address: u8,
    pub expect: Option<Expect>,
    pub late: &'a LateSet,
    pub now: Duration,
}

/// What the hunter found in the byte stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Found {
    /// The answer awaited.
    Answer(Reply),
    /// A word that begins like a late answer: dropped (counted), never paired.
    Late(Word),
}

/// Finds the expected answer in the received bytes. The line has no start byte and no
/// checksum (6.1), but the host knows what it waits for: a word that starts with its
/// response address and the query's command and decodes. A word that begins like a late
/// answer (module `late`) is taken out whole as late. Anything else before the answer is
/// garbage and is skipped byte by byte, so a reply is found even right after a burst of
/// noise (the pack's own resynchronisation, the packet timeout, needs a silent gap).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct ReplyHunter {
    #[serde(with = "serde_big_array::BigArray")]
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

    /// Bytes held that may still become a word (the rest of it has not arrived).
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Forgets everything (a new request was sent).
    pub fn reset(&mut self) {
        self.len = 0;
        self.skipped = 0;
    }

    /// Takes `bytes` until it finds the answer or a late word; returns what it found and
    /// how many of `bytes` it took (the rest is for the next call).
    pub fn push(&mut self, want: &Want<'_>, bytes: &[u8]) -> (Option<Found>, usize) {
        for (taken, &byte) in bytes.iter().enumerate() {
            if self.len == WINDOW {
                self.shift(1);
                self.skipped += 1;
            }
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = byte;
                self.len += 1;
            }
            if let Some(found) = self.scan(want) {
                return (Some(found), taken + 1);
            }
        }
        (None, bytes.len())
    }

    fn scan(&mut self, want: &Want<'_>) -> Option<Found> {
        loop {
            let head = self.buf.get(..self.len)?;
            let first = *head.first()?;
            if let Some(expect) = want.expect
                && first == want.reply_address
                && head.get(1).is_none_or(|c| *c == expect.command.code())
            {
                if self.len < FRAME_LEN {
                    return None;
                }
                if let Some(reply) = self
                    .buf
                    .get(..FRAME_LEN)
                    .and_then(|word| ReplyFrame::decode(word).ok())
                    .map(|frame| frame.reply)
                    .filter(|reply| matches(reply, expect))
                {
                    self.shift(FRAME_LEN);
                    return Some(Found::Answer(reply));
                }
            }
            let told = head.get(..head.len().min(3)).unwrap_or_default();
            if want.late.matches(told, want.now) {
                if self.len < FRAME_LEN {
                    return None;
                }
                let mut word = [0u8; FRAME_LEN];
                word.copy_from_slice(self.buf.get(..FRAME_LEN)?);
                self.shift(FRAME_LEN);
                return Some(Found::Late(word));
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
    use crate::driver::wire::Purpose;
    use tmcpack::Command;

    const POLL: Expect = Expect {
        command: Command::QueryPosition,
        motor: Some(1),
        purpose: Purpose::Poll,
    };

    // Manual 8.4 $20 response: CMD $20, P0 motnr, P1..4 posact LSB first, P5 action, P6 stop.
    const ANSWER: [u8; 9] = [0xFE, 0x20, 0x01, 0xD0, 0x07, 0x00, 0x00, 0x05, 0x00];

    fn want(late: &LateSet) -> Want<'_> {
        Want {
            reply_address: 0xFE,
            expect: Some(POLL),
            late,
            now: Duration::ZERO,
        }
    }

    /// Everything `bytes` holds, in order.
    fn hunt(hunter: &mut ReplyHunter, want: &Want<'_>, mut bytes: &[u8]) -> Vec<Found> {
        let mut found = Vec::new();
        while !bytes.is_empty() {
            let (event, used) = hunter.push(want, bytes);
            found.extend(event);
            bytes = &bytes[used..];
        }
        found
    }

    fn answer(found: &[Found]) -> Option<Reply> {
        found.iter().find_map(|f| match f {
            Found::Answer(reply) => Some(*reply),
            Found::Late(_) => None,
        })
    }

    #[test]
    fn finds_the_answer_in_any_chunking() {
        let late = LateSet::new();
        for chunk in 1..=FRAME_LEN {
            let mut hunter = ReplyHunter::new();
            let mut found = Vec::new();
            for part in ANSWER.chunks(chunk) {
                found.extend(hunt(&mut hunter, &want(&late), part));
            }
            assert!(matches!(
                answer(&found),
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
        let late = LateSet::new();
        let mut hunter = ReplyHunter::new();
        let mut bytes = vec![0x13, 0xFE, 0x20, 0x07, 0xFE, 0xFE];
        bytes.extend_from_slice(&ANSWER);
        let found = hunt(&mut hunter, &want(&late), &bytes);
        assert!(matches!(
            answer(&found),
            Some(Reply::Position { position: 2000, .. })
        ));
        assert_eq!(hunter.skipped, 6);
    }

    #[test]
    fn ignores_another_motor_and_another_address() {
        let late = LateSet::new();
        let mut hunter = ReplyHunter::new();
        let mut other_motor = ANSWER;
        other_motor[2] = 2;
        let mut other_address = ANSWER;
        other_address[0] = 0x01;
        assert!(hunt(&mut hunter, &want(&late), &other_motor).is_empty());
        assert!(hunt(&mut hunter, &want(&late), &other_address).is_empty());
        assert!(answer(&hunt(&mut hunter, &want(&late), &ANSWER)).is_some());
    }

    #[test]
    fn endless_noise_never_overflows() {
        let late = LateSet::new();
        let mut hunter = ReplyHunter::new();
        let noise: Vec<u8> = (0..1000u32).map(|i| (i * 37 % 251) as u8).collect();
        assert!(hunt(&mut hunter, &want(&late), &noise).is_empty());
        assert!(answer(&hunt(&mut hunter, &want(&late), &ANSWER)).is_some());
    }

    /// A late `$20` of motor 0 (its query timed out) in front of the answer of motor 1, in
    /// any chunking: taken out whole as late, and the answer still found.
    #[test]
    fn a_late_word_is_taken_out_whole_and_never_paired() {
        let mut late = LateSet::new();
        late.add(&[0xFE, 0x20, 0], Duration::from_millis(500));
        let mut stale = ANSWER;
        stale[2] = 0;
        let mut bytes = stale.to_vec();
        bytes.extend_from_slice(&ANSWER);
        for chunk in 1..=bytes.len() {
            let mut hunter = ReplyHunter::new();
            let mut found = Vec::new();
            for part in bytes.chunks(chunk) {
                found.extend(hunt(&mut hunter, &want(&late), part));
            }
            assert_eq!(found.first(), Some(&Found::Late(stale)), "chunk {chunk}");
            assert!(matches!(
                answer(&found),
                Some(Reply::Position { motor: 1, .. })
            ));
            assert_eq!(hunter.skipped, 0);
        }
        // Nothing awaited: the late word is still recognised, garbage is skipped.
        let mut hunter = ReplyHunter::new();
        let idle = Want {
            expect: None,
            ..want(&late)
        };
        let mut bytes = vec![0x55];
        bytes.extend_from_slice(&stale);
        assert_eq!(hunt(&mut hunter, &idle, &bytes), vec![Found::Late(stale)]);
        assert_eq!(hunter.skipped, 1);
    }
}
