//! MOSI transactions: what the host clocks into the board.

use crate::port;
use crate::value::{Coils, Direction, IDENTIFICATION_CAPACITY, Motor, SerialNumber, StepDelay};
use crate::{Access, Address, Error, Header};

/// The byte the host clocks on MOSI while it reads the answer of a read transaction (the
/// datasheet's "xx"; the board ignores it).
pub const DUMMY: u8 = 0x00;

/// Data bytes a host clocks by default when it reads the identification string: room for
/// [`IDENTIFICATION_CAPACITY`] text bytes and the terminating 0.
pub const IDENTIFICATION_READ_LEN: u16 = IDENTIFICATION_CAPACITY as u16 + 1;

/// Longest data part of a transaction this crate encodes or decodes.
pub const MAX_DATA_LEN: usize = u16::MAX as usize;

/// A write transaction's port and value ("write ports" table).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Write {
    /// 0x10: drive intensity for stepper mode.
    StepperIntensity(u8),
    /// 0x20 / 0x21 / 0x30 / 0x31: spin a brushed motor in a direction with an intensity.
    Spin {
        /// Motor A (0x2x) or B (0x3x).
        motor: Motor,
        /// Direction A (0x20, 0x30) or B (0x21, 0x31).
        direction: Direction,
        /// Drive intensity, 0 (none) to 255 (full).
        intensity: u8,
    },
    /// 0x22 / 0x32: stop a brushed motor. The datasheet lists no data for these ports, so
    /// the transaction is the address and port bytes alone.
    Stop(Motor),
    /// 0x40: set current position (redefines where the stepper is; it does not move).
    CurrentPosition(i32),
    /// 0x41: set target position (the stepper steps towards it).
    TargetPosition(i32),
    /// 0x42: set relative position (a target relative to the current position).
    RelativePosition(i32),
    /// 0x43: set step delay.
    StepDelay(StepDelay),
    /// 0x44: set number of driven coils.
    Coils(Coils),
    /// 0xf1 ← 0x55: first step of the address-change unlock.
    UnlockAddress1,
    /// 0xf2 ← 0xaa: second step of the address-change unlock.
    UnlockAddress2,
    /// 0xf0 ← new address: takes effect only right after the two unlock steps.
    ChangeAddress(Address),
}

impl Write {
    /// The port byte.
    pub const fn port(&self) -> u8 {
        match *self {
            Self::StepperIntensity(_) => port::STEPPER_INTENSITY,
            Self::Spin {
                motor, direction, ..
            } => match (motor, direction) {
                (Motor::A, Direction::A) => port::MOTOR_A_DIRECTION_A,
                (Motor::A, Direction::B) => port::MOTOR_A_DIRECTION_B,
                (Motor::B, Direction::A) => port::MOTOR_B_DIRECTION_A,
                (Motor::B, Direction::B) => port::MOTOR_B_DIRECTION_B,
            },
            Self::Stop(Motor::A) => port::MOTOR_A_STOP,
            Self::Stop(Motor::B) => port::MOTOR_B_STOP,
            Self::CurrentPosition(_) => port::CURRENT_POSITION,
            Self::TargetPosition(_) => port::TARGET_POSITION,
            Self::RelativePosition(_) => port::RELATIVE_POSITION,
            Self::StepDelay(_) => port::STEP_DELAY,
            Self::Coils(_) => port::COILS,
            Self::UnlockAddress1 => port::UNLOCK_1,
            Self::UnlockAddress2 => port::UNLOCK_2,
            Self::ChangeAddress(_) => port::CHANGE_ADDRESS,
        }
    }

    /// Data bytes after the port byte: 0 (stop), 1 or 4.
    pub const fn data_len(&self) -> usize {
        match self {
            Self::Stop(_) => 0,
            Self::CurrentPosition(_) | Self::TargetPosition(_) | Self::RelativePosition(_) => 4,
            _ => 1,
        }
    }

    /// The data bytes (little-endian for 4-byte values) and how many of `out` they fill.
    fn data(&self) -> ([u8; 4], usize) {
        let one = |b: u8| ([b, 0, 0, 0], 1);
        match *self {
            Self::StepperIntensity(v) | Self::Spin { intensity: v, .. } => one(v),
            Self::Stop(_) => ([0; 4], 0),
            Self::CurrentPosition(v) | Self::TargetPosition(v) | Self::RelativePosition(v) => {
                (v.to_le_bytes(), 4)
            }
            Self::StepDelay(d) => one(d.tenths_ms()),
            Self::Coils(c) => one(c.to_byte()),
            Self::UnlockAddress1 => one(port::UNLOCK_KEY_1),
            Self::UnlockAddress2 => one(port::UNLOCK_KEY_2),
            Self::ChangeAddress(a) => one(a.get()),
        }
    }

