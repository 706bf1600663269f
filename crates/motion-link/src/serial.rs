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
    /// The rate the port runs at now ([`Link::set_baud`]; the configured one after a reopen).
    baud: u32,
}

impl SerialLink {
    /// Validates `config` without opening the port; the link is closed (every call returns
    /// `Disconnected`) until [`reopen`](Link::reopen) succeeds.
    pub fn new(config: SerialConfig) -> Result<Self, LinkError> {
        let name = Self::name_at(&config, config.baud);
        if config.path.is_empty() {
            return Err(LinkError::Config {
                link: name,
                reason: "empty tty path; give the device path, e.g. /dev/ttyUSB0".into(),
            });
        }
        check_baud(&name, config.baud)?;
        Ok(Self {
            baud: config.baud,
            config,
            name,
            port: None,
            stats: LinkStats::default(),
        })
    }

    fn name_at(config: &SerialConfig, baud: u32) -> Arc<str> {
        format!("serial {} @ {baud} 8N1", config.path).into()
    }

    /// The rate the port runs at now: the configured one, or the last
    /// [`set_baud`](Link::set_baud) since the port was opened.
    pub fn baud(&self) -> u32 {
        self.baud
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
        // A (re)opened port runs at the configured rate again.
        self.baud = self.config.baud;
        self.name = Self::name_at(&self.config, self.baud);
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

fn check_baud(name: &Arc<str>, baud: u32) -> Result<(), LinkError> {
    if baud == 0 || baud > 4_000_000 {
        return Err(LinkError::Config {
            link: name.clone(),
            reason: format!("baud {baud} out of range 1..=4000000"),
        });
    }
    Ok(())
}

/// The output rate the tty behind `fd` is set to (termios2 `c_ospeed`, which holds any
/// rate, standard or not, as `serialport` sets it). On the master side of a
/// pseudo-terminal it reads the slave's settings: a simulator serving a pty learns the rate
/// its client set ([`Link::set_baud`] on the other end) and can garble what crosses at
/// another rate, as a real line would.
///
/// # Errors
/// The `ioctl(TCGETS2)` error (not a tty).
#[allow(unsafe_code)] // one ioctl filling a plain C struct we own
pub fn tty_speed(fd: BorrowedFd<'_>) -> io::Result<u32> {
    use nix::libc;
    // SAFETY: `termios2` is a plain C struct for which all-zero bytes are a valid value;
    // TCGETS2 writes at most `size_of::<termios2>()` bytes into the struct we pass by
    // pointer, which lives until the call returns; `fd` is a valid open descriptor for the
    // duration of the borrow.
    let mut settings: libc::termios2 = unsafe { core::mem::zeroed() };
    // SAFETY: see above.
    let result = unsafe { libc::ioctl(fd.as_raw_fd(), libc::TCGETS2, &mut settings) };
    if result < 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(settings.c_ospeed)
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
        crate::link::write_in_turn(self, now, parts)
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

    /// Waits for nothing: the caller flushed (the I/O thread does before a rate change).
    fn set_baud(&mut self, _now: Duration, baud: u32) -> Result<(), LinkError> {
        check_baud(&self.name, baud)?;
        let Some(port) = self.port.as_mut() else {
            return Err(self.closed());
        };
        match port.set_baud_rate(baud) {
            Ok(()) => {
                self.baud = baud;
                self.name = Self::name_at(&self.config, baud);
                Ok(())
            }
            Err(e) => {
                self.stats.errors += 1;
                Err(match e.kind {
                    serialport::ErrorKind::Io(kind) => LinkError::Io {
                        link: self.name.clone(),
                        op: "set the baud rate",
                        kind,
                        errno: None,
                    },
                    _ => LinkError::Config {
                        link: self.name.clone(),
                        reason: format!("cannot set {baud} baud: {}", e.description),
                    },
                })
            }
        }
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
