//! The driver's side of the SPI wire: transactions waiting to be sent, transactions whose
//! MISO bytes are still due, and reassembly of those bytes (which the link may deliver in
//! any chunking).

use core::time::Duration;

use spimotor::{Address, Header, Read, ReadPort, StepDelay, Transaction, Write};

use motion_base::FixedQueue;

use super::{PRESENCE_EVERY, Phase, REPLY_MARGIN, SpimotorDriver};
use motion_drivers::{Priority, Transmit};

/// One transaction the driver wants on the wire.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// A write port.
    Write(Write),
    /// A read of `len` data bytes of a port.
    Read(ReadPort, u16),
}

impl Op {
    /// A read of the whole value of `port`.
    pub const fn read(port: ReadPort) -> Self {
        Self::Read(port, port.default_len())
    }

    /// The transaction to board `address`.
    pub const fn transaction(self, address: Address) -> Transaction {
        match self {
            Self::Write(write) => Transaction::write(address, write),
            Self::Read(port, len) => Transaction {
                address,
                request: spimotor::Request::Read(Read { port, len }),
            },
        }
    }

    /// Bytes on the wire (and of the MISO answer), header included.
    pub const fn len(self) -> usize {
        match self {
            Self::Write(write) => Header::LEN + write.data_len(),
            Self::Read(_, len) => Header::LEN + len as usize,
        }
    }
}

/// A queued op and who it belongs to.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Queued {
    /// The transaction.
    pub op: Op,
    /// Its urgency on the bus.
    pub priority: Priority,
    /// The channel whose goal it serves (a new goal drops the channel's unsent ops).
    pub channel: u8,
}

impl Queued {
    /// Whether this is an unsent goal op ([`Priority::Command`]) of `channel` (a new goal
    /// drops them; setup ops stay).
    pub fn is_goal_of(&self, channel: u8) -> bool {
        self.channel == channel && self.priority == Priority::Command
    }
}

/// A bounded FIFO of ops (no allocation; a full queue refuses).
pub type OpQueue<const N: usize> = FixedQueue<Queued, N>;

/// What the board should answer to a read, as the driver's writes left it when the read
/// was sent.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Expect {
    /// Step delay in force.
    pub delay: StepDelay,
    /// Target in force (`None`: unknown, after a stop).
    pub target: Option<i32>,
    /// Position epoch: bumped by every write of the position counter.
    pub epoch: u32,
    /// Target sequence: bumped by every write that changes the target.
    pub target_seq: u32,
}

/// A transaction on the wire whose MISO bytes are due.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sent {
    /// What was sent.
    pub op: Op,
    /// Queued at, then (once reported) written at: its MISO is due from here.
    pub at: Duration,
    /// Its message number (`IoStamps::sent`).
    pub number: u64,
    /// The board state the answer should agree with.
    pub expect: Expect,
}

/// Longest transaction the driver sends: an identification read (2 + 33 bytes).
pub const MAX_TRANSACTION: usize = Header::LEN + spimotor::IDENTIFICATION_READ_LEN as usize;

/// Transactions whose MISO bytes have not all come back, oldest first, and the bytes of
/// the oldest received so far.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct InFlight<const N: usize> {
    sent: FixedQueue<Sent, N>,
    #[serde(with = "serde_big_array::BigArray")]
    miso: [u8; MAX_TRANSACTION],
    received: usize,
}

impl<const N: usize> InFlight<N> {
    /// Nothing in flight.
    pub const fn new() -> Self {
        Self {
            sent: FixedQueue::new(),
            miso: [0; MAX_TRANSACTION],
            received: 0,
        }
    }

    /// Records a transaction just written; `false` when full (the caller checks first).
    pub fn push(&mut self, sent: Sent) -> bool {
        self.sent.push(sent)
    }

    /// Whether another transaction may be recorded.
    pub const fn has_room(&self) -> bool {
        !self.sent.is_full()
    }

    /// Transactions in flight.
    pub const fn len(&self) -> usize {
        self.sent.len()
    }

    /// Whether nothing is in flight.
    pub const fn is_empty(&self) -> bool {
        self.sent.is_empty()
    }

    /// The oldest transaction in flight.
    pub fn oldest(&self) -> Option<Sent> {
        self.sent.front()
    }

    /// Transaction `number` went out at `at`.
    pub fn written(&mut self, number: u64, at: Duration) {
        self.sent.for_each_mut(|sent| {
            if sent.number == number {
                sent.at = sent.at.max(at);
            }
        });
    }

    /// Whether a read of `port` is in flight.
    pub fn reading(&self, port: ReadPort) -> bool {
        self.sent
            .iter()
            .any(|sent| matches!(sent.op, Op::Read(p, _) if p == port))
    }

