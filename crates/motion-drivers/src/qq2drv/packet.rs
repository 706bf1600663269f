//! The single-channel packets a goal turns into, encoded through the `qq2drv` crate.

use motion_base::FixedQueue;
use qq2drv::{
    AccelerationLimitEntry, ChannelMask, ControlMode, ControlModeEntry, Entries, InputConfig,
    InputModeEntry, MotorPowerEntry, PacketId, PositionRampEntry, PositionTargetEntry,
    PositionValue, Request, SetPositionEntry, VelocityRampEntry,
};

/// Most packets one goal step sends in its transaction.
pub(super) const MAX_STEP_PACKETS: usize = 5;

/// One packet for one channel (a one-entry payload).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Packet {
    /// 16 - Set Control Mode.
    Mode(ControlMode),
    /// 18 - Set Motor Power, ±8191.
    Power(i16),
    /// 20 - Set Position Control Target.
    Target(i32),
    /// 34 - Position Ramp: target, velocity and acceleration (both shl 12).
    PositionRamp {
        position: i32,
        velocity: u32,
        accel: u32,
    },
    /// 36 - Velocity Ramp: plain transitions/s, acceleration shl 12.
    VelocityRamp { velocity: i32, accel: u32 },
    /// 10 - Set Position (32-bit value).
    SetCounter(i32),
    /// 14 - Set Input Mode; `position` is omitted when the mode is Disabled.
    Input {
        config: InputConfig,
        spacing: u16,
        position: i32,
    },
    /// 28 - Set Acceleration Limit, shl 12 (0 disables limiting: a stop lifts it while it
    /// resets the board's velocity target, then restores it).
    AccelLimit(u32),
}

impl Packet {
    /// The packet id (what its reply carries).
    pub(super) fn id(self) -> PacketId {
        match self {
            Self::Mode(_) => PacketId::SetControlMode,
            Self::Power(_) => PacketId::SetMotorPower,
            Self::Target(_) => PacketId::SetPositionTarget,
            Self::PositionRamp { .. } => PacketId::PositionRamp,
            Self::VelocityRamp { .. } => PacketId::VelocityRamp,
            Self::SetCounter(_) => PacketId::SetPosition,
            Self::Input { .. } => PacketId::SetInputMode,
            Self::AccelLimit(_) => PacketId::SetAccelerationLimit,
        }
    }

    /// Encodes the packet for `channel` (0-based) into `buf`; returns its length.
    pub(super) fn encode(self, channel: usize, buf: &mut [u8]) -> Result<usize, qq2drv::Error> {
        let channels = ChannelMask::single(channel);
        match self {
            Self::Mode(mode) => {
                Request::SetControlMode(Entries::new(&[ControlModeEntry { channels, mode }]))
                    .encode(buf)
            }
            Self::Power(power) => {
                Request::SetMotorPower(Entries::new(&[MotorPowerEntry { channels, power }]))
                    .encode(buf)
            }
            Self::Target(position) => {
                Request::SetPositionTarget(Entries::new(&[PositionTargetEntry {
                    channels,
                    position,
                }]))
                .encode(buf)
            }
            Self::PositionRamp {
                position,
                velocity,
                accel,
            } => Request::PositionRamp(Entries::new(&[PositionRampEntry {
                channels,
                position,
                velocity,
                acceleration: accel,
            }]))
            .encode(buf),
            Self::VelocityRamp { velocity, accel } => {
                Request::VelocityRamp(Entries::new(&[VelocityRampEntry {
                    channels,
                    velocity,
                    acceleration: accel,
                }]))
                .encode(buf)
            }
            Self::SetCounter(value) => Request::SetPosition(Entries::new(&[SetPositionEntry {
                channels,
                position: Some(PositionValue::I32(value)),
            }]))
            .encode(buf),
            Self::Input {
                config,
                spacing,
                position,
            } => {
                let position = if config.mode() == qq2drv::InputMode::Disabled {
                    0
                } else {
                    position
                };
                Request::SetInputMode(Entries::new(&[InputModeEntry {
                    channels,
                    config,
                    spacing,
                    position,
                }]))
                .encode(buf)
            }
            Self::AccelLimit(limit) => {
                Request::SetAccelerationLimit(Entries::new(&[AccelerationLimitEntry {
                    channels,
                    limit,
                }]))
                .encode(buf)
            }
        }
    }
}

/// Up to [`MAX_STEP_PACKETS`] packets of one goal step, sent back to back in one
/// transaction (the step tables never exceed the capacity).
pub(super) type Packets = FixedQueue<Packet, MAX_STEP_PACKETS>;
