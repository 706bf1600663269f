//! A serial port (RS-232, RS-485 adapter, USB CDC) through `serialport`, 8N1, non-blocking.

use core::time::Duration;
use std::io::{self, Read, Write};
use std::os::fd::{AsRawFd, BorrowedFd};
use std::sync::Arc;

use serialport::{SerialPort, TTYPort};

use crate::error::LinkError;
use crate::link::{Link, LinkKind, LinkStats};

/// The largest write handed to the tty at once, so that a write after `poll` said
/// "writable" cannot block for long.
const WRITE_CHUNK: usize = 512;

/// How to open a serial link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SerialConfig {
    /// The tty path, e.g. `/dev/ttyUSB0` or a pseudo-terminal printed by `motion-sim --pty`.
    pub path: String,
    /// Line rate in baud (8 data bits, no parity, 1 stop bit).
    pub baud: u32,
    /// Take the port exclusively (TIOCEXCL + flock), as the server should. Default `true`.
    pub exclusive: bool,
}

impl SerialConfig {
    /// A configuration for `path` at `baud`, exclusive.
    pub fn new(path: impl Into<String>, baud: u32) -> Self {
        Self {
            path: path.into(),
            baud,
            exclusive: true,
        }
    }
}

/// A serial port behind the [`Link`] trait.
///
/// Reads and writes never wait: the port's timeout is zero, so an idle read returns `Ok(0)`.
/// A hang-up (`POLLHUP`), a read of 0 bytes after the port said it was readable, or an
/// `EIO`/`ENXIO`/`ENODEV` (an unplugged USB adapter) makes the link
/// [`Disconnected`](crate::LinkErrorKind::Disconnected), and it stays so, without touching
/// the port again, until [`reopen`](Link::reopen).
#[derive(Debug)]
pub struct SerialLink {
    config: SerialConfig,
    name: Arc<str>,
    port: Option<TTYPort>,
    stats: LinkStats,
}

impl SerialLink {
    /// Validates `config` without opening the port; the link is closed (every call returns
    /// `Disconnected`) until [`reopen`](Link::reopen) succeeds.
    pub fn new(config: SerialConfig) -> Result<Self, LinkError> {
        let name: Arc<str> = format!("serial {} @ {} 8N1", config.path, config.baud).into();
        if config.path.is_empty() {
            return Err(LinkError::Config {
                link: name,
                reason: "empty tty path; give the device path, e.g. /dev/ttyUSB0".into(),
            });
        }
        if config.baud == 0 || config.baud > 4_000_000 {
            return Err(LinkError::Config {
                link: name,
                reason: format!("baud {} out of range 1..=4000000", config.baud),
            });
        }
        Ok(Self {
            config,
            name,
            port: None,
            stats: LinkStats::default(),
        })
    }

    /// Validates `config` and opens the port.
    pub fn open(config: SerialConfig) -> Result<Self, LinkError> {
        let mut link = Self::new(config)?;
        link.open_port()?;
        Ok(link)
    }

    /// The configuration this link was made with.
    pub fn config(&self) -> &SerialConfig {
        &self.config
    }

    fn open_port(&mut self) -> Result<(), LinkError> {
        self.port = None;
        let opened = serialport::new(self.config.path.as_str(), self.config.baud)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(Duration::ZERO)
            .exclusive(self.config.exclusive)
            .open_native();
        let port = opened.map_err(|e| self.open_error(&e))?;
        port.clear(serialport::ClearBuffer::All)
            .map_err(|e| self.open_error(&e))?;
        self.port = Some(port);
        Ok(())
    }

    fn open_error(&self, err: &serialport::Error) -> LinkError {
        match err.kind {
            serialport::ErrorKind::NoDevice => LinkError::Io {
                link: self.name.clone(),
                op: "open (port busy or not a tty; is another process using it?)",
                kind: io::ErrorKind::ResourceBusy,
                errno: None,
            },
            serialport::ErrorKind::InvalidInput => LinkError::Config {
                link: self.name.clone(),
                reason: format!("cannot configure the port: {}", err.description),
            },
            serialport::ErrorKind::Io(io::ErrorKind::NotFound) => LinkError::Disconnected {
                link: self.name.clone(),
                detail: "no such device; plug it in, then reopen",
            },
            serialport::ErrorKind::Io(kind) => LinkError::Io {
                link: self.name.clone(),
                op: "open",
                kind,
                errno: None,
            },
            serialport::ErrorKind::Unknown => LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the tty failed to open or configure (EIO/ENXIO)",
            },
        }
    }

    fn closed(&mut self) -> LinkError {
        self.stats.errors += 1;
        LinkError::Disconnected {
            link: self.name.clone(),
            detail: "the port is closed after an earlier failure; reopen it",
        }
    }

    /// Classifies an error from an I/O call on an open port, closing it when fatal.
    fn io_failure(&mut self, op: &'static str, err: &io::Error) -> LinkError {
        self.stats.errors += 1;
        // serialport reports POLLHUP as BrokenPipe and loses the errno of EIO/ENXIO
        // ("Other"): on a tty both mean the device is gone.
        let err = match err.kind() {
            io::ErrorKind::Other => LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the tty reported an I/O error (EIO/ENXIO): the device is gone",
            },
            _ => LinkError::from_io(&self.name, op, err),
        };
        if matches!(err, LinkError::Disconnected { .. }) {
            self.port = None;
        }
        err
    }
}

