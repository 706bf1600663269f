//! The CAN 2.0A form of the protocol (manual 6.2, 6.3).
//!
//! Telegrams have a fixed length of 8 bytes: the command and P0..P6 (the 9-byte word without
//! its address). The 11-bit identifier is the 8-bit address shifted left by 3; the lower three
//! bits are `000` for commands and responses (a response goes to the response address shifted
//! the same way) and `001` for bytes to forward to the pack's RS-232 port. Address 0 is not
//! valid on CAN, so identifiers run from $008 to $7F8.

use crate::{Error, FRAME_LEN, ReplyFrame, RequestFrame, Word};

/// Length of a command or response telegram.
pub const CAN_LEN: usize = 8;

/// One CAN 2.0A data frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    /// 11-bit identifier.
    pub id: u16,
    /// Data length 0..=8.
    pub len: u8,
    /// Data bytes (only `len` are meaningful).
    pub data: [u8; 8],
}

/// What the lower three identifier bits say a telegram is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CanChannel {
    /// `000`: a command (or a response, when sent by a pack).
    Command,
    /// `001`: bytes to forward to the RS-232 port.
    Rs232,
}

/// The identifier for an 8-bit address and channel.
pub const fn can_id(address: u8, channel: CanChannel) -> Result<u16, Error> {
    if address == 0 {
        return Err(Error::InvalidCanId(0));
    }
    let low = match channel {
        CanChannel::Command => 0,
        CanChannel::Rs232 => 1,
    };
    Ok(((address as u16) << 3) | low)
}

/// The 8-bit address and channel of an identifier.
pub const fn split_can_id(id: u16) -> Result<(u8, CanChannel), Error> {
    let address = (id >> 3) as u8;
    if id > 0x7FF || address == 0 {
        return Err(Error::InvalidCanId(id));
    }
    match id & 7 {
        0 => Ok((address, CanChannel::Command)),
        1 => Ok((address, CanChannel::Rs232)),
        _ => Err(Error::InvalidCanId(id)),
    }
}

impl CanFrame {
    /// The payload bytes.
    pub fn payload(&self) -> &[u8] {
        self.data.get(..usize::from(self.len)).unwrap_or(&self.data)
    }

    /// 1..=8 bytes for the RS-232 port of the pack at `address` (manual 6.3).
    pub fn rs232_forward(address: u8, bytes: &[u8]) -> Result<Self, Error> {
        if bytes.is_empty() || bytes.len() > CAN_LEN {
            return Err(Error::WrongLength {
                expected: CAN_LEN,
                got: bytes.len(),
            });
        }
        let mut data = [0u8; 8];
        data.get_mut(..bytes.len())
            .unwrap_or(&mut [])
            .copy_from_slice(bytes);
        Ok(Self {
            id: can_id(address, CanChannel::Rs232)?,
            len: bytes.len() as u8,
            data,
        })
    }

    fn from_word(w: &Word) -> Result<Self, Error> {
        let mut data = [0u8; 8];
        data.copy_from_slice(&w[1..]);
        Ok(Self {
            id: can_id(w[0], CanChannel::Command)?,
            len: CAN_LEN as u8,
            data,
        })
    }

    fn to_word(self) -> Result<Word, Error> {
        if usize::from(self.len) != CAN_LEN {
            return Err(Error::WrongLength {
                expected: CAN_LEN,
                got: usize::from(self.len),
            });
        }
        let (address, channel) = split_can_id(self.id)?;
        if channel != CanChannel::Command {
            return Err(Error::InvalidCanId(self.id));
        }
        let mut w = [0u8; FRAME_LEN];
        w[0] = address;
        w[1..].copy_from_slice(&self.data);
        Ok(w)
    }
}

impl RequestFrame {
    /// The CAN telegram for this request (identifier = address << 3).
    pub fn to_can(&self) -> Result<CanFrame, Error> {
        CanFrame::from_word(&self.to_word()?)
    }

    /// The request a CAN command telegram carries.
    pub fn from_can(frame: &CanFrame) -> Result<Self, Error> {
        Self::decode(&frame.to_word()?)
    }
}

impl ReplyFrame {
    /// The CAN telegram for this reply (identifier = response address << 3).
    pub fn to_can(&self) -> Result<CanFrame, Error> {
        CanFrame::from_word(&self.to_word()?)
    }

    /// The reply a CAN response telegram carries.
    pub fn from_can(frame: &CanFrame) -> Result<Self, Error> {
        Self::decode(&frame.to_word()?)
    }
}
