//! One I/O thread per link, exchanging bytes with the tick through bounded lock-free
//! queues (rtrb single-producer single-consumer rings: wait-free push and pop, no
//! allocation after construction, no lock shared with the real-time thread).
//!
//! The thread owns the link: it opens it (a link is handed over closed, as
//! `LinkConfig::create` makes it) and reports `Up` when it first opened — until then the
//! link's boards are starting, not down; retried with the same backoff as a reopen, so a
//! tty that appears late is opened once it is there. It writes what the tick queued, reads
//! what arrived, and when the link fails it reports `Down`, reopens with exponential
//! backoff (100 ms .. 2 s) and reports `Up` — the other links and the tick go on
//! meanwhile. A blocking transport (spidev, a full serial buffer) only ever blocks its own
//! thread.
//!
//! Between passes the thread sleeps in poll(2) on two descriptors: the link's own
//! ([`Link::poll_fd`]: readable when bytes or a hang-up arrived, writable when a partial
//! write can go on) and an eventfd the tick writes to when it queued output ([`Waker`]).
//! A link without a descriptor (a simulated wire) is looked at again at its
//! [`Link::next_event`], and every link by the instant the tick asks for
//! ([`LinkPort::queued_and_look_by`]: its drivers' next deadline); nothing else wakes the thread on a
//! timer except the idle limit given to [`spawn`].
//!
//! Each thread takes the real-time set-up it is given before its first pass
//! ([`IoThreadOptions`]: `[server] io_rt_priority`, `io_cpu`) and reports what it got.
//!
//! Stamps (time since the server's epoch, as the tick's `now`): each received chunk
//! carries the instant it was read; each message written whole is reported back as
//! [`Written`] with the instant its last byte was accepted; [`IoCounters::heard_ns`] is the
//! thread's horizon — every byte that arrived before it has been handed over and every
//! message queued before it has been written — against which drivers judge silence.

pub mod inline;
mod worker;

use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::thread::JoinHandle;

use motion_link::Link;
use nix::sys::eventfd::{EfdFlags, EventFd};
use rtrb::{Consumer, Producer, RingBuffer};

use worker::Worker;

use crate::error::RtError;

/// Bytes one packet carries (a driver message, or a chunk of received bytes).
pub const PACKET_LEN: usize = motion_drivers::MESSAGE_LEN;
/// Packets each queue holds.
pub const QUEUE_PACKETS: usize = 256;
/// Write reports the ring back to the tick holds (more than the transmit queue: the tick
/// drains it before it queues more).
pub const WRITTEN_REPORTS: usize = 2 * QUEUE_PACKETS;

/// The longest an I/O thread sleeps with nothing to wait for: how soon a fault injected
/// into a simulated link (which has no descriptor to report it) is noticed on an idle
/// link. Real transports report failures on their descriptor.
pub const IDLE_WAIT: Duration = Duration::from_millis(100);

/// "No such instant" in the stamps kept as nanoseconds.
pub const NEVER: u64 = u64::MAX;

/// A message or a chunk of bytes, with its stamp: when the tick queued it (to send), or
/// when the I/O thread read it (received). To send, it may instead be a change of the
/// link's line rate ([`Packet::rate_change`]), taken in order with the messages.
#[derive(Debug, Clone, Copy)]
pub struct Packet {
    len: u16,
    at: Duration,
    /// Not 0: no bytes; the link is to run at this rate from the next message on.
    rate: u32,
    data: [u8; PACKET_LEN],
}

impl Packet {
    /// A packet holding `bytes` (at most [`PACKET_LEN`]; more is cut), stamped 0.
    pub fn new(bytes: &[u8]) -> Self {
        Self::stamped(bytes, Duration::ZERO)
    }

    /// A packet holding `bytes`, stamped `at`.
    pub fn stamped(bytes: &[u8], at: Duration) -> Self {
        let len = bytes.len().min(PACKET_LEN);
        let mut data = [0u8; PACKET_LEN];
        data[..len].copy_from_slice(&bytes[..len]);
        Self {
            len: len as u16,
            at,
            rate: 0,
            data,
        }
    }

    /// A change of the link's line rate to `baud` (a driver changed its board's rate, e.g.
    /// the Trinamic pack's `$40`), queued at `at`: the I/O thread writes every message
    /// before it, waits until they left ([`Link::flush`]), sets the rate
    /// ([`Link::set_baud`]) and goes on with the messages after it. No write report.
    pub fn rate_change(baud: u32, at: Duration) -> Self {
        let mut packet = Self::stamped(&[], at);
        packet.rate = baud.max(1);
        packet
    }

    /// The rate of a [`rate_change`](Self::rate_change), `None` for bytes.
    pub fn rate(&self) -> Option<u32> {
        (self.rate != 0).then_some(self.rate)
    }

    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.data[..usize::from(self.len)]
    }

    /// Queued at (to send) or read at (received), since the epoch.
    pub fn at(&self) -> Duration {
        self.at
    }
}

