//! Bit fields and small values shared by several packets.

use crate::error::Error;
use crate::wire::{Reader, Writer};

/// Number of quadrature channels.
pub const CHANNELS: usize = 4;

/// Channel Mask: bit 0 = channel 1 … bit 3 = channel 4; bits 7..4 unused (kept as sent).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct ChannelMask(pub u8);

impl ChannelMask {
    /// All four channels.
    pub const ALL: Self = Self(0x0F);

    /// The mask selecting only `channel` (0-based, 0..=3); empty for other values.
    pub const fn single(channel: usize) -> Self {
        if channel < CHANNELS {
            Self(1 << channel)
        } else {
            Self(0)
        }
    }

    /// Whether the 0-based `channel` is selected.
    pub const fn contains(self, channel: usize) -> bool {
        channel < CHANNELS && self.0 & (1 << channel) != 0
    }

    /// The selected 0-based channel indices.
    pub fn channels(self) -> impl Iterator<Item = usize> {
        (0..CHANNELS).filter(move |c| self.contains(*c))
    }
}

/// Position Size (packets 6, 10, 11): how many bits represent a position value.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
#[repr(u8)]
pub enum PositionSize {
    /// 0x00: position omitted.
    Omitted = 0,
    /// 0x01: 8-bit signed integer.
    I8 = 1,
    /// 0x02: 16-bit signed integer.
    I16 = 2,
    /// 0x03: 32-bit signed integer.
    #[default]
    I32 = 3,
}

impl PositionSize {
    /// From the two-bit code (upper bits ignored).
    pub const fn from_bits(bits: u8) -> Self {
        match bits & 0x03 {
            0 => Self::Omitted,
            1 => Self::I8,
            2 => Self::I16,
            _ => Self::I32,
        }
    }

    /// From a whole byte that must be 0..=3 (packet 11, size-4 form).
    pub const fn from_byte(byte: u8) -> Result<Self, Error> {
        if byte > 3 {
            Err(Error::InvalidField)
        } else {
            Ok(Self::from_bits(byte))
        }
    }

    /// Bytes on the wire.
    pub const fn byte_len(self) -> usize {
        match self {
            Self::Omitted => 0,
            Self::I8 => 1,
            Self::I16 => 2,
            Self::I32 => 4,
        }
    }

    /// True for [`PositionSize::Omitted`].
    pub const fn is_omitted(self) -> bool {
        matches!(self, Self::Omitted)
    }

    pub(crate) fn read(self, r: &mut Reader<'_>) -> Result<Option<PositionValue>, Error> {
        Ok(match self {
            Self::Omitted => None,
            Self::I8 => Some(PositionValue::I8(r.i8()?)),
            Self::I16 => Some(PositionValue::I16(r.i16()?)),
            Self::I32 => Some(PositionValue::I32(r.i32()?)),
        })
    }
}

/// A position as sent on the wire in one of its three sizes.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PositionValue {
    /// 8-bit signed.
    I8(i8),
    /// 16-bit signed.
    I16(i16),
    /// 32-bit signed.
    I32(i32),
}

impl PositionValue {
    /// The lower 8 or 16 bits of `position` for the smaller sizes ("wrapping will occur on
    /// overflow", packet 2); `None` when the size is [`PositionSize::Omitted`].
    pub const fn truncate(size: PositionSize, position: i32) -> Option<Self> {
        match size {
            PositionSize::Omitted => None,
            PositionSize::I8 => Some(Self::I8(position as i8)),
            PositionSize::I16 => Some(Self::I16(position as i16)),
            PositionSize::I32 => Some(Self::I32(position)),
        }
    }

    /// The sign-extended value.
    pub const fn get(self) -> i32 {
        match self {
            Self::I8(v) => v as i32,
            Self::I16(v) => v as i32,
            Self::I32(v) => v,
        }
    }

    /// The size this value is sent in.
    pub const fn size(self) -> PositionSize {
        match self {
            Self::I8(_) => PositionSize::I8,
            Self::I16(_) => PositionSize::I16,
            Self::I32(_) => PositionSize::I32,
        }
    }

    pub(crate) fn write(self, w: &mut Writer<'_>) -> Result<(), Error> {
        match self {
            Self::I8(v) => w.bytes(&v.to_le_bytes()),
            Self::I16(v) => w.i16(v),
            Self::I32(v) => w.i32(v),
        }
    }
}

