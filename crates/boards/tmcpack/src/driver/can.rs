//! The pack on a CAN link (manual 6.2): the same driver, framed as CAN telegrams.
//!
//! Only the framing and the line timing differ from RS-232 / RS-485; the requests, the
//! replies, the polling plan and the one request in flight are the same:
//!
//! - **framing**: a request is the telegram `address << 3` with the word's command and
//!   P0..P6 ("Telegrams with a fixed length of 8 bytes"), written to the link as one
//!   16-byte CAN record; a reply is the telegram `reply address << 3` ("For responding the
//!   address is shifted to the left by 3 bits"), turned back into the 9-byte word the
//!   reply hunter takes. Records with other identifiers (other nodes, other packs'
//!   requests) are not for this driver and are skipped without counting a bad reply.
//! - **timing**: no switch-over, no packet timeout (a CAN frame arrives whole or not at
//!   all): a request occupies the bus for its frame time; the pack processes each command
//!   in about 2 ms from its 16-command cache. The driver mirrors that cache
//!   ([`tmcpack::CanCache`]) to know when an answer can come (the end of the query's
//!   processing behind the commands before it, plus the answer's frame time, one more
//!   [`PACK_PROCESSING`](super::PACK_PROCESSING) for the "approx." and the host's latency),
//!   and keeps at most [`CACHE_LIMIT`] commands in
//!   it — half the cache, as the manual's "approx. 2 ms" may be longer on a busy pack — so
//!   a burst (the start-up's forty-odd commands, a coordinated move's goals) never loses a
//!   command to a full cache.
//! - **not sent**: `$40` (RS-232 baud rate and switch-over) and `$41` (RS-232 packet
//!   timeout) configure the serial line, which a CAN link does not use.

use core::time::Duration;

use motion_base::{CAN_RECORD_LEN, CanRecord};
use tmcpack::{CAN_LEN, CanCache, FRAME_LEN, Request, RequestFrame, Word, can_command_id};

/// Commands the driver lets wait in the pack's cache at once (of its 16).
pub const CACHE_LIMIT: usize = tmcpack::CAN_CACHE_COMMANDS / 2;

/// The driver's end of a CAN link.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct CanLine {
    /// Bus time of one 8-byte telegram.
    pub frame_time: Duration,
    /// The driver's mirror of the pack's command cache.
    pub cache: CanCache<()>,
    /// A record received in part.
    rx: [u8; CAN_RECORD_LEN],
    rx_len: usize,
    /// Telegrams received for the driver's reply identifier.
    pub answers: u64,
    /// Records received that were not for this driver (other identifiers).
    pub foreign: u64,
}

impl CanLine {
    pub fn new(bitrate: u32) -> Self {
        let frame = CanRecord::standard(0x008, &[0; CAN_LEN]).unwrap_or(CanRecord {
            can_id: 0x008,
            len: 8,
            data: [0; 8],
        });
        Self {
            frame_time: frame.time(bitrate),
            cache: CanCache::new(),
            rx: [0; CAN_RECORD_LEN],
            rx_len: 0,
            answers: 0,
            foreign: 0,
        }
    }

    /// The link was reset: nothing is in flight any more, on either side.
    pub fn reset(&mut self) {
        self.cache.clear();
        self.rx_len = 0;
    }

    /// Whether a command may go to the pack at `now` (its cache has room to spare).
    pub fn may_send(&self, now: Duration) -> bool {
        self.cache.waiting(now) < CACHE_LIMIT
    }

    /// Writes `request` to the pack at `address` into `buf` as one CAN record; returns its
    /// length. The command is counted into the cache mirror.
    pub fn encode(
        &mut self,
        now: Duration,
        address: u8,
        request: Request,
        buf: &mut [u8],
    ) -> Option<usize> {
        let telegram = RequestFrame::new(address, request).to_can().ok()?;
        let record = CanRecord::standard(telegram.id, &telegram.data)?;
        buf.get_mut(..CAN_RECORD_LEN)?
            .copy_from_slice(&record.to_bytes());
        // The pack takes it in when its frame has crossed the bus.
        let _ = self.cache.push(now + self.frame_time, ());
        Some(CAN_RECORD_LEN)
    }

    /// The reply deadline of a query written at `now` (after [`encode`](Self::encode)
    /// counted it): the end of its processing behind the commands before it, its answer's
    /// frame, and `slack` (the "approx." of the 2 ms, the host's latency).
    pub fn reply_deadline(&self, now: Duration, slack: Duration) -> Duration {
        let done = self
            .cache
            .idle_at(now)
            .max(now + self.frame_time + self.cache.command_time());
        done + self.frame_time + slack
    }

