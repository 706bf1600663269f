//! Board → host: [`Reply`], and the incremental [`ReplyDecoder`].

use super::line::{LineDecoder, SliceWriter, channel, int, tokens};
use super::{CodecError, MAX_SPEED};

/// The capacity of a firmware version.
pub const VERSION_LEN: usize = 16;

/// A firmware version as the board reports it: 1..=16 printable ASCII bytes, no space.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Version {
    bytes: [u8; VERSION_LEN],
    len: u8,
}

impl Version {
    /// `text` as a version.
    ///
    /// # Errors
    /// [`CodecError::Malformed`] for an empty or overlong text, or one with a space or a
    /// byte that is not printable ASCII.
    pub fn new(text: &str) -> Result<Self, CodecError> {
        let valid =
            (1..=VERSION_LEN).contains(&text.len()) && text.bytes().all(|b| b.is_ascii_graphic());
        if !valid {
            return Err(CodecError::Malformed);
        }
        let mut bytes = [0; VERSION_LEN];
        bytes[..text.len()].copy_from_slice(text.as_bytes());
        Ok(Self {
            bytes,
            len: text.len() as u8,
        })
    }

    /// The version text.
    #[must_use]
    pub fn as_str(&self) -> &str {
        // Only ASCII is ever stored (`new`).
        core::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

impl core::fmt::Debug for Version {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Version({:?})", self.as_str())
    }
}

/// What a channel does, as the status letter of a position reply says.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// `I`: standing, coils energised (holding).
    Idle,
    /// `M`: stepping (a move, a jog or a stop ramp).
    Moving,
    /// `O`: coils off, the motor is free.
    Off,
}

impl Motion {
    const fn letter(self) -> char {
        match self {
            Self::Idle => 'I',
            Self::Moving => 'M',
            Self::Off => 'O',
        }
    }
}

/// The error codes of an `E<n>` reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoardError {
    /// `E1`: not a command (unknown letter, missing or malformed argument, overlong line).
    Syntax = 1,
    /// `E2`: no such channel.
    NoSuchChannel = 2,
    /// `E3`: a value out of range (speed, acceleration, velocity).
    OutOfRange = 3,
}

/// One reply of the board (README "Replies").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reply {
    /// `AS2 <version>`: the answer to `?`.
    Identity(Version),
    /// `P<ch> <position> <velocity> <I|M|O>`: the answer to `P<ch>?`.
    Position {
        /// Channel.
        channel: u8,
        /// Position counter, steps.
        position: i32,
        /// Step rate now, steps/s (signed).
        velocity: i32,
        /// What the channel does.
        motion: Motion,
    },
    /// `OK`: a command was accepted.
    Done,
    /// `E<n>`: a request was refused; nothing changed.
    Error(BoardError),
}

impl Reply {
    /// Writes the reply, terminator included, at the start of `buf`; the bytes written.
    ///
    /// # Errors
    /// [`CodecError::BufferTooSmall`] when `buf` cannot hold the line (40 bytes always do).
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, CodecError> {
        let out = SliceWriter::new(buf);
        match self {
            Self::Identity(version) => out.line(format_args!("AS2 {}", version.as_str())),
            Self::Position {
                channel,
                position,
                velocity,
                motion,
            } => out.line(format_args!(
                "P{channel} {position} {velocity} {}",
                motion.letter()
            )),
            Self::Done => out.line(format_args!("OK")),
            Self::Error(error) => out.line(format_args!("E{}", *error as u8)),
        }
    }

    /// The reply on `line` (without its terminator).
    ///
    /// # Errors
    /// [`CodecError::Malformed`] for a line that is no reply.
    pub fn parse(line: &[u8]) -> Result<Self, CodecError> {
        let mut words = tokens(line)?;
        let first = words.next().ok_or(CodecError::Malformed)?;
        let reply = match first {
            "OK" => Self::Done,
            "E1" => Self::Error(BoardError::Syntax),
            "E2" => Self::Error(BoardError::NoSuchChannel),
            "E3" => Self::Error(BoardError::OutOfRange),
            "AS2" => Self::Identity(Version::new(words.next().ok_or(CodecError::Malformed)?)?),
            _ => {
                let channel = channel(first.strip_prefix('P').ok_or(CodecError::Malformed)?)?;
                let mut next = || words.next().ok_or(CodecError::Malformed);
                let position = int(next()?)?;
                let velocity = int(next()?)?;
                if velocity.unsigned_abs() > MAX_SPEED {
                    return Err(CodecError::Malformed);
                }
                let motion = match next()? {
                    "I" => Motion::Idle,
                    "M" => Motion::Moving,
                    "O" => Motion::Off,
                    _ => return Err(CodecError::Malformed),
                };
                Self::Position {
                    channel,
                    position,
                    velocity,
                    motion,
                }
            }
        };
        if words.next().is_some() {
            return Err(CodecError::Malformed);
        }
        Ok(reply)
    }
}

/// The bytes a reply starts with: where a line with garbage in front is tried again.
const REPLY_STARTS: &[u8] = b"AEOP";

/// Replies out of a byte stream, in any chunking. A line that is no reply is tried again
/// from each later byte a reply can start with (`A`, `E`, `O`, `P`), so noise in front of
/// a reply costs nothing; a line with no reply in it is one [`CodecError`].
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Default)]
pub struct ReplyDecoder {
    lines: LineDecoder,
}

impl ReplyDecoder {
    /// Nothing received yet.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            lines: LineDecoder::new(),
        }
    }

    /// Takes one byte: a reply or a bad line once its terminator arrived, else `None`.
    pub fn push(&mut self, byte: u8) -> Option<Result<Reply, CodecError>> {
        let line = match self.lines.push(byte)? {
            Ok(line) => line,
            Err(error) => return Some(Err(error)),
        };
        let found = (0..line.len())
            .filter(|&start| REPLY_STARTS.contains(&line[start]))
            .find_map(|start| Reply::parse(&line[start..]).ok());
        Some(found.ok_or(CodecError::Malformed))
    }

    /// Forgets a partial line (the link went down).
    pub fn clear(&mut self) {
        self.lines.clear();
    }
}
