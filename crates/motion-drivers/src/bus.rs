//! Several drivers on one link: who may send next, and whose bytes are these.
//!
//! A [`LinkBus`] owns the drivers of one link and enforces the wire rules that no single
//! driver can see:
//! - stream links (RS-232/RS-485/USB serial): at most one request in flight on the whole
//!   bus (Trinamic manual 7.1); the next sender is the driver with the most urgent
//!   message ([`Priority`]), round-robin among equals, so stops go before everything else
//!   and commands before polls;
//!   received bytes belong to the driver whose reply is awaited (or, when none is, to the
//!   last one that sent: a late reply) — with one driver, everything is its own;
//! - SPI links: every transaction is owned by the driver that wrote it, and the same
//!   number of MISO bytes is routed back to it in order.
//!
//! It also routes the link's write reports ([`LinkBus::handle_written`]) to the driver
//! whose message went out, in the order the messages were made, and the link's horizon
//! ([`LinkBus::handle_heard`]) to every driver (see [`Driver`]: reply timeouts run from
//! the write, silence is judged up to the horizon). A shell that does not stamp leaves
//! the bus unstamped: each message then counts as written when it is made.
//!
//! On a stream link with several drivers it also shares the answers each driver's board
//! may still send late ([`Driver::late_answers`], module `late`): before it picks the next
//! sender and before it routes received bytes, every driver learns the others'
//! ([`Driver::handle_late_answers`]), so that no driver asks a question whose answer would
//! look like another board's late one, and none pairs another board's late answer with its
//! own request (the Trinamic packs of one RS-485 bus all answer to the same response
//! address, and an answer does not say which pack sent it).
//!
//! On a stream link it also keeps the line rate: a driver that changes its board's rate
//! says at which rate its next message must go ([`Driver::line_rate`]); when that differs
//! from the link's, the bus notes the change before it hands the message out, and the
//! shell, asking [`LinkBus::take_rate_change`] after each message, changes the link's rate
//! before that message is written (after the messages before it went out at the old one).
//!
//! No allocation after construction: the SPI ownership queue and the queue of messages
//! not reported written have fixed capacities, and a full queue holds senders back.

use core::time::Duration;

use motion_base::{FixedQueue, LinkKind};

use crate::driver::{Driver, Priority, Transmit};
use crate::late::{LATE_ANSWERS, LateAnswer};

/// Transactions whose MISO bytes may be outstanding at once on an SPI bus.
pub const SPI_PENDING_CAPACITY: usize = 64;

/// Messages one bus may send in one step (bounds the work of a step).
pub const MAX_SENDS_PER_STEP: usize = 16;

/// Messages whose write report may be outstanding at once on a stamped bus.
pub const UNWRITTEN_CAPACITY: usize = 64;

/// A message made and not reported written yet.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Unwritten {
    /// The driver that made it (index in config order).
    pub driver: usize,
    /// Its [`Transmit::goal_starts`].
    pub goal_starts: u8,
    /// The `now` it was made at.
    pub queued_at: Duration,
}

#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default)]
struct PendingMiso {
    driver: usize,
    remaining: usize,
    /// Stamped: when the transaction was written (once reported).
    written_at: Option<Duration>,
}

