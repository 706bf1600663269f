//! UTF-8 text in fixed buffers, always cut on a character boundary.

use core::fmt;

/// The largest index `<= index` that is a character boundary of `text` (`text.len()` when
/// `index` is beyond it).
#[must_use]
pub fn floor_char_boundary(text: &str, index: usize) -> usize {
    let mut end = index.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    end
}

/// Writes `text` into `field`, zero padded. Text longer than the field is cut at the last
/// whole UTF-8 character that fits; returns `false` when anything was cut.
pub fn write_text(field: &mut [u8], text: &str) -> bool {
    let end = floor_char_boundary(text, field.len());
    let (head, tail) = field.split_at_mut(end);
    head.copy_from_slice(&text.as_bytes()[..end]);
    tail.fill(0);
    end == text.len()
}

/// Reads a zero-padded UTF-8 field. Stops at the first zero byte; bytes that are not valid
/// UTF-8 end the text there (a field from a foreign writer never makes this fail).
#[must_use]
pub fn read_text(field: &[u8]) -> &str {
    let len = field.iter().position(|&b| b == 0).unwrap_or(field.len());
    let bytes = &field[..len];
    match core::str::from_utf8(bytes) {
        Ok(text) => text,
        Err(error) => core::str::from_utf8(&bytes[..error.valid_up_to()]).unwrap_or_default(),
    }
}

/// A string of at most `N` bytes formatted in place (no allocation) with `write!`. What does
/// not fit is cut at the last whole character and dropped; writing never fails, and
/// [`truncated`](Self::truncated) tells whether anything was cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FixedText<const N: usize> {
    bytes: [u8; N],
    len: usize,
    truncated: bool,
}

impl<const N: usize> Default for FixedText<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> FixedText<N> {
    /// Empty text.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            bytes: [0; N],
            len: 0,
            truncated: false,
        }
    }

    /// The text written so far.
    #[must_use]
    pub fn as_str(&self) -> &str {
        read_text(self.bytes.get(..self.len).unwrap_or_default())
    }

    /// Whether some text did not fit and was dropped.
    #[must_use]
    pub const fn truncated(&self) -> bool {
        self.truncated
    }
}

/// Written as its text: a snapshot holds what was said, not the spare room.
impl<const N: usize> serde::Serialize for FixedText<N> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.as_str())
    }
}

/// Read back from its text (cut to `N` bytes on a character boundary, as written).
impl<'de, const N: usize> serde::Deserialize<'de> for FixedText<N> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor<const N: usize>;
        impl<const N: usize> serde::de::Visitor<'_> for Visitor<N> {
            type Value = FixedText<N>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a text of at most {N} bytes")
            }
            fn visit_str<E: serde::de::Error>(self, text: &str) -> Result<Self::Value, E> {
                let mut out = FixedText::new();
                let _ = fmt::Write::write_str(&mut out, text);
                Ok(out)
            }
        }
        deserializer.deserialize_str(Visitor::<N>)
    }
}

impl<const N: usize> fmt::Write for FixedText<N> {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        if self.truncated {
            // Once something was cut, nothing later may follow it.
            return Ok(());
        }
        let room = N - self.len;
        let end = floor_char_boundary(text, room);
        if let Some(slot) = self.bytes.get_mut(self.len..self.len + end) {
            slot.copy_from_slice(&text.as_bytes()[..end]);
            self.len += end;
        }
        self.truncated = end < text.len();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{FixedText, floor_char_boundary, read_text, write_text};
    use core::fmt::Write;

    #[test]
    fn round_trip_pads_and_cuts_on_char_boundaries() {
        let mut field = [0xAAu8; 8];
        assert!(write_text(&mut field, "mm"));
        assert_eq!(field, *b"mm\0\0\0\0\0\0");
        assert_eq!(read_text(&field), "mm");

        assert!(!write_text(&mut field, "abcdefgé")); // é is two bytes: cut before it
        assert_eq!(read_text(&field), "abcdefg");

        let invalid = [b'o', b'k', 0xFF, b'x'];
        assert_eq!(read_text(&invalid), "ok");
    }

    #[test]
    fn fixed_text_cuts_on_a_char_boundary_and_stops_there() {
        let mut text = FixedText::<5>::new();
        let tail = "cé";
        let _ = write!(text, "ab{tail}");
        assert_eq!(text.as_str(), "abcé");
        assert!(!text.truncated());
        let _ = write!(text, "éz");
        assert_eq!(text.as_str(), "abcé");
        assert!(text.truncated());
        let mut text = FixedText::<2>::new();
        let _ = write!(text, "aé");
        let _ = write!(text, "z");
        assert_eq!(text.as_str(), "a"); // nothing after a cut

        assert_eq!(floor_char_boundary("aé", 2), 1);
        let mut said = FixedText::<8>::new();
        let _ = write!(said, "late é");
        let bytes = postcard::to_allocvec(&said).expect("serializes");
        let back: FixedText<8> = postcard::from_bytes(&bytes).expect("deserializes");
        assert_eq!(back, said);
        let wide = postcard::to_allocvec(&"0123456789").expect("serializes");
        let cut: FixedText<4> = postcard::from_bytes(&wide).expect("deserializes");
        assert_eq!(cut.as_str(), "0123");
        assert_eq!(floor_char_boundary("aé", 9), 3);
    }
}