/// The size of an optional position value (omitted when `None`).
pub const fn position_size_of(value: Option<PositionValue>) -> PositionSize {
    match value {
        Some(v) => v.size(),
        None => PositionSize::Omitted,
    }
}

/// Data Mask (packet 6): which fields a channel contributes to motion data.
///
/// Bits: 5 Status, 4 Reserved, 3 Velocity, 2 Position Relative, 1..0 Position Size.
/// Unused and reserved bits are kept as sent.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DataMask(pub u8);

impl DataMask {
    /// Status bit.
    pub const STATUS: u8 = 1 << 5;
    /// Velocity bit.
    pub const VELOCITY: u8 = 1 << 3;
    /// Position Relative bit.
    pub const RELATIVE: u8 = 1 << 2;
    /// Default at start-up: 32-bit position, absolute, velocity on, status off.
    pub const DEFAULT: Self = Self(Self::VELOCITY | PositionSize::I32 as u8);

    /// Builds a mask from its fields.
    pub const fn new(size: PositionSize, relative: bool, velocity: bool, status: bool) -> Self {
        let mut bits = size as u8;
        if relative {
            bits |= Self::RELATIVE;
        }
        if velocity {
            bits |= Self::VELOCITY;
        }
        if status {
            bits |= Self::STATUS;
        }
        Self(bits)
    }

    /// Position Size field.
    pub const fn position_size(self) -> PositionSize {
        PositionSize::from_bits(self.0)
    }

    /// Relative position mode.
    pub const fn relative(self) -> bool {
        self.0 & Self::RELATIVE != 0
    }

    /// Velocity included.
    pub const fn velocity(self) -> bool {
        self.0 & Self::VELOCITY != 0
    }

    /// Status included.
    pub const fn status(self) -> bool {
        self.0 & Self::STATUS != 0
    }

    /// Bytes one channel contributes to motion data under this mask.
    pub const fn channel_len(self) -> usize {
        self.position_size().byte_len()
            + if self.velocity() { 4 } else { 0 }
            + if self.status() { 1 } else { 0 }
    }
}

impl Default for DataMask {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Stream Config Mask (packet 8): bit 0 Stream Period Timing, bit 1 Stream Periods Elapsed.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct StreamConfig(pub u8);

impl StreamConfig {
    /// Stream Period Timing bit.
    pub const TIMING: u8 = 1 << 0;
    /// Stream Periods Elapsed bit.
    pub const PERIODS_ELAPSED: u8 = 1 << 1;

    /// Builds a mask from its fields.
    pub const fn new(timing: bool, periods_elapsed: bool) -> Self {
        Self(
            if timing { Self::TIMING } else { 0 }
                | if periods_elapsed {
                    Self::PERIODS_ELAPSED
                } else {
                    0
                },
        )
    }

    /// Stream Period Timing (U16) included in packet 3.
    pub const fn timing(self) -> bool {
        self.0 & Self::TIMING != 0
    }

    /// Stream Periods Elapsed (U8) included in packet 3.
    pub const fn periods_elapsed(self) -> bool {
        self.0 & Self::PERIODS_ELAPSED != 0
    }
}

/// Channel Status byte (packet 2).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct Status(pub u8);

impl Status {
    /// Bit 7: invalid A/B transition seen.
    pub const GLITCH: u8 = 1 << 7;
    /// Bit 6: rated maximum velocity exceeded.
    pub const OVERSPEED: u8 = 1 << 6;
    /// Bit 3: input currently active (after polarity).
    pub const INPUT_ACTIVE: u8 = 1 << 3;
    /// Bit 2: input active at least once since status was last transmitted.
    pub const INPUT_ACTIVE_ACCUMULATOR: u8 = 1 << 2;
    /// Bit 1: negative-edge trigger since status was last transmitted.
    pub const TRIGGER_NEGATIVE: u8 = 1 << 1;
    /// Bit 0: positive-edge trigger since status was last transmitted.
    pub const TRIGGER_POSITIVE: u8 = 1 << 0;

    /// Glitch bit.
    pub const fn glitch(self) -> bool {
        self.0 & Self::GLITCH != 0
    }

    /// Overspeed bit.
    pub const fn overspeed(self) -> bool {
        self.0 & Self::OVERSPEED != 0
    }

