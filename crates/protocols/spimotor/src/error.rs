//! The one error type of the crate.

use core::fmt;

/// Why a transaction could not be encoded or decoded.
///
/// Small and `Copy`, so decoders can return it on any input without allocating.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Error {
    /// The caller's buffer is too small for the transaction; `needed` bytes are required.
    BufferTooSmall {
        /// Bytes the encoding needs.
        needed: usize,
    },
    /// The transaction ended before its address byte and port byte were clocked.
    MissingHeader,
    /// A write transaction carried fewer data bytes than its port takes, or more than a
    /// fixed 4-byte port takes; or a read clocked no data byte at all.
    Length {
        /// The port of the transaction.
        port: u8,
        /// Data bytes present (after the address and port bytes).
        got: usize,
    },
    /// The port is not documented for this direction (write or read).
    UnknownPort {
        /// The port byte.
        port: u8,
        /// `true` for a read transaction (address bit 0 set).
        read: bool,
    },
    /// An address-change unlock port (0xf1, 0xf2) was written with a value other than the
    /// key it takes (0x55, 0xaa).
    WrongUnlockKey {
        /// The port byte.
        port: u8,
        /// The value written.
        value: u8,
    },
    /// An SPI address must be even: bit 0 of the address byte is the read/write flag.
    OddAddress(u8),
    /// The identification string was not terminated by a 0 byte within the bytes clocked.
    Unterminated,
    /// An identification string longer than [`crate::IDENTIFICATION_CAPACITY`] bytes, or one
    /// containing a 0 byte.
    InvalidIdentification,
    /// A step delay outside 0..=255 tenths of a millisecond.
    StepDelayRange,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::BufferTooSmall { needed } => {
                write!(f, "buffer too small: the transaction needs {needed} bytes")
            }
            Self::MissingHeader => {
                f.write_str("transaction shorter than its address and port bytes")
            }
            Self::Length { port, got } => {
                write!(f, "port {port:#04x}: wrong number of data bytes ({got})")
            }
            Self::UnknownPort { port, read } => {
                let dir = if read { "read" } else { "write" };
                write!(f, "port {port:#04x} is not a documented {dir} port")
            }
            Self::WrongUnlockKey { port, value } => {
                write!(f, "port {port:#04x}: {value:#04x} is not its unlock key")
            }
            Self::OddAddress(a) => {
                write!(f, "SPI address {a:#04x} is odd (bit 0 is the read flag)")
            }
            Self::Unterminated => f.write_str("identification string not terminated by 0"),
            Self::InvalidIdentification => {
                f.write_str("identification string too long or containing a 0 byte")
            }
            Self::StepDelayRange => {
                f.write_str("step delay outside 0..=25.5 ms (one byte of 0.1 ms)")
            }
        }
    }
}

impl std::error::Error for Error {}
