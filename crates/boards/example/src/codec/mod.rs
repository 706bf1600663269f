//! The AS-2's wire format, sans I/O (the crate's README is its datasheet): requests
//! ([`Request`]) encoded into a caller's buffer and parsed from a line, replies ([`Reply`])
//! likewise, and the incremental decoders that cut a byte stream into lines
//! ([`LineDecoder`]) and replies ([`ReplyDecoder`]). Nothing here reads a clock, touches
//! a file descriptor or allocates; the driver and the simulator share it, so both ends
//! speak the same bytes.
//!
//! ```
//! use board_example::codec::{Motion, Reply, ReplyDecoder, Request};
//!
//! let mut buf = [0u8; 64];
//! let len = Request::Move { channel: 0, target: -1200, speed: 4000, accel: 20_000 }
//!     .encode(&mut buf)
//!     .expect("in range");
//! assert_eq!(&buf[..len], b"M0 -1200 4000 20000\r");
//!
//! // Replies arrive in any chunking, after any garbage.
//! let mut decoder = ReplyDecoder::new();
//! let mut replies = b"\xff\x00P0 -1200 0 I\r".iter().filter_map(|b| decoder.push(*b));
//! assert_eq!(
//!     replies.next(),
//!     Some(Ok(Reply::Position { channel: 0, position: -1200, velocity: 0, motion: Motion::Idle }))
//! );
//! ```

mod line;
mod reply;
mod request;
#[cfg(test)]
mod tests;

pub use line::LineDecoder;
pub use reply::{BoardError, Motion, Reply, ReplyDecoder, VERSION_LEN, Version};
pub use request::Request;

/// Stepper channels on the board (`<ch>` is `0` or `1`).
pub const CHANNELS: usize = 2;
/// The fastest step rate the board runs at, steps/s (speed of a move, |velocity| of a jog).
pub const MAX_SPEED: u32 = 50_000;
/// The hardest acceleration (or deceleration) the board ramps with, steps/s².
pub const MAX_ACCEL: u32 = 1_000_000;
/// The longest line either side sends, terminator included; a longer line is garbage.
pub const MAX_LINE: usize = 40;
/// Every request and every reply ends with this byte.
pub const END: u8 = b'\r';

/// Why bytes could not be encoded or decoded. Small and `Copy`: the driver counts them,
/// the simulator answers `E1` / `E3` for them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CodecError {
    /// The caller's buffer cannot hold the message.
    #[error("the buffer of {0} bytes cannot hold the message")]
    BufferTooSmall(usize),
    /// A value the board does not take (channel, speed, acceleration out of range).
    #[error(
        "a value outside the board's range (channel 0..=1, speed 1..=50000, accel 1..=1000000)"
    )]
    OutOfRange,
    /// A line longer than [`MAX_LINE`] bytes: dropped up to its terminator.
    #[error("a line longer than {MAX_LINE} bytes")]
    LineTooLong,
    /// A line that is no message of the protocol.
    #[error("a line that is not an AS-2 message")]
    Malformed,
}
