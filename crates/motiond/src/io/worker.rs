//! The I/O thread's loop: write what the tick queued, read what arrived, publish the
//! stamps, sleep in poll(2) until something needs the thread; reopen a failed link with
//! backoff.

use core::time::Duration;
use std::os::fd::AsFd;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use motion_link::{Link, LinkErrorKind, LinkKind};
use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::time::TimeSpec;
use rtrb::{Consumer, Producer};

use super::{IoCounters, LinkEvent, NEVER, PACKET_LEN, Packet, Waker, Written, duration_ns};
use crate::rt::monotonic_now;

const BACKOFF_MIN: Duration = Duration::from_millis(100);
const BACKOFF_MAX: Duration = Duration::from_secs(2);
/// The pause after a pass whose calls failed (a link that keeps erroring without
/// disconnecting, or a descriptor that keeps reporting readiness without data, must not
/// make the thread spin).
const ERROR_PAUSE: Duration = Duration::from_millis(1);
/// Wake-ups on the link's descriptor without a byte moved before [`ERROR_PAUSE`] applies.
const MAX_IDLE_WAKES: u32 = 64;

/// The thread's ends of the rings.
pub(super) struct Rings {
    pub tx: Consumer<Packet>,
    pub rx: Producer<Packet>,
    pub events: Producer<LinkEvent>,
    pub written: Producer<Written>,
}

pub(super) struct Worker {
    link: Box<dyn Link>,
    rings: Rings,
    counters: Arc<IoCounters>,
    waker: Arc<Waker>,
    stop: Arc<AtomicBool>,
    epoch: Duration,
    /// The longest sleep with nothing to wait for.
    idle: Duration,
    /// Part of a stream message the link did not take yet.
    pending: Option<(Packet, usize)>,
    /// The link is not open: never opened yet, or failed and not reopened.
    down: bool,
    /// The link opened at least once (its first opening is no reconnection).
    opened: bool,
    /// A failure to open it the first time was logged.
    said_not_open: bool,
    /// `Down` events reported.
    generation: u32,
    backoff: Duration,
    next_reopen: Duration,
    /// A call of this pass failed without taking the link down.
    failed: bool,
    /// The last sleep ended because the link's descriptor was ready.
    fd_ready: bool,
    /// Such wake-ups in a row that moved no byte.
    idle_wakes: u32,
    /// When the last pass began to read.
    looked_at: Duration,
    /// Line rates logged since the link was opened (0: free).
    rates_said: [u32; 4],
}

impl Worker {
    pub(super) fn new(
        link: Box<dyn Link>,
        rings: Rings,
        counters: Arc<IoCounters>,
        waker: Arc<Waker>,
        stop: Arc<AtomicBool>,
        idle: Duration,
    ) -> Self {
        Self {
            link,
            rings,
            counters,
            waker,
            stop,
            epoch: Duration::ZERO,
            idle,
            pending: None,
            // A link is handed over closed: the first pass opens it and reports `Up`.
            down: true,
            opened: false,
            said_not_open: false,
            generation: 0,
            backoff: BACKOFF_MIN,
            next_reopen: Duration::ZERO,
            failed: false,
            fd_ready: false,
            idle_wakes: 0,
            looked_at: Duration::ZERO,
            rates_said: [0; 4],
        }
    }

    pub(super) fn now(&self) -> Duration {
        monotonic_now().saturating_sub(self.epoch)
    }

    /// The instant `now` counts from (the thread's [`Worker::run`] sets it too).
    pub(super) fn set_epoch(&mut self, epoch: Duration) {
        self.epoch = epoch;
    }

    /// Whether the link is open.
    pub(super) fn is_up(&self) -> bool {
        !self.down
    }

