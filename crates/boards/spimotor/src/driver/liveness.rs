//! Whether the board is there, and the verdicts that drop its goals (module docs,
//! "Faults"; docs/ARCHITECTURE.md "What evidence each board verdict needs").
//!
//! An SPI transaction's MISO bytes come back with it: a spidev transfer returns them, an
//! SPI socket peer answers each transaction with exactly its length. What the host holds
//! back — a peer or the server without CPU — comes later, every byte, in order. So:
//! - MISO that has not come back is **waited for**, up to `silence`
//!   ([`SpimotorDriverConfig::silence`](super::SpimotorDriverConfig::silence), the
//!   `silence_ms` key); then the board is not answering, and the bytes still owed by the
//!   transactions it gave up on are recognised when they come
//!   ([`SpimotorDriver::late_miso`]) and never taken for a later transaction's;
//! - what comes back is **proof** on its own: MISO that nobody drives reads 0xFF (an
//!   absent board: identification, presence reads, polls of position −1, target −1, delay
//!   255), power-on registers (position and target 0, or the step delay 200) a board that
//!   lost its registers — each only when it repeats ([`CONFIRMATIONS`](super::CONFIRMATIONS),
//!   [`START_ATTEMPTS`](super::START_ATTEMPTS)), never on one corrupted transfer.

use core::time::Duration;

use super::SpimotorDriver;
use super::wire::Op;
use motion_drivers::{DeviceFault, Seconds, Verdict};

impl SpimotorDriver {
    /// MISO bytes that came back for transactions given up on (the board was declared
    /// not answering before they came): recognised and dropped.
    pub fn late_miso(&self) -> u64 {
        self.late_miso
    }

    /// MISO of the oldest transaction in flight not back for `silence`, judged up to the
    /// link's horizon: not answering.
    pub(super) fn judge_miso(&mut self, now: Duration) {
        let judged = self.io_stamps.judged(now);
        let Some(oldest) = self.in_flight.oldest() else {
            return;
        };
        let waited = judged.saturating_sub(oldest.at);
        if waited < self.config.silence {
            return;
        }
        let verdict = Verdict::new(
            DeviceFault::NotResponding,
            now,
            format_args!(
                "MISO of {} transactions not back; the oldest ({}) written at {}, the link \
                 heard until {}: {} ms (silence_ms {})",
                self.in_flight.len(),
                OpText(oldest.op),
                Seconds(oldest.at),
                Seconds(judged),
                waited.as_millis(),
                self.config.silence.as_millis(),
            ),
        );
        // Their bytes still come, before any later transaction's: dropped when they do.
        self.discard_miso = self.discard_miso.saturating_add(self.in_flight.owed());
        self.in_flight.clear();
        self.absent(now, verdict);
    }

    /// Drops the front of `bytes` still owed by transactions given up on; the rest.
    pub(super) fn drop_late<'a>(&mut self, bytes: &'a [u8]) -> &'a [u8] {
        let late = self.discard_miso.min(bytes.len());
        self.discard_miso -= late;
        self.late_miso = self.late_miso.saturating_add(late as u64);
        bytes.get(late..).unwrap_or_default()
    }

    /// The board is not there (`verdict` says why): not answering, started again.
    pub(super) fn absent(&mut self, now: Duration, verdict: Verdict) {
        if self.status.fault != Some(DeviceFault::NotResponding) {
            self.status.declare(verdict);
        }
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        self.raise(DeviceFault::NotResponding);
        self.restart(now, super::START_ATTEMPTS);
    }

    /// The board lost its registers (`verdict` says which reading showed it): started
    /// again, goals lost.
    pub(super) fn board_reset(&mut self, now: Duration, verdict: Verdict) {
        self.status.declare(verdict);
        self.status.resets = self.status.resets.saturating_add(1);
        self.raise(DeviceFault::Reset);
        self.stepper.homed = false;
        self.restart(now, 0);
    }
}

/// A transaction in words: `read port 0x40` / `write port 0x43`.
pub(super) struct OpText(pub(super) Op);

impl core::fmt::Display for OpText {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Op::Read(port, _) => write!(f, "read port 0x{:02x}", port.port()),
            Op::Write(write) => write!(f, "write port 0x{:02x}", write.port()),
        }
    }
}
