//! Replies: what the slave clocks out on MISO, including the packet-3 stream.

use crate::error::Error;
use crate::fields::{
    CHANNELS, DataMask, HistoryDimensions, PositionValue, ReturnCode, StreamConfig,
};
use crate::frame::{Frame, PacketId, write_packet};
use crate::motion::{MotionData, MotionLayout, PositionLayout, StreamData};
use crate::wire::{Reader, Writer};

/// What a reply decoder must know that the reply itself does not say.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ReplyLayout {
    /// Layout of packets 2 and 3 (configured data masks and stream config).
    pub motion: MotionLayout,
    /// Layout of the packet-11 reply (from the request form, see
    /// [`crate::GetPosition::reply_layout`]).
    pub position: PositionLayout,
}

/// Every reply the slave can send.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reply {
    /// 1 - Get Version.
    Version {
        /// Return Code.
        code: ReturnCode,
        /// Firmware Version Major.
        firmware_major: u8,
        /// Firmware Version Minor.
        firmware_minor: u8,
        /// Protocol Version.
        protocol: u8,
    },
    /// 2 - Get Binary Motion Data.
    MotionData {
        /// Return Code.
        code: ReturnCode,
        /// Channel data, as the data masks select.
        data: MotionData,
    },
    /// 3 - Binary Stream Data (a Return Code only when the board sends one:
    /// [`StreamData::code`]).
    StreamData(StreamData),
    /// 5 - Get Stream Period.
    StreamPeriod {
        /// Return Code.
        code: ReturnCode,
        /// Stream Period in 40.96 µs units.
        period: u16,
    },
    /// 7 - Get Data Mask.
    DataMasks {
        /// Return Code.
        code: ReturnCode,
        /// Data Mask of channels 1..4.
        masks: [DataMask; CHANNELS],
    },
    /// 9 - Get Stream Config.
    StreamConfig {
        /// Return Code.
        code: ReturnCode,
        /// Stream Config Mask.
        config: StreamConfig,
    },
    /// 11 - Get Position.
    Positions {
        /// Return Code.
        code: ReturnCode,
        /// Positions 1..4 as the request form selected.
        positions: [Option<PositionValue>; CHANNELS],
    },
    /// 13 - Get History Dimensions.
    HistoryDimensions {
        /// Return Code.
        code: ReturnCode,
        /// History Length and Maximum Averaging Time in Bits.
        dimensions: HistoryDimensions,
    },
    /// The Return Code alone: the documented reply of every set/ramp packet, and how a
    /// get request is answered when it fails (non-zero code, no data).
    Ack {
        /// The packet answered.
        id: PacketId,
        /// Return Code.
        code: ReturnCode,
    },
}

impl Reply {
    /// The Packet ID (the id of the request answered, or 3 for stream data).
    pub const fn id(&self) -> PacketId {
        match self {
            Self::Version { .. } => PacketId::GetVersion,
            Self::MotionData { .. } => PacketId::GetMotionData,
            Self::StreamData(_) => PacketId::StreamData,
            Self::StreamPeriod { .. } => PacketId::GetStreamPeriod,
            Self::DataMasks { .. } => PacketId::GetDataMask,
            Self::StreamConfig { .. } => PacketId::GetStreamConfig,
            Self::Positions { .. } => PacketId::GetPosition,
            Self::HistoryDimensions { .. } => PacketId::GetHistoryDimensions,
            Self::Ack { id, .. } => *id,
        }
    }

    /// The Return Code; for stream data the one the board sent, if any.
    pub const fn code(&self) -> Option<ReturnCode> {
        match self {
            Self::Version { code, .. }
            | Self::MotionData { code, .. }
            | Self::StreamPeriod { code, .. }
            | Self::DataMasks { code, .. }
            | Self::StreamConfig { code, .. }
            | Self::Positions { code, .. }
            | Self::HistoryDimensions { code, .. }
            | Self::Ack { code, .. } => Some(*code),
            Self::StreamData(s) => s.code,
        }
    }

