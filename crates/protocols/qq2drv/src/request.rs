//! Requests: what the master sends on MOSI.

use crate::entries::{
    AccelerationLimitEntry, ControlModeEntry, DataMaskEntry, Entries, InputModeEntry,
    MotorPowerEntry, PositionPidEntry, PositionRampEntry, PositionTargetEntry, PowerLimitEntry,
    SetPositionEntry, VelocityLimitEntry, VelocityPidEntry, VelocityRampEntry, VelocityTargetEntry,
};
use crate::error::Error;
use crate::fields::{
    CHANNELS, ChannelMask, DataMask, HistoryDimensions, PositionSize, StreamConfig,
};
use crate::frame::{Frame, PacketId, write_packet};
use crate::motion::PositionLayout;
use crate::wire::{Reader, Writer};

/// Packet 11 - Get Position: the three request forms, told apart by payload size.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GetPosition {
    /// Size 0: positions in the sizes configured by packet 6 (omitted where size is 0).
    Configured,
    /// Size 1: the positions of the selected channels.
    ///
    /// The datasheet does not give their size; we read them as 32-bit (I32), the width of
    /// the position counter (an interpretation, see the crate docs).
    Channels(ChannelMask),
    /// Size 4: an explicit Position Size per channel.
    Sizes([PositionSize; CHANNELS]),
}

impl GetPosition {
    /// The layout of the reply to this request, given the configured data masks.
    pub fn reply_layout(&self, data_masks: &[DataMask; CHANNELS]) -> PositionLayout {
        let mut sizes = [PositionSize::Omitted; CHANNELS];
        for (i, s) in sizes.iter_mut().enumerate() {
            *s = match self {
                Self::Configured => data_masks
                    .get(i)
                    .map_or(PositionSize::Omitted, |m| m.position_size()),
                Self::Channels(mask) if mask.contains(i) => PositionSize::I32,
                Self::Channels(_) => PositionSize::Omitted,
                Self::Sizes(sz) => sz.get(i).copied().unwrap_or_default(),
            };
        }
        PositionLayout(sizes)
    }
}

