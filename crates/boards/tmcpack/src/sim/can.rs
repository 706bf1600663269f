//! The simulated pack's CAN interface (manual 6.2), a [`CanDevice`] on a simulated CAN bus.
//!
//! What it models, with the manual's words:
//!
//! - "The address of the unit (upper 8 address bits) can be set via rotary switches … The
//!   lower 3 address bits are fixed to "000"": the pack takes the telegrams with identifier
//!   `address << 3` and 8 data bytes (command, P0..P6); others are not its own
//!   ([`CanStats::foreign`]); `…001` telegrams (6.3, bytes for its RS-232 port) are counted
//!   and not forwarded ([`CanStats::rs232`]).
//! - "The PACK has an internal cache for 16 CAN-commands, internal processing time is
//!   approx. 2 ms per command": telegrams wait in a 16-command cache ([`tmcpack::CanCache`])
//!   and are executed one after the other, each [`TmcpackSimConfig::can_command_time`]
//!   (2 ms) after the previous one ended; a telegram that arrives while 16 wait is lost
//!   ([`CanStats::overflowed`]). A command acts, and answers, at the end of its processing.
//! - "For responding the address is shifted to the left by 3 bits": an answer goes out as
//!   the telegram `response address << 3` as soon as its command is processed (no
//!   switch-over on CAN); a response address 0 has no valid identifier and gets no answer
//!   ([`CanStats::unanswerable`]).
//! - "After receiving the first valid instruction via CAN, control via RS 232 or RS 485
//!   will be terminated": from then on words on the serial side are ignored
//!   ([`CanStats::serial_ignored`]) and every answer, the delayed `$28` included, goes out
//!   on CAN, until a reset ($CC or a power cycle) initialises both interfaces again.
//! - While the pack boots after a reset it hears nothing on CAN either.
//!
//! [`TmcpackSimConfig::can_command_time`]: super::TmcpackSimConfig

use core::time::Duration;
use std::collections::VecDeque;

use motion_base::CanRecord;
use motion_link::sim::CanDevice;
use tmcpack::{CAN_LEN, CanCache, CanChannel, CanFrame, Reply, ReplyFrame, RequestFrame};

use super::TmcpackSim;

/// What the pack saw on its CAN interface.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CanStats {
    /// Telegrams for the pack's identifier taken into the cache.
    pub cached: u64,
    /// Telegrams lost because 16 commands were waiting (manual 6.2: "an internal cache for
    /// 16 CAN-commands").
    pub overflowed: u64,
    /// Commands processed and executed.
    pub executed: u64,
    /// Telegrams for the pack's identifier that did not decode (length, command, range,
    /// a motor the variant lacks).
    pub invalid: u64,
    /// Telegrams for other identifiers (other nodes, other packs' answers).
    pub foreign: u64,
    /// Telegrams for the pack's RS-232 port (`…001`, 6.3; not forwarded here).
    pub rs232: u64,
    /// Telegrams lost while the pack booted.
    pub lost_booting: u64,
    /// Answers sent.
    pub answers: u64,
    /// Answers not sent: the response address was 0, no valid identifier.
    pub unanswerable: u64,
    /// Serial words ignored because CAN had taken over.
    pub serial_ignored: u64,
    /// The most commands that waited in the cache at once.
    pub deepest: u64,
}

/// The pack's CAN side: its cache, its answers waiting for the bus, its counters.
#[derive(Debug, Clone)]
pub(super) struct CanSide {
    cache: CanCache<CanFrame>,
    outbox: VecDeque<(Duration, CanRecord)>,
    /// "After receiving the first valid instruction via CAN, control via RS 232 or RS 485
    /// will be terminated."
    pub(super) active: bool,
    pub(super) stats: CanStats,
}

impl CanSide {
    pub(super) fn new(command_time: Duration) -> Self {
        Self {
            cache: CanCache::with_command_time(command_time),
            outbox: VecDeque::new(),
            active: false,
            stats: CanStats::default(),
        }
    }

