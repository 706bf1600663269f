//! The one trait every byte transport implements.

use core::fmt;
use core::time::Duration;
use std::os::fd::BorrowedFd;

use crate::error::LinkError;

/// Whether a link carries a byte stream or SPI transactions (one enum with the drivers'
/// buses: `motion_base::LinkKind`).
pub use motion_base::LinkKind;

/// Counters of one link since it was created (they survive [`Link::reopen`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Bytes handed to the caller by [`Link::read`].
    pub bytes_in: u64,
    /// Bytes accepted from the caller by [`Link::write`].
    pub bytes_out: u64,
    /// SPI transactions performed (always 0 on a stream link).
    pub transactions: u64,
    /// Calls that returned an error.
    pub errors: u64,
    /// Successful [`Link::reopen`] calls.
    pub reconnects: u64,
}

/// A byte transport to one device or bus: serial port, spidev, SPI socket or simulated wire.
///
/// Every call is non-blocking unless documented otherwise, so an I/O thread can service
/// many links and the tick loop is never held up. `now` is the caller's monotonic time since
/// an arbitrary epoch, never decreasing; the real transports ignore it, the simulated wire
/// uses it as its only clock.
///
/// After a [`LinkErrorKind::Disconnected`](crate::LinkErrorKind::Disconnected) error the link
/// stays disconnected (every call returns the error again, without a system call) until
/// [`reopen`](Self::reopen) succeeds.
pub trait Link: Send + fmt::Debug {
    /// Stream or SPI.
    fn kind(&self) -> LinkKind;

    /// A human description naming the transport and its path, e.g.
    /// `serial /dev/ttyUSB0 @ 19200 8N1`.
    fn name(&self) -> &str;

    /// Stream: queues or sends `bytes`, returning how many were accepted (possibly fewer,
    /// possibly 0 when the transmit buffer is full). SPI: performs exactly one transaction
    /// (one chip-select assertion) clocking out all of `bytes` and queues as many MISO
    /// bytes for [`read`](Self::read); returns `bytes.len()`.
    fn write(&mut self, now: Duration, bytes: &[u8]) -> Result<usize, LinkError>;

    /// Like [`write`](Self::write) with the bytes of `parts` in order. On an SPI link the
    /// parts form ONE transaction (chip select held across them); a stream link writes as
    /// much as it can and returns the total accepted.
    fn write_parts(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError>;

    /// Moves bytes received so far into `buf`; `Ok(0)` means nothing yet. Never blocks.
    fn read(&mut self, now: Duration, buf: &mut [u8]) -> Result<usize, LinkError>;

    /// Like [`read`](Self::read), but when nothing has arrived yet it waits up to `timeout`
    /// for the first byte (a blocking call for a link's own I/O thread, so it can sleep in
    /// the kernel instead of polling). A simulated link has no clock and never waits: ask
    /// it for [`next_event`](Self::next_event) instead. The default does not wait.
    fn read_wait(
        &mut self,
        now: Duration,
        buf: &mut [u8],
        timeout: Duration,
    ) -> Result<usize, LinkError> {
        let _ = timeout;
        self.read(now, buf)
    }

    /// Pushes queued outgoing bytes towards the device. May block until the operating
    /// system has taken them (serial: until transmitted); never used on the tick thread.
    fn flush(&mut self, now: Duration) -> Result<(), LinkError>;

    /// Closes and opens the underlying transport again (after a disconnection, or to
    /// resynchronise). Pending bytes in both directions are discarded.
    fn reopen(&mut self, now: Duration) -> Result<(), LinkError>;

    /// The earliest instant at which something may become readable without further writes
    /// (a simulated byte finishing its wire time, a device's scheduled reply). `None` when
    /// the link cannot tell (the real transports: poll their file descriptor instead).
    fn next_event(&self, now: Duration) -> Option<Duration> {
        let _ = now;
        None
    }

    /// The file descriptor an I/O thread waits on with poll(2) until the link has
    /// something for it: readable when bytes (or a hang-up) arrived, writable when
    /// [`write_pending`](Self::write_pending) and the transport takes bytes again. `None`
    /// while closed, and for links without one worth polling: a simulated wire (its
    /// [`next_event`](Self::next_event) says when to look) and spidev (a transaction's MISO
    /// bytes are there as soon as [`write`](Self::write) returns).
    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        None
    }