/// The drivers of one link and the arbitration between them. `D` is the driver type: the
/// server's is an enum of every registered board's driver (static dispatch on the tick
/// path); tests and tools use `Box<dyn Driver>`, the default.
#[derive(serde::Serialize, serde::Deserialize, Debug)]
pub struct LinkBus<D: Driver = Box<dyn Driver>> {
    kind: LinkKind,
    drivers: Vec<D>,
    /// Stream: the driver whose reply is awaited.
    in_flight: Option<usize>,
    /// Stream: the driver that sent last (receives unsolicited bytes).
    last_sender: usize,
    /// Round-robin start for the next pick.
    next_turn: usize,
    /// SPI: ring of transactions whose MISO bytes have not come back yet.
    pending: FixedQueue<PendingMiso, SPI_PENDING_CAPACITY>,
    /// Received bytes no driver could take (SPI bytes beyond every pending transaction).
    stray_bytes: u64,
    /// The shell reports writes and the horizon.
    stamped: bool,
    /// Stamped: messages made and not reported written, oldest first.
    unwritten: FixedQueue<Unwritten, UNWRITTEN_CAPACITY>,
    /// Stamped SPI, per driver: the write stamp of its newest transaction whose MISO bytes
    /// all came back — how far the board's output has been clocked out and seen.
    clocked: Vec<Option<Duration>>,
    /// Stream: the line rate the link runs at as far as the bus made it (`None`: as it was
    /// opened).
    rate: Option<u32>,
    /// Stream: a rate the link must take before the last message handed out.
    rate_change: Option<u32>,
    /// Stream with several drivers: some driver was last handed late answers of others
    /// (so an empty set must be handed once when they are gone).
    late_shared: bool,
}

impl<D: Driver> LinkBus<D> {
    /// A bus of `kind` with `drivers` (in config order; at least one).
    pub fn new(kind: LinkKind, drivers: Vec<D>) -> Self {
        Self {
            kind,
            in_flight: None,
            last_sender: 0,
            next_turn: 0,
            pending: FixedQueue::new(),
            stray_bytes: 0,
            stamped: false,
            unwritten: FixedQueue::new(),
            clocked: vec![None; drivers.len()],
            rate: None,
            rate_change: None,
            late_shared: false,
            drivers,
        }
    }

    /// The rate the link must take before the message [`poll_transmit`](Self::poll_transmit)
    /// handed out last is written (a driver's [`Driver::line_rate`] differed from the
    /// link's), taken: the shell changes the link's rate (after writing everything queued
    /// before) and then writes the message. `None` (almost always): no change.
    pub fn take_rate_change(&mut self) -> Option<u32> {
        self.rate_change.take()
    }

    /// The line rate the bus last asked the link to take since it was (re)opened.
    pub fn line_rate(&self) -> Option<u32> {
        self.rate
    }

    /// Whether the shell reports writes ([`handle_written`](Self::handle_written)) and the
    /// horizon ([`handle_heard`](Self::handle_heard)). Unstamped (the default), every
    /// message counts as written at the `now` it was made.
    pub fn set_stamped(&mut self, stamped: bool) {
        self.stamped = stamped;
        if !stamped {
            // Reports owed then never come; those messages keep the deadlines they were
            // made with.
            self.unwritten.clear();
        }
    }

    /// Whether the bus waits for write reports.
    pub fn stamped(&self) -> bool {
        self.stamped
    }

    /// The oldest message not reported written yet.
    pub fn oldest_unwritten(&self) -> Option<Unwritten> {
        self.unwritten.front()
    }

    /// The link wrote the oldest message not reported yet at `at`: its driver learns it.
    /// Returns that message (`None`: no report was owed, e.g. after the link went down).
    pub fn handle_written(&mut self, at: Duration) -> Option<Unwritten> {
        let message = self.unwritten.pop()?;
        if let Some(driver) = self.drivers.get_mut(message.driver) {
            driver.handle_written(at);
        }
        if self.kind == LinkKind::Spi {
            // The oldest transaction not stamped yet is this one (both queues are in the
            // order the messages were made).
            let mut stamped = false;
            self.pending.for_each_mut(|pending| {
                if !stamped && pending.written_at.is_none() {
                    pending.written_at = Some(at);
                    stamped = true;
                }
            });
        }
        Some(message)
    }

