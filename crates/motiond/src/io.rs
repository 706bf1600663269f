//! One I/O thread per link, exchanging bytes with the tick through bounded lock-free
//! queues (rtrb single-producer single-consumer rings: wait-free push and pop, no
//! allocation after construction, no lock shared with the real-time thread).
//!
//! The thread owns the link: it writes what the tick queued, reads what arrived, and when
//! the link fails it reports `Down`, reopens with exponential backoff (100 ms .. 2 s) and
//! reports `Up` — the other links and the tick go on meanwhile. A blocking transport
//! (spidev, a full serial buffer) only ever blocks its own thread.

use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;

use motion_link::{Link, LinkErrorKind, LinkKind};
use rtrb::{Consumer, Producer, RingBuffer};

use crate::rt::monotonic_now;

/// Bytes one packet carries (a driver message, or a chunk of received bytes).
pub const PACKET_LEN: usize = 256;
/// Packets each queue holds.
pub const QUEUE_PACKETS: usize = 256;

/// A message or a chunk of bytes.
#[derive(Debug, Clone, Copy)]
pub struct Packet {
    len: u16,
    data: [u8; PACKET_LEN],
}

impl Packet {
    /// A packet holding `bytes` (at most [`PACKET_LEN`]; more is cut).
    pub fn new(bytes: &[u8]) -> Self {
        let len = bytes.len().min(PACKET_LEN);
        let mut data = [0u8; PACKET_LEN];
        data[..len].copy_from_slice(&bytes[..len]);
        Self {
            len: len as u16,
            data,
        }
    }

    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.data[..usize::from(self.len)]
    }
}

/// What happened to a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkEvent {
    /// The link failed; its devices are unreachable until `Up`.
    Down,
    /// The link was (re)opened.
    Up,
}

/// Counters an I/O thread keeps, read by the tick for `ServerStats`.
#[derive(Debug, Default)]
pub struct IoCounters {
    /// Bytes read from the link.
    pub bytes_in: AtomicU64,
    /// Bytes written to the link.
    pub bytes_out: AtomicU64,
    /// I/O errors.
    pub errors: AtomicU64,
    /// Successful reopens.
    pub reconnects: AtomicU64,
    /// Packets or events dropped because a ring between the threads was full.
    pub dropped: AtomicU64,
    /// The link is open.
    pub up: AtomicBool,
}

/// The tick's end of one link.
#[derive(Debug)]
pub struct LinkPort {
    /// Messages to send.
    pub tx: Producer<Packet>,
    /// Bytes received.
    pub rx: Consumer<Packet>,
    /// Down/up events.
    pub events: Consumer<LinkEvent>,
    /// Counters.
    pub counters: Arc<IoCounters>,
    /// The I/O thread, to wake it when something was queued.
    pub thread: std::thread::Thread,
}

/// A running I/O thread.
#[derive(Debug)]
pub struct IoThread {
    handle: JoinHandle<()>,
}

impl IoThread {
    /// Waits for the thread to finish (after `stop` was set).
    pub fn join(self) {
        if self.handle.join().is_err() {
            tracing::error!("an I/O thread panicked");
        }
    }
}

struct Worker {
    link: Box<dyn Link>,
    tx: Consumer<Packet>,
    rx: Producer<Packet>,
    events: Producer<LinkEvent>,
    counters: Arc<IoCounters>,
    stop: Arc<AtomicBool>,
    poll: Duration,
    /// Part of a stream message the link did not take yet.
    pending: Option<(Packet, usize)>,
    down: bool,
    backoff: Duration,
    next_reopen: Duration,
}

const BACKOFF_MIN: Duration = Duration::from_millis(100);
const BACKOFF_MAX: Duration = Duration::from_secs(2);

/// Starts the I/O thread of `link` (named `io-<name>`); `epoch` is the monotonic instant
/// all of the server's `now` values count from; `poll` bounds how long received bytes can
/// wait before the thread looks.
pub fn spawn(
    name: &str,
    link: Box<dyn Link>,
    epoch: Duration,
    poll: Duration,
    stop: Arc<AtomicBool>,
) -> std::io::Result<(LinkPort, IoThread)> {
    let (tx_producer, tx_consumer) = RingBuffer::new(QUEUE_PACKETS);
    let (rx_producer, rx_consumer) = RingBuffer::new(QUEUE_PACKETS);
    let (event_producer, event_consumer) = RingBuffer::new(16);
    let counters = Arc::new(IoCounters::default());
    counters.up.store(true, Ordering::Relaxed);
    let mut worker = Worker {
        link,
        tx: tx_consumer,
        rx: rx_producer,
        events: event_producer,
        counters: Arc::clone(&counters),
        stop,
        poll,
        pending: None,
        down: false,
        backoff: BACKOFF_MIN,
        next_reopen: Duration::ZERO,
    };
    let handle = std::thread::Builder::new()
        .name(format!("io-{name}"))
        .spawn(move || worker.run(epoch))?;
    let port = LinkPort {
        tx: tx_producer,
        rx: rx_consumer,
        events: event_consumer,
        counters,
        thread: handle.thread().clone(),
    };
    Ok((port, IoThread { handle }))
}