    /// Whether bytes accepted by [`write`](Self::write) still wait inside the link for the
    /// transport to take them (an SPI socket's outgoing buffer): the I/O thread then also
    /// waits for [`poll_fd`](Self::poll_fd) to become writable, and calls
    /// [`read`](Self::read) (which pushes them on) when it is.
    fn write_pending(&self) -> bool {
        false
    }

    /// While `on`, [`write`](Self::write) may only queue what it accepts; turning it off
    /// hands everything queued to the transport at once, without waiting (an SPI socket
    /// then sends the transactions of one pass in one system call, and wakes its peer
    /// once). Links that send in `write` ignore it (the default).
    fn batch(&mut self, now: Duration, on: bool) -> Result<(), LinkError> {
        let _ = (now, on);
        Ok(())
    }

    /// Changes the line rate of a serial link to `baud` for the bytes written from now on
    /// (a board told to change its rate, e.g. the Trinamic pack's `$40`). Bytes queued
    /// before go at whatever rate the transport has when they leave: call
    /// [`flush`](Self::flush) first. [`reopen`](Self::reopen) goes back to the configured
    /// rate. The default, and every SPI link: [`LinkError::Unsupported`].
    fn set_baud(&mut self, now: Duration, baud: u32) -> Result<(), LinkError> {
        let _ = (now, baud);
        Err(LinkError::Unsupported {
            link: self.name().into(),
            what: "changing the line rate",
        })
    }

    /// Counters since creation.
    fn stats(&self) -> LinkStats;
}

impl<L: Link + ?Sized> Link for Box<L> {
    fn kind(&self) -> LinkKind {
        (**self).kind()
    }
    fn name(&self) -> &str {
        (**self).name()
    }
    fn write(&mut self, now: Duration, bytes: &[u8]) -> Result<usize, LinkError> {
        (**self).write(now, bytes)
    }
    fn write_parts(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        (**self).write_parts(now, parts)
    }
    fn read(&mut self, now: Duration, buf: &mut [u8]) -> Result<usize, LinkError> {
        (**self).read(now, buf)
    }
    fn read_wait(
        &mut self,
        now: Duration,
        buf: &mut [u8],
        timeout: Duration,
    ) -> Result<usize, LinkError> {
        (**self).read_wait(now, buf, timeout)
    }
    fn flush(&mut self, now: Duration) -> Result<(), LinkError> {
        (**self).flush(now)
    }
    fn reopen(&mut self, now: Duration) -> Result<(), LinkError> {
        (**self).reopen(now)
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        (**self).next_event(now)
    }
    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        (**self).poll_fd()
    }
    fn write_pending(&self) -> bool {
        (**self).write_pending()
    }
    fn batch(&mut self, now: Duration, on: bool) -> Result<(), LinkError> {
        (**self).batch(now, on)
    }
    fn set_baud(&mut self, now: Duration, baud: u32) -> Result<(), LinkError> {
        (**self).set_baud(now, baud)
    }
    fn stats(&self) -> LinkStats {
        (**self).stats()
    }
}

/// `write_parts` for a link without a gather write: each part through
/// [`Link::write`] in turn, stopping at the first one not taken whole; the bytes taken.
pub(crate) fn write_in_turn<L: Link + ?Sized>(
    link: &mut L,
    now: Duration,
    parts: &[&[u8]],
) -> Result<usize, LinkError> {
    let mut total = 0;
    for part in parts {
        let n = link.write(now, part)?;
        total += n;
        if n < part.len() {
            break;
        }
    }
    Ok(total)
}
