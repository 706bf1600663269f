//! SPI transactions over a Unix stream socket (docs/ARCHITECTURE.md, "SPI socket contract").
//!
//! Each transaction is sent as a `u16` little-endian length followed by that many MOSI
//! bytes; the peer (a simulator such as `motion-sim --spi-socket`, or a hardware bridge)
//! answers exactly `length` MISO bytes. This side is the socket's client.

use core::time::Duration;
use std::io::{self, Read, Write};
use std::os::fd::{AsFd, BorrowedFd};
use std::os::unix::net::UnixStream;

use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::time::TimeSpec;
use std::sync::Arc;

use crate::error::LinkError;
use crate::link::{Link, LinkKind, LinkStats};

/// How to connect an SPI-socket link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SpiSocketConfig {
    /// Path of the listening Unix socket.
    pub path: String,
    /// Capacity of the outgoing buffer (headers + MOSI not yet taken by the socket).
    pub tx_capacity: usize,
}

impl SpiSocketConfig {
    /// A configuration for `path` with room for two longest transactions outgoing.
    pub fn new(path: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            tx_capacity: 2 * (2 + usize::from(u16::MAX)),
        }
    }
}

/// An SPI-socket link behind the [`Link`] trait. Non-blocking: `write` queues the framed
/// transaction and sends what the socket takes; `read` returns MISO bytes as the peer's
/// answers arrive, in transaction order. A peer that closes the socket, even in the middle
/// of an answer, makes the link [`Disconnected`](crate::LinkErrorKind::Disconnected); a
/// peer that sends bytes nobody asked for is a [`Protocol`](crate::LinkErrorKind::Protocol)
/// error.
#[derive(Debug)]
pub struct SpiSocketLink {
    config: SpiSocketConfig,
    name: Arc<str>,
    stream: Option<UnixStream>,
    tx: Vec<u8>,
    /// MISO bytes asked for and not yet read.
    expected: usize,
    /// Writes only queue ([`Link::batch`]).
    batching: bool,
    stats: LinkStats,
}

impl SpiSocketLink {
    /// Validates `config` without connecting (closed until [`reopen`](Link::reopen)).
    pub fn new(config: SpiSocketConfig) -> Result<Self, LinkError> {
        let name: Arc<str> = format!("spi-socket {}", config.path).into();
        if config.path.is_empty() {
            return Err(LinkError::Config {
                link: name,
                reason: "empty socket path".into(),
            });
        }
        if config.tx_capacity < 2 + usize::from(u16::MAX) {
            return Err(LinkError::Config {
                link: name,
                reason: format!(
                    "tx_capacity {} too small; at least 65537 (one longest transaction)",
                    config.tx_capacity
                ),
            });
        }
        Ok(Self {
            tx: Vec::with_capacity(config.tx_capacity),
            config,
            name,
            stream: None,
            expected: 0,
            batching: false,
            stats: LinkStats::default(),
        })
    }

    /// Validates `config` and connects to the socket.
    pub fn connect(config: SpiSocketConfig) -> Result<Self, LinkError> {
        let mut link = Self::new(config)?;
        link.connect_stream()?;
        Ok(link)
    }

    fn connect_stream(&mut self) -> Result<(), LinkError> {
        self.stream = None;
        self.tx.clear();
        self.expected = 0;
        let stream = UnixStream::connect(&self.config.path).map_err(|e| {
            if e.kind() == io::ErrorKind::ConnectionRefused {
                LinkError::Disconnected {
                    link: self.name.clone(),
                    detail: "nobody listens on the socket; start the simulator or bridge",
                }
            } else {
                LinkError::from_io(&self.name, "connect", &e)
            }
        })?;
        stream
            .set_nonblocking(true)
            .map_err(|e| LinkError::from_io(&self.name, "set_nonblocking", &e))?;
        self.stream = Some(stream);
        Ok(())
    }