impl Worker {
    fn run(&mut self, epoch: Duration) {
        let mut buf = [0u8; PACKET_LEN];
        while !self.stop.load(Ordering::Relaxed) {
            let now = monotonic_now().saturating_sub(epoch);
            if self.down {
                if now >= self.next_reopen {
                    self.try_reopen(now);
                }
                if self.down {
                    // Drop what the tick queued for a dead link: it is stale by now.
                    while self.tx.pop().is_ok() {}
                    self.pending = None;
                    std::thread::park_timeout(
                        self.next_reopen.saturating_sub(now).min(self.poll * 4),
                    );
                    continue;
                }
            }
            self.write_queued(now);
            self.read_available(now, &mut buf);
            let wait = self
                .link
                .next_event(now)
                .map_or(self.poll, |at| at.saturating_sub(now).min(self.poll));
            if !wait.is_zero() && self.tx.is_empty() {
                std::thread::park_timeout(wait);
            }
        }
    }

    fn fail(&mut self, now: Duration, kind: LinkErrorKind) {
        self.counters.errors.fetch_add(1, Ordering::Relaxed);
        if kind == LinkErrorKind::Disconnected && !self.down {
            self.down = true;
            self.counters.up.store(false, Ordering::Relaxed);
            self.backoff = BACKOFF_MIN;
            self.next_reopen = now + self.backoff;
            if self.events.push(LinkEvent::Down).is_err() {
                self.counters.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    fn try_reopen(&mut self, now: Duration) {
        match self.link.reopen(now) {
            Ok(()) => {
                self.down = false;
                self.counters.up.store(true, Ordering::Relaxed);
                self.counters.reconnects.fetch_add(1, Ordering::Relaxed);
                if self.events.push(LinkEvent::Up).is_err() {
                    self.counters.dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
            Err(_) => {
                self.backoff = (self.backoff * 2).min(BACKOFF_MAX);
                self.next_reopen = now + self.backoff;
            }
        }
    }

    fn write_queued(&mut self, now: Duration) {
        loop {
            let (packet, offset) = match self.pending.take() {
                Some(pending) => pending,
                None => match self.tx.pop() {
                    Ok(packet) => (packet, 0),
                    Err(_) => return,
                },
            };
            let bytes = &packet.bytes()[offset..];
            match self.link.write(now, bytes) {
                Ok(written) => {
                    self.counters
                        .bytes_out
                        .fetch_add(written as u64, Ordering::Relaxed);
                    if written < bytes.len() {
                        // A full transmit buffer: keep the rest, try again next round.
                        self.pending = Some((packet, offset + written));
                        return;
                    }
                }
                Err(error) => {
                    if self.link.kind() == LinkKind::Spi
                        && error.kind() != LinkErrorKind::Disconnected
                    {
                        // The transaction did not happen; the driver still waits for its
                        // MISO bytes. Hand it a floating bus (0xFF) of the same length so
                        // the bytes of later transactions reach their owners, never a
                        // neighbour's.
                        let floating = [0xFF; PACKET_LEN];
                        let len = bytes.len().min(PACKET_LEN);
                        if self.rx.push(Packet::new(&floating[..len])).is_err() {
                            self.counters
                                .dropped
                                .fetch_add(len as u64, Ordering::Relaxed);
                        }
                    }
                    self.fail(now, error.kind());
                    return;
                }
            }
        }
    }

    fn read_available(&mut self, now: Duration, buf: &mut [u8; PACKET_LEN]) {
        loop {
            match self.link.read(now, buf) {
                Ok(0) => return,
                Ok(len) => {
                    self.counters
                        .bytes_in
                        .fetch_add(len as u64, Ordering::Relaxed);
                    if self.rx.push(Packet::new(&buf[..len])).is_err() {
                        // The tick has not drained for QUEUE_PACKETS packets: count it.
                        self.counters
                            .dropped
                            .fetch_add(len as u64, Ordering::Relaxed);
                    }
                }
                Err(error) => {
                    self.fail(now, error.kind());
                    return;
                }
            }
        }
    }
}
