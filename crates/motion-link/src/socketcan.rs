//! A Linux SocketCAN interface (`can0`, a USB adapter's `can1`, a virtual `vcan0`) through a
//! raw `AF_CAN` socket, non-blocking.
//!
//! The link carries CAN frames as fixed 16-byte records ([`motion_base::CanRecord`]: Linux's
//! `struct can_frame` with a little-endian identifier): a write takes whole records and
//! sends one frame each, a read returns whole records, one a received frame. Its kind is
//! [`LinkKind::Stream`]: a board on it keeps the stream rules (one request in flight on the
//! bus) and frames its messages as CAN telegrams instead of bytes.
//!
//! Opened with raw sockets through `nix` (no `socketcan` crate): `socket(2)`,
//! `if_nametoindex(3)`, `read(2)`/`write(2)` of 16-byte frames and `poll(2)` are all
//! there; only `bind(2)` needs `libc`, because nix's socket addresses are sealed and have
//! no `sockaddr_can` (one `unsafe` call, with its SAFETY note). The `socketcan` crate would
//! bring a second `nix` (0.31 beside the workspace's 0.30), `socket2`, `embedded-can`,
//! `nb`, `hex`, `log` and `smallvec` for the same four calls.
//!
//! The bit rate is the interface's (`ip link set can0 up type can bitrate 250000`; a raw
//! socket cannot set it): the configured one only names the link and times the boards.
//!
//! Errors: an interface that does not exist (yet: a USB adapter not plugged in) or is down
//! is [`Disconnected`](crate::LinkErrorKind::Disconnected), so the server retries;
//! a kernel without SocketCAN (`EAFNOSUPPORT`) is
//! [`Unsupported`](crate::LinkErrorKind::Unsupported) and says which module to load.

use core::time::Duration;
use std::os::fd::{AsFd, AsRawFd, BorrowedFd, OwnedFd};
use std::sync::Arc;

use motion_base::{CAN_RECORD_LEN, CanRecord};
use nix::errno::Errno;
use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::socket::{AddressFamily, SockFlag, SockProtocol, SockType, socket};
use nix::sys::time::TimeSpec;

use crate::can_records::RecordSender;
use crate::error::LinkError;
use crate::link::{Link, LinkKind, LinkStats};

/// Frames one read may take from the socket before it returns (bounds a pass on a busy bus).
const READ_FRAMES: usize = 64;

/// How to open a SocketCAN link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SocketCanConfig {
    /// The network interface, e.g. `can0` or `vcan0`.
    pub interface: String,
    /// The bus's bit rate, bits per second (the interface's own, set with `ip link`; named
    /// here for the link's name and the boards' timing).
    pub bitrate: u32,
}

impl SocketCanConfig {
    /// A configuration for `interface` at `bitrate`.
    pub fn new(interface: impl Into<String>, bitrate: u32) -> Self {
        Self {
            interface: interface.into(),
            bitrate,
        }
    }
}

/// Whether this kernel can open `AF_CAN` raw sockets at all (the `can` and `can_raw`
/// modules): `Err` says why not.
pub fn kernel_support() -> Result<(), Errno> {
    open_socket().map(drop)
}

fn open_socket() -> Result<OwnedFd, Errno> {
    socket(
        AddressFamily::Can,
        SockType::Raw,
        SockFlag::SOCK_NONBLOCK | SockFlag::SOCK_CLOEXEC,
        SockProtocol::CanRaw,
    )
}

/// A SocketCAN interface behind the [`Link`] trait (see the module docs).
#[derive(Debug)]
pub struct SocketCanLink {
    config: SocketCanConfig,
    name: Arc<str>,
    socket: Option<OwnedFd>,
    /// Bytes of a record written in part.
    tx: [u8; CAN_RECORD_LEN],
    tx_len: usize,
    /// A received record handed out in part (a read buffer shorter than a record).
    rx: [u8; CAN_RECORD_LEN],
    rx_from: usize,
    rx_to: usize,
    stats: LinkStats,
    /// Frames received and sent.
    frames_in: u64,
    frames_out: u64,
}