    /// Takes received bytes (whole records, possibly cut anywhere) and hands each complete
    /// answer for `reply_address` to `answer` as the 9-byte word it would be on RS-232.
    pub fn receive(&mut self, reply_address: u8, bytes: &[u8], mut answer: impl FnMut(Word)) {
        let Ok(reply_id) = can_command_id(reply_address) else {
            return;
        };
        for &byte in bytes {
            if let Some(slot) = self.rx.get_mut(self.rx_len) {
                *slot = byte;
            }
            self.rx_len += 1;
            if self.rx_len < CAN_RECORD_LEN {
                continue;
            }
            self.rx_len = 0;
            let Some(record) = CanRecord::from_bytes(&self.rx) else {
                self.foreign += 1;
                continue;
            };
            if record.standard_id() != Some(reply_id) || usize::from(record.len) != CAN_LEN {
                self.foreign += 1;
                continue;
            }
            let mut word = [0u8; FRAME_LEN];
            word[0] = reply_address;
            word[1..].copy_from_slice(record.payload());
            self.answers += 1;
            answer(word);
        }
    }
}

impl super::TmcpackDriver {
    /// Received bytes on a CAN link: the answer to the query in flight among the
    /// telegrams for the reply identifier.
    pub(super) fn receive_can(&mut self, now: Duration, bytes: &[u8]) {
        let Some(mut line) = self.can.take() else {
            return;
        };
        let reply_address = self.reply_address;
        line.receive(reply_address, bytes, |word| self.on_can_answer(now, word));
        self.can = Some(line);
    }

    /// One telegram for the reply identifier, as its RS-232 word.
    fn on_can_answer(&mut self, now: Duration, word: Word) {
        let (expect, sent_at) = match self.wire {
            super::wire::Wire::Awaiting {
                expect, sent_at, ..
            } => (Some(expect), sent_at),
            _ => (None, Duration::ZERO),
        };
        // A telegram is whole: it is the answer, a late one, or neither.
        self.hunter.reset();
        let want = super::hunter::Want {
            reply_address: self.reply_address,
            expect,
            late: &self.late,
            now,
        };
        match (self.hunter.push(&want, &word).0, expect) {
            (Some(super::hunter::Found::Late(word)), _) => self.on_late_word(now, word),
            (Some(super::hunter::Found::Answer(reply)), Some(expect)) => {
                // No line to turn around on CAN: the bus is free for the next request at
                // once.
                self.wire = super::wire::Wire::Idle;
                self.on_reply(now, expect, sent_at, reply);
            }
            _ => self.status.bad_replies = self.status.bad_replies.saturating_add(1),
        }
    }

    /// Forgets what the cache mirror knows is done by `now`.
    pub(super) fn prune_can(&mut self, now: Duration) {
        if let Some(line) = self.can.as_mut() {
            while line.cache.pop_done(now).is_some() {}
        }
    }

    /// When the cache mirror lets a command go again, while it holds them back.
    pub(super) fn can_held_until(&self) -> Option<Duration> {
        let line = self.can.as_ref()?;
        (line.cache.len() >= CACHE_LIMIT)
            .then(|| line.cache.fewer_than_at(Duration::ZERO, CACHE_LIMIT))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tmcpack::Command;

    #[test]
    fn a_query_is_one_record_to_address_shl_3() {
        let mut line = CanLine::new(250_000);
        assert_eq!(line.frame_time, Duration::from_micros(444));
        let mut buf = [0u8; 32];
        let len = line
            .encode(
                Duration::ZERO,
                2,
                Request::QueryPosition {
                    motor: 1,
                    reply_to: 0xFE,
                },
                &mut buf,
            )
            .expect("fits");
        assert_eq!(len, 16);
        assert_eq!(
            buf[..16],
            [
                0x10, 0x00, 0, 0, 8, 0, 0, 0, 0x20, 0x01, 0xFE, 0, 0, 0, 0, 0
            ]
        );
        // Processing ends 2 ms after the frame crossed the bus; the answer's frame and the
        // margin follow.
        let slack = Duration::from_millis(7);
        assert_eq!(
            line.reply_deadline(Duration::ZERO, slack),
            Duration::from_micros(444 + 2000 + 444) + slack
        );
    }

    #[test]
    fn answers_for_the_reply_id_become_words_and_others_are_skipped() {
        let mut line = CanLine::new(500_000);
        let answer = CanRecord::standard(0x7F0, &[0x20, 1, 0xD0, 0x07, 0, 0, 5, 0]).expect("ok");
        let other = CanRecord::standard(0x010, &[0x20, 1, 0xFE, 0, 0, 0, 0, 0]).expect("ok");
        let mut bytes = other.to_bytes().to_vec();
        bytes.extend_from_slice(&answer.to_bytes());
        let mut words = Vec::new();
        // Cut anywhere.
        for chunk in bytes.chunks(5) {
            line.receive(0xFE, chunk, |w| words.push(w));
        }
        assert_eq!(
            words,
            vec![[0xFE, 0x20, 1, 0xD0, 0x07, 0, 0, 5, 0]],
            "the $20 answer"
        );
        assert_eq!((line.answers, line.foreign), (1, 1));
        assert_eq!(words[0][1], Command::QueryPosition.code());
    }

    #[test]
    fn the_cache_mirror_holds_the_sender_back_at_half_the_cache() {
        let mut line = CanLine::new(1_000_000);
        let mut buf = [0u8; 16];
        let t = Duration::from_millis(1);
        for _ in 0..CACHE_LIMIT {
            assert!(line.may_send(t));
            line.encode(t, 1, Request::HardwareReset, &mut buf)
                .expect("fits");
        }
        assert!(!line.may_send(t));
        let again = line.cache.fewer_than_at(t, CACHE_LIMIT);
        assert!(
            again > t && again <= t + Duration::from_millis(3),
            "{again:?}"
        );
        assert!(line.may_send(again));
    }
}

#[cfg(test)]
mod driver_tests {
    use super::*;
    use crate::driver::{TmcpackChannel, TmcpackDriver, TmcpackDriverConfig};
    use motion_drivers::Driver;
    use tmcpack::{Action, Reply, ReplyFrame};

