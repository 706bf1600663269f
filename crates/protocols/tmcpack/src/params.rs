//! Little-endian parameter access on the seven parameter bytes P0..P6 (manual section 8:
//! "Parameters with more than 1 byte are to be transmitted with the least significant byte
//! first").

/// Number of parameter bytes in a frame.
pub(crate) const PARAMS: usize = 7;

pub(crate) fn u16_at(p: &[u8; PARAMS], i: usize) -> u16 {
    u16::from_le_bytes([byte(p, i), byte(p, i + 1)])
}

pub(crate) fn i16_at(p: &[u8; PARAMS], i: usize) -> i16 {
    i16::from_le_bytes([byte(p, i), byte(p, i + 1)])
}

pub(crate) fn u32_at(p: &[u8; PARAMS], i: usize) -> u32 {
    u32::from_le_bytes([byte(p, i), byte(p, i + 1), byte(p, i + 2), byte(p, i + 3)])
}

pub(crate) fn i32_at(p: &[u8; PARAMS], i: usize) -> i32 {
    u32_at(p, i) as i32
}

pub(crate) fn byte(p: &[u8; PARAMS], i: usize) -> u8 {
    p.get(i).copied().unwrap_or(0)
}

pub(crate) fn put(p: &mut [u8; PARAMS], i: usize, bytes: &[u8]) {
    for (k, b) in bytes.iter().enumerate() {
        if let Some(slot) = p.get_mut(i + k) {
            *slot = *b;
        }
    }
}

pub(crate) fn bit0(p: &[u8; PARAMS], i: usize) -> bool {
    byte(p, i) & 1 != 0
}