    /// MISO bytes still owed by the transactions in flight.
    pub fn owed(&self) -> usize {
        self.sent
            .iter()
            .map(|sent| sent.op.len())
            .sum::<usize>()
            .saturating_sub(self.received)
    }

    /// Forgets everything in flight (link down, the board given up on).
    pub fn clear(&mut self) {
        self.sent.clear();
        self.received = 0;
    }

    /// Takes MISO bytes from the front of `bytes` for the oldest transaction. Returns how
    /// many were taken and, when that completed the transaction, the transaction with its
    /// MISO bytes (which stay valid until the next call). Takes nothing when nothing is in
    /// flight.
    pub fn take(&mut self, bytes: &[u8]) -> (usize, Option<(Sent, &[u8])>) {
        let Some(sent) = self.oldest() else {
            return (0, None);
        };
        let len = sent.op.len();
        let want = len.saturating_sub(self.received);
        let take = want.min(bytes.len());
        for (offset, byte) in bytes.iter().take(take).enumerate() {
            if let Some(slot) = self.miso.get_mut(self.received + offset) {
                *slot = *byte;
            }
        }
        self.received += take;
        if self.received < len {
            return (take, None);
        }
        self.received = 0;
        self.sent.pop();
        let miso = self.miso.get(..len.min(MAX_TRANSACTION)).unwrap_or(&[]);
        (take, Some((sent, miso)))
    }
}

/// Board registers as the driver's writes leave them.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Registers {
    pub(super) delay: spimotor::StepDelay,
    /// `None`: unknown (after 0x42 ← 0, until a poll reads it).
    pub(super) target: Option<i32>,
    pub(super) intensity: Option<u8>,
    /// Bumped by every write that changes the target.
    pub(super) target_seq: u32,
}

impl Registers {
    pub(super) const UNKNOWN: Self = Self {
        delay: spimotor::StepDelay::DEFAULT,
        target: None,
        intensity: None,
        target_seq: 0,
    };

    /// The registers after `write`.
    pub(super) fn apply(&mut self, write: Write) {
        match write {
            Write::StepDelay(delay) => self.delay = delay,
            Write::TargetPosition(target) => {
                self.target = Some(target);
                self.target_seq = self.target_seq.wrapping_add(1);
            }
            Write::RelativePosition(_) => {
                self.target = None;
                self.target_seq = self.target_seq.wrapping_add(1);
            }
            Write::StepperIntensity(value) => self.intensity = Some(value),
            _ => {}
        }
    }
}

impl SpimotorDriver {
    /// Queues a setup or goal transaction; `false` when the queue is full.
    pub(super) fn push_command(&mut self, op: Op, priority: Priority, channel: u8) -> bool {
        let pushed = self.commands.push(Queued {
            op,
            priority,
            channel,
        });
        if pushed && let Op::Write(write) = op {
            self.planned.apply(write);
        }
        pushed
    }

    /// Reply timeout: the wire time of everything in flight plus [`REPLY_MARGIN`].
    pub(super) fn reply_timeout(&self) -> Duration {
        self.config
            .wire_time(self.in_flight.len() * MAX_TRANSACTION)
            .saturating_add(REPLY_MARGIN)
    }

    /// Queues the reads of one poll when due.
    pub(super) fn schedule_poll(&mut self, now: Duration) {
        if !self.running() || now < self.next_poll_at || !self.polls.is_empty() {
            return;
        }
        let poll_reads_in_flight = self.in_flight.reading(ReadPort::StepDelay)
            || (!self.is_stepper() && self.in_flight.reading(ReadPort::Identification));
        if poll_reads_in_flight {
            return;
        }
        self.next_poll_at = now.saturating_add(self.config.poll_period);
        let presence_len = self
            .identification
            .map_or(spimotor::IDENTIFICATION_READ_LEN, |id| {
                u16::try_from(id.wire_len()).unwrap_or(spimotor::IDENTIFICATION_READ_LEN)
            });
        let presence = Op::Read(ReadPort::Identification, presence_len);
        let poll = |op| Queued {
            op,
            priority: Priority::Poll,
            channel: 0,
        };
        if self.is_stepper() {
            if self.polls_done % PRESENCE_EVERY == PRESENCE_EVERY - 1 {
                self.polls.push(poll(presence));
            }
            for port in [
                ReadPort::CurrentPosition,
                ReadPort::TargetPosition,
                ReadPort::StepDelay,
            ] {
                self.polls.push(poll(Op::read(port)));
            }
        } else {
            self.polls.push(poll(presence));
        }
        self.polls_done = self.polls_done.wrapping_add(1);
    }

