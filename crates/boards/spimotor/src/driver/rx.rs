//! What the driver does with the MISO bytes of its transactions: the start-up's
//! identification and serial number, the presence check, the survey's and the stepper's
//! readings (module docs, "Faults").

use core::time::Duration;

use spimotor::{Identification, ReadPort, Reply, SerialNumber};

use super::wire::{self, Op, Sent};
use super::{
    CONFIRMATIONS, OFFLINE_RETRY_PERIOD, Phase, RETRY_PERIOD, START_ATTEMPTS, SpimotorDriver,
};
use motion_drivers::{DeviceFault, Seconds, Verdict};

/// What a read's MISO shows: nobody driving it (all 0xFF), or something else.
struct Undriven<'a>(&'a [u8]);

impl core::fmt::Display for Undriven<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let data = self.0.get(spimotor::REPLY_OFFSET..).unwrap_or_default();
        if data.iter().all(|b| *b == 0xFF) {
            f.write_str("MISO all 0xFF, nobody drives it")
        } else {
            f.write_str("not the identification the board gave at start-up")
        }
    }
}

impl SpimotorDriver {
    /// MISO bytes: reassembled per transaction, each completed one handled.
    pub(super) fn receive(&mut self, now: Duration, mut bytes: &[u8]) {
        bytes = self.drop_late(bytes);
        while !bytes.is_empty() {
            let (taken, complete) = self.in_flight.take(bytes);
            if taken == 0 {
                // Bytes for nothing in flight (late MISO after a timeout): ignore them.
                self.bad_reply();
                return;
            }
            let rest = bytes.get(taken..).unwrap_or(&[]);
            if let Some((sent, miso)) = complete {
                let mut copy = [0u8; wire::MAX_TRANSACTION];
                let len = miso.len().min(copy.len());
                copy[..len].copy_from_slice(&miso[..len]);
                self.complete(now, sent, &copy[..len]);
            }
            bytes = rest;
        }
    }

    /// Fresh, consistent data arrived: faults other than a down link clear.
    pub(super) fn refreshed(&mut self, now: Duration) {
        self.refreshed_at = Some(now);
        self.presence_misses = 0;
        if self.link_up {
            self.status.fault = None;
        }
    }

    pub(super) fn good_reply(&mut self) {
        self.status.replies = self.status.replies.saturating_add(1);
    }

    pub(super) fn bad_reply(&mut self) {
        self.status.bad_replies = self.status.bad_replies.saturating_add(1);
    }

    /// Handles one completed transaction.
    pub(super) fn complete(&mut self, now: Duration, sent: Sent, miso: &[u8]) {
        let Op::Read(port, _) = sent.op else {
            return; // MISO of a write carries nothing.
        };
        let reply = Reply::decode(port, miso);
        match (self.phase, port) {
            (Phase::Identify { attempts, .. }, ReadPort::Identification) => {
                match reply.ok().and_then(valid_identification) {
                    Some(id) => {
                        self.good_reply();
                        self.identification = Some(id);
                        self.phase = Phase::Serial;
                    }
                    None => {
                        let attempts = attempts.saturating_add(1);
                        let retry = if attempts >= START_ATTEMPTS {
                            if self.status.fault != Some(DeviceFault::NotResponding) {
                                let address = self.config.address.get();
                                self.status.declare(Verdict::new(
                                    DeviceFault::NotResponding,
                                    now,
                                    format_args!(
                                        "the identification (read port 0x01) at address \
                                         0x{address:02x} read {attempts} times without a valid \
                                         string, the last at {}: {}",
                                        Seconds(now),
                                        Undriven(miso),
                                    ),
                                ));
                            }
                            self.status.timeouts = self.status.timeouts.saturating_add(1);
                            self.raise(DeviceFault::NotResponding);
                            self.status.online = false;
                            OFFLINE_RETRY_PERIOD
                        } else {
                            RETRY_PERIOD
                        };
                        self.phase = Phase::Identify {
                            attempts,
                            next_at: now.saturating_add(retry),
                        };
                    }
                }
            }
            (Phase::Serial, ReadPort::Serial) => {
                let serial = match reply {
                    Ok(Reply::Serial(serial)) => {
                        self.good_reply();
                        serial
                    }
                    _ => SerialNumber::default(),
                };
                self.set_firmware(serial);
                if self.is_stepper() {
                    self.begin_survey();
                } else {
                    self.status.online = true;
                    self.phase = Phase::Running;
                    self.next_poll_at = now;
                    self.polls_done = 0;
                    self.configure(now, false);
                }
            }
            (Phase::Survey, _) => match reply {
                Ok(reply) => self.survey_reading(now, reply, sent.at),
                Err(_) => self.bad_reply(),
            },
            (Phase::Running, ReadPort::Identification) => {
                let matches = reply.ok().and_then(valid_identification).is_some_and(|id| {
                    self.identification
                        .is_some_and(|known| known.as_bytes() == id.as_bytes())
                });
                if matches {
                    self.good_reply();
                    self.presence_misses = 0;
                    if !self.is_stepper() {
                        self.refreshed(now);
                    }
                } else {
                    self.bad_reply();
                    self.presence_misses = self.presence_misses.saturating_add(1);
                    if self.presence_misses >= CONFIRMATIONS {
                        let address = self.config.address.get();
                        let verdict = Verdict::new(
                            DeviceFault::NotResponding,
                            now,
                            format_args!(
                                "the presence read (port 0x01) at address 0x{address:02x} \
                                 failed {CONFIRMATIONS} times in a row, the last at {}: {}",
                                Seconds(now),
                                Undriven(miso),
                            ),
                        );
                        self.absent(now, verdict);
                    }
                }
            }
            (Phase::Running, _) if self.is_stepper() => match reply {
                Ok(reply) => self.stepper_reading(now, reply, sent),
                Err(_) => self.bad_reply(),
            },
            // An answer to a read of an earlier phase: nothing to learn from it.
            _ => {}
        }
    }
}

/// An identification worth believing: non-empty printable ASCII.
fn valid_identification(reply: Reply) -> Option<Identification> {
    match reply {
        Reply::Identification(id)
            if !id.as_bytes().is_empty()
                && id
                    .as_bytes()
                    .iter()
                    .all(|b| b.is_ascii_graphic() || *b == b' ') =>
        {
            Some(id)
        }
        _ => None,
    }
}
