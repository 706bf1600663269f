//! The one error type of the crate.

use core::fmt;

/// Everything that can go wrong while encoding or decoding QSB traffic.
///
/// Small and `Copy`, so that decoders can return it on every byte without allocating.
/// [`Error::Rejected`] and [`Error::Unsupported`] are not codec failures: they are the
/// board's own `e` and `x` replies, surfaced by [`crate::Response::check`] so that a driver
/// can never drop them silently.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Error {
    /// The caller's output buffer is too small for the encoded line.
    BufferTooSmall,
    /// The input ended before a complete field.
    Truncated,
    /// The first character is not a command type (`R`, `W`, `S`) or response type
    /// (`r`, `w`, `s`, `e`, `x`).
    BadType,
    /// A register or data field holds a character that is not a hexadecimal digit.
    BadHex,
    /// A data field has more than eight significant hexadecimal digits.
    DataTooLong,
    /// A response line does not have the `!` end-of-line indicator where it must be.
    MissingBang,
    /// Bytes follow where the line must end.
    TrailingBytes,
    /// A command line is longer than the decoder's line buffer.
    LineTooLong,
    /// The register number is not in the command list (00–16).
    UnknownRegister,
    /// The register does not accept this command type (e.g. `W07`, `S00`), or the
    /// product variant does not have it: the board answers `x`.
    NotPermitted,
    /// The data is outside the register's documented data range or meaning: the board
    /// answers `e` and does not write it.
    OutOfRange,
    /// The register's data field was expected to carry a value and did not.
    MissingData,
    /// The board answered `e`: the data sent to `register` was refused.
    Rejected {
        /// Register of the refused command.
        register: u8,
        /// The refused data, as echoed by the board.
        data: u32,
    },
    /// The board answered `x`: it does not support the command.
    Unsupported {
        /// Register of the unsupported command.
        register: u8,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall => f.write_str("output buffer too small for the QSB line"),
            Self::Truncated => f.write_str("QSB line ends before a complete field"),
            Self::BadType => f.write_str("QSB line does not start with a command or response type"),
            Self::BadHex => f.write_str("QSB line holds a non-hexadecimal digit in a hex field"),
            Self::DataTooLong => f.write_str("QSB data field has more than eight hex digits"),
            Self::MissingBang => {
                f.write_str("QSB response line lacks its '!' end-of-line indicator")
            }
            Self::TrailingBytes => f.write_str("unexpected bytes after the end of a QSB line"),
            Self::LineTooLong => f.write_str("QSB command line longer than the line buffer"),
            Self::UnknownRegister => f.write_str("QSB register number is not in the command list"),
            Self::NotPermitted => {
                f.write_str("QSB register does not accept this command type on this product")
            }
            Self::OutOfRange => f.write_str("data outside the QSB register's documented range"),
            Self::MissingData => f.write_str("QSB write command without a data field"),
            Self::Rejected { register, data } => write!(
                f,
                "QSB refused data {data:08X} for register {register:02X} (error reply 'e')"
            ),
            Self::Unsupported { register } => write!(
                f,
                "QSB does not support the command on register {register:02X} (reply 'x')"
            ),
        }
    }
}

impl std::error::Error for Error {}