    /// A reset initialises the interface again: nothing cached, nothing to send, the
    /// serial side listens again.
    pub(super) fn reset(&mut self) {
        self.cache.clear();
        self.outbox.clear();
        self.active = false;
    }
}

impl TmcpackSim {
    /// Counters of the CAN interface.
    pub fn can_stats(&self) -> CanStats {
        self.can.stats
    }

    /// Whether CAN has taken over from RS-232 / RS-485 (the first valid CAN instruction).
    pub fn can_active(&self) -> bool {
        self.can.active
    }

    /// Commands waiting in the CAN cache at `now`.
    pub fn can_cached(&self, now: Duration) -> usize {
        self.can.cache.waiting(now)
    }

    /// Queues `reply` to `reply_to` on CAN, ready at `t` (the end of its command's
    /// processing).
    pub(super) fn send_can(&mut self, t: Duration, reply_to: u8, reply: Reply) {
        let Ok(telegram) = ReplyFrame::new(reply_to, reply).to_can() else {
            self.can.stats.unanswerable += 1;
            return;
        };
        if let Some(record) = CanRecord::standard(telegram.id, &telegram.data) {
            self.can.outbox.push_back((t, record));
            self.can.stats.answers += 1;
        }
    }

    /// Executes every cached command whose processing ended by `now`, in order, each at
    /// its own instant.
    fn process_can(&mut self, now: Duration) {
        while let Some((done, telegram)) = self.can.cache.pop_done(now) {
            self.advance(done);
            match RequestFrame::from_can(&telegram) {
                Ok(frame)
                    if frame
                        .request
                        .motor()
                        .is_none_or(|m| m < self.cfg.variant.motors()) =>
                {
                    self.can.active = true;
                    self.can.stats.executed += 1;
                    self.execute(done, frame.request);
                }
                _ => self.can.stats.invalid += 1,
            }
        }
    }
}

impl CanDevice for TmcpackSim {
    fn receive(&mut self, now: Duration, record: &CanRecord) {
        self.process_can(now);
        self.advance(now);
        let Some(id) = record.standard_id() else {
            self.can.stats.foreign += 1;
            return;
        };
        let mine = match tmcpack::split_can_id(id) {
            Ok((address, channel)) if address == self.st.address => Some(channel),
            _ => None,
        };
        match mine {
            None => self.can.stats.foreign += 1,
            Some(_) if self.deaf_until.is_some_and(|d| now < d) => {
                self.can.stats.lost_booting += 1;
            }
            Some(CanChannel::Rs232) => self.can.stats.rs232 += 1,
            Some(CanChannel::Command) => {
                let mut data = [0u8; CAN_LEN];
                data.copy_from_slice(&record.data);
                let telegram = CanFrame {
                    id,
                    len: record.len,
                    data,
                };
                match self.can.cache.push(now, telegram) {
                    Ok(_) => {
                        self.can.stats.cached += 1;
                        let depth = self.can.cache.waiting(now) as u64;
                        self.can.stats.deepest = self.can.stats.deepest.max(depth);
                    }
                    Err(_) => self.can.stats.overflowed += 1,
                }
            }
        }
    }

    fn transmit(&mut self, now: Duration) -> Option<(Duration, CanRecord)> {
        self.process_can(now);
        self.advance(now);
        match self.can.outbox.front() {
            Some((ready, _)) if *ready <= now => self.can.outbox.pop_front(),
            _ => None,
        }
    }

    fn next_event(&self, now: Duration) -> Option<Duration> {
        let tick = self
            .st
            .delayed
            .map(|_| self.next_tick.unwrap_or(now).max(now));
        [
            self.can.cache.next_done(),
            self.can.outbox.front().map(|(ready, _)| *ready),
            tick,
            self.deaf_until.filter(|&d| d > now),
        ]
        .into_iter()
        .flatten()
        .min()
    }
}