/// Every request the master can send (all documented packets except 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Request<'a> {
    /// 1 - Get Version.
    GetVersion,
    /// 2 - Get Binary Motion Data.
    GetMotionData,
    /// 4 - Set Stream Period, in 40.96 µs units; 0 disables the stream.
    SetStreamPeriod(u16),
    /// 5 - Get Stream Period.
    GetStreamPeriod,
    /// 6 - Set Data Mask.
    SetDataMask(Entries<'a, DataMaskEntry>),
    /// 7 - Get Data Mask.
    GetDataMask,
    /// 8 - Set Stream Config.
    SetStreamConfig(StreamConfig),
    /// 9 - Get Stream Config.
    GetStreamConfig,
    /// 10 - Set Position.
    SetPosition(Entries<'a, SetPositionEntry>),
    /// 11 - Get Position.
    GetPosition(GetPosition),
    /// 12 - Set History Dimensions.
    SetHistoryDimensions(HistoryDimensions),
    /// 13 - Get History Dimensions.
    GetHistoryDimensions,
    /// 14 - Set Input Mode.
    SetInputMode(Entries<'a, InputModeEntry>),
    /// 16 - Set Control Mode.
    SetControlMode(Entries<'a, ControlModeEntry>),
    /// 18 - Set Motor Power.
    SetMotorPower(Entries<'a, MotorPowerEntry>),
    /// 20 - Set Position Control Target.
    SetPositionTarget(Entries<'a, PositionTargetEntry>),
    /// 22 - Set Velocity Control Target.
    SetVelocityTarget(Entries<'a, VelocityTargetEntry>),
    /// 24 - Set Power Limit.
    SetPowerLimit(Entries<'a, PowerLimitEntry>),
    /// 26 - Set Velocity Limit.
    SetVelocityLimit(Entries<'a, VelocityLimitEntry>),
    /// 28 - Set Acceleration Limit.
    SetAccelerationLimit(Entries<'a, AccelerationLimitEntry>),
    /// 30 - Set Position Control PID Constants.
    SetPositionPid(Entries<'a, PositionPidEntry>),
    /// 32 - Set Velocity Control PID Constants.
    SetVelocityPid(Entries<'a, VelocityPidEntry>),
    /// 34 - Position Ramp.
    PositionRamp(Entries<'a, PositionRampEntry>),
    /// 36 - Velocity Ramp.
    VelocityRamp(Entries<'a, VelocityRampEntry>),
}

impl<'a> Request<'a> {
    /// The Packet ID.
    pub const fn id(&self) -> PacketId {
        match self {
            Self::GetVersion => PacketId::GetVersion,
            Self::GetMotionData => PacketId::GetMotionData,
            Self::SetStreamPeriod(_) => PacketId::SetStreamPeriod,
            Self::GetStreamPeriod => PacketId::GetStreamPeriod,
            Self::SetDataMask(_) => PacketId::SetDataMask,
            Self::GetDataMask => PacketId::GetDataMask,
            Self::SetStreamConfig(_) => PacketId::SetStreamConfig,
            Self::GetStreamConfig => PacketId::GetStreamConfig,
            Self::SetPosition(_) => PacketId::SetPosition,
            Self::GetPosition(_) => PacketId::GetPosition,
            Self::SetHistoryDimensions(_) => PacketId::SetHistoryDimensions,
            Self::GetHistoryDimensions => PacketId::GetHistoryDimensions,
            Self::SetInputMode(_) => PacketId::SetInputMode,
            Self::SetControlMode(_) => PacketId::SetControlMode,
            Self::SetMotorPower(_) => PacketId::SetMotorPower,
            Self::SetPositionTarget(_) => PacketId::SetPositionTarget,
            Self::SetVelocityTarget(_) => PacketId::SetVelocityTarget,
            Self::SetPowerLimit(_) => PacketId::SetPowerLimit,
            Self::SetVelocityLimit(_) => PacketId::SetVelocityLimit,
            Self::SetAccelerationLimit(_) => PacketId::SetAccelerationLimit,
            Self::SetPositionPid(_) => PacketId::SetPositionPid,
            Self::SetVelocityPid(_) => PacketId::SetVelocityPid,
            Self::PositionRamp(_) => PacketId::PositionRamp,
            Self::VelocityRamp(_) => PacketId::VelocityRamp,
        }
    }

    /// Encodes the whole packet (STX … checksum) into `buf`; returns its length.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        write_packet(buf, self.id().as_u8(), |w| self.write_payload(w))
    }

    fn write_payload(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        match self {
            Self::GetVersion
            | Self::GetMotionData
            | Self::GetStreamPeriod
            | Self::GetDataMask
            | Self::GetStreamConfig
            | Self::GetHistoryDimensions => Ok(()),
            Self::SetStreamPeriod(p) => w.u16(*p),
            Self::SetStreamConfig(c) => w.u8(c.0),
            Self::SetHistoryDimensions(d) => w.bytes(&[d.history_length, d.averaging_bits]),
            Self::GetPosition(GetPosition::Configured) => Ok(()),
            Self::GetPosition(GetPosition::Channels(m)) => w.u8(m.0),
            Self::GetPosition(GetPosition::Sizes(s)) => {
                s.iter().try_for_each(|size| w.u8(*size as u8))
            }
            Self::SetDataMask(e) => e.write(w),
            Self::SetPosition(e) => e.write(w),
            Self::SetInputMode(e) => e.write(w),
            Self::SetControlMode(e) => e.write(w),
            Self::SetMotorPower(e) => e.write(w),
            Self::SetPositionTarget(e) => e.write(w),
            Self::SetVelocityTarget(e) => e.write(w),
            Self::SetPowerLimit(e) => e.write(w),
            Self::SetVelocityLimit(e) => e.write(w),
            Self::SetAccelerationLimit(e) => e.write(w),
            Self::SetPositionPid(e) => e.write(w),
            Self::SetVelocityPid(e) => e.write(w),
            Self::PositionRamp(e) => e.write(w),
            Self::VelocityRamp(e) => e.write(w),
        }
    }

    /// Parses one whole packet and decodes it as a request.
    pub fn parse(packet: &'a [u8]) -> Result<Self, Error> {
        Self::decode(Frame::parse(packet)?)
    }

    /// Decodes a framed packet as a request. Requests need no context: packet 10 carries its
    /// sizes, packet 14 its modes and packet 11 its form in the payload length.
    pub fn decode(frame: Frame<'a>) -> Result<Self, Error> {
        let p = frame.payload;
        let mut r = Reader::new(p);
        let empty = |req: Self| {
            if p.is_empty() {
                Ok(req)
            } else {
                Err(Error::Length)
            }
        };
        let req = match PacketId::try_from(frame.id)? {
            PacketId::GetVersion => return empty(Self::GetVersion),
            PacketId::GetMotionData => return empty(Self::GetMotionData),
            PacketId::StreamData => return Err(Error::WrongDirection(frame.id)),
            PacketId::SetStreamPeriod => Self::SetStreamPeriod(r.u16()?),
            PacketId::GetStreamPeriod => return empty(Self::GetStreamPeriod),
            PacketId::SetDataMask => return Ok(Self::SetDataMask(Entries::from_wire(p)?)),
            PacketId::GetDataMask => return empty(Self::GetDataMask),
            PacketId::SetStreamConfig => Self::SetStreamConfig(StreamConfig(r.u8()?)),
            PacketId::GetStreamConfig => return empty(Self::GetStreamConfig),
            PacketId::SetPosition => return Ok(Self::SetPosition(Entries::from_wire(p)?)),
            PacketId::GetPosition => Self::GetPosition(match p {
                [] => GetPosition::Configured,
                [m] => GetPosition::Channels(ChannelMask(*m)),
                [a, b, c, d] => GetPosition::Sizes([
                    PositionSize::from_byte(*a)?,
                    PositionSize::from_byte(*b)?,
                    PositionSize::from_byte(*c)?,
                    PositionSize::from_byte(*d)?,
                ]),
                _ => return Err(Error::Length),
            }),
            PacketId::SetHistoryDimensions => Self::SetHistoryDimensions(HistoryDimensions {
                history_length: r.u8()?,
                averaging_bits: r.u8()?,
            }),
            PacketId::GetHistoryDimensions => return empty(Self::GetHistoryDimensions),
            PacketId::SetInputMode => Self::SetInputMode(Entries::from_wire(p)?),
            PacketId::SetControlMode => Self::SetControlMode(Entries::from_wire(p)?),
            PacketId::SetMotorPower => Self::SetMotorPower(Entries::from_wire(p)?),
            PacketId::SetPositionTarget => Self::SetPositionTarget(Entries::from_wire(p)?),
            PacketId::SetVelocityTarget => Self::SetVelocityTarget(Entries::from_wire(p)?),
            PacketId::SetPowerLimit => Self::SetPowerLimit(Entries::from_wire(p)?),
            PacketId::SetVelocityLimit => Self::SetVelocityLimit(Entries::from_wire(p)?),
            PacketId::SetAccelerationLimit => Self::SetAccelerationLimit(Entries::from_wire(p)?),
            PacketId::SetPositionPid => Self::SetPositionPid(Entries::from_wire(p)?),
            PacketId::SetVelocityPid => Self::SetVelocityPid(Entries::from_wire(p)?),
            PacketId::PositionRamp => Self::PositionRamp(Entries::from_wire(p)?),
            PacketId::VelocityRamp => Self::VelocityRamp(Entries::from_wire(p)?),
        };
        if matches!(
            req,
            Self::SetStreamPeriod(_) | Self::SetStreamConfig(_) | Self::SetHistoryDimensions(_)
        ) {
            r.finish()?;
        }
        Ok(req)
    }
}
