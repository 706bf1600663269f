//! MISO answers: what a board clocks out during a read transaction.

use crate::request::ReadPort;
use crate::value::{Identification, SerialNumber, StepDelay};
use crate::{Error, Header};

/// MISO offset of the first answer byte of a read transaction.
///
/// The board shifts a byte out while the host shifts one in, so it can only answer what it
/// already knows: the address byte (offset 0) and the port byte (offset 1) must be clocked
/// in completely before the board knows it is selected and which port is read. The answer
/// therefore starts with the first byte after the port byte, as in the datasheet's "read
/// identification" table ('s' is received while the first `xx` after port 0x01 is sent).
pub const REPLY_OFFSET: usize = Header::LEN;

/// What [`Reply::encode_miso`] clocks out after the end of the answer (after the
/// identification string's 0, after the 4th byte of a position). The datasheet is silent;
/// 0x00 keeps a too-long identification read terminated.
pub const PAD: u8 = 0x00;

/// The value a read port returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reply {
    /// 0x01: identification string.
    Identification(Identification),
    /// 0x02: eeprom serial number.
    Serial(SerialNumber),
    /// 0x40: current position.
    CurrentPosition(i32),
    /// 0x41: target position.
    TargetPosition(i32),
    /// 0x43: step delay.
    StepDelay(StepDelay),
}

impl Reply {
    /// The port this is the answer of.
    pub const fn port(&self) -> ReadPort {
        match self {
            Self::Identification(_) => ReadPort::Identification,
            Self::Serial(_) => ReadPort::Serial,
            Self::CurrentPosition(_) => ReadPort::CurrentPosition,
            Self::TargetPosition(_) => ReadPort::TargetPosition,
            Self::StepDelay(_) => ReadPort::StepDelay,
        }
    }

    /// Bytes of the answer (the identification string counts its terminating 0).
    pub fn len(&self) -> usize {
        match self {
            Self::Identification(id) => id.wire_len(),
            Self::Serial(_) | Self::CurrentPosition(_) | Self::TargetPosition(_) => 4,
            Self::StepDelay(_) => 1,
        }
    }

    /// Always `false`: every answer has at least one byte.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Writes the answer bytes (without the two header positions) into `buf`.
    ///
    /// # Errors
    /// [`Error::BufferTooSmall`] when `buf` is shorter than [`Self::len`].
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        let len = self.len();
        let out = buf
            .get_mut(..len)
            .ok_or(Error::BufferTooSmall { needed: len })?;
        match self {
            Self::Identification(id) => {
                let (text, end) = out.split_at_mut(id.as_bytes().len());
                text.copy_from_slice(id.as_bytes());
                end.fill(0);
            }
            Self::Serial(SerialNumber(v)) => out.copy_from_slice(&v.to_le_bytes()),
            Self::CurrentPosition(v) | Self::TargetPosition(v) => {
                out.copy_from_slice(&v.to_le_bytes());
            }
            Self::StepDelay(d) => out.fill(d.tenths_ms()),
        }
        Ok(len)
    }

    /// Fills the MISO buffer of a read transaction the way the board clocks it out: the
    /// answer from [`REPLY_OFFSET`] on, cut short when the host clocks fewer bytes, then
    /// [`PAD`] to the end. The two header positions are left as they are (the board cannot
    /// know what to answer while they are clocked). Returns the answer bytes written.
    pub fn encode_miso(&self, miso: &mut [u8]) -> usize {
        let mut answer = [0u8; crate::value::IDENTIFICATION_CAPACITY + 1];
        let n = self.encode(&mut answer).unwrap_or(0);
        let Some(data) = miso.get_mut(REPLY_OFFSET..) else {
            return 0;
        };
        let mut written = 0;
        for (i, out) in data.iter_mut().enumerate() {
            *out = if i < n {
                written += 1;
                answer.get(i).copied().unwrap_or(PAD)
            } else {
                PAD
            };
        }
        written
    }

    /// The answer to a read of `port`, from the bytes clocked after the header. Bytes after
    /// the value (padding) are ignored.
    ///
    /// # Errors
    /// [`Error::Length`] when fewer bytes than the value were clocked;
    /// [`Error::Unterminated`] when no 0 ends the identification string;
    /// [`Error::InvalidIdentification`] when the string is longer than this crate holds.
    pub fn decode_data(port: ReadPort, data: &[u8]) -> Result<Self, Error> {
        let four = || match data {
            [a, b, c, d, ..] => Ok([*a, *b, *c, *d]),
            _ => Err(Error::Length {
                port: port.port(),
                got: data.len(),
            }),
        };
        match port {
            ReadPort::Identification => {
                let end = data
                    .iter()
                    .position(|&b| b == 0)
                    .ok_or(Error::Unterminated)?;
                let text = data.get(..end).ok_or(Error::Unterminated)?;
                Identification::new(text).map(Self::Identification)
            }
            ReadPort::Serial => four().map(|b| Self::Serial(SerialNumber(u32::from_le_bytes(b)))),
            ReadPort::CurrentPosition => {
                four().map(|b| Self::CurrentPosition(i32::from_le_bytes(b)))
            }
            ReadPort::TargetPosition => four().map(|b| Self::TargetPosition(i32::from_le_bytes(b))),
            ReadPort::StepDelay => match data.first() {
                Some(&b) => Ok(Self::StepDelay(StepDelay::from_tenths_ms(b))),
                None => Err(Error::Length {
                    port: port.port(),
                    got: 0,
                }),
            },
        }
    }

    /// The answer to a read of `port` from the whole MISO buffer of the transaction
    /// (header positions included; they are ignored).
    ///
    /// # Errors
    /// [`Error::MissingHeader`] under two bytes, then as [`Self::decode_data`].
    pub fn decode(port: ReadPort, miso: &[u8]) -> Result<Self, Error> {
        let data = miso.get(REPLY_OFFSET..).ok_or(Error::MissingHeader)?;
        Self::decode_data(port, data)
    }
}
