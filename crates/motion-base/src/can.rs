//! CAN frames as the bytes of a link ([`CanRecord`]), and how a link frames its boards'
//! messages ([`LinkFraming`]).
//!
//! A CAN link (a SocketCAN interface, or the simulated CAN wire) carries frames, not a byte
//! stream; behind the one `Link` trait every link shares it moves them as fixed
//! [`CAN_RECORD_LEN`]-byte records, one a frame: a write takes whole records (one frame
//! each), a read returns whole records. The record is Linux's `struct can_frame` with its
//! identifier little-endian — byte for byte what a SocketCAN socket reads and writes on a
//! little-endian host:
//!
//! | bytes | field |
//! |---|---|
//! | 0..4 | `can_id`, u32 little-endian: the identifier (11 bits, or 29 with `EFF`) and the flags `EFF` (bit 31), `RTR` (30), `ERR` (29) |
//! | 4 | data length 0..=8 |
//! | 5..8 | zero |
//! | 8..16 | data (bytes past the length are zero) |
//!
//! Links know no protocol: what an identifier means is the board's (a Trinamic pack's
//! address shifted left by 3, its manual 6.2).
//!
//! ```
//! use motion_base::{CAN_RECORD_LEN, CanRecord};
//!
//! let frame = CanRecord::standard(0x010, &[0x20, 0x00, 0xFE]).expect("11-bit id, ≤ 8 bytes");
//! let bytes = frame.to_bytes();
//! assert_eq!(bytes.len(), CAN_RECORD_LEN);
//! assert_eq!(bytes[..5], [0x10, 0x00, 0x00, 0x00, 3]);
//! assert_eq!(CanRecord::from_bytes(&bytes), Some(frame));
//! assert_eq!(frame.standard_id(), Some(0x010));
//! ```

use core::time::Duration;

/// Bytes of one [`CanRecord`] on a link (Linux's `CAN_MTU`).
pub const CAN_RECORD_LEN: usize = 16;

/// The highest 11-bit (CAN 2.0A) identifier.
pub const CAN_SFF_MAX: u32 = 0x7FF;

/// How a link frames the messages of the boards on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum LinkFraming {
    /// A byte stream (serial) or SPI transactions: a board's own framing.
    #[default]
    Bytes,
    /// CAN frames, one [`CanRecord`] each.
    Can,
}

/// One CAN frame as a link carries it (see the module docs for the byte layout).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanRecord {
    /// Linux's `can_id`: the identifier with the [`EFF`](Self::EFF), [`RTR`](Self::RTR) and
    /// [`ERR`](Self::ERR) flags.
    pub can_id: u32,
    /// Data length 0..=8.
    pub len: u8,
    /// Data; bytes past `len` are zero.
    pub data: [u8; 8],
}

impl CanRecord {
    /// Extended (29-bit) identifier flag.
    pub const EFF: u32 = 0x8000_0000;
    /// Remote transmission request flag.
    pub const RTR: u32 = 0x4000_0000;
    /// Error frame flag (only sockets that ask for them read error frames).
    pub const ERR: u32 = 0x2000_0000;

    /// A CAN 2.0A data frame: `id` of 11 bits, up to 8 bytes of data. `None` beyond either.
    pub fn standard(id: u16, data: &[u8]) -> Option<Self> {
        if u32::from(id) > CAN_SFF_MAX || data.len() > 8 {
            return None;
        }
        let mut bytes = [0u8; 8];
        bytes.get_mut(..data.len())?.copy_from_slice(data);
        Some(Self {
            can_id: u32::from(id),
            len: data.len() as u8,
            data: bytes,
        })
    }

    /// The 11-bit identifier of a CAN 2.0A data frame; `None` for extended, remote and error
    /// frames.
    pub fn standard_id(&self) -> Option<u16> {
        if self.can_id & (Self::EFF | Self::RTR | Self::ERR) != 0 || self.can_id > CAN_SFF_MAX {
            return None;
        }
        Some(self.can_id as u16)
    }

    /// The data bytes (`len` of them, at most 8).
    pub fn payload(&self) -> &[u8] {
        self.data.get(..usize::from(self.len)).unwrap_or(&self.data)
    }

    /// The record's bytes.
    pub fn to_bytes(&self) -> [u8; CAN_RECORD_LEN] {
        let mut out = [0u8; CAN_RECORD_LEN];
        out[..4].copy_from_slice(&self.can_id.to_le_bytes());
        out[4] = self.len.min(8);
        out[8..].copy_from_slice(&self.data);
        for (i, byte) in out[8..].iter_mut().enumerate() {
            if i >= usize::from(self.len) {
                *byte = 0;
            }
        }
        out
    }

    /// The frame a record carries; `None` when its length byte is above 8.
    pub fn from_bytes(bytes: &[u8; CAN_RECORD_LEN]) -> Option<Self> {
        let len = bytes[4];
        if len > 8 {
            return None;
        }
        let mut data = [0u8; 8];
        data[..usize::from(len)].copy_from_slice(&bytes[8..8 + usize::from(len)]);
        Some(Self {
            can_id: u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
            len,
            data,
        })
    }

    /// Bits the frame takes on the bus, without stuffing: a CAN 2.0A data frame is 47 bits
    /// (SOF, 11-bit identifier, RTR, IDE, r0, DLC, 15-bit CRC and its delimiter, ACK slot
    /// and delimiter, 7-bit end of frame, 3-bit intermission) and 8 per data byte; an
    /// extended one 20 bits more (SRR, IDE, 18 identifier bits, r1).
    pub fn bits(&self) -> u64 {
        let extended = if self.can_id & Self::EFF != 0 { 20 } else { 0 };
        let data = if self.can_id & Self::RTR != 0 {
            0
        } else {
            8 * u64::from(self.len.min(8))
        };
        47 + extended + data
    }

    /// How long the frame occupies a bus at `bitrate` bits per second (without stuffing,
    /// which may add up to a fifth of the bits between SOF and CRC).
    pub fn time(&self, bitrate: u32) -> Duration {
        let rate = u64::from(bitrate.max(1));
        Duration::from_nanos((self.bits() * 1_000_000_000).div_ceil(rate))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_is_linux_can_frame_little_endian() {
        let frame = CanRecord::standard(0x7F8, &[1, 2, 3, 4, 5, 6, 7, 8]).expect("valid");
        assert_eq!(
            frame.to_bytes(),
            [0xF8, 0x07, 0, 0, 8, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8]
        );
        assert_eq!(CanRecord::from_bytes(&frame.to_bytes()), Some(frame));
        assert_eq!(CanRecord::standard(0x800, &[]), None);
        assert_eq!(CanRecord::standard(1, &[0; 9]), None);
        let mut bad = frame.to_bytes();
        bad[4] = 9;
        assert_eq!(CanRecord::from_bytes(&bad), None);
    }

    #[test]
    fn flags_hide_the_standard_id() {
        let mut frame = CanRecord::standard(0x010, &[]).expect("valid");
        assert_eq!(frame.standard_id(), Some(0x010));
        for flag in [CanRecord::EFF, CanRecord::RTR, CanRecord::ERR] {
            frame.can_id = 0x010 | flag;
            assert_eq!(frame.standard_id(), None);
        }
    }

    #[test]
    fn an_eight_byte_frame_takes_111_bits() {
        let frame = CanRecord::standard(0x008, &[0; 8]).expect("valid");
        assert_eq!(frame.bits(), 111);
        // 111 bits at 250 kbit/s: 444 µs.
        assert_eq!(frame.time(250_000), Duration::from_micros(444));
    }
}