/// What happened to a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkEvent {
    /// The link failed; its devices are unreachable until `Up`. Never sent before the
    /// first `Up` (a link that never opened is not down: its boards are starting).
    Down,
    /// The link was opened (the first time, or again after `Down`).
    Up,
}

/// A queued message went out whole: its last byte was accepted by the link at `at`.
/// Reports come in queue order; `generation` counts the `Down` events before the write
/// (a report from before a `Down` belongs to no message the tick still tracks).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Written {
    /// `Down` events the I/O thread had reported when it wrote the message.
    pub generation: u32,
    /// Since the epoch.
    pub at: Duration,
}

/// Counters and stamps an I/O thread keeps, read by the tick (for `ServerStats` and the
/// drivers' horizon). Stamps are nanoseconds since the epoch.
#[derive(Debug)]
pub struct IoCounters {
    /// Bytes read from the link.
    pub bytes_in: AtomicU64,
    /// Bytes written to the link.
    pub bytes_out: AtomicU64,
    /// I/O errors.
    pub errors: AtomicU64,
    /// Successful reopens (after a `Down`; the first opening is not counted).
    pub reconnects: AtomicU64,
    /// Packets or events dropped because a ring between the threads was full.
    pub dropped: AtomicU64,
    /// The link is open (false until the I/O thread first opened it).
    pub up: AtomicBool,
    /// Messages written whole (on an SPI link: transactions).
    pub transactions: AtomicU64,
    /// Reads that returned bytes.
    pub reads: AtomicU64,
    /// When the last bytes were written ([`NEVER`] before).
    pub last_write_ns: AtomicU64,
    /// When the last bytes were read ([`NEVER`] before).
    pub last_read_ns: AtomicU64,
    /// The horizon: every byte that arrived before it is in the receive ring and every
    /// message queued before it was written. Stored after the pass's pushes.
    pub heard_ns: AtomicU64,
    /// When the tick wants the link looked at again ([`NEVER`]: no wish).
    pub look_by_ns: AtomicU64,
    /// When the thread's current sleep ends (0 while it is awake).
    pub sleep_until_ns: AtomicU64,
    /// Messages a link the tick runs itself (`io = "tick"`) put off to a later tick because
    /// the tick's wire-time budget was spent: each tick adds the messages left waiting.
    pub deferred: AtomicU64,
    /// The line rate the I/O thread last set ([`Packet::rate_change`]); 0 while the link
    /// runs at its configured rate (since it was last opened).
    pub baud: AtomicU32,
}

impl Default for IoCounters {
    fn default() -> Self {
        Self {
            bytes_in: AtomicU64::new(0),
            bytes_out: AtomicU64::new(0),
            errors: AtomicU64::new(0),
            reconnects: AtomicU64::new(0),
            dropped: AtomicU64::new(0),
            up: AtomicBool::new(false),
            transactions: AtomicU64::new(0),
            reads: AtomicU64::new(0),
            last_write_ns: AtomicU64::new(NEVER),
            last_read_ns: AtomicU64::new(NEVER),
            heard_ns: AtomicU64::new(0),
            look_by_ns: AtomicU64::new(NEVER),
            sleep_until_ns: AtomicU64::new(0),
            deferred: AtomicU64::new(0),
            baud: AtomicU32::new(0),
        }
    }
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
    /// Messages written whole, in queue order.
    pub written: Consumer<Written>,
    /// `Down` events taken from `events` so far (to tell stale [`Written`] reports).
    pub generation: u32,
    /// Counters and stamps.
    pub counters: Arc<IoCounters>,
    /// Wakes the I/O thread when something was queued.
    pub waker: Arc<Waker>,
    /// The tick's own I/O, for a link without an I/O thread (`io = "tick"`).
    pub inline: Option<Box<inline::InlineIo>>,
}

impl LinkPort {
    /// The tick's end-of-tick call. Asks the I/O thread to look at the link again by `at`
    /// (a driver's reply deadline: only a look after it can tell a silent board; `None`:
    /// no wish), storing that wish first, then wakes the thread once if output was
    /// `queued` or the wish is earlier than its sleep — one eventfd write per link and tick
    /// at most (each is a cross-core wake-up, the dearest thing the tick does).
    pub fn queued_and_look_by(&self, queued: bool, at: Option<Duration>) {
        let ns = at.map_or(NEVER, duration_ns);
        let counters = &self.counters;
        let changed = counters.look_by_ns.swap(ns, Ordering::SeqCst) != ns;
        // Either the thread reads the new wish before it sleeps, or this sees its sleep;
        // woken for output, it reads the wish stored above before it sleeps again.
        if queued || (changed && ns < counters.sleep_until_ns.load(Ordering::SeqCst)) {
            self.waker.wake();
        }
    }

