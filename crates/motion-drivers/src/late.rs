//! Answers that may still come after their reply window ended ([`LateAnswer`]), and what
//! a shared stream bus does with them.
//!
//! A board answers within a window its datasheet bounds (request and answer on the wire,
//! a turn-around, the board's processing); a driver waits that long and then counts the
//! request unanswered. A board or its host process that was starved (an emulator on a
//! loaded machine, a board's firmware stalled) may still send the answer later. On a line
//! without message identifiers — the Trinamic pack's answer is its response address, the
//! command and its parameters, nothing that names the request — a late answer looks
//! exactly like the answer to a later request of the same kind, and pairing the two gives
//! a driver another moment's data (or another board's: every pack on an RS-485 bus answers
//! to the same response address). So a driver that counted a request unanswered keeps the
//! opening bytes of its answer as a [`LateAnswer`] for a while; it never asks a question
//! whose answer would begin with those bytes, and takes a word that begins with them for
//! late, never for the answer it awaits. A [`LinkBus`](crate::LinkBus) with several
//! drivers on one stream link hands each driver the late answers of the others
//! ([`Driver::handle_late_answers`](crate::Driver::handle_late_answers)) before it picks
//! the next sender and before it routes received bytes, so the rule holds across boards.

use core::time::Duration;

/// Most opening bytes a late answer is told by.
pub const LATE_PREFIX_LEN: usize = 4;

/// Most late answers a bus shares at once (the rest wait for room).
pub const LATE_ANSWERS: usize = 16;

/// The opening bytes of an answer that may still arrive after its window, and until when
/// the driver that awaited it keeps it for late.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct LateAnswer {
    prefix: [u8; LATE_PREFIX_LEN],
    len: u8,
    until: Duration,
}

impl LateAnswer {
    /// No bytes, kept until 0 (a filler for fixed arrays).
    pub const EMPTY: Self = Self {
        prefix: [0; LATE_PREFIX_LEN],
        len: 0,
        until: Duration::ZERO,
    };

    /// A late answer that begins with `prefix` (at most [`LATE_PREFIX_LEN`] bytes; more are
    /// cut), kept until `until`.
    pub fn new(prefix: &[u8], until: Duration) -> Self {
        let len = prefix.len().min(LATE_PREFIX_LEN);
        let mut bytes = [0; LATE_PREFIX_LEN];
        bytes[..len].copy_from_slice(&prefix[..len]);
        Self {
            prefix: bytes,
            len: len as u8,
            until,
        }
    }

    /// The opening bytes.
    pub fn prefix(&self) -> &[u8] {
        &self.prefix[..usize::from(self.len).min(LATE_PREFIX_LEN)]
    }

    /// Until when it is kept.
    pub fn until(&self) -> Duration {
        self.until
    }

    /// Whether a word that begins with `head` may be this answer (`head` may be shorter
    /// than the prefix: the rest has not arrived yet), or an answer that begins with `head`
    /// could not be told from it: one of the two begins with the other.
    pub fn overlaps(&self, head: &[u8]) -> bool {
        let prefix = self.prefix();
        let n = prefix.len().min(head.len());
        prefix[..n] == head[..n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_late_answer_is_told_by_its_opening_bytes() {
        let late = LateAnswer::new(&[0xFE, 0x20, 1], Duration::from_millis(5));
        assert_eq!(late.prefix(), &[0xFE, 0x20, 1]);
        assert_eq!(late.until(), Duration::from_millis(5));
        assert!(late.overlaps(&[0xFE, 0x20, 1, 0xD0, 7]));
        assert!(late.overlaps(&[0xFE, 0x20]), "not told apart yet");
        assert!(!late.overlaps(&[0xFE, 0x20, 2]));
        assert!(!late.overlaps(&[0xFE, 0x43]));
        assert!(LateAnswer::new(&[0xFE, 0x43], Duration::ZERO).overlaps(&[0xFE, 0x43, 149]));
        let long = LateAnswer::new(&[1, 2, 3, 4, 5, 6], Duration::ZERO);
        assert_eq!(long.prefix(), &[1, 2, 3, 4]);
    }
}