    fn fail(&mut self, err: LinkError) -> LinkError {
        self.stats.errors += 1;
        if matches!(
            err,
            LinkError::Disconnected { .. } | LinkError::Protocol { .. }
        ) {
            self.stream = None;
        }
        err
    }

    fn closed(&mut self) -> LinkError {
        self.fail(LinkError::Disconnected {
            link: self.name.clone(),
            detail: "the socket is closed after an earlier failure; reopen it",
        })
    }

    /// Sends as much of the outgoing buffer as the socket takes now.
    fn push_tx(&mut self) -> Result<(), LinkError> {
        let Some(stream) = self.stream.as_mut() else {
            return Err(self.closed());
        };
        let mut sent = 0;
        let result = loop {
            let Some(rest) = self.tx.get(sent..).filter(|r| !r.is_empty()) else {
                break Ok(());
            };
            match stream.write(rest) {
                Ok(0) => {
                    break Err(LinkError::Disconnected {
                        link: self.name.clone(),
                        detail: "the peer stopped accepting bytes",
                    });
                }
                Ok(n) => sent += n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break Ok(()),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => break Err(LinkError::from_io(&self.name, "send", &e)),
            }
        };
        self.tx.drain(..sent);
        result.map_err(|e| self.fail(e))
    }

    fn transact(&mut self, parts: &[&[u8]]) -> Result<usize, LinkError> {
        if self.stream.is_none() {
            return Err(self.closed());
        }
        let len: usize = parts.iter().map(|p| p.len()).sum();
        let Ok(wire_len) = u16::try_from(len) else {
            return Err(self.fail(LinkError::Unsupported {
                link: self.name.clone(),
                what: "transaction longer than 65535 bytes",
            }));
        };
        if len == 0 {
            return Ok(0);
        }
        if self.tx.len() + 2 + len > self.config.tx_capacity {
            return Err(self.fail(LinkError::Overflow {
                link: self.name.clone(),
                what: "outgoing socket buffer",
                capacity: self.config.tx_capacity,
            }));
        }
        self.tx.extend_from_slice(&wire_len.to_le_bytes());
        for part in parts {
            self.tx.extend_from_slice(part);
        }
        self.expected += len;
        self.stats.bytes_out += len as u64;
        self.stats.transactions += 1;
        if !self.batching {
            self.push_tx()?;
        }
        Ok(len)
    }
}

