//! Fixed-size, zero-padded UTF-8 text fields.

/// Writes `text` into `field`, zero padded. Text longer than the field is cut at the last
/// whole UTF-8 character that fits; returns `false` when anything was cut.
pub fn write_text(field: &mut [u8], text: &str) -> bool {
    let mut end = text.len().min(field.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let (head, tail) = field.split_at_mut(end);
    head.copy_from_slice(&text.as_bytes()[..end]);
    tail.fill(0);
    end == text.len()
}

/// Reads a zero-padded UTF-8 field. Stops at the first zero byte; bytes that are not valid
/// UTF-8 end the text there (a field from a foreign writer never makes this fail).
pub fn read_text(field: &[u8]) -> &str {
    let len = field.iter().position(|&b| b == 0).unwrap_or(field.len());
    let bytes = &field[..len];
    match core::str::from_utf8(bytes) {
        Ok(text) => text,
        Err(error) => core::str::from_utf8(&bytes[..error.valid_up_to()]).unwrap_or_default(),
    }
}

#[cfg(test)]
mod tests {
    use super::{read_text, write_text};

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
}