    /// The tick's look at a link it runs itself ([`super::inline`]): reopens a failed link
    /// when its backoff is over (dropping what was queued while it was down), otherwise
    /// hands over what arrived and publishes the horizon. Never waits.
    pub(super) fn look(&mut self, buf: &mut [u8; PACKET_LEN]) {
        let now = self.now();
        if self.still_down(now) {
            return;
        }
        self.failed = false;
        self.looked_at = now;
        self.read_available(now, buf);
        if !self.down {
            self.publish_horizon();
        }
    }

    /// A failed link is reopened when its backoff is over; while it stays down, what the
    /// tick queued for it is dropped (stale by the time it could go). Whether it is down.
    fn still_down(&mut self, now: Duration) -> bool {
        if !self.down {
            return false;
        }
        if now >= self.next_reopen {
            self.try_reopen(now);
        }
        if self.down {
            while self.rings.tx.pop().is_ok() {}
            self.pending = None;
        }
        self.down
    }

    pub(super) fn run(&mut self, epoch: Duration) {
        self.epoch = epoch;
        let mut buf = [0u8; PACKET_LEN];
        while !self.stop.load(Ordering::Relaxed) {
            let now = self.now();
            if self.still_down(now) {
                self.sleep(now, self.next_reopen.saturating_sub(now), false);
                continue;
            }
            self.failed = false;
            let moved = self.bytes_moved();
            self.write_queued(now, |_| true);
            self.looked_at = self.now();
            self.read_available(now, &mut buf);
            if self.down {
                continue;
            }
            self.publish_horizon();
            if !self.fd_ready || self.bytes_moved() != moved {
                self.idle_wakes = 0;
            } else {
                self.idle_wakes = self.idle_wakes.saturating_add(1);
            }
            self.fd_ready = false;
            if self.failed || self.idle_wakes > MAX_IDLE_WAKES {
                self.idle_wakes = 0;
                self.sleep(now, ERROR_PAUSE, false);
                continue;
            }
            let wait = self
                .link
                .next_event(now)
                .map_or(self.idle, |at| at.saturating_sub(now).min(self.idle));
            if !wait.is_zero() {
                self.sleep(now, wait, true);
            }
        }
    }

    /// Every byte that arrived before the last look is in the ring; every message queued
    /// before the oldest one still unwritten is written.
    fn publish_horizon(&self) {
        let unwritten = self
            .pending
            .as_ref()
            .map(|(packet, _)| packet.at())
            .or_else(|| self.rings.tx.peek().ok().map(Packet::at));
        let heard = unwritten.map_or(self.looked_at, |at| at.min(self.looked_at));
        self.counters
            .heard_ns
            .store(duration_ns(heard), Ordering::Release);
    }

    /// Bytes moved either way so far (to tell a wake-up that did something).
    fn bytes_moved(&self) -> u64 {
        self.counters.bytes_in.load(Ordering::Relaxed)
            + self.counters.bytes_out.load(Ordering::Relaxed)
    }

    /// Sleeps in poll(2) up to `timeout` after `now`, or until the tick's wish
    /// ([`super::LinkPort::queued_and_look_by`]) if that comes first and no look after it happened
    /// yet: until the tick wakes the thread or, with `on_link`, the link's descriptor is
    /// ready (readable; writable too while bytes wait to go out).
    fn sleep(&mut self, now: Duration, timeout: Duration, on_link: bool) {
        let mut timeout = timeout;
        if on_link {
            let until = duration_ns(now.saturating_add(timeout));
            self.counters
                .sleep_until_ns
                .store(until.max(1), Ordering::SeqCst);
            let wish = self.counters.look_by_ns.load(Ordering::SeqCst);
            if wish != NEVER && wish > duration_ns(self.looked_at) {
                let wish = Duration::from_nanos(wish);
                timeout = timeout.min(wish.saturating_sub(self.now()));
                // The sleep ends at the wish: say so, so that a later wish (the deadline
                // moved on with a reply) needs no wake-up. The tick that saw the first,
                // later end in between only wakes the thread once too often.
                let until = duration_ns(now.saturating_add(timeout)).min(duration_ns(wish));
                self.counters
                    .sleep_until_ns
                    .store(until.max(1), Ordering::SeqCst);
            }
        }
        if !timeout.is_zero() {
            self.poll(timeout, on_link);
        }
        self.counters.sleep_until_ns.store(0, Ordering::SeqCst);
    }

