//! Answers that may still come after their window ([`LateAnswer`], motion-drivers' `late`
//! module), on the pack's line.
//!
//! A pack's answer is `response address, command, P0..P6` (manual 6.1, 8.4): nothing in it
//! names the request, and every pack on an RS-485 bus answers to the same response address.
//! So when a query went unanswered (its window ended: module `wire`), its answer is told by
//! its opening bytes — the response address, the command and, for `$20` / `$21` / `$30`,
//! the motor or channel in P0 — and kept as late for [`TmcpackDriverConfig::not_answering`]
//! (the longest a pack or its host is taken to hold an answer and still be answering):
//!
//! - a word that begins like a late answer (the driver's own or, through the link bus,
//!   another pack's) is counted ([`TmcpackDriver::late_replies`]) and dropped, never paired
//!   with the query in flight;
//! - no query goes out whose answer would begin like a late answer: the polling plan skips
//!   to another motor, a due `$43` / `$45` check waits, and any other such query is replaced
//!   by a probe — `$21` of a motor or `$30` of a channel whose answer cannot be confused —
//!   whose answer only shows that the pack answers again;
//! - a pack answers in the order it was asked, so its answer to a later query means the
//!   earlier ones came or never will: the driver's own late answers are then forgotten
//!   (another pack's are kept until that pack answers, or until they expire).
//!
//! A late `$43` answer of the driver's own with the reset flag set (and no other pack's
//! late `$43` it could be) is still the proof of a reboot it is: the flag is "during first
//! read out 1, afterwards 0", so dropping it would hide the reset for good.
//!
//! [`TmcpackDriverConfig::not_answering`]: super::TmcpackDriverConfig::not_answering

use core::time::Duration;

use motion_drivers::{LATE_ANSWERS, LateAnswer};
use tmcpack::{Command, Request};

use super::wire::{Expect, Pick, Purpose};
use super::{Phase, TmcpackDriver};

/// Late answers of the driver's own kept at once (the oldest is dropped for a newer one).
pub(crate) const OWN_LATE: usize = 16;

/// The opening bytes of the answer `expect` waits for, at response address `reply`:
/// address, command and, for the motor's or channel's queries, P0.
pub(crate) fn answer_prefix(reply: u8, expect: &Expect) -> ([u8; 3], usize) {
    match expect.motor {
        Some(selector) => ([reply, expect.command.code(), selector], 3),
        None => ([reply, expect.command.code(), 0], 2),
    }
}

/// The late answers a driver knows: its own, in the order they were asked, and the other
/// packs' on the bus.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct LateSet {
    own: [LateAnswer; OWN_LATE],
    own_len: usize,
    others: [LateAnswer; LATE_ANSWERS],
    others_len: usize,
}

impl LateSet {
    pub const fn new() -> Self {
        Self {
            own: [LateAnswer::EMPTY; OWN_LATE],
            own_len: 0,
            others: [LateAnswer::EMPTY; LATE_ANSWERS],
            others_len: 0,
        }
    }

    /// The driver's own.
    pub fn own(&self) -> &[LateAnswer] {
        self.own.get(..self.own_len).unwrap_or_default()
    }

    fn others(&self) -> &[LateAnswer] {
        self.others.get(..self.others_len).unwrap_or_default()
    }

    /// The other packs' late answers, as the bus handed them.
    pub fn set_others(&mut self, others: &[LateAnswer]) {
        let n = others.len().min(LATE_ANSWERS);
        if let (Some(slots), Some(given)) = (self.others.get_mut(..n), others.get(..n)) {
            slots.copy_from_slice(given);
        }
        self.others_len = n;
    }

    /// The answer beginning with `prefix` is late from now on, until `until`.
    pub fn add(&mut self, prefix: &[u8], until: Duration) {
        if let Some(i) = self.own().iter().position(|l| l.prefix() == prefix) {
            // Asked again after it timed out (it could not be, see `blocks`): kept once,
            // at its newest place.
            self.remove_own(i);
        }
        if self.own_len == OWN_LATE {
            self.remove_own(0);
        }
        if let Some(slot) = self.own.get_mut(self.own_len) {
            *slot = LateAnswer::new(prefix, until);
            self.own_len += 1;
        }
    }

    fn remove_own(&mut self, index: usize) {
        if index < self.own_len {
            self.own.copy_within(index + 1..self.own_len, index);
            self.own_len -= 1;
        }
    }

    /// Forgets the own late answers kept until `now` or before.
    pub fn expire(&mut self, now: Duration) {
        while let Some(i) = self.own().iter().position(|l| l.until() <= now) {
            self.remove_own(i);
        }
    }

    /// The pack answered a later query: its earlier answers came or never will.
    pub fn clear_own(&mut self) {
        self.own_len = 0;
    }

    /// Forgets everything (the link was reset).
    pub fn clear(&mut self) {
        self.own_len = 0;
        self.others_len = 0;
    }

    /// A late word of the driver's own that begins with `head` came: it and every one asked
    /// before it are done with (the pack answers in order). The driver's late answer it
    /// was, if any.
    pub fn answered_own(&mut self, head: &[u8]) -> Option<LateAnswer> {
        let i = self.own().iter().rposition(|l| l.overlaps(head))?;
        let found = self.own.get(i).copied();
        self.own.copy_within(i + 1..self.own_len, 0);
        self.own_len -= i + 1;
        found
    }

    /// Whether a word beginning with `head` may be a late answer (own or another pack's)
    /// still kept at `now`.
    pub fn matches(&self, head: &[u8], now: Duration) -> bool {
        self.own()
            .iter()
            .chain(self.others())
            .any(|l| l.until() > now && l.overlaps(head))
    }

