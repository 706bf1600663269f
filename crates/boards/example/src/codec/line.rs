//! Lines: the incremental splitter both sides use, the number tokens, and a writer on a
//! caller's slice.

use core::fmt;

use super::{CodecError, END, MAX_LINE};

/// Cuts a byte stream into lines at [`END`], in a fixed buffer. A line longer than
/// [`MAX_LINE`] is reported once as [`CodecError::LineTooLong`] and dropped up to its
/// terminator; `\n` and NUL before a line starts are skipped (a host that sends `\r\n`, a
/// line that was idle), and an empty line is nothing.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct LineDecoder {
    #[serde(with = "serde_big_array::BigArray")]
    buf: [u8; MAX_LINE],
    len: usize,
    overflow: bool,
}

impl Default for LineDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl LineDecoder {
    /// Nothing received yet.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_LINE],
            len: 0,
            overflow: false,
        }
    }

    /// Takes one byte: a complete line (without its terminator), an overlong line's error,
    /// or `None` while a line is incomplete.
    pub fn push(&mut self, byte: u8) -> Option<Result<&[u8], CodecError>> {
        if byte == END {
            let len = core::mem::take(&mut self.len);
            if core::mem::take(&mut self.overflow) {
                return Some(Err(CodecError::LineTooLong));
            }
            return (len > 0).then_some(Ok(&self.buf[..len]));
        }
        if self.len == 0 && matches!(byte, b'\n' | 0) {
            return None;
        }
        // One byte of room stays for the terminator: a line is at most MAX_LINE with it.
        if self.len + 1 >= MAX_LINE {
            self.overflow = true;
            self.len = 0;
        } else if !self.overflow {
            self.buf[self.len] = byte;
            self.len += 1;
        }
        None
    }

    /// Whether no line is under way (the next byte that is not `\n`, NUL or the end
    /// begins one).
    #[must_use]
    pub const fn is_idle(&self) -> bool {
        self.len == 0 && !self.overflow
    }

    /// Forgets a partial line (the link went down).
    pub fn clear(&mut self) {
        self.len = 0;
        self.overflow = false;
    }
}

/// A signed decimal token: `-?[0-9]+`, nothing else (no `+`, no spaces).
pub(super) fn signed(token: &str) -> Result<i64, CodecError> {
    let digits = token.strip_prefix('-').unwrap_or(token);
    if digits.is_empty() || digits.len() > 10 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(CodecError::Malformed);
    }
    token.parse().map_err(|_| CodecError::Malformed)
}

/// An `i32` token.
pub(super) fn int(token: &str) -> Result<i32, CodecError> {
    i32::try_from(signed(token)?).map_err(|_| CodecError::Malformed)
}

/// A `u32` token in `1..=max`.
pub(super) fn rate(token: &str, max: u32) -> Result<u32, CodecError> {
    let value = signed(token)?;
    if (1..=i64::from(max)).contains(&value) {
        Ok(value as u32)
    } else {
        Err(CodecError::OutOfRange)
    }
}

/// The channel digit that follows a command letter.
pub(super) fn channel(token: &str) -> Result<u8, CodecError> {
    match token.as_bytes() {
        [digit @ b'0'..=b'9'] => Ok(digit - b'0'),
        _ => Err(CodecError::Malformed),
    }
}

/// The line as text, split at single spaces.
pub(super) fn tokens(line: &[u8]) -> Result<core::str::Split<'_, char>, CodecError> {
    let text = core::str::from_utf8(line).map_err(|_| CodecError::Malformed)?;
    if !text.is_ascii() {
        return Err(CodecError::Malformed);
    }
    Ok(text.split(' '))
}

/// `fmt::Write` into a caller's slice, refusing what does not fit.
pub(super) struct SliceWriter<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> SliceWriter<'a> {
    pub(super) fn new(buf: &'a mut [u8]) -> Self {
        Self { buf, len: 0 }
    }

    /// Writes `args` and the terminator; the bytes written.
    pub(super) fn line(mut self, args: fmt::Arguments<'_>) -> Result<usize, CodecError> {
        let capacity = self.buf.len();
        fmt::write(&mut self, args).map_err(|_| CodecError::BufferTooSmall(capacity))?;
        fmt::Write::write_str(&mut self, "\r").map_err(|_| CodecError::BufferTooSmall(capacity))?;
        Ok(self.len)
    }
}

impl fmt::Write for SliceWriter<'_> {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        let end = self.len + text.len();
        let slot = self.buf.get_mut(self.len..end).ok_or(fmt::Error)?;
        slot.copy_from_slice(text.as_bytes());
        self.len = end;
        Ok(())
    }
}