    /// The write a port byte and its data bytes mean.
    ///
    /// One-byte ports take the last byte written: the datasheet calls more than one byte to
    /// such a port "redundant", each one setting the value again. Stop ports ignore data.
    /// Position ports take exactly 4 bytes.
    ///
    /// # Errors
    /// [`Error::UnknownPort`], [`Error::Length`], [`Error::WrongUnlockKey`],
    /// [`Error::OddAddress`] (a new address with bit 0 set).
    pub fn decode(port: u8, data: &[u8]) -> Result<Self, Error> {
        let length = Error::Length {
            port,
            got: data.len(),
        };
        let last = data.last().copied();
        let one = || last.ok_or(length);
        let four = || match data {
            [a, b, c, d] => Ok(i32::from_le_bytes([*a, *b, *c, *d])),
            _ => Err(length),
        };
        let spin = |motor, direction| {
            one().map(|intensity| Self::Spin {
                motor,
                direction,
                intensity,
            })
        };
        let key = |expected: u8, write: Self| {
            let value = one()?;
            if value == expected {
                Ok(write)
            } else {
                Err(Error::WrongUnlockKey { port, value })
            }
        };
        match port {
            port::STEPPER_INTENSITY => one().map(Self::StepperIntensity),
            port::MOTOR_A_DIRECTION_A => spin(Motor::A, Direction::A),
            port::MOTOR_A_DIRECTION_B => spin(Motor::A, Direction::B),
            port::MOTOR_A_STOP => Ok(Self::Stop(Motor::A)),
            port::MOTOR_B_DIRECTION_A => spin(Motor::B, Direction::A),
            port::MOTOR_B_DIRECTION_B => spin(Motor::B, Direction::B),
            port::MOTOR_B_STOP => Ok(Self::Stop(Motor::B)),
            port::CURRENT_POSITION => four().map(Self::CurrentPosition),
            port::TARGET_POSITION => four().map(Self::TargetPosition),
            port::RELATIVE_POSITION => four().map(Self::RelativePosition),
            port::STEP_DELAY => one().map(|b| Self::StepDelay(StepDelay::from_tenths_ms(b))),
            port::COILS => one().map(|b| Self::Coils(Coils::from_byte(b))),
            port::UNLOCK_1 => key(port::UNLOCK_KEY_1, Self::UnlockAddress1),
            port::UNLOCK_2 => key(port::UNLOCK_KEY_2, Self::UnlockAddress2),
            port::CHANGE_ADDRESS => Address::new(one()?).map(Self::ChangeAddress),
            _ => Err(Error::UnknownPort { port, read: false }),
        }
    }
}

/// A read port ("read ports" table).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ReadPort {
    /// 0x01: identification string, terminated with 0.
    Identification,
    /// 0x02: eeprom serial number, 4 bytes.
    Serial,
    /// 0x40: current position, 4 bytes.
    CurrentPosition,
    /// 0x41: target position, 4 bytes.
    TargetPosition,
    /// 0x43: step delay, 1 byte.
    StepDelay,
}

impl ReadPort {
    /// Every read port.
    pub const ALL: [Self; 5] = [
        Self::Identification,
        Self::Serial,
        Self::CurrentPosition,
        Self::TargetPosition,
        Self::StepDelay,
    ];

    /// The port byte.
    pub const fn port(self) -> u8 {
        match self {
            Self::Identification => port::IDENTIFICATION,
            Self::Serial => port::SERIAL,
            Self::CurrentPosition => port::CURRENT_POSITION,
            Self::TargetPosition => port::TARGET_POSITION,
            Self::StepDelay => port::STEP_DELAY,
        }
    }

    /// The read port of a port byte.
    pub const fn from_port(port: u8) -> Option<Self> {
        match port {
            port::IDENTIFICATION => Some(Self::Identification),
            port::SERIAL => Some(Self::Serial),
            port::CURRENT_POSITION => Some(Self::CurrentPosition),
            port::TARGET_POSITION => Some(Self::TargetPosition),
            port::STEP_DELAY => Some(Self::StepDelay),
            _ => None,
        }
    }

