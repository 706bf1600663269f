//! One I/O thread per link, exchanging bytes with the tick through bounded lock-free
//! queues (rtrb single-producer single-consumer rings: wait-free push and pop, no
//! allocation after construction, no lock shared with the real-time thread).
//!
//! The thread owns the link: it writes what the tick queued, reads what arrived, and when
//! the link fails it reports `Down`, reopens with exponential backoff (100 ms .. 2 s) and
//! reports `Up` — the other links and the tick go on meanwhile. A blocking transport
//! (spidev, a full serial buffer) only ever blocks its own thread.
//!
//! Between passes the thread sleeps in poll(2) on two descriptors: the link's own
//! ([`Link::poll_fd`]: readable when bytes or a hang-up arrived, writable when a partial
//! write can go on) and an eventfd the tick writes to when it queued output ([`Waker`]).
//! A link without a descriptor (a simulated wire) is looked at again at its
//! [`Link::next_event`]; nothing wakes the thread on a timer otherwise, except the idle
//! limit given to [`spawn`].

use core::time::Duration;
use std::os::fd::AsFd;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;

use motion_link::{Link, LinkErrorKind, LinkKind};
use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::eventfd::{EfdFlags, EventFd};
use nix::sys::time::TimeSpec;
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
    /// Wakes the I/O thread when something was queued.
    pub waker: Arc<Waker>,
}

/// Wakes an I/O thread out of its poll(2): an eventfd that is readable while woken.
#[derive(Debug)]
pub struct Waker {
    fd: EventFd,
}

impl Waker {
    fn new() -> std::io::Result<Self> {
        let fd = EventFd::from_flags(EfdFlags::EFD_NONBLOCK | EfdFlags::EFD_CLOEXEC)?;
        Ok(Self { fd })
    }

    /// Makes the thread's current or next sleep return at once (one write(2), no
    /// allocation; a wake-up while one is pending adds nothing).
    pub fn wake(&self) {
        // Fails only when the counter would overflow: it is then readable anyway.
        let _ = self.fd.write(1);
    }

    /// Takes the pending wake-up, if any.
    fn take(&self) {
        let _ = self.fd.read();
    }
}

/// A running I/O thread.
#[derive(Debug)]
pub struct IoThread {
    handle: JoinHandle<()>,
    waker: Arc<Waker>,
}