impl SocketCanLink {
    /// Validates `config` without opening the socket; the link is closed (every call
    /// returns `Disconnected`) until [`reopen`](Link::reopen) succeeds.
    pub fn new(config: SocketCanConfig) -> Result<Self, LinkError> {
        let name: Arc<str> =
            format!("socketcan {} @ {} bit/s", config.interface, config.bitrate).into();
        // IFNAMSIZ is 16 with the terminating zero.
        if config.interface.is_empty()
            || config.interface.len() > 15
            || config.interface.contains(['/', '\0', ' '])
        {
            return Err(LinkError::Config {
                link: name,
                reason: format!(
                    "{:?} is no network interface name (1 to 15 characters, e.g. can0)",
                    config.interface
                ),
            });
        }
        if config.bitrate == 0 || config.bitrate > 1_000_000 {
            return Err(LinkError::Config {
                link: name,
                reason: format!(
                    "bit rate {} out of range 1..=1000000 (CAN 2.0)",
                    config.bitrate
                ),
            });
        }
        Ok(Self {
            config,
            name,
            socket: None,
            tx: [0; CAN_RECORD_LEN],
            tx_len: 0,
            rx: [0; CAN_RECORD_LEN],
            rx_from: 0,
            rx_to: 0,
            stats: LinkStats::default(),
            frames_in: 0,
            frames_out: 0,
        })
    }

    /// Validates `config` and opens the socket on the interface.
    pub fn open(config: SocketCanConfig) -> Result<Self, LinkError> {
        let mut link = Self::new(config)?;
        link.open_socket()?;
        Ok(link)
    }

    /// The configuration this link was made with.
    pub fn config(&self) -> &SocketCanConfig {
        &self.config
    }

    /// Frames received and sent since creation.
    pub fn frames(&self) -> (u64, u64) {
        (self.frames_in, self.frames_out)
    }

    fn open_socket(&mut self) -> Result<(), LinkError> {
        self.socket = None;
        self.tx_len = 0;
        self.rx_from = 0;
        self.rx_to = 0;
        let index =
            nix::net::if_::if_nametoindex(self.config.interface.as_str()).map_err(|errno| {
                match errno {
                    Errno::ENODEV | Errno::ENXIO | Errno::ENOENT => LinkError::Disconnected {
                        link: self.name.clone(),
                        detail: "no such network interface; plug the adapter in or create it \
                             (ip link add dev vcan0 type vcan), then reopen",
                    },
                    other => self.os_error("if_nametoindex", other),
                }
            })?;
        let fd = open_socket().map_err(|errno| match errno {
            Errno::EAFNOSUPPORT | Errno::EPROTONOSUPPORT => LinkError::Unsupported {
                link: self.name.clone(),
                what: "SocketCAN: this kernel has no AF_CAN raw sockets; load the can and \
                       can_raw modules (modprobe can_raw)",
            },
            other => self.os_error("socket(AF_CAN)", other),
        })?;
        bind_interface(&fd, index).map_err(|errno| match errno {
            Errno::ENODEV | Errno::ENXIO => LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the interface vanished while the socket was bound; reopen",
            },
            other => self.os_error("bind", other),
        })?;
        self.socket = Some(fd);
        Ok(())
    }

    fn os_error(&self, op: &'static str, errno: Errno) -> LinkError {
        match errno {
            Errno::ENETDOWN => LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the CAN interface is down; bring it up \
                         (ip link set can0 up type can bitrate 250000)",
            },
            Errno::ENODEV | Errno::ENXIO => LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the CAN interface vanished (ENODEV)",
            },
            other => LinkError::from_io(&self.name, op, &std::io::Error::from(other)),
        }
    }

    fn fail(&mut self, err: LinkError) -> LinkError {
        self.stats.errors += 1;
        if matches!(err, LinkError::Disconnected { .. }) {
            self.socket = None;
        }
        err
    }

    fn closed(&mut self) -> LinkError {
        self.fail(LinkError::Disconnected {
            link: self.name.clone(),
            detail: "the socket is closed after an earlier failure; reopen it",
        })
    }

    /// Sends the assembled record; `Ok(false)` when the interface's queue is full.
    fn send_record(&mut self) -> Result<bool, LinkError> {
        let Some(record) = CanRecord::from_bytes(&self.tx) else {
            self.tx_len = 0;
            return Err(self.fail(LinkError::Unsupported {
                link: self.name.clone(),
                what: "a CAN record with a length byte above 8 (CAN 2.0 carries 0..=8 bytes); \
                       the record was dropped",
            }));
        };
        let frame = native_frame(&record);
        let Some(fd) = self.socket.as_ref() else {
            return Err(self.closed());
        };
        match nix::unistd::write(fd, &frame) {
            Ok(n) if n == frame.len() => {
                self.tx_len = 0;
                self.frames_out += 1;
                Ok(true)
            }
            Ok(_) => Err(self.fail(LinkError::Protocol {
                link: self.name.clone(),
                what: "the kernel took part of a CAN frame",
            })),
            // A full transmit queue (ENOBUFS on a real controller) or a non-blocking socket
            // that would wait: the record stays, the caller comes back.
            Err(Errno::EAGAIN | Errno::ENOBUFS | Errno::EINTR) => Ok(false),
            Err(errno) => {
                let err = self.os_error("write", errno);
                Err(self.fail(err))
            }
        }
    }

    /// Reads one frame into `self.rx`; `Ok(false)` when none is waiting.
    fn receive_record(&mut self) -> Result<bool, LinkError> {
        let Some(fd) = self.socket.as_ref() else {
            return Err(self.closed());
        };
        let mut frame = [0u8; CAN_RECORD_LEN];
        loop {
            match nix::unistd::read(fd, &mut frame) {
                Ok(n) if n == CAN_RECORD_LEN => {
                    let Some(record) = record_of_native(&frame) else {
                        // Not a classic frame; look at the next one.
                        continue;
                    };
                    self.rx = record.to_bytes();
                    self.rx_from = 0;
                    self.rx_to = CAN_RECORD_LEN;
                    self.frames_in += 1;
                    return Ok(true);
                }
                // CAN FD frames (72 bytes) only reach sockets that ask for them; anything
                // else is not ours.
                Ok(_) => {}
                Err(Errno::EAGAIN | Errno::EINTR) => return Ok(false),
                Err(errno) => {
                    let err = self.os_error("read", errno);
                    return Err(self.fail(err));
                }
            }
        }
    }
}