    fn answer(reply: Reply) -> [u8; CAN_RECORD_LEN] {
        let telegram = ReplyFrame::new(0xFE, reply).to_can().expect("valid");
        CanRecord::standard(telegram.id, &telegram.data)
            .expect("valid")
            .to_bytes()
    }

    /// The request in a record the driver wrote.
    fn request(bytes: &[u8]) -> Request {
        let record = CanRecord::from_bytes(bytes.try_into().expect("one record")).expect("ok");
        assert_eq!(record.standard_id(), Some(0x008), "to address 1 << 3");
        let mut word = [0u8; FRAME_LEN];
        word[0] = 1;
        word[1..].copy_from_slice(record.payload());
        RequestFrame::decode(&word).expect("a request").request
    }

    /// On the fake clock: `$43` and `$28` go out as telegrams and their answers come back as
    /// telegrams; the configuration follows without `$40` and `$41`, never more than
    /// [`CACHE_LIMIT`] commands ahead of the pack's processing.
    #[test]
    fn the_driver_starts_a_pack_over_can() {
        let mut channels = [None; 6];
        channels[0] = Some(TmcpackChannel::default());
        let mut driver = TmcpackDriver::new(TmcpackDriverConfig {
            channels,
            can_bitrate: Some(250_000),
            ..TmcpackDriverConfig::default()
        });
        let mut buf = [0u8; 64];
        let mut now = Duration::ZERO;
        let sent = driver.poll_transmit(now, &mut buf).expect("$43");
        assert_eq!(sent.len, CAN_RECORD_LEN);
        assert_eq!(request(&buf[..16]), Request::UnitInfo { reply_to: 0xFE });
        assert!(
            driver.poll_transmit(now, &mut buf).is_none(),
            "one in flight"
        );
        now += Duration::from_millis(3);
        driver.handle_rx(
            now,
            &answer(Reply::UnitInfo {
                firmware: 149,
                reset: true,
                temperature: 30,
                serial: 7,
            }),
        );
        let sent = driver.poll_transmit(now, &mut buf).expect("$28");
        assert_eq!(sent.len, CAN_RECORD_LEN);
        assert!(matches!(
            request(&buf[..16]),
            Request::QueryActions { reply_to: 0xFE, .. }
        ));
        now += Duration::from_millis(3);
        driver.handle_rx(
            now,
            &answer(Reply::Actions {
                actions: [Action::Inactive; 6],
            }),
        );
        let mut plan = Vec::new();
        let mut times = Vec::new();
        for _ in 0..2000 {
            driver.handle_timeout(now);
            if let Some(sent) = driver.poll_transmit(now, &mut buf) {
                let r = request(&buf[..sent.len]);
                if matches!(r, Request::QueryPosition { .. } | Request::UnitInfo { .. }) {
                    break;
                }
                plan.push(r);
                times.push(now);
            }
            now += Duration::from_micros(100);
        }
        assert!(plan.len() >= 8, "{plan:?}");
        assert!(
            !plan
                .iter()
                .any(|r| matches!(r, Request::SetBaud { .. } | Request::PacketTimeout { .. })),
            "{plan:?}"
        );
        // At most CACHE_LIMIT commands within any 2 ms × CACHE_LIMIT window.
        let window = tmcpack::CAN_COMMAND_TIME * CACHE_LIMIT as u32;
        for (i, t) in times.iter().enumerate() {
            let within = times[i..].iter().take_while(|u| **u < *t + window).count();
            assert!(within <= CACHE_LIMIT + 1, "{within} commands from {t:?}");
        }
    }
}