    /// The link's horizon `until`, for every driver, never below `floor` (see
    /// [`Driver::handle_heard`]). On SPI a board's output comes out only in the driver's own
    /// transactions: while some of them have not returned their MISO bytes, the driver's
    /// horizon is no later than the write of its newest transaction that did — what was
    /// clocked out after that has not been seen yet, whenever it arrives. (A driver with
    /// nothing outstanding has seen all there is.)
    pub fn handle_heard(&mut self, until: Duration, floor: Duration) {
        for (index, driver) in self.drivers.iter_mut().enumerate() {
            let outstanding = self.kind == LinkKind::Spi
                && self.stamped
                && self.pending.iter().any(|pending| pending.driver == index);
            let heard = if outstanding {
                let clocked = self.clocked.get(index).copied().flatten();
                until.min(clocked.unwrap_or(Duration::ZERO))
            } else {
                until
            };
            driver.handle_heard(heard.max(floor));
        }
    }

    /// Stream or SPI.
    pub fn kind(&self) -> LinkKind {
        self.kind
    }

    /// The drivers in config order.
    pub fn drivers(&self) -> &[D] {
        &self.drivers
    }

    /// Mutable access to one driver (goals).
    pub fn driver_mut(&mut self, index: usize) -> Option<&mut D> {
        self.drivers.get_mut(index)
    }

    /// Received bytes that belonged to no driver.
    pub fn stray_bytes(&self) -> u64 {
        self.stray_bytes
    }

    /// Routes bytes received from the link to their drivers.
    pub fn handle_rx(&mut self, now: Duration, mut bytes: &[u8]) {
        match self.kind {
            LinkKind::Stream => {
                self.share_late_answers();
                let owner = self.in_flight.unwrap_or(self.last_sender);
                if let Some(driver) = self.drivers.get_mut(owner) {
                    driver.handle_rx(now, bytes);
                } else {
                    self.stray_bytes += bytes.len() as u64;
                }
                self.release_if_answered();
            }
            LinkKind::Spi => {
                while !bytes.is_empty() {
                    let Some(head) = self.pending.front_mut() else {
                        self.stray_bytes += bytes.len() as u64;
                        return;
                    };
                    let take = head.remaining.min(bytes.len());
                    let (mine, rest) = bytes.split_at(take);
                    if let Some(driver) = self.drivers.get_mut(head.driver) {
                        driver.handle_rx(now, mine);
                    }
                    head.remaining -= take;
                    if head.remaining == 0 {
                        if let Some(at) = head.written_at
                            && let Some(clocked) = self.clocked.get_mut(head.driver)
                        {
                            *clocked = Some(clocked.map_or(at, |c| c.max(at)));
                        }
                        self.pending.pop();
                    }
                    bytes = rest;
                }
            }
        }
    }

    /// Lets time pass for every driver.
    pub fn handle_timeout(&mut self, now: Duration) {
        for driver in &mut self.drivers {
            driver.handle_timeout(now);
        }
        self.release_if_answered();
    }