    /// Input Active bit.
    pub const fn input_active(self) -> bool {
        self.0 & Self::INPUT_ACTIVE != 0
    }

    /// Input Active Accumulator bit.
    pub const fn input_active_accumulator(self) -> bool {
        self.0 & Self::INPUT_ACTIVE_ACCUMULATOR != 0
    }

    /// Input Trigger Accumulator: bit 1 negative edge, bit 0 positive edge.
    pub const fn trigger_accumulator(self) -> u8 {
        self.0 & 0x03
    }
}

/// Input Mode (packet 14, bits 1..0 of Input Configuration).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
#[repr(u8)]
pub enum InputMode {
    /// 0x00: signal on input has no effect.
    #[default]
    Disabled = 0,
    /// 0x01: home switch, acts while active.
    Home = 1,
    /// 0x02: index, acts while active and A = B = 0.
    Index = 2,
    /// 0x03: edge, acts on the inactive-to-active transition.
    Edge = 3,
}

/// Edge field (packet 14, bits 5..4; the datasheet table mistitled "Input Polarity").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(u8)]
pub enum EdgeAction {
    /// 0x00: record position only; with Spacing 0 a positive end-stop.
    #[default]
    RecordPositive = 0,
    /// 0x01: record position only; with Spacing 0 a negative end-stop.
    RecordNegative = 1,
    /// 0x02: set the position counter on a positive-end trigger.
    SetOnPositive = 2,
    /// 0x03: set the position counter on a negative-end trigger.
    SetOnNegative = 3,
}

/// Input Configuration (packet 14): bits 5..4 Edge, 3 Polarity, 2 Reserved, 1..0 Mode.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct InputConfig(pub u8);

impl InputConfig {
    /// Polarity bit: set = input active when high.
    pub const ACTIVE_HIGH: u8 = 1 << 3;

    /// Builds the byte from its fields.
    pub const fn new(mode: InputMode, active_high: bool, edge: EdgeAction) -> Self {
        Self((edge as u8) << 4 | if active_high { Self::ACTIVE_HIGH } else { 0 } | mode as u8)
    }

    /// Input Mode.
    pub const fn mode(self) -> InputMode {
        match self.0 & 0x03 {
            0 => InputMode::Disabled,
            1 => InputMode::Home,
            2 => InputMode::Index,
            _ => InputMode::Edge,
        }
    }

    /// Input Polarity: true when the input is active high.
    pub const fn active_high(self) -> bool {
        self.0 & Self::ACTIVE_HIGH != 0
    }

    /// Edge.
    pub const fn edge(self) -> EdgeAction {
        match (self.0 >> 4) & 0x03 {
            0 => EdgeAction::RecordPositive,
            1 => EdgeAction::RecordNegative,
            2 => EdgeAction::SetOnPositive,
            _ => EdgeAction::SetOnNegative,
        }
    }
}

/// Control Mode (packet 16).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
#[repr(u8)]
pub enum ControlMode {
    /// 0x00: motor output zero / off.
    #[default]
    Off = 0,
    /// 0x01: output set by packet 18.
    Power = 1,
    /// 0x02: closed-loop position PID.
    PositionPid = 2,
    /// 0x03: closed-loop velocity PID.
    VelocityPid = 3,
}

impl TryFrom<u8> for ControlMode {
    type Error = Error;

    fn try_from(v: u8) -> Result<Self, Error> {
        match v {
            0 => Ok(Self::Off),
            1 => Ok(Self::Power),
            2 => Ok(Self::PositionPid),
            3 => Ok(Self::VelocityPid),
            _ => Err(Error::InvalidField),
        }
    }
}

/// Return Code of a reply: 0 is success, anything else an error to report (docs/ARCHITECTURE.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ReturnCode(pub u8);

impl ReturnCode {
    /// Success.
    pub const SUCCESS: Self = Self(0);

    /// True for code 0.
    pub const fn is_success(self) -> bool {
        self.0 == 0
    }
}

/// History Length and Maximum Averaging Time in Bits (packets 12 and 13).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct HistoryDimensions {
    /// Capture events averaged, 2..=127 (default 31).
    pub history_length: u8,
    /// Averaging time 2^bits × 0.64 µs, bits 14..=32 (default 20).
    pub averaging_bits: u8,
}

impl Default for HistoryDimensions {
    fn default() -> Self {
        Self {
            history_length: 31,
            averaging_bits: 20,
        }
    }
}
