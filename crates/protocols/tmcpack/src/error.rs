//! The crate's one error type.

use core::fmt;

/// Everything that can go wrong while encoding or decoding a tmcpack frame.
///
/// Small and `Copy`, so that it can be returned from a real-time path without allocation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Error {
    /// The output buffer is shorter than the frame (`needed` bytes).
    BufferTooSmall {
        /// Bytes the frame needs.
        needed: usize,
    },
    /// The input is not exactly one frame long (9 bytes on RS-232/RS-485, 8 on CAN).
    WrongLength {
        /// Bytes expected.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// The command byte is not in the instruction table (manual section 9).
    UnknownCommand(u8),
    /// The command exists but the manual documents no response for it.
    NoReply(u8),
    /// A motor number outside 0..=5 (manual section 8: "motnr (0..5)").
    InvalidMotor(u8),
    /// A parameter outside the range its table gives.
    OutOfRange {
        /// The parameter, named as in the manual.
        field: &'static str,
    },
    /// A CAN identifier that no pack uses (address 0 is not valid on CAN, manual 6.2; the
    /// identifier has 11 bits).
    InvalidCanId(u16),
    /// A conversion asked for a microstep frequency above the 200 kHz limit (manual 8.2).
    FrequencyTooHigh,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::BufferTooSmall { needed } => {
                write!(
                    f,
                    "output buffer too small: a tmcpack frame needs {needed} bytes"
                )
            }
            Self::WrongLength { expected, got } => {
                write!(f, "tmcpack frame must be {expected} bytes, got {got}")
            }
            Self::UnknownCommand(c) => write!(f, "unknown tmcpack command ${c:02X}"),
            Self::NoReply(c) => write!(f, "tmcpack command ${c:02X} has no response"),
            Self::InvalidMotor(m) => write!(f, "motor number {m} out of range 0..=5"),
            Self::OutOfRange { field } => write!(f, "tmcpack parameter `{field}` out of range"),
            Self::InvalidCanId(id) => write!(f, "CAN identifier ${id:03X} is not a pack address"),
            Self::FrequencyTooHigh => {
                write!(
                    f,
                    "microstep frequency above the 200 kHz limit (manual 8.2)"
                )
            }
        }
    }
}

impl core::error::Error for Error {}