impl IoThread {
    /// Wakes the thread so it sees `stop` (set before), and waits for it to finish.
    pub fn join(self) {
        self.waker.wake();
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
    waker: Arc<Waker>,
    stop: Arc<AtomicBool>,
    /// The longest sleep with nothing to wait for.
    idle: Duration,
    /// Part of a stream message the link did not take yet.
    pending: Option<(Packet, usize)>,
    down: bool,
    backoff: Duration,
    next_reopen: Duration,
    /// A call of this pass failed without taking the link down.
    failed: bool,
    /// The last sleep ended because the link's descriptor was ready.
    fd_ready: bool,
    /// Such wake-ups in a row that moved no byte.
    idle_wakes: u32,
}

/// The longest an I/O thread sleeps with nothing to wait for: how soon a fault injected
/// into a simulated link (which has no descriptor to report it) is noticed on an idle
/// link. Real transports report failures on their descriptor.
pub const IDLE_WAIT: Duration = Duration::from_millis(100);

const BACKOFF_MIN: Duration = Duration::from_millis(100);
const BACKOFF_MAX: Duration = Duration::from_secs(2);
/// The pause after a pass whose calls failed (a link that keeps erroring without
/// disconnecting, or a descriptor that keeps reporting readiness without data, must not
/// make the thread spin).
const ERROR_PAUSE: Duration = Duration::from_millis(1);
/// Wake-ups on the link's descriptor without a byte moved before [`ERROR_PAUSE`] applies.
const MAX_IDLE_WAKES: u32 = 64;

/// Starts the I/O thread of `link` (named `io-<name>`); `epoch` is the monotonic instant
/// all of the server's `now` values count from; `idle` is the longest the thread sleeps
/// when neither the link's descriptor, its next event nor the tick wake it (only a
/// simulated link's injected faults need it: a real transport's failure shows on its
/// descriptor).
pub fn spawn(
    name: &str,
    link: Box<dyn Link>,
    epoch: Duration,
    idle: Duration,
    stop: Arc<AtomicBool>,
) -> std::io::Result<(LinkPort, IoThread)> {
    let (tx_producer, tx_consumer) = RingBuffer::new(QUEUE_PACKETS);
    let (rx_producer, rx_consumer) = RingBuffer::new(QUEUE_PACKETS);
    let (event_producer, event_consumer) = RingBuffer::new(16);
    let counters = Arc::new(IoCounters::default());
    counters.up.store(true, Ordering::Relaxed);
    let waker = Arc::new(Waker::new()?);
    let mut worker = Worker {
        link,
        tx: tx_consumer,
        rx: rx_producer,
        events: event_producer,
        counters: Arc::clone(&counters),
        waker: Arc::clone(&waker),
        stop,
        idle,
        pending: None,
        down: false,
        backoff: BACKOFF_MIN,
        next_reopen: Duration::ZERO,
        failed: false,
        fd_ready: false,
        idle_wakes: 0,
    };
    let handle = std::thread::Builder::new()
        .name(format!("io-{name}"))
        .spawn(move || worker.run(epoch))?;
    let port = LinkPort {
        tx: tx_producer,
        rx: rx_consumer,
        events: event_consumer,
        counters,
        waker: Arc::clone(&waker),
    };
    Ok((port, IoThread { handle, waker }))
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
                    self.sleep(self.next_reopen.saturating_sub(now), false);
                    continue;
                }
            }
            self.failed = false;
            let moved = self.counters_moved();
            self.write_queued(now);
            self.read_available(now, &mut buf);
            if self.down {
                continue;
            }
            if !self.fd_ready || self.counters_moved() != moved {
                self.idle_wakes = 0;
            } else {
                self.idle_wakes = self.idle_wakes.saturating_add(1);
            }
            self.fd_ready = false;
            if self.failed || self.idle_wakes > MAX_IDLE_WAKES {
                self.idle_wakes = 0;
                self.sleep(ERROR_PAUSE, false);
                continue;
            }
            let wait = self
                .link
                .next_event(now)
                .map_or(self.idle, |at| at.saturating_sub(now).min(self.idle));
            if !wait.is_zero() {
                self.sleep(wait, true);
            }
        }
    }

    /// Bytes moved either way so far (to tell a wake-up that did something).
    fn counters_moved(&self) -> u64 {
        self.counters.bytes_in.load(Ordering::Relaxed)
            + self.counters.bytes_out.load(Ordering::Relaxed)
    }

    /// Sleeps in poll(2) up to `timeout`: until the tick wakes the thread or, with
    /// `on_link`, the link's descriptor is ready (readable; writable too while bytes wait
    /// to go out).
    fn sleep(&mut self, timeout: Duration, on_link: bool) {
        let link_fd = if on_link { self.link.poll_fd() } else { None };
        let mut interest = PollFlags::POLLIN;
        if self.pending.is_some() || self.link.write_pending() {
            interest |= PollFlags::POLLOUT;
        }
        let waker = PollFd::new(self.waker.fd.as_fd(), PollFlags::POLLIN);
        let mut fds = match link_fd {
            Some(fd) => [waker, PollFd::new(fd, interest)],
            None => [
                waker,
                PollFd::new(self.waker.fd.as_fd(), PollFlags::empty()),
            ],
        };
        let count = if link_fd.is_some() { 2 } else { 1 };
        let spec = TimeSpec::from_duration(timeout);
        // EINTR or a timeout: either way the next pass looks at everything again.
        let _ = ppoll(&mut fds[..count], Some(spec), None);
        let woken = fds[0]
            .revents()
            .is_some_and(|r| r.contains(PollFlags::POLLIN));
        let ready = count == 2 && fds[1].revents().is_some_and(|r| !r.is_empty());
        if woken {
            self.waker.take();
        }
        // The tick's wake-up is not the link's readiness.
        self.fd_ready = ready && !woken;
    }

    fn fail(&mut self, now: Duration, kind: LinkErrorKind) {
        self.counters.errors.fetch_add(1, Ordering::Relaxed);
        self.failed = true;
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