    /// The queue the next transaction comes from (commands before polls).
    pub(super) fn next_queued(&self) -> Option<Queued> {
        if !self.link_up || !self.in_flight.has_room() {
            return None;
        }
        self.commands.front().or_else(|| self.polls.front())
    }

    /// Writes the next queued transaction into `buf` (commands before polls) and puts it in
    /// flight with what its reads must agree with.
    pub(super) fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        let queued = self.next_queued()?;
        let len = queued
            .op
            .transaction(self.config.address)
            .encode(buf)
            .ok()?;
        if self.commands.front() == Some(queued) {
            self.commands.pop();
        } else {
            self.polls.pop();
        }
        if let Op::Write(write) = queued.op {
            self.written.apply(write);
            if let Write::CurrentPosition(position) = write {
                self.epoch = self.epoch.wrapping_add(1);
                self.stepper.position_written(now, position);
            }
            if let Write::Spin { motor, .. } | Write::Stop(motor) = write
                && let Some(state) = self.motors.get_mut(usize::from(motor.channel()))
            {
                state.written(write);
            }
        }
        let expect = Expect {
            delay: self.written.delay,
            target: self.written.target,
            epoch: self.epoch,
            target_seq: self.written.target_seq,
        };
        self.in_flight.push(Sent {
            op: queued.op,
            at: now,
            number: self.io_stamps.sent(),
            expect,
        });
        let mut goal_starts = 0;
        let bit = 1u8.checked_shl(u32::from(queued.channel)).unwrap_or(0);
        if queued.is_goal_of(queued.channel) && self.goal_unsent & bit != 0 {
            self.goal_unsent &= !bit;
            goal_starts = bit;
        }
        if let Op::Write(Write::ChangeAddress(address)) = queued.op {
            // Module `commission`: the board answers at its new address from now on.
            self.address_written(now, address);
        }
        Some(Transmit {
            len,
            expects_reply: matches!(queued.op, Op::Read(..)),
            goal_starts,
        })
    }

    /// Lets time pass: MISO that never came back, the stepper's profile, the next poll or
    /// start-up read.
    pub(super) fn pass_time(&mut self, now: Duration) {
        if !self.link_up {
            return;
        }
        // MISO that never came back: only as far as the link was looked at (module
        // `liveness`).
        self.judge_miso(now);
        if self.phase == Phase::Running {
            if self.is_stepper() {
                self.drive_stepper(now, false);
            }
            self.schedule_poll(now);
        } else {
            self.schedule_startup(now);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sent(op: Op) -> Sent {
        Sent {
            op,
            at: Duration::ZERO,
            number: 0,
            expect: Expect {
                delay: StepDelay::DEFAULT,
                target: None,
                epoch: 0,
                target_seq: 0,
            },
        }
    }

    #[test]
    fn miso_bytes_are_reassembled_per_transaction_in_any_chunking() {
        let mut flight = InFlight::<4>::new();
        assert!(flight.push(sent(Op::read(ReadPort::CurrentPosition))));
        assert!(flight.push(sent(Op::Write(Write::Stop(spimotor::Motor::A)))));
        let stream = [0xFF, 0x00, 1, 2, 3, 4, 0xFF, 0x00];
        for chunk in 1..=stream.len() {
            let mut flight = flight.clone();
            let mut done = Vec::new();
            for piece in stream.chunks(chunk) {
                let mut rest = piece;
                while !rest.is_empty() {
                    let (taken, complete) = flight.take(rest);
                    if let Some((sent, miso)) = complete {
                        done.push((sent.op, miso.to_vec()));
                    }
                    rest = &rest[taken..];
                    if taken == 0 {
                        break;
                    }
                }
            }
            assert_eq!(done.len(), 2, "chunk {chunk}");
            assert_eq!(done[0].1, [0xFF, 0x00, 1, 2, 3, 4]);
            assert_eq!(done[1].1, [0xFF, 0x00]);
            assert!(flight.is_empty());
        }
        assert_eq!(InFlight::<4>::new().take(&[1, 2]).0, 0);
    }

    #[test]
    fn queue_is_bounded_and_drops_a_channel() {
        let mut queue = OpQueue::<3>::new();
        let op = |channel| Queued {
            op: Op::Write(Write::StepperIntensity(channel)),
            priority: Priority::Command,
            channel,
        };
        assert!(queue.push(op(0)) && queue.push(op(1)) && queue.push(op(0)));
        assert!(!queue.push(op(1)));
        queue.retain(|queued| !queued.is_goal_of(0));
        assert_eq!(queue.pop(), Some(op(1)));
        assert!(queue.is_empty() && queue.pop().is_none());
    }
}