    /// Data bytes a host clocks to read the whole value (for the identification string,
    /// [`IDENTIFICATION_READ_LEN`]: the longest string this crate holds and its 0).
    pub const fn default_len(self) -> u16 {
        match self {
            Self::Identification => IDENTIFICATION_READ_LEN,
            Self::Serial => SerialNumber::LEN as u16,
            Self::CurrentPosition | Self::TargetPosition => 4,
            Self::StepDelay => 1,
        }
    }
}

/// A read transaction: the port, and how many data bytes the host clocks after the header
/// (each one a [`DUMMY`] on MOSI and a byte of the answer on MISO).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Read {
    /// The port read.
    pub port: ReadPort,
    /// Data bytes clocked after the address and port bytes (at least 1).
    pub len: u16,
}

impl Read {
    /// A read of the whole value of `port` ([`ReadPort::default_len`] data bytes).
    pub const fn new(port: ReadPort) -> Self {
        Self {
            port,
            len: port.default_len(),
        }
    }
}

/// What a transaction does: write a port or read one.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Request {
    /// Address bit 0 cleared.
    Write(Write),
    /// Address bit 0 set.
    Read(Read),
}

/// One SPI transaction (one chip-select assertion) as the host clocks it on MOSI:
/// address byte, port byte, data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Transaction {
    /// The board selected by the first byte.
    pub address: Address,
    /// The port and the data or read length.
    pub request: Request,
}

impl Transaction {
    /// A write transaction.
    pub const fn write(address: Address, write: Write) -> Self {
        Self {
            address,
            request: Request::Write(write),
        }
    }

    /// A read of the whole value of `port`.
    pub const fn read(address: Address, port: ReadPort) -> Self {
        Self {
            address,
            request: Request::Read(Read::new(port)),
        }
    }

    /// The header (address byte and port byte) of the transaction.
    pub const fn header(&self) -> Header {
        match self.request {
            Request::Write(w) => Header {
                address: self.address,
                access: Access::Write,
                port: w.port(),
            },
            Request::Read(r) => Header {
                address: self.address,
                access: Access::Read,
                port: r.port.port(),
            },
        }
    }

    /// Bytes in the transaction, header included; also the length of its MISO answer.
    pub const fn len(&self) -> usize {
        Header::LEN
            + match self.request {
                Request::Write(w) => w.data_len(),
                Request::Read(r) => r.len as usize,
            }
    }

    /// Always `false`: every transaction has at least its two header bytes.
    pub const fn is_empty(&self) -> bool {
        false
    }

    /// Writes the MOSI bytes into `buf` (dummy bytes included for a read) and returns how
    /// many were written.
    ///
    /// # Errors
    /// [`Error::BufferTooSmall`] when `buf` is shorter than [`Self::len`]; [`Error::Length`]
    /// for a read of 0 data bytes.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        let len = self.len();
        let out = buf
            .get_mut(..len)
            .ok_or(Error::BufferTooSmall { needed: len })?;
        let header = self.header();
        let (head, data) = out.split_at_mut(Header::LEN);
        head.copy_from_slice(&[header.address.byte(header.access), header.port]);
        match self.request {
            Request::Write(w) => {
                let (bytes, n) = w.data();
                data.copy_from_slice(bytes.get(..n).unwrap_or(&[]));
            }
            Request::Read(r) => {
                if r.len == 0 {
                    return Err(Error::Length {
                        port: header.port,
                        got: 0,
                    });
                }
                data.fill(DUMMY);
            }
        }
        Ok(len)
    }

    /// The transaction a whole MOSI buffer carries.
    ///
    /// # Errors
    /// [`Error::MissingHeader`] under two bytes; [`Error::UnknownPort`] for a port not
    /// documented in that direction; [`Error::Length`] for a write with too few (or, on a
    /// 4-byte port, too many) data bytes or a read of none or more than [`MAX_DATA_LEN`];
    /// [`Error::WrongUnlockKey`]; [`Error::OddAddress`] for a new address with bit 0 set.
    pub fn decode(mosi: &[u8]) -> Result<Self, Error> {
        let header = Header::decode(mosi)?;
        let data = mosi.get(Header::LEN..).unwrap_or(&[]);
        let request = match header.access {
            Access::Write => Request::Write(Write::decode(header.port, data)?),
            Access::Read => {
                let port = ReadPort::from_port(header.port).ok_or(Error::UnknownPort {
                    port: header.port,
                    read: true,
                })?;
                let length = Error::Length {
                    port: header.port,
                    got: data.len(),
                };
                let len = u16::try_from(data.len()).map_err(|_| length)?;
                if len == 0 {
                    return Err(length);
                }
                Request::Read(Read { port, len })
            }
        };
        Ok(Self {
            address: header.address,
            request,
        })
    }
}