/// `bind(2)` of an `AF_CAN` socket to interface `index`.
#[allow(unsafe_code)] // nix has no sockaddr_can (its SockaddrLike is sealed): libc's bind.
fn bind_interface(fd: &OwnedFd, index: u32) -> Result<(), Errno> {
    let ifindex = nix::libc::c_int::try_from(index).map_err(|_| Errno::ENODEV)?;
    // SAFETY: `sockaddr_can` is a plain C struct for which all-zero bytes are a valid value
    // (the kernel reads the family and index only for CAN_RAW).
    let mut addr: nix::libc::sockaddr_can = unsafe { core::mem::zeroed() };
    addr.can_family = nix::libc::AF_CAN as nix::libc::sa_family_t;
    addr.can_ifindex = ifindex;
    let len = core::mem::size_of::<nix::libc::sockaddr_can>() as nix::libc::socklen_t;
    // SAFETY: `fd` is an open socket owned by the caller for the whole call; `addr` is a
    // live, initialised `sockaddr_can` of `len` bytes that the kernel only reads.
    let rc = unsafe {
        nix::libc::bind(
            fd.as_raw_fd(),
            (&raw const addr).cast::<nix::libc::sockaddr>(),
            len,
        )
    };
    Errno::result(rc).map(drop)
}

/// The kernel's `struct can_frame` (native byte order) for a record.
fn native_frame(record: &CanRecord) -> [u8; CAN_RECORD_LEN] {
    let mut frame = record.to_bytes();
    frame[..4].copy_from_slice(&record.can_id.to_ne_bytes());
    frame
}

/// The record of a `struct can_frame` read from the kernel; `None` for a length above 8.
fn record_of_native(frame: &[u8; CAN_RECORD_LEN]) -> Option<CanRecord> {
    let mut bytes = *frame;
    let id = u32::from_ne_bytes([frame[0], frame[1], frame[2], frame[3]]);
    bytes[..4].copy_from_slice(&id.to_le_bytes());
    // The kernel's padding and len8_dlc bytes are not part of the record.
    bytes[5..8].fill(0);
    CanRecord::from_bytes(&bytes)
}

impl RecordSender for SocketCanLink {
    fn pending(&mut self) -> (&mut [u8; CAN_RECORD_LEN], &mut usize) {
        (&mut self.tx, &mut self.tx_len)
    }
    fn send_pending(&mut self, _now: Duration) -> Result<bool, LinkError> {
        self.send_record()
    }
    fn count_out(&mut self, bytes: usize) {
        self.stats.bytes_out += bytes as u64;
    }
}

