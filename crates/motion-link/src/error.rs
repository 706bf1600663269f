//! What can go wrong on a link, as honest fault kinds.

use std::io;
use std::sync::Arc;

/// The kind of a [`LinkError`], small and `Copy`, for matching and counting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LinkErrorKind {
    /// The device or peer is gone (unplugged adapter, hung-up tty, closed socket).
    Disconnected,
    /// An operating-system I/O error that is not a disconnection.
    Io,
    /// A bounded operation did not complete in time.
    Timeout,
    /// The link cannot do what was asked (e.g. a transfer longer than the link allows).
    Unsupported,
    /// Bytes arrived garbled: a stop bit was missing, typically a baud-rate mismatch.
    Framing,
    /// The link's configuration is invalid (bad speed, mode, path…).
    Config,
    /// A bounded queue in the link is full; read what is pending first.
    Overflow,
    /// The peer broke the link's framing contract (e.g. an SPI socket answering more bytes
    /// than were asked for).
    Protocol,
}

/// A failure on one link. Every message names the link and says what to do.
///
/// The link name is shared (`Arc<str>`), so creating or cloning an error never copies it.
#[derive(Debug, Clone, thiserror::Error)]
pub enum LinkError {
    /// See [`LinkErrorKind::Disconnected`].
    #[error("link {link}: disconnected ({detail}); check the cable or peer, then reopen the link")]
    Disconnected {
        /// Link description.
        link: Arc<str>,
        /// What was observed.
        detail: &'static str,
    },
    /// See [`LinkErrorKind::Io`].
    #[error("link {link}: I/O error during {op}: {kind}{}; the link stays open, retry or reopen it",
        errno.map(|e| format!(" (errno {e})")).unwrap_or_default())]
    Io {
        /// Link description.
        link: Arc<str>,
        /// The operation that failed.
        op: &'static str,
        /// The I/O error kind.
        kind: io::ErrorKind,
        /// The raw OS error number, when there is one.
        errno: Option<i32>,
    },
    /// See [`LinkErrorKind::Timeout`].
    #[error("link {link}: timed out during {op}; is the peer alive and answering?")]
    Timeout {
        /// Link description.
        link: Arc<str>,
        /// The operation that timed out.
        op: &'static str,
    },
    /// See [`LinkErrorKind::Unsupported`].
    #[error("link {link}: unsupported: {what}")]
    Unsupported {
        /// Link description.
        link: Arc<str>,
        /// What was asked.
        what: &'static str,
    },
    /// See [`LinkErrorKind::Framing`].
    #[error(
        "link {link}: framing error (stop bit missing); check that the link baud rate matches the device's"
    )]
    Framing {
        /// Link description.
        link: Arc<str>,
    },
    /// See [`LinkErrorKind::Config`].
    #[error("link {link}: invalid configuration: {reason}")]
    Config {
        /// Link description.
        link: Arc<str>,
        /// What is wrong and what would be valid.
        reason: String,
    },
    /// See [`LinkErrorKind::Overflow`].
    #[error("link {link}: {what} full ({capacity} bytes); read pending bytes before writing more")]
    Overflow {
        /// Link description.
        link: Arc<str>,
        /// Which queue.
        what: &'static str,
        /// Its capacity.
        capacity: usize,
    },
    /// See [`LinkErrorKind::Protocol`].
    #[error("link {link}: peer broke the framing contract: {what}; reopen the link")]
    Protocol {
        /// Link description.
        link: Arc<str>,
        /// What the peer did.
        what: &'static str,
    },
}

impl LinkError {
    /// The fault kind, for matching.
    pub fn kind(&self) -> LinkErrorKind {
        match self {
            Self::Disconnected { .. } => LinkErrorKind::Disconnected,
            Self::Io { .. } => LinkErrorKind::Io,
            Self::Timeout { .. } => LinkErrorKind::Timeout,
            Self::Unsupported { .. } => LinkErrorKind::Unsupported,
            Self::Framing { .. } => LinkErrorKind::Framing,
            Self::Config { .. } => LinkErrorKind::Config,
            Self::Overflow { .. } => LinkErrorKind::Overflow,
            Self::Protocol { .. } => LinkErrorKind::Protocol,
        }
    }

    /// The description of the link that failed.
    pub fn link(&self) -> &str {
        match self {
            Self::Disconnected { link, .. }
            | Self::Io { link, .. }
            | Self::Timeout { link, .. }
            | Self::Unsupported { link, .. }
            | Self::Framing { link }
            | Self::Config { link, .. }
            | Self::Overflow { link, .. }
            | Self::Protocol { link, .. } => link,
        }
    }

    /// Classifies an OS error from `op` on `link`: hang-ups and vanished devices
    /// (`EIO`, `ENXIO`, `ENODEV`, `EPIPE`, `ECONNRESET`…) become
    /// [`Disconnected`](Self::Disconnected), timeouts [`Timeout`](Self::Timeout), the rest
    /// [`Io`](Self::Io).
    pub fn from_io(link: &Arc<str>, op: &'static str, err: &io::Error) -> Self {
        let link = link.clone();
        let errno = err.raw_os_error();
        let vanished = matches!(
            errno,
            Some(e) if e == nix::libc::EIO
                || e == nix::libc::ENXIO
                || e == nix::libc::ENODEV
                || e == nix::libc::ENOENT
        );
        if vanished {
            return Self::Disconnected {
                link,
                detail: "the device vanished (EIO/ENXIO/ENODEV)",
            };
        }
        match err.kind() {
            io::ErrorKind::BrokenPipe
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::NotConnected
            | io::ErrorKind::UnexpectedEof
            | io::ErrorKind::NotFound => Self::Disconnected {
                link,
                detail: "the peer hung up",
            },
            io::ErrorKind::TimedOut => Self::Timeout { link, op },
            kind => Self::Io {
                link,
                op,
                kind,
                errno,
            },
        }
    }
}