    /// Whether a word beginning with `head` may be another pack's late answer.
    pub fn matches_other(&self, head: &[u8], now: Duration) -> bool {
        self.others()
            .iter()
            .any(|l| l.until() > now && l.overlaps(head))
    }

    /// The earliest instant an own late answer is forgotten.
    pub fn next_expiry(&self) -> Option<Duration> {
        self.own().iter().map(|l| l.until()).min()
    }
}

impl TmcpackDriver {
    /// Whether a query whose answer `expect` describes may go at `now`: its answer could
    /// not be told from a late one.
    pub(super) fn free(&self, now: Duration, expect: &Expect) -> bool {
        let (prefix, len) = answer_prefix(self.reply_address, expect);
        !self
            .late
            .matches(prefix.get(..len).unwrap_or_default(), now)
    }

    /// `pick` as it may go now: itself, or a probe in place of a query whose answer could
    /// be taken for a late one; `None` when no probe is free either (the line then waits
    /// for a late answer to come or expire).
    pub(super) fn avoid_late(&self, now: Duration, pick: Pick) -> Option<Pick> {
        match pick.expect {
            Some(expect) if !self.free(now, &expect) => self.probe(now),
            _ => Some(pick),
        }
    }

    /// A query whose answer cannot be confused with a late one and that changes nothing on
    /// the pack: `$21` of a motor, else `$30` of a channel (manual 8.4, 8.5).
    pub(super) fn probe(&self, now: Duration) -> Option<Pick> {
        let reply_to = self.reply_address;
        let motors = self.variant.motors();
        let velocity = (0..motors).map(|motor| {
            self.query(
                Request::QueryVelocity { motor, reply_to },
                Command::QueryVelocity,
                Some(motor),
                Purpose::Probe,
            )
        });
        // Channels 6 (external input) and 7 (supply) on every pack, then the motors'.
        let input = [6, 7].into_iter().chain(0..motors).map(|channel| {
            self.query(
                Request::ReadInput { channel, reply_to },
                Command::ReadInput,
                Some(channel),
                Purpose::Probe,
            )
        });
        velocity
            .chain(input)
            .find(|pick| pick.expect.is_some_and(|e| self.free(now, &e)))
    }

    /// Records the query `expect` unanswered at `now`: its answer is late from now on,
    /// unless the pack was declared not answering (beyond the bound, its answers are not
    /// waited for; its `$43` retries must not keep other packs from asking theirs).
    pub(super) fn remember_late(&mut self, now: Duration, expect: &Expect) {
        if self.declared_not_answering() {
            return;
        }
        let (prefix, len) = answer_prefix(self.reply_address, expect);
        self.late.add(
            prefix.get(..len).unwrap_or_default(),
            now + self.not_answering,
        );
    }

    /// Whether the pack is declared not answering and not found again yet.
    pub(super) fn declared_not_answering(&self) -> bool {
        self.phase == Phase::Identify
            && self.status.fault == Some(motion_drivers::DeviceFault::NotResponding)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn own_late_answers_go_in_order_and_an_answer_ends_those_before_it() {
        let mut set = LateSet::new();
        set.add(&[0xFE, 0x20, 0], 100 * MS);
        set.add(&[0xFE, 0x20, 1], 110 * MS);
        set.add(&[0xFE, 0x43], 120 * MS);
        assert!(set.matches(&[0xFE, 0x20, 1, 5], 50 * MS));
        assert!(!set.matches(&[0xFE, 0x20, 2], 50 * MS));
        assert!(!set.matches(&[0xFE, 0x20, 1], 110 * MS), "expired");
        // The late answer of the second came: the first never will.
        assert_eq!(
            set.answered_own(&[0xFE, 0x20, 1, 0, 0]).map(|l| l.until()),
            Some(110 * MS)
        );
        assert_eq!(set.own().len(), 1);
        assert!(set.matches(&[0xFE, 0x43], 50 * MS));
        assert_eq!(set.answered_own(&[0xFE, 0x21, 0]), None);
        set.expire(120 * MS);
        assert!(set.own().is_empty());
        assert_eq!(set.next_expiry(), None);
    }

    #[test]
    fn other_packs_late_answers_match_but_are_not_the_drivers_own() {
        let mut set = LateSet::new();
        set.set_others(&[LateAnswer::new(&[0xFE, 0x43], 100 * MS)]);
        assert!(set.matches(&[0xFE, 0x43, 149], 10 * MS));
        assert!(set.matches_other(&[0xFE, 0x43], 10 * MS));
        assert_eq!(set.answered_own(&[0xFE, 0x43, 149]), None);
        set.clear_own();
        assert!(
            set.matches(&[0xFE, 0x43], 10 * MS),
            "kept until its pack answers"
        );
        set.clear();
        assert!(!set.matches(&[0xFE, 0x43], 10 * MS));
    }

    #[test]
    fn the_set_keeps_the_newest_and_each_answer_once() {
        let mut set = LateSet::new();
        for i in 0..OWN_LATE as u8 + 3 {
            set.add(&[0xFE, 0x20, i], 100 * MS);
        }
        assert_eq!(set.own().len(), OWN_LATE);
        assert!(!set.matches(&[0xFE, 0x20, 0], MS), "the oldest went");
        set.add(&[0xFE, 0x20, 5], 200 * MS);
        assert_eq!(set.own().len(), OWN_LATE);
        assert_eq!(set.own().last().map(LateAnswer::until), Some(200 * MS));
    }
}