impl Link for SocketCanLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Stream
    }

    fn name(&self) -> &str {
        &self.name
    }

    /// Takes bytes up to whole records, sending each as one frame; a record's first bytes
    /// may come in one call and the rest in the next. Stops (returning what it took) when
    /// the interface's transmit queue is full.
    fn write(&mut self, now: Duration, bytes: &[u8]) -> Result<usize, LinkError> {
        if self.socket.is_none() {
            return Err(self.closed());
        }
        crate::can_records::write_records(self, now, bytes)
    }

    fn write_parts(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        crate::link::write_in_turn(self, now, parts)
    }

    fn read(&mut self, now: Duration, buf: &mut [u8]) -> Result<usize, LinkError> {
        self.read_wait(now, buf, Duration::ZERO)
    }

    /// Whole records while they fit (a buffer shorter than a record gets its first bytes,
    /// the next read the rest).
    fn read_wait(
        &mut self,
        _now: Duration,
        buf: &mut [u8],
        timeout: Duration,
    ) -> Result<usize, LinkError> {
        let Some(fd) = self.socket.as_ref() else {
            return Err(self.closed());
        };
        if !timeout.is_zero() && self.rx_from == self.rx_to {
            let mut fds = [PollFd::new(fd.as_fd(), PollFlags::POLLIN)];
            // Whatever poll says, the read below tells frames and errors apart.
            let _ = ppoll(&mut fds, Some(TimeSpec::from_duration(timeout)), None);
        }
        let mut n = 0;
        let mut frames = 0;
        while n < buf.len() {
            if self.rx_from == self.rx_to {
                if frames == READ_FRAMES || buf.len() - n < CAN_RECORD_LEN && n > 0 {
                    break;
                }
                match self.receive_record() {
                    Ok(true) => frames += 1,
                    Ok(false) => break,
                    Err(e) if n == 0 => return Err(e),
                    // Hand out what was read; the failure shows on the next call.
                    Err(_) => break,
                }
            }
            let chunk = (self.rx_to - self.rx_from).min(buf.len() - n);
            if let (Some(dst), Some(src)) = (
                buf.get_mut(n..n + chunk),
                self.rx.get(self.rx_from..self.rx_from + chunk),
            ) {
                dst.copy_from_slice(src);
            }
            self.rx_from += chunk;
            n += chunk;
        }
        self.stats.bytes_in += n as u64;
        Ok(n)
    }

    /// Frames go to the kernel in `write`: nothing waits here.
    fn flush(&mut self, _now: Duration) -> Result<(), LinkError> {
        if self.socket.is_none() {
            return Err(self.closed());
        }
        Ok(())
    }

    fn reopen(&mut self, _now: Duration) -> Result<(), LinkError> {
        match self.open_socket() {
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

    fn poll_fd(&self) -> Option<BorrowedFd<'_>> {
        self.socket.as_ref().map(AsFd::as_fd)
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
        for bad in ["", "can0/x", "a-name-of-16-chr", "can 0"] {
            let err = SocketCanLink::new(SocketCanConfig::new(bad, 250_000)).unwrap_err();
            assert_eq!(err.kind(), LinkErrorKind::Config, "{bad:?}: {err}");
        }
        let err = SocketCanLink::new(SocketCanConfig::new("can0", 0)).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Config);
        assert!(err.to_string().contains("can0"), "{err}");
        let link = SocketCanLink::new(SocketCanConfig::new("can0", 250_000)).expect("valid");
        assert_eq!(link.name(), "socketcan can0 @ 250000 bit/s");
        assert_eq!(link.kind(), LinkKind::Stream);
    }

    #[test]
    fn a_closed_link_says_so_and_an_absent_interface_is_disconnected_or_unsupported() {
        let mut link =
            SocketCanLink::new(SocketCanConfig::new("motiondcan9", 250_000)).expect("valid");
        let err = link.read(Duration::ZERO, &mut [0; 16]).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Disconnected);
        assert_eq!(link.stats().errors, 1);
        let err = link.reopen(Duration::ZERO).unwrap_err();
        // No such interface is looked up before the socket is made: Disconnected on any
        // kernel (the server retries until the adapter is there).
        assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
        assert!(
            err.to_string().contains("no such network interface"),
            "{err}"
        );
    }

    #[test]
    fn native_frames_and_records_agree() {
        let record = CanRecord::standard(0x7F0, &[0x20, 1, 2]).expect("valid");
        let native = native_frame(&record);
        assert_eq!(native[4], 3);
        let mut from_kernel = native;
        // The kernel may set len8_dlc and leave padding; the record has neither.
        from_kernel[7] = 9;
        assert_eq!(record_of_native(&from_kernel), Some(record));
    }
}