    /// The horizon ([`IoCounters::heard_ns`]). Read it before draining `rx`.
    pub fn heard(&self) -> Duration {
        Duration::from_nanos(self.counters.heard_ns.load(Ordering::Acquire))
    }
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
    rt: Option<IoRtOutcome>,
}

/// What an I/O thread's real-time set-up achieved ([`IoThreadOptions`]): `None` where
/// nothing was asked for.
#[derive(Debug, Default)]
pub struct IoRtOutcome {
    /// The SCHED_FIFO priority, or why not.
    pub fifo: Option<Result<u8, RtError>>,
    /// The core the thread is pinned to, or why not.
    pub pinned: Option<Result<usize, RtError>>,
}

impl IoThread {
    /// What became of the priority and the core asked for at [`spawn`]; taken once
    /// (`None` the second time).
    pub fn take_rt(&mut self) -> Option<IoRtOutcome> {
        self.rt.take()
    }

    /// Wakes the thread so it sees `stop` (set before), and waits for it to finish.
    pub fn join(self) {
        self.waker.wake();
        if self.handle.join().is_err() {
            tracing::error!("an I/O thread panicked");
        }
    }
}

/// How an I/O thread is started.
#[derive(Debug, Clone, Copy)]
pub struct IoThreadOptions {
    /// The monotonic instant all of the server's `now` values count from.
    pub epoch: Duration,
    /// The longest the thread sleeps when neither the link's descriptor, its next event,
    /// the tick's wish nor a wake-up rouse it (only a simulated link's injected faults need
    /// it: a real transport's failure shows on its descriptor).
    pub idle: Duration,
    /// SCHED_FIFO priority the thread takes before its first pass (`None`: the normal
    /// policy). Failing to get it is reported by [`IoThread::take_rt`]; the thread runs on
    /// at the normal policy.
    pub rt_priority: Option<u8>,
    /// Core the thread pins itself to before its first pass (`None`: any). Failing is
    /// reported by [`IoThread::take_rt`]; the thread runs on unpinned.
    pub cpu: Option<usize>,
}

/// Starts the I/O thread of `link` (named `io-<name>`) and waits until it has tried its
/// real-time set-up (priority, core).
pub fn spawn(
    name: &str,
    link: Box<dyn Link>,
    options: IoThreadOptions,
    stop: Arc<AtomicBool>,
) -> std::io::Result<(LinkPort, IoThread)> {
    let (port, mut worker) = port_and_worker(link, stop, options.idle)?;
    let (rt_tx, rt_rx) = std::sync::mpsc::sync_channel(1);
    let priority = options.rt_priority;
    let cpu = options.cpu;
    let epoch = options.epoch;
    let handle = std::thread::Builder::new()
        .name(format!("io-{name}"))
        .spawn(move || {
            let pinned = cpu.map(|c| crate::rt::pin_to(c).map(|()| c));
            let fifo = priority.map(|p| crate::rt::set_fifo(p).map(|()| p));
            let _ = rt_tx.send(IoRtOutcome { fifo, pinned });
            drop(rt_tx);
            worker.run(epoch);
        })?;
    // The thread sends before anything else; a thread that died first reports nothing.
    let rt = rt_rx.recv().unwrap_or_default();
    let waker = Arc::clone(&port.waker);
    Ok((
        port,
        IoThread {
            handle,
            waker,
            rt: Some(rt),
        },
    ))
}

/// The tick's end of a new link and the [`Worker`] that serves it, joined by their rings.
fn port_and_worker(
    link: Box<dyn Link>,
    stop: Arc<AtomicBool>,
    idle: Duration,
) -> std::io::Result<(LinkPort, Worker)> {
    let (tx_producer, tx_consumer) = RingBuffer::new(QUEUE_PACKETS);
    let (rx_producer, rx_consumer) = RingBuffer::new(QUEUE_PACKETS);
    let (event_producer, event_consumer) = RingBuffer::new(16);
    let (written_producer, written_consumer) = RingBuffer::new(WRITTEN_REPORTS);
    let counters = Arc::new(IoCounters::default());
    let waker = Arc::new(Waker::new()?);
    let worker = Worker::new(
        link,
        worker::Rings {
            tx: tx_consumer,
            rx: rx_producer,
            events: event_producer,
            written: written_producer,
        },
        Arc::clone(&counters),
        Arc::clone(&waker),
        stop,
        idle,
    );
    let port = LinkPort {
        tx: tx_producer,
        rx: rx_consumer,
        events: event_consumer,
        written: written_consumer,
        generation: 0,
        counters,
        waker,
        inline: None,
    };
    Ok((port, worker))
}

/// Nanoseconds of `duration`, saturating.
pub fn duration_ns(duration: Duration) -> u64 {
    u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX)
}
