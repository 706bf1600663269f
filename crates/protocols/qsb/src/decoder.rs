//! Incremental line decoders for both directions of the wire.
//!
//! [`CommandDecoder`] is what the board (or the simulator) runs on the bytes the host
//! sends: a line buffer closed by CR or LF, with backspace support. [`ResponseDecoder`] is
//! what a driver runs on the bytes the board sends: a response ends at its `!` (the EOR
//! termination may be empty), so the decoder finds lines by their type letter and
//! resynchronises after garbage without waiting for a line end.

use crate::response::{MAX_RESPONSE_LEN, Prefix, parse_prefix};
use crate::{CommandLine, Error, Response, ResponseType};

/// Bytes a command line may hold before it is discarded as over-long. Eleven are enough
/// for the longest command; the rest leaves room for leading zeros in the data field.
pub const COMMAND_LINE_CAPACITY: usize = 32;

/// ASCII backspace: "will erase a partially entered command from the command buffer".
pub const BACKSPACE: u8 = 0x08;

/// Incremental decoder of command lines (host → board).
///
/// A line ends at CR or LF; empty lines (the second byte of a CR LF pair, say) are
/// skipped. A backspace discards the partial line. A line longer than
/// [`COMMAND_LINE_CAPACITY`] is reported as [`Error::LineTooLong`] at its end. Every
/// non-empty line yields exactly one result, so a board can answer each one.
#[derive(Debug, Clone)]
pub struct CommandDecoder {
    buf: [u8; COMMAND_LINE_CAPACITY],
    len: usize,
    overflow: bool,
    bad: u64,
}

impl Default for CommandDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl CommandDecoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; COMMAND_LINE_CAPACITY],
            len: 0,
            overflow: false,
            bad: 0,
        }
    }

    /// Feeds one byte; returns the decoded line when the byte ended one.
    pub fn push(&mut self, byte: u8) -> Option<Result<CommandLine, Error>> {
        match byte {
            b'\r' | b'\n' => {
                let result = if self.overflow {
                    Some(Err(Error::LineTooLong))
                } else if self.len == 0 {
                    None
                } else {
                    Some(CommandLine::decode(
                        self.buf.get(..self.len).unwrap_or_default(),
                    ))
                };
                self.len = 0;
                self.overflow = false;
                if matches!(result, Some(Err(_))) {
                    self.bad += 1;
                }
                result
            }
            BACKSPACE => {
                self.len = 0;
                self.overflow = false;
                None
            }
            _ => {
                match self.buf.get_mut(self.len) {
                    Some(slot) if !self.overflow => {
                        *slot = byte;
                        self.len += 1;
                    }
                    _ => self.overflow = true,
                }
                None
            }
        }
    }

    /// Feeds bytes from `input` until one ends a line; returns how many were consumed and
    /// the line, if any. Call again with the rest of the input.
    pub fn decode(&mut self, input: &[u8]) -> (usize, Option<Result<CommandLine, Error>>) {
        for (i, &b) in input.iter().enumerate() {
            if let Some(r) = self.push(b) {
                return (i + 1, Some(r));
            }
        }
        (input.len(), None)
    }

    /// Number of lines that failed to decode so far.
    pub const fn bad_lines(&self) -> u64 {
        self.bad
    }

    /// Whether a partial line is buffered.
    pub const fn is_idle(&self) -> bool {
        self.len == 0 && !self.overflow
    }

    /// Discards any partial line (a board reset).
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflow = false;
    }
}

/// Incremental decoder of response lines (board → host).
///
/// Accepts every EOR format: with or without spaces, time stamp, CR and LF (CR, LF and
/// spaces between lines are skipped). After garbage it restarts at the next byte that can
/// begin a line, re-examining the bytes it had buffered, so a valid line right after a
/// truncated one is never lost. One stretch of discarded bytes between two valid lines
/// counts as one bad frame.
///
/// Limitation: a response type `e` is also a hex digit, so garbage made of a type letter
/// and hex digits can swallow the start of an `e` line that follows it with no byte in
/// between; no decoder can tell those apart on the wire.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct ResponseDecoder {
    buf: [u8; MAX_RESPONSE_LEN],
    len: usize,
    in_garbage: bool,
    bad: u64,
}

impl Default for ResponseDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl ResponseDecoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_RESPONSE_LEN],
            len: 0,
            in_garbage: false,
            bad: 0,
        }
    }

    fn garbage(&mut self) {
        if !self.in_garbage {
            self.in_garbage = true;
            self.bad += 1;
        }
    }

    /// Feeds one byte; returns a response when the byte completed one.
    pub fn push(&mut self, byte: u8) -> Option<Response> {
        if self.len == 0 {
            if ResponseType::from_letter(byte).is_some() {
                if let Some(slot) = self.buf.first_mut() {
                    *slot = byte;
                    self.len = 1;
                }
            } else if !matches!(byte, b'\r' | b'\n' | b' ') {
                self.garbage();
            }
            return None;
        }
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
            }
            None => {
                // Cannot happen (the grammar ends a line within the buffer), but never
                // index out of bounds: treat as garbage.
                self.len = 0;
                self.garbage();
                return None;
            }
        }
        self.examine()
    }

    /// Looks at the buffered bytes, dropping leading bytes until they are a valid line
    /// prefix.
    fn examine(&mut self) -> Option<Response> {
        let mut start = 0;
        while start < self.len {
            let window = self.buf.get(start..self.len).unwrap_or_default();
            let is_start = window
                .first()
                .is_some_and(|b| ResponseType::from_letter(*b).is_some());
            let verdict = if is_start {
                parse_prefix(window)
            } else {
                Prefix::Invalid(Error::BadType)
            };
            match verdict {
                Prefix::Incomplete => {
                    self.buf.copy_within(start..self.len, 0);
                    self.len -= start;
                    return None;
                }
                Prefix::Complete(response, used) => {
                    // A valid prefix holds no `!` before its end, so a line completed
                    // here always ends at the newest byte: `start + used == self.len`.
                    let _ = used;
                    self.len = 0;
                    self.in_garbage = false;
                    return Some(response);
                }
                Prefix::Invalid(_) => {
                    self.garbage();
                    start += 1;
                }
            }
        }
        self.len = 0;
        None
    }

    /// Feeds bytes from `input` until one completes a response; returns how many were
    /// consumed and the response, if any. Call again with the rest of the input.
    pub fn decode(&mut self, input: &[u8]) -> (usize, Option<Response>) {
        for (i, &b) in input.iter().enumerate() {
            if let Some(r) = self.push(b) {
                return (i + 1, Some(r));
            }
        }
        (input.len(), None)
    }

    /// Number of stretches of garbage discarded so far.
    pub const fn bad_frames(&self) -> u64 {
        self.bad
    }

    /// Discards any partial line (after a reconnect).
    pub fn clear(&mut self) {
        self.len = 0;
        self.in_garbage = false;
    }
}