    /// The earliest instant any driver has timed work.
    #[must_use]
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.drivers
            .iter()
            .filter_map(|driver| driver.poll_timeout())
            .min()
    }

    /// The next message to put on the link, with the index of the driver that wrote it.
    /// `None` when nobody may or wants to send now.
    #[must_use]
    pub fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<(usize, Transmit)> {
        self.release_if_answered();
        if self.kind == LinkKind::Stream
            && (self.in_flight.is_some() || self.drivers.iter().any(Driver::awaiting_reply))
        {
            // One request in flight; and a driver that holds the line without one (bytes
            // it did not ask for are still coming: a late answer) holds it for everyone.
            return None;
        }
        if self.kind == LinkKind::Spi && self.pending.is_full() {
            return None;
        }
        if self.stamped && self.unwritten.is_full() {
            return None;
        }
        if self.kind == LinkKind::Stream {
            self.share_late_answers();
        }
        let count = self.drivers.len();
        // The most urgent first, round-robin among equals; a driver that wanted to send but
        // has nothing after all (its question must wait) gives way to the next.
        let mut tried: Option<(Priority, usize)> = None;
        let (index, wanted, transmit) = loop {
            let mut best: Option<(usize, Priority, usize)> = None;
            for offset in 0..count {
                let index = (self.next_turn + offset) % count;
                let Some(priority) = self.drivers[index].wants_transmit(now) else {
                    continue;
                };
                let after_tried =
                    tried.is_none_or(|(p, o)| priority < p || (priority == p && offset > o));
                if after_tried && best.is_none_or(|(_, best_priority, _)| priority > best_priority)
                {
                    best = Some((index, priority, offset));
                }
            }
            let (index, priority, offset) = best?;
            tried = Some((priority, offset));
            let wanted = match self.kind {
                LinkKind::Stream => self.drivers[index].line_rate(),
                LinkKind::Spi => None,
            };
            if let Some(transmit) = self.drivers[index].poll_transmit(now, buf) {
                break (index, wanted, transmit);
            }
        };
        if let Some(rate) = wanted.filter(|rate| self.rate != Some(*rate)) {
            // The message goes at the driver's rate: the shell changes the link's first.
            self.rate = Some(rate);
            self.rate_change = Some(rate);
        }
        if transmit.len > buf.len() {
            // A driver bug; never put a truncated message on the wire.
            return None;
        }
        self.next_turn = (index + 1) % count;
        self.last_sender = index;
        if self.stamped {
            // Room was checked above.
            self.unwritten.push(Unwritten {
                driver: index,
                goal_starts: transmit.goal_starts,
                queued_at: now,
            });
        } else {
            self.drivers[index].handle_written(now);
        }
        match self.kind {
            LinkKind::Stream => {
                if transmit.expects_reply {
                    self.in_flight = Some(index);
                }
            }
            LinkKind::Spi => {
                if transmit.len > 0 {
                    // Room was checked above.
                    self.pending.push(PendingMiso {
                        driver: index,
                        remaining: transmit.len,
                        written_at: None,
                    });
                }
            }
        }
        Some((index, transmit))
    }

    /// The link went down: every driver is told, outstanding routing is dropped.
    pub fn link_down(&mut self, now: Duration) {
        self.rate = None;
        self.rate_change = None;
        self.in_flight = None;
        self.pending.clear();
        self.unwritten.clear();
        self.clocked.fill(None);
        for driver in &mut self.drivers {
            driver.link_down(now);
        }
    }

    /// The link is open again: every driver restarts its board.
    pub fn link_up(&mut self, now: Duration) {
        // Reopened at its configured rate.
        self.rate = None;
        self.rate_change = None;
        self.in_flight = None;
        self.pending.clear();
        self.unwritten.clear();
        self.clocked.fill(None);
        for driver in &mut self.drivers {
            driver.link_up(now);
        }
    }

    /// Stream with several drivers: hands every driver the late answers of the others (at
    /// most [`LATE_ANSWERS`]; more are handed once there is room). Nothing allocates.
    fn share_late_answers(&mut self) {
        if self.drivers.len() < 2 {
            return;
        }
        let any = self.drivers.iter().any(|d| !d.late_answers().is_empty());
        if !any && !self.late_shared {
            return;
        }
        self.late_shared = any;
        for index in 0..self.drivers.len() {
            let mut others = [LateAnswer::EMPTY; LATE_ANSWERS];
            let mut count = 0;
            for (other, driver) in self.drivers.iter().enumerate() {
                if other == index {
                    continue;
                }
                for late in driver.late_answers() {
                    if let Some(slot) = others.get_mut(count) {
                        *slot = *late;
                        count += 1;
                    }
                }
            }
            if let Some(driver) = self.drivers.get_mut(index) {
                driver.handle_late_answers(&others[..count]);
            }
        }
    }

    fn release_if_answered(&mut self) {
        if let Some(index) = self.in_flight
            && !self
                .drivers
                .get(index)
                .is_some_and(|driver| driver.awaiting_reply())
        {
            self.in_flight = None;
        }
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_late;
#[cfg(test)]
mod tests_rate;
