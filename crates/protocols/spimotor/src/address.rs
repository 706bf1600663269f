//! The first byte of every transaction: the board address and the read/write flag.

use crate::Error;

/// Whether a transaction writes to a port or reads from it (bit 0 of the address byte).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    /// Bit 0 cleared: data flows host → board on MOSI.
    Write,
    /// Bit 0 set: the board answers on MISO.
    Read,
}

impl Access {
    /// The access an address byte asks for.
    pub const fn of_byte(byte: u8) -> Self {
        if byte & 1 == 0 {
            Self::Write
        } else {
            Self::Read
        }
    }
}

/// A board's SPI address: "7 bits wide", stored here as the even byte the board answers to
/// (`0x90` answers to `0x90` for writes and `0x91` for reads).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord,
)]
pub struct Address(u8);

impl Address {
    /// The factory address of an SPI_motor board (the datasheet's examples use 0x90).
    pub const DEFAULT: Self = Self(0x90);

    /// An address from its even byte form.
    ///
    /// # Errors
    /// [`Error::OddAddress`] when bit 0 (the read/write flag) is set.
    pub const fn new(byte: u8) -> Result<Self, Error> {
        if byte & 1 == 0 {
            Ok(Self(byte))
        } else {
            Err(Error::OddAddress(byte))
        }
    }

    /// The address a transaction's first byte selects (bit 0 masked off).
    pub const fn of_byte(byte: u8) -> Self {
        Self(byte & !1)
    }

    /// The even byte form (0x90).
    pub const fn get(self) -> u8 {
        self.0
    }

    /// The 7-bit address proper (0x48 for 0x90).
    pub const fn seven_bit(self) -> u8 {
        self.0 >> 1
    }

    /// The first byte of a transaction to this board.
    pub const fn byte(self, access: Access) -> u8 {
        match access {
            Access::Write => self.0,
            Access::Read => self.0 | 1,
        }
    }
}

impl Default for Address {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl core::fmt::Display for Address {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:#04x}", self.0)
    }
}

/// The address byte and port byte every transaction starts with.
///
/// This is all a board knows when it has to decide whether to drive MISO and what to
/// answer: see the crate docs, "Where the answer appears on MISO".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Header {
    /// The board the transaction selects.
    pub address: Address,
    /// Write or read.
    pub access: Access,
    /// The port byte.
    pub port: u8,
}

impl Header {
    /// Bytes in a header.
    pub const LEN: usize = 2;

    /// The header of a MOSI transaction.
    ///
    /// # Errors
    /// [`Error::MissingHeader`] when fewer than two bytes were clocked.
    pub fn decode(mosi: &[u8]) -> Result<Self, Error> {
        match mosi {
            [a, port, ..] => Ok(Self {
                address: Address::of_byte(*a),
                access: Access::of_byte(*a),
                port: *port,
            }),
            _ => Err(Error::MissingHeader),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_address_byte_splits_into_address_and_access() {
        for byte in 0..=255u8 {
            let address = Address::of_byte(byte);
            let access = Access::of_byte(byte);
            assert_eq!(address.byte(access), byte);
            assert_eq!(Address::new(address.get()), Ok(address));
        }
        assert_eq!(Address::default().to_string(), "0x90");
        assert_eq!(Header::decode(&[0x90]), Err(Error::MissingHeader));
    }
}