    /// Encodes the whole packet into `buf`; returns its length.
    ///
    /// An [`Reply::Ack`] for packet 3 or a successful [`Reply::Ack`] for a get request (whose
    /// documented reply carries data) is [`Error::Inconsistent`].
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        if let Self::Ack { id, code } = self
            && (*id == PacketId::StreamData
                || (!id.reply_is_return_code_only() && code.is_success()))
        {
            return Err(Error::Inconsistent);
        }
        write_packet(buf, self.id().as_u8(), |w| self.write_payload(w))
    }

    fn write_payload(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        // Stream data writes its own (optional) Return Code.
        if let (false, Some(code)) = (matches!(self, Self::StreamData(_)), self.code()) {
            w.u8(code.0)?;
        }
        match self {
            Self::Version {
                firmware_major,
                firmware_minor,
                protocol,
                ..
            } => w.bytes(&[*firmware_major, *firmware_minor, *protocol]),
            Self::MotionData { data, .. } => data.write(w),
            Self::StreamData(s) => s.write(w),
            Self::StreamPeriod { period, .. } => w.u16(*period),
            Self::DataMasks { masks, .. } => masks.iter().try_for_each(|m| w.u8(m.0)),
            Self::StreamConfig { config, .. } => w.u8(config.0),
            Self::Positions { positions, .. } => {
                positions.iter().flatten().try_for_each(|p| p.write(w))
            }
            Self::HistoryDimensions { dimensions, .. } => {
                w.bytes(&[dimensions.history_length, dimensions.averaging_bits])
            }
            Self::Ack { .. } => Ok(()),
        }
    }

    /// Parses one whole packet and decodes it as a reply under `layout`.
    pub fn parse(packet: &[u8], layout: &ReplyLayout) -> Result<Self, Error> {
        Self::decode(Frame::parse(packet)?, layout)
    }

    /// Decodes a framed packet as a reply. Packets 2, 3 and 11 are read with `layout`;
    /// a one-byte payload with a non-zero code is an error reply ([`Reply::Ack`]) for any id.
    pub fn decode(frame: Frame<'_>, layout: &ReplyLayout) -> Result<Self, Error> {
        let id = PacketId::try_from(frame.id)?;
        let mut r = Reader::new(frame.payload);
        if id == PacketId::StreamData {
            let s = StreamData::read(&mut r, &layout.motion, frame.payload.len())?;
            r.finish()?;
            return Ok(Self::StreamData(s));
        }
        let code = ReturnCode(r.u8()?);
        if id.reply_is_return_code_only() || (r.is_empty() && !code.is_success()) {
            r.finish()?;
            return Ok(Self::Ack { id, code });
        }
        let reply = match id {
            PacketId::GetVersion => Self::Version {
                code,
                firmware_major: r.u8()?,
                firmware_minor: r.u8()?,
                protocol: r.u8()?,
            },
            PacketId::GetMotionData => Self::MotionData {
                code,
                data: MotionData::read(&mut r, &layout.motion.data_masks)?,
            },
            PacketId::GetStreamPeriod => Self::StreamPeriod {
                code,
                period: r.u16()?,
            },
            PacketId::GetDataMask => Self::DataMasks {
                code,
                masks: [
                    DataMask(r.u8()?),
                    DataMask(r.u8()?),
                    DataMask(r.u8()?),
                    DataMask(r.u8()?),
                ],
            },
            PacketId::GetStreamConfig => Self::StreamConfig {
                code,
                config: StreamConfig(r.u8()?),
            },
            PacketId::GetPosition => {
                let mut positions = [None; CHANNELS];
                for (p, size) in positions.iter_mut().zip(layout.position.0) {
                    *p = size.read(&mut r)?;
                }
                Self::Positions { code, positions }
            }
            PacketId::GetHistoryDimensions => Self::HistoryDimensions {
                code,
                dimensions: HistoryDimensions {
                    history_length: r.u8()?,
                    averaging_bits: r.u8()?,
                },
            },
            _ => return Err(Error::WrongDirection(frame.id)),
        };
        r.finish()?;
        Ok(reply)
    }
}