fn is_idle(err: &io::Error) -> bool {
    matches!(
        err.kind(),
        io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted
    )
}

impl Link for SerialLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Stream
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn write(&mut self, _now: Duration, bytes: &[u8]) -> Result<usize, LinkError> {
        let Some(port) = self.port.as_mut() else {
            return Err(self.closed());
        };
        if bytes.is_empty() {
            return Ok(0);
        }
        let chunk = bytes.get(..WRITE_CHUNK.min(bytes.len())).unwrap_or(bytes);
        match port.write(chunk) {
            Ok(n) => {
                self.stats.bytes_out += n as u64;
                Ok(n)
            }
            Err(e) if is_idle(&e) => Ok(0),
            Err(e) => Err(self.io_failure("write", &e)),
        }
    }

    fn write_parts(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        let mut total = 0;
        for part in parts {
            let n = self.write(now, part)?;
            total += n;
            if n < part.len() {
                break;
            }
        }
        Ok(total)
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
        let Some(port) = self.port.as_mut() else {
            return Err(self.closed());
        };
        if buf.is_empty() {
            return Ok(0);
        }
        // The port's timeout is the poll before its read; it is zero except right here.
        let _ = port.set_timeout(timeout);
        let outcome = port.read(buf);
        let _ = port.set_timeout(Duration::ZERO);
        match outcome {
            Ok(0) => {
                self.stats.errors += 1;
                self.port = None;
                Err(LinkError::Disconnected {
                    link: self.name.clone(),
                    detail: "end of file on the tty (hung up)",
                })
            }
            Ok(n) => {
                self.stats.bytes_in += n as u64;
                Ok(n)
            }
            Err(e) if is_idle(&e) => Ok(0),
            Err(e) => Err(self.io_failure("read", &e)),
        }
    }

    fn flush(&mut self, _now: Duration) -> Result<(), LinkError> {
        let Some(port) = self.port.as_mut() else {
            return Err(self.closed());
        };
        match port.flush() {
            Ok(()) => Ok(()),
            Err(e) if is_idle(&e) => Ok(()),
            Err(e) => Err(self.io_failure("flush", &e)),
        }
    }

    #[allow(unsafe_code)] // serialport's TTYPort implements AsRawFd but not AsFd
    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        let port = self.port.as_ref()?;
        // SAFETY: the descriptor is owned by `port`, which `self` owns and keeps open for
        // at least as long as the returned borrow of `self` lives (closing it needs
        // `&mut self`: `reopen` or a failed call), so it stays valid for `'_`.
        Some(unsafe { BorrowedFd::borrow_raw(port.as_raw_fd()) })
    }

    fn reopen(&mut self, _now: Duration) -> Result<(), LinkError> {
        match self.open_port() {
            Ok(()) => {
                self.stats.reconnects += 1;
                Ok(())
            }
            Err(e) => {
                self.stats.errors += 1;
                Err(e)
            }
        }
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
    fn config_is_validated_before_opening() {
        let err = SerialLink::new(SerialConfig::new("", 9600)).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Config);
        let err = SerialLink::new(SerialConfig::new("/dev/ttyUSB9", 0)).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Config);
        assert!(err.to_string().contains("/dev/ttyUSB9"), "{err}");
    }

    #[test]
    fn a_missing_device_is_disconnected_and_a_closed_link_says_so() {
        let err =
            SerialLink::open(SerialConfig::new("/dev/motiond-no-such-tty", 19200)).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
        let mut link =
            SerialLink::new(SerialConfig::new("/dev/motiond-no-such-tty", 19200)).unwrap();
        let err = link.read(Duration::ZERO, &mut [0; 4]).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Disconnected);
        assert_eq!(link.stats().errors, 1);
    }
}
