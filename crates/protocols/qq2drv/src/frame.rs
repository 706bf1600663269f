//! Packet framing (datasheet "Packet Format"): STX, Packet Size, Packet ID, Payload, Checksum.
//!
//! Packet Size counts the whole packet. The checksum is chosen so that the 8-bit sum of every
//! byte of the packet, checksum included, is zero (docs/ARCHITECTURE.md; worked example `2,4,1,249`).

use crate::error::Error;
use crate::wire::Writer;

/// Start of a packet: ASCII STX.
pub const STX: u8 = 2;
/// STX, Packet Size and Packet ID.
pub const HEADER_LEN: usize = 3;
/// The smallest packet: header and checksum, no payload.
pub const MIN_PACKET_LEN: usize = 4;
/// The largest packet a U8 Packet Size can describe.
pub const MAX_PACKET_LEN: usize = 255;
/// The largest payload.
pub const MAX_PAYLOAD_LEN: usize = MAX_PACKET_LEN - MIN_PACKET_LEN;

/// The checksum byte that makes the 8-bit sum of `bytes` plus the checksum zero.
pub fn checksum(bytes: &[u8]) -> u8 {
    0u8.wrapping_sub(bytes.iter().fold(0u8, |acc, b| acc.wrapping_add(*b)))
}

/// Every Packet ID the datasheet documents (interface protocol v1).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord,
)]
#[repr(u8)]
pub enum PacketId {
    /// 1 - Get Version.
    GetVersion = 1,
    /// 2 - Get Binary Motion Data.
    GetMotionData = 2,
    /// 3 - Binary Stream Data (slave to master only).
    StreamData = 3,
    /// 4 - Set Stream Period.
    SetStreamPeriod = 4,
    /// 5 - Get Stream Period.
    GetStreamPeriod = 5,
    /// 6 - Set Data Mask.
    SetDataMask = 6,
    /// 7 - Get Data Mask.
    GetDataMask = 7,
    /// 8 - Set Stream Config.
    SetStreamConfig = 8,
    /// 9 - Get Stream Config.
    GetStreamConfig = 9,
    /// 10 - Set Position.
    SetPosition = 10,
    /// 11 - Get Position.
    GetPosition = 11,
    /// 12 - Set History Dimensions.
    SetHistoryDimensions = 12,
    /// 13 - Get History Dimensions.
    GetHistoryDimensions = 13,
    /// 14 - Set Input Mode.
    SetInputMode = 14,
    /// 16 - Set Control Mode.
    SetControlMode = 16,
    /// 18 - Set Motor Power.
    SetMotorPower = 18,
    /// 20 - Set Position Control Target.
    SetPositionTarget = 20,
    /// 22 - Set Velocity Control Target.
    SetVelocityTarget = 22,
    /// 24 - Set Power Limit.
    SetPowerLimit = 24,
    /// 26 - Set Velocity Limit.
    SetVelocityLimit = 26,
    /// 28 - Set Acceleration Limit.
    SetAccelerationLimit = 28,
    /// 30 - Set Position Control PID Constants.
    SetPositionPid = 30,
    /// 32 - Set Velocity Control PID Constants.
    SetVelocityPid = 32,
    /// 34 - Position Ramp.
    PositionRamp = 34,
    /// 36 - Velocity Ramp.
    VelocityRamp = 36,
}

impl PacketId {
    /// All documented ids, in datasheet order.
    pub const ALL: [PacketId; 25] = [
        Self::GetVersion,
        Self::GetMotionData,
        Self::StreamData,
        Self::SetStreamPeriod,
        Self::GetStreamPeriod,
        Self::SetDataMask,
        Self::GetDataMask,
        Self::SetStreamConfig,
        Self::GetStreamConfig,
        Self::SetPosition,
        Self::GetPosition,
        Self::SetHistoryDimensions,
        Self::GetHistoryDimensions,
        Self::SetInputMode,
        Self::SetControlMode,
        Self::SetMotorPower,
        Self::SetPositionTarget,
        Self::SetVelocityTarget,
        Self::SetPowerLimit,
        Self::SetVelocityLimit,
        Self::SetAccelerationLimit,
        Self::SetPositionPid,
        Self::SetVelocityPid,
        Self::PositionRamp,
        Self::VelocityRamp,
    ];

    /// The id byte.
    pub const fn as_u8(self) -> u8 {
        self as u8
    }

    /// True for packets whose documented reply is the Return Code alone.
    pub const fn reply_is_return_code_only(self) -> bool {
        !matches!(
            self,
            Self::GetVersion
                | Self::GetMotionData
                | Self::StreamData
                | Self::GetStreamPeriod
                | Self::GetDataMask
                | Self::GetStreamConfig
                | Self::GetPosition
                | Self::GetHistoryDimensions
        )
    }
}

impl PacketId {
    /// The longest packet this id can have in either direction: the largest layout of the
    /// get replies and of packet 3 (all four channels with 32-bit position, velocity and
    /// status, plus the stream timing fields and a Return Code, which the text has and the
    /// table does not), 255 for the multi-entry packets.
    pub const fn max_packet_len(self) -> usize {
        const CHANNEL: usize = 4 + 4 + 1;
        match self {
            Self::GetVersion => MIN_PACKET_LEN + 4,
            Self::GetMotionData => MIN_PACKET_LEN + 1 + 4 * CHANNEL,
            Self::StreamData => MIN_PACKET_LEN + 1 + 3 + 4 * CHANNEL,
            Self::SetStreamPeriod | Self::GetStreamPeriod => MIN_PACKET_LEN + 3,
            Self::GetDataMask => MIN_PACKET_LEN + 5,
            Self::SetStreamConfig | Self::GetStreamConfig => MIN_PACKET_LEN + 2,
            Self::GetPosition => MIN_PACKET_LEN + 1 + 4 * 4,
            Self::SetHistoryDimensions | Self::GetHistoryDimensions => MIN_PACKET_LEN + 3,
            _ => MAX_PACKET_LEN,
        }
    }

