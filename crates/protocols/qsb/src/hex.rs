//! ASCII hexadecimal fields.

use crate::Error;

/// Upper-case digits, as the board writes them.
const DIGITS: &[u8; 16] = b"0123456789ABCDEF";

/// The value of one ASCII hex digit (either case).
pub(crate) const fn digit(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'A'..=b'F' => Some(b - b'A' + 10),
        b'a'..=b'f' => Some(b - b'a' + 10),
        _ => None,
    }
}

/// Parses `field` (1.. digits, either case) as a hex number; leading zeros are ignored,
/// at most eight significant digits.
pub(crate) fn parse(field: &[u8]) -> Result<u32, Error> {
    if field.is_empty() {
        return Err(Error::Truncated);
    }
    let mut value: u32 = 0;
    let mut significant = 0usize;
    for &b in field {
        let d = digit(b).ok_or(Error::BadHex)?;
        if significant > 0 || d != 0 {
            significant += 1;
        }
        if significant > 8 {
            return Err(Error::DataTooLong);
        }
        value = (value << 4) | u32::from(d);
    }
    Ok(value)
}

/// Writes `value` as exactly `width` upper-case hex digits (the low `width` nibbles).
pub(crate) fn write(out: &mut [u8], value: u32, width: usize) -> Result<(), Error> {
    let out = out.get_mut(..width).ok_or(Error::BufferTooSmall)?;
    for (i, slot) in out.iter_mut().enumerate() {
        let shift = 4 * (width - 1 - i);
        let nibble = if shift >= 32 {
            0
        } else {
            (value >> shift) & 0xF
        };
        *slot = DIGITS[nibble as usize];
    }
    Ok(())
}

/// Writes `value` with the fewest hex digits (at least one), as a terse command would.
/// Returns the number of digits written.
pub(crate) fn write_minimal(out: &mut [u8], value: u32) -> Result<usize, Error> {
    let width = if value == 0 {
        1
    } else {
        (8 - value.leading_zeros() as usize / 4).max(1)
    };
    write(out, value, width)?;
    Ok(width)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_write() {
        assert_eq!(parse(b"63"), Ok(0x63));
        assert_eq!(parse(b"0000000000ff"), Ok(0xFF));
        assert_eq!(parse(b"123456789"), Err(Error::DataTooLong));
        assert_eq!(parse(b"1g"), Err(Error::BadHex));
        let mut b = [0u8; 8];
        write(&mut b, 0x1201, 8).unwrap();
        assert_eq!(&b, b"00001201");
        assert_eq!(write_minimal(&mut b, 0x60A), Ok(3));
        assert_eq!(&b[..3], b"60A");
        assert_eq!(write_minimal(&mut b, 0), Ok(1));
        assert_eq!(write_minimal(&mut b, 0xFFFF_CD38), Ok(8));
    }
}
