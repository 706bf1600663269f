//! Whether the board still answers, and the verdicts that drop its goals (module docs,
//! "Faults"; docs/ARCHITECTURE.md "What evidence each board verdict needs").
//!
//! The board answers in the master's later transactions, in the order it made its packets
//! (replies in request order, stream packets between them by the time they became ready).
//! MISO held back on the host — an SPI socket peer or the server without CPU — comes
//! later, all of it, in that order. So:
//! - a request past its reply timeout is **lost** only once the board was heard for a
//!   whole reply window after that (packets made after its reply: it is not coming), or
//!   a later request's reply came first (skipped: the rx module); a reply held up on the
//!   host is waited for;
//! - a stream that stopped while the board still answers is **checked**: Get Stream
//!   Period (5), nothing voided; an answer that is not the period start-up wrote (0 at
//!   power-up) sends the driver back to its probe, whose reading is the reset's evidence;
//! - the board is **not answering** only when no valid packet at all came for `silence`
//!   ([`Qq2drvDriverConfig::silence`](super::Qq2drvDriverConfig::silence), the
//!   `silence_ms` key), judged up to the link's horizon.

use core::time::Duration;

use qq2drv::{PacketId, Request};

use super::wire::{Sent, Tag};
use super::{Phase, Qq2drvDriver};
use motion_drivers::{DeviceFault, Seconds, Verdict};

impl Qq2drvDriver {
    /// Replies that came for requests already declared lost (never paired).
    pub fn late_replies(&self) -> u64 {
        self.late_replies
    }

    /// A valid packet arrived at `now`: the board talks.
    pub(super) fn heard_packet(&mut self, now: Duration) {
        self.last_valid_at = Some(now);
        let timeout = self.reply_timeout();
        self.in_flight.for_each_mut(|sent| {
            if sent.heard_after.is_none() && now >= sent.at.saturating_add(timeout) {
                sent.heard_after = Some(now);
            }
        });
    }

    /// Requests whose replies are not coming: past their reply timeout, with the board
    /// heard for a reply window since (module docs).
    pub(super) fn judge_requests(&mut self, now: Duration, judged: Duration) {
        let timeout = self.reply_timeout();
        let last = self.last_valid_at;
        while let Some(oldest) = self.in_flight.front()
            && judged.saturating_sub(oldest.at) > timeout
            && oldest
                .heard_after
                .zip(last)
                .is_some_and(|(first, last)| last >= first.saturating_add(timeout))
        {
            self.in_flight.pop();
            self.status.timeouts = self.status.timeouts.saturating_add(1);
            self.on_lost(now, oldest);
        }
    }

    /// No valid packet for `silence`: not answering, with the evidence.
    pub(super) fn judge_silence(&mut self, now: Duration, judged: Duration) {
        let since = self
            .last_valid_at
            .or(self.listening_since)
            .unwrap_or(judged);
        let silent = judged.saturating_sub(since);
        if silent < self.config.silence || self.status.fault == Some(DeviceFault::NotResponding) {
            return;
        }
        let oldest = self.in_flight.front();
        let verdict = Verdict::new(
            DeviceFault::NotResponding,
            now,
            format_args!(
                "no valid packet on MISO since {}, the link heard until {}: {} ms of silence \
                 (silence_ms {}); {} requests unanswered{}",
                Seconds(since),
                Seconds(judged),
                silent.as_millis(),
                self.config.silence.as_millis(),
                self.in_flight.len(),
                Oldest(oldest),
            ),
        );
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        self.not_responding(verdict);
        if self.phase == Phase::Running {
            self.restart(now);
        }
    }

    /// A stream that stopped is checked with Get Stream Period, at most once a stall time.
    pub(super) fn judge_stream(&mut self, judged: Duration) {
        let stalled = judged.saturating_sub(self.last_stream_at) > self.stall_timeout();
        let checking = self
            .in_flight
            .iter()
            .any(|sent| matches!(sent.tag, Tag::Check));
        if stalled && !checking && judged >= self.check_after {
            self.check_due = true;
        }
    }

    /// Writes the stream check (Get Stream Period).
    pub(super) fn write_check(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        let request = Request::GetStreamPeriod;
        let len = request.encode(buf).ok()?;
        self.in_flight.push(Sent {
            id: request.id(),
            at: now,
            number: self.io_stamps.next_number(),
            tag: Tag::Check,
            heard_after: None,
        });
        self.check_due = false;
        Some(len)
    }

    /// The stream check's answer: the period start-up wrote (the stream was only held up,
    /// or starved: checked again a stall time later), or not (back to the probe).
    pub(super) fn checked(&mut self, now: Duration, period: Option<u16>) {
        self.check_after = now.saturating_add(self.stall_timeout());
        if period.is_some_and(|period| period != self.config.stream_period_units()) {
            // The probe reads the whole layout; its evaluation is the reset's evidence.
            self.restart(now);
        }
    }

    /// The board does not answer (`verdict` says why).
    pub(super) fn not_responding(&mut self, verdict: Verdict) {
        if self.status.fault != Some(DeviceFault::NotResponding) {
            self.status.declare(verdict);
        }
        self.raise(DeviceFault::NotResponding);
        self.status.online = false;
    }
}

/// ", the oldest (packet N) written at T" when a request is unanswered.
struct Oldest(Option<Sent>);

impl core::fmt::Display for Oldest {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Some(sent) => write!(
                f,
                ", the oldest (packet {}) written at {}",
                PacketId::as_u8(sent.id),
                Seconds(sent.at)
            ),
            None => Ok(()),
        }
    }
}