    fn poll(&mut self, timeout: Duration, on_link: bool) {
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
            self.generation = self.generation.wrapping_add(1);
            self.counters.up.store(false, Ordering::Relaxed);
            self.backoff = BACKOFF_MIN;
            self.next_reopen = now + self.backoff;
            if self.rings.events.push(LinkEvent::Down).is_err() {
                self.counters.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    fn try_reopen(&mut self, now: Duration) {
        match self.link.reopen(now) {
            Ok(()) => {
                self.down = false;
                // Reopened at its configured rate.
                self.counters.baud.store(0, Ordering::Relaxed);
                self.rates_said = [0; 4];
                self.counters.up.store(true, Ordering::Relaxed);
                if self.opened {
                    self.counters.reconnects.fetch_add(1, Ordering::Relaxed);
                }
                self.opened = true;
                if self.rings.events.push(LinkEvent::Up).is_err() {
                    self.counters.dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
            Err(error) => {
                self.counters.errors.fetch_add(1, Ordering::Relaxed);
                if !self.opened && !self.said_not_open {
                    // Once: an operator whose boards stay `starting` learns why. (This
                    // thread is not the tick; a rare log line here costs the tick nothing.)
                    self.said_not_open = true;
                    tracing::warn!(
                        "link {}: not open yet ({error}); its boards stay starting until it \
                         opens, retried every {} ms .. {} s",
                        self.link.name(),
                        BACKOFF_MIN.as_millis(),
                        BACKOFF_MAX.as_secs()
                    );
                }
                self.backoff = (self.backoff * 2).min(BACKOFF_MAX);
                self.next_reopen = now + self.backoff;
            }
        }
    }

    /// A message went out whole (or, on SPI, was answered with a floating bus).
    fn report_written(&mut self) {
        let at = self.now();
        self.counters
            .last_write_ns
            .store(duration_ns(at), Ordering::Relaxed);
        self.counters.transactions.fetch_add(1, Ordering::Relaxed);
        let report = Written {
            generation: self.generation,
            at,
        };
        if self.rings.written.push(report).is_err() {
            self.counters.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Writes what the tick queued, in order, as one batch ([`Link::batch`]: an SPI
    /// socket sends them in one system call). A message not begun yet is written only when
    /// `admit(its length)` says so; otherwise it stays queued (and is counted as deferred).
    pub(super) fn write_queued(&mut self, now: Duration, admit: impl FnMut(usize) -> bool) {
        if self.rings.tx.is_empty() && self.pending.is_none() {
            return;
        }
        if let Err(error) = self.link.batch(now, true) {
            self.fail(now, error.kind());
            return;
        }
        self.write_each(now, admit);
        if self.down {
            return;
        }
        if let Err(error) = self.link.batch(now, false) {
            self.fail(now, error.kind());
        }
    }

    fn write_each(&mut self, now: Duration, mut admit: impl FnMut(usize) -> bool) {
        loop {
            let (packet, offset) = match self.pending.take() {
                Some(pending) => pending,
                None => match self.rings.tx.peek() {
                    Ok(next) if !admit(next.bytes().len()) => {
                        let waiting = self.rings.tx.slots() as u64;
                        self.counters.deferred.fetch_add(waiting, Ordering::Relaxed);
                        return;
                    }
                    Ok(_) => match self.rings.tx.pop() {
                        Ok(packet) => (packet, 0),
                        Err(_) => return,
                    },
                    Err(_) => return,
                },
            };
            if let Some(baud) = packet.rate() {
                if !self.change_rate(now, baud) {
                    return;
                }
                continue;
            }
            let bytes = &packet.bytes()[offset..];
            match self.link.write(now, bytes) {
                Ok(written) => {
                    self.counters
                        .bytes_out
                        .fetch_add(written as u64, Ordering::Relaxed);
                    if written < bytes.len() {
                        if written > 0 {
                            let at = duration_ns(self.now());
                            self.counters.last_write_ns.store(at, Ordering::Relaxed);
                        }
                        // A full transmit buffer: keep the rest, go on when it drains.
                        self.pending = Some((packet, offset + written));
                        return;
                    }
                    self.report_written();
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
                        let chunk = Packet::stamped(&floating[..len], self.now());
                        if self.rings.rx.push(chunk).is_err() {
                            self.counters
                                .dropped
                                .fetch_add(len as u64, Ordering::Relaxed);
                        }
                        self.report_written();
                    }
                    self.fail(now, error.kind());
                    return;
                }
            }
        }
    }

    /// A queued rate change: the messages before it leave the transmitter first
    /// ([`Link::flush`], which waits until they did), then the link takes `baud`. Whether
    /// the link is still up and the next packet may go.
    fn change_rate(&mut self, now: Duration, baud: u32) -> bool {
        if let Err(error) = self.link.batch(now, false) {
            self.fail(now, error.kind());
            return false;
        }
        // What the link runs at now, as its name says it (`serial /dev/ttyUSB0 @ 19200 8N1`).
        let before = named_rate(self.link.name());
        let result = self
            .link
            .flush(now)
            .and_then(|()| self.link.set_baud(now, baud));
        match result {
            Ok(()) => {
                self.counters.baud.store(baud, Ordering::Relaxed);
                // A driver says the rate its board listens at even when the link runs at it
                // already (after every opening): only a change is worth a line. A thread of
                // its own, not the tick: a rare line here costs the tick nothing (for a link
                // the tick runs itself it is one line per rate change).
                // On a bus whose boards talk at two rates (one pack switched, the other not
                // yet) the rate changes before every other message: each rate is said once
                // per opening.
                let new_rate = !self.rates_said.contains(&baud);
                if before != Some(baud) && new_rate {
                    if let Some(slot) = self.rates_said.iter_mut().find(|slot| **slot == 0) {
                        *slot = baud;
                    }
                    tracing::info!("link {}: line rate now {baud} baud", self.link.name());
                }
            }
            Err(error) => {
                tracing::warn!(
                    "link {}: cannot change to {baud} baud: {error}",
                    self.link.name()
                );
                self.fail(now, error.kind());
                if self.down {
                    return false;
                }
            }
        }
        if let Err(error) = self.link.batch(now, true) {
            self.fail(now, error.kind());
            return false;
        }
        true
    }

    pub(super) fn read_available(&mut self, now: Duration, buf: &mut [u8; PACKET_LEN]) {
        loop {
            match self.link.read(now, buf) {
                Ok(0) => return,
                Ok(len) => {
                    // A short read took everything there was: another would only say so
                    // (one system call fewer a pass).
                    let all = len < buf.len();
                    let at = self.now();
                    self.counters
                        .bytes_in
                        .fetch_add(len as u64, Ordering::Relaxed);
                    self.counters.reads.fetch_add(1, Ordering::Relaxed);
                    self.counters
                        .last_read_ns
                        .store(duration_ns(at), Ordering::Relaxed);
                    if self
                        .rings
                        .rx
                        .push(Packet::stamped(&buf[..len], at))
                        .is_err()
                    {
                        // The tick has not drained for QUEUE_PACKETS packets: count it.
                        self.counters
                            .dropped
                            .fetch_add(len as u64, Ordering::Relaxed);
                    }
                    if all {
                        return;
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

/// The rate a link's name gives after its ` @ ` (`serial /dev/ttyUSB0 @ 19200 8N1`).
fn named_rate(name: &str) -> Option<u32> {
    let (_, after) = name.rsplit_once(" @ ")?;
    let digits = after.split(' ').next()?;
    digits.parse().ok()
}
