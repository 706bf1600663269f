//! The board's SPI slave: request bytes in on MOSI, queued packets (or filler) out on MISO.
//!
//! A packet queued while a transaction is under way can only start in a later transaction
//! (MISO is clocked while MOSI comes in, docs/ARCHITECTURE.md), and only once it is ready.

use core::time::Duration;
use std::collections::VecDeque;

use qq2drv::{PacketBuf, StreamDecoder};

/// A packet waiting for the master to clock it out.
#[derive(Debug, Clone, Copy)]
struct Outgoing {
    /// When the packet becomes available for transmission.
    ready_at: Duration,
    /// It may start only in a transaction after this one.
    after_txn: u64,
    packet: PacketBuf,
    stream: bool,
}

/// MISO queue, MOSI decoder and transaction counter.
#[derive(Debug, Clone)]
pub(crate) struct Wire {
    pub(crate) rx: StreamDecoder,
    /// Number of the transaction under way (1 for the first).
    pub(crate) txn: u64,
    queue: VecDeque<Outgoing>,
    /// Packet being clocked out and the index of its next byte.
    current: Option<(PacketBuf, usize, bool)>,
    /// The transaction the packet being clocked out began in.
    current_txn: u64,
    /// A stream packet is queued or being clocked out.
    stream_in_flight: bool,
    /// The request processor is busy until then.
    busy_until: Duration,
    capacity: usize,
    /// Replies dropped because the queue was full.
    pub(crate) dropped: u64,
}

impl Wire {
    pub(crate) fn new(capacity: usize) -> Self {
        Self {
            rx: StreamDecoder::new(),
            txn: 0,
            queue: VecDeque::with_capacity(capacity + 1),
            current: None,
            current_txn: 0,
            stream_in_flight: false,
            busy_until: Duration::ZERO,
            capacity: capacity.max(1),
            dropped: 0,
        }
    }

    /// Queues a reply to a request that finished arriving at `at`, ready after the
    /// processing time (requests are processed one after the other).
    pub(crate) fn queue_reply(&mut self, at: Duration, processing: Duration, packet: PacketBuf) {
        if self.queue.len() >= self.capacity {
            self.dropped += 1;
            return;
        }
        let ready_at = at.max(self.busy_until) + processing;
        self.busy_until = ready_at;
        self.insert(Outgoing {
            ready_at,
            after_txn: self.txn,
            packet,
            stream: false,
        });
    }

    /// Whether the previous stream packet has not been read out yet.
    pub(crate) fn stream_in_flight(&self) -> bool {
        self.stream_in_flight
    }

    /// Queues a stream packet available at `ready_at`.
    pub(crate) fn queue_stream(&mut self, ready_at: Duration, packet: PacketBuf) {
        self.stream_in_flight = true;
        self.insert(Outgoing {
            ready_at,
            after_txn: 0,
            packet,
            stream: true,
        });
    }

    fn insert(&mut self, out: Outgoing) {
        let at = self
            .queue
            .iter()
            .position(|o| o.ready_at > out.ready_at)
            .unwrap_or(self.queue.len());
        self.queue.insert(at, out);
    }

    /// The MISO byte whose clocking starts at `t`.
    pub(crate) fn miso_byte(&mut self, t: Duration, filler: u8) -> u8 {
        if self.current.is_none() {
            let txn = self.txn;
            if let Some(i) = self
                .queue
                .iter()
                .position(|o| o.ready_at <= t && o.after_txn < txn)
                && let Some(o) = self.queue.remove(i)
            {
                self.current = Some((o.packet, 0, o.stream));
                self.current_txn = txn;
            }
        }
        let Some((packet, index, stream)) = self.current.as_mut() else {
            return filler;
        };
        let bytes = packet.as_bytes();
        let byte = bytes.get(*index).copied().unwrap_or(filler);
        *index += 1;
        if *index >= bytes.len() {
            if *stream {
                self.stream_in_flight = false;
            }
            self.current = None;
        }
        byte
    }

    /// A packet begun in an earlier transaction is partly clocked out: the master has not
    /// read it out entirely.
    pub(crate) fn reading_older_packet(&self) -> bool {
        self.current.is_some() && self.current_txn < self.txn
    }

    /// SRDY: a packet is available (or partly clocked out) at `now`.
    pub(crate) fn packet_ready(&self, now: Duration) -> bool {
        self.current.is_some() || self.queue.iter().any(|o| o.ready_at <= now)
    }

    /// The earliest instant a queued packet becomes available.
    pub(crate) fn next_ready(&self) -> Option<Duration> {
        self.queue.iter().map(|o| o.ready_at).min()
    }

    /// Drops everything queued (power cycle).
    pub(crate) fn clear(&mut self) {
        self.queue.clear();
        self.current = None;
        self.stream_in_flight = false;
        self.rx.clear();
    }
}

/// Stream scheduling state (packets 3, 4 and 8).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct StreamClock {
    /// Stream Period in 40.96 µs units; 0 = off.
    pub(crate) period: u16,
    /// When the period was set: ticks fall at `epoch + k·period`.
    epoch: Duration,
    /// Index of the next tick.
    next_index: u64,
    /// Tick index of the last packet produced (0 = the epoch).
    last_index: u64,
    /// When the calculation of the previous stream packet started.
    prev_calc: Duration,
    /// Stream packets produced and ticks missed because the master had not read out.
    pub(crate) produced: u64,
    pub(crate) missed: u64,
}

impl StreamClock {
    fn period_duration(&self) -> Duration {
        qq2drv::limits::stream_units_to_duration(self.period)
    }

    /// Packet 4 at `now`.
    pub(crate) fn set_period(&mut self, period: u16, now: Duration) {
        *self = Self {
            period,
            epoch: now,
            next_index: 1,
            last_index: 0,
            prev_calc: now,
            ..*self
        };
    }

    /// The next tick, when streaming.
    pub(crate) fn next_tick(&self) -> Option<Duration> {
        (self.period != 0).then(|| {
            let nanos = self
                .period_duration()
                .as_nanos()
                .saturating_mul(u128::from(self.next_index));
            self.epoch + Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX))
        })
    }

    /// A tick happened at `t`. Returns `None` when the previous packet is still unread
    /// (the period is missed), otherwise the (timing, periods elapsed) fields for a packet
    /// that becomes available at `t + overhead`.
    pub(crate) fn tick(
        &mut self,
        t: Duration,
        overhead: Duration,
        in_flight: bool,
    ) -> Option<(u16, u8)> {
        let index = self.next_index;
        self.next_index += 1;
        if in_flight {
            self.missed += 1;
            return None;
        }
        let elapsed = index.saturating_sub(self.last_index).max(1);
        let missed_time = self
            .period_duration()
            .saturating_mul(u32::try_from(elapsed - 1).unwrap_or(u32::MAX));
        let age = (t + overhead)
            .saturating_sub(self.prev_calc)
            .saturating_sub(missed_time);
        let units = qq2drv::limits::duration_to_stream_units(age);
        self.last_index = index;
        self.prev_calc = t;
        self.produced += 1;
        Some((units, u8::try_from(elapsed).unwrap_or(u8::MAX)))
    }
}