    /// The shortest packet this id can have in either direction (a set request carries at
    /// least one byte, its reply the Return Code).
    pub const fn min_packet_len(self) -> usize {
        if self.reply_is_return_code_only() {
            MIN_PACKET_LEN + 1
        } else {
            MIN_PACKET_LEN
        }
    }
}

impl TryFrom<u8> for PacketId {
    type Error = Error;

    fn try_from(value: u8) -> Result<Self, Error> {
        Self::ALL
            .iter()
            .copied()
            .find(|id| id.as_u8() == value)
            .ok_or(Error::UnknownPacket(value))
    }
}

/// A framed packet borrowed from a received buffer: its id and payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame<'a> {
    /// The Packet ID byte (not checked against the documented ids here).
    pub id: u8,
    /// The payload between Packet ID and Checksum.
    pub payload: &'a [u8],
}

impl<'a> Frame<'a> {
    /// Parses exactly one whole packet: STX, a size equal to `bytes.len()`, a zero checksum sum.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        let [stx, size, id, rest @ ..] = bytes else {
            return Err(Error::BadSize);
        };
        if *stx != STX {
            return Err(Error::BadStx);
        }
        if usize::from(*size) < MIN_PACKET_LEN || usize::from(*size) != bytes.len() {
            return Err(Error::BadSize);
        }
        if checksum(bytes) != 0 {
            return Err(Error::BadChecksum);
        }
        let (_, payload) = rest.split_last().ok_or(Error::BadSize)?;
        Ok(Self { id: *id, payload })
    }

    /// The whole packet length for this payload.
    pub const fn packet_len(&self) -> usize {
        self.payload.len() + MIN_PACKET_LEN
    }

    /// Frames the payload into `buf`; returns the packet length.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        write_packet(buf, self.id, |w| w.bytes(self.payload))
    }
}

/// An owned copy of one packet, as produced by the [`crate::StreamDecoder`].
#[derive(serde::Serialize, serde::Deserialize, Clone, Copy, PartialEq, Eq)]
pub struct PacketBuf {
    #[serde(with = "serde_big_array::BigArray")]
    bytes: [u8; MAX_PACKET_LEN],
    len: u8,
}

impl PacketBuf {
    /// Copies one whole packet after checking its framing (STX, size, checksum).
    pub fn from_packet(packet: &[u8]) -> Result<Self, Error> {
        Frame::parse(packet)?;
        Self::copy_from(packet).ok_or(Error::BadSize)
    }

    /// Copies a whole, already validated packet.
    pub(crate) fn copy_from(packet: &[u8]) -> Option<Self> {
        let mut bytes = [0u8; MAX_PACKET_LEN];
        bytes.get_mut(..packet.len())?.copy_from_slice(packet);
        Some(Self {
            bytes,
            len: u8::try_from(packet.len()).ok()?,
        })
    }

    /// The raw packet bytes, STX to checksum.
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..usize::from(self.len)).unwrap_or_default()
    }

    /// The framed view (id and payload).
    pub fn frame(&self) -> Frame<'_> {
        // Only validated packets are stored, so parsing cannot fail; fall back to an empty
        // frame rather than panic.
        Frame::parse(self.as_bytes()).unwrap_or(Frame {
            id: 0,
            payload: &[],
        })
    }
}

impl core::fmt::Debug for PacketBuf {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_tuple("PacketBuf").field(&self.as_bytes()).finish()
    }
}

/// Writes header, the payload produced by `body` and the checksum into `buf`.
pub(crate) fn write_packet(
    buf: &mut [u8],
    id: u8,
    body: impl FnOnce(&mut Writer<'_>) -> Result<(), Error>,
) -> Result<usize, Error> {
    if buf.len() < MIN_PACKET_LEN {
        return Err(Error::BufferTooSmall);
    }
    let room = buf.len() - MIN_PACKET_LEN;
    let cap = room.min(MAX_PAYLOAD_LEN);
    let payload_len = {
        let area = buf
            .get_mut(HEADER_LEN..HEADER_LEN + cap)
            .ok_or(Error::BufferTooSmall)?;
        let mut w = Writer::new(area);
        match body(&mut w) {
            Ok(()) => w.written(),
            Err(Error::BufferTooSmall) if room >= MAX_PAYLOAD_LEN => {
                return Err(Error::PayloadTooLong);
            }
            Err(e) => return Err(e),
        }
    };
    let len = payload_len + MIN_PACKET_LEN;
    let size = u8::try_from(len).map_err(|_| Error::PayloadTooLong)?;
    let head = buf.get_mut(..HEADER_LEN).ok_or(Error::BufferTooSmall)?;
    head.copy_from_slice(&[STX, size, id]);
    let sum = checksum(buf.get(..len - 1).ok_or(Error::BufferTooSmall)?);
    *buf.get_mut(len - 1).ok_or(Error::BufferTooSmall)? = sum;
    Ok(len)
}