impl Link for SpiSocketLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Spi
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn write(&mut self, _now: Duration, bytes: &[u8]) -> Result<usize, LinkError> {
        self.transact(&[bytes])
    }

    fn write_parts(&mut self, _now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        self.transact(parts)
    }

    fn read(&mut self, now: Duration, buf: &mut [u8]) -> Result<usize, LinkError> {
        self.read_wait(now, buf, Duration::ZERO)
    }

    fn read_wait(
        &mut self,
        _now: Duration,
        buf: &mut [u8],
        timeout: Duration,
    ) -> Result<usize, LinkError> {
        self.push_tx()?;
        if !timeout.is_zero()
            && let Some(stream) = self.stream.as_ref()
        {
            let mut fds = [PollFd::new(stream.as_fd(), PollFlags::POLLIN)];
            let spec = TimeSpec::from_duration(timeout);
            // Whatever poll says, the read below tells data, hang-up and errors apart.
            let _ = ppoll(&mut fds, Some(spec), None);
        }
        let Some(stream) = self.stream.as_mut() else {
            return Err(self.closed());
        };
        let mut probe = [0u8; 1];
        let want = buf.len().min(self.expected);
        let target = if self.expected == 0 {
            // Nothing asked for: still look, to notice a hang-up or unsolicited bytes.
            &mut probe[..]
        } else if want == 0 {
            return Ok(0);
        } else {
            buf.get_mut(..want).unwrap_or_default()
        };
        let result = match stream.read(target) {
            Ok(0) => Err(LinkError::Disconnected {
                link: self.name.clone(),
                detail: if self.expected == 0 {
                    "the peer closed the socket"
                } else {
                    "the peer closed the socket before answering every MISO byte"
                },
            }),
            Ok(_) if self.expected == 0 => Err(LinkError::Protocol {
                link: self.name.clone(),
                what: "MISO bytes arrived that no transaction asked for",
            }),
            Ok(n) => {
                self.expected -= n;
                self.stats.bytes_in += n as u64;
                Ok(n)
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted
                ) =>
            {
                Ok(0)
            }
            Err(e) => Err(LinkError::from_io(&self.name, "receive", &e)),
        };
        result.map_err(|e| self.fail(e))
    }

    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        self.stream.as_ref().map(AsFd::as_fd)
    }

    fn write_pending(&self) -> bool {
        !self.tx.is_empty()
    }

    /// Blocks until every queued transaction has been handed to the socket.
    fn flush(&mut self, _now: Duration) -> Result<(), LinkError> {
        let Some(stream) = self.stream.as_mut() else {
            return Err(self.closed());
        };
        let result = stream
            .set_nonblocking(false)
            .and_then(|()| stream.write_all(&self.tx))
            .and_then(|()| stream.set_nonblocking(true));
        self.tx.clear();
        result.map_err(|e| {
            let err = LinkError::from_io(&self.name, "flush", &e);
            self.fail(err)
        })
    }

    fn reopen(&mut self, _now: Duration) -> Result<(), LinkError> {
        match self.connect_stream() {
            Ok(()) => {
                self.stats.reconnects += 1;
                Ok(())
            }
            Err(e) => Err(self.fail(e)),
        }
    }

    fn batch(&mut self, _now: Duration, on: bool) -> Result<(), LinkError> {
        self.batching = on;
        if on || self.tx.is_empty() {
            return Ok(());
        }
        self.push_tx()
    }

    fn stats(&self) -> LinkStats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LinkErrorKind;

    #[test]
    fn a_batch_only_queues_and_its_end_sends_every_transaction_at_once() {
        let path =
            std::env::temp_dir().join(format!("motion-link-batch-{}.sock", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let listener = std::os::unix::net::UnixListener::bind(&path).expect("bind");
        let mut link =
            SpiSocketLink::connect(SpiSocketConfig::new(path.to_string_lossy())).expect("connect");
        let (mut peer, _) = listener.accept().expect("accept");
        peer.set_nonblocking(true).expect("non-blocking");
        let now = Duration::ZERO;
        link.batch(now, true).expect("batch");
        assert_eq!(link.write(now, &[1, 2]).expect("write"), 2);
        assert_eq!(link.write_parts(now, &[&[3], &[4, 5]]).expect("write"), 3);
        let mut got = [0u8; 64];
        let nothing = peer.read(&mut got).map_err(|e| e.kind());
        assert_eq!(nothing, Err(io::ErrorKind::WouldBlock), "queued, not sent");
        assert!(link.write_pending());
        link.batch(now, false).expect("sent");
        assert!(!link.write_pending());
        peer.set_nonblocking(false).expect("blocking");
        let mut stream = Vec::new();
        while stream.len() < 9 {
            let n = peer.read(&mut got).expect("read");
            assert!(n > 0, "the link hung up");
            stream.extend_from_slice(&got[..n]);
        }
        // Each transaction framed as the contract says, in order.
        assert_eq!(stream, [2, 0, 1, 2, 3, 0, 3, 4, 5]);
        // Outside a batch a write sends at once.
        assert_eq!(link.write(now, &[6]).expect("write"), 1);
        assert!(!link.write_pending());
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn config_is_validated_and_absent_listener_is_disconnected() {
        let err = SpiSocketLink::new(SpiSocketConfig::new("")).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Config);
        let mut small = SpiSocketConfig::new("/tmp/x.sock");
        small.tx_capacity = 100;
        assert_eq!(
            SpiSocketLink::new(small).unwrap_err().kind(),
            LinkErrorKind::Config
        );
        let err =
            SpiSocketLink::connect(SpiSocketConfig::new("/tmp/motiond-no-such.sock")).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
    }
}
