//! The one error type of this crate.

use core::fmt;

/// Everything that can go wrong while encoding or decoding a QuadQuad2Drv packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Error {
    /// The caller's buffer cannot hold the encoded packet.
    BufferTooSmall,
    /// The payload would make the packet longer than the 255 bytes its U8 size can describe.
    PayloadTooLong,
    /// The first byte is not STX (2).
    BadStx,
    /// The Packet Size byte is impossible (below 4) or disagrees with the bytes given.
    BadSize,
    /// The 8-bit sum of all bytes, checksum included, is not zero.
    BadChecksum,
    /// The Packet ID is not one the datasheet documents (the value is kept).
    UnknownPacket(u8),
    /// The packet is documented but never travels in this direction (packet 3 from the
    /// master, or a reply id that has no such reply).
    WrongDirection(u8),
    /// The payload length does not match the packet's layout.
    Length,
    /// A field holds a value the datasheet does not define (e.g. control mode 7).
    InvalidField,
    /// Typed data disagrees with itself or with its layout (e.g. a success reply without data).
    Inconsistent,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BufferTooSmall => f.write_str("qq2drv: output buffer too small for the packet"),
            Self::PayloadTooLong => f.write_str("qq2drv: payload exceeds 251 bytes"),
            Self::BadStx => f.write_str("qq2drv: packet does not start with STX (2)"),
            Self::BadSize => f.write_str("qq2drv: impossible packet size"),
            Self::BadChecksum => f.write_str("qq2drv: checksum mismatch"),
            Self::UnknownPacket(id) => write!(f, "qq2drv: unknown packet id {id}"),
            Self::WrongDirection(id) => {
                write!(
                    f,
                    "qq2drv: packet id {id} does not travel in this direction"
                )
            }
            Self::Length => f.write_str("qq2drv: payload length does not match the packet layout"),
            Self::InvalidField => f.write_str("qq2drv: field value not defined by the datasheet"),
            Self::Inconsistent => f.write_str("qq2drv: typed data inconsistent with its layout"),
        }
    }
}

impl std::error::Error for Error {}
