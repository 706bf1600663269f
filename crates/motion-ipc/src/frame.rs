//! The per-tick snapshot: [`MotionFrame`] and [`AxisState`].

use iceoryx2::prelude::ZeroCopySend;

use crate::command::{ClientId, UnknownValue};
use crate::{MAX_AXES, SCHEMA_VERSION};

/// What an axis is doing, as the server drives it. Travels as `u8` in [`AxisState::mode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum AxisMode {
    /// Not driven (motor off / unpowered, or never commanded).
    Off = 0,
    /// Actively holding its position.
    Hold = 1,
    /// Open-loop power (duty) command.
    Power = 2,
    /// Position target handed straight to the board's controller.
    Position = 3,
    /// Velocity command (deadman applies).
    Velocity = 4,
    /// Position reached along a velocity/acceleration-limited profile.
    RampPosition = 5,
    /// Velocity reached along an acceleration-limited profile (deadman applies).
    RampVelocity = 6,
    /// Reference search in progress.
    Homing = 7,
    /// Decelerating to a stop (stop, deadman expiry, e-stop, fault).
    Stopping = 8,
}

impl TryFrom<u8> for AxisMode {
    type Error = UnknownValue;
    fn try_from(value: u8) -> Result<Self, Self::Error> {
        Ok(match value {
            0 => Self::Off,
            1 => Self::Hold,
            2 => Self::Power,
            3 => Self::Position,
            4 => Self::Velocity,
            5 => Self::RampPosition,
            6 => Self::RampVelocity,
            7 => Self::Homing,
            8 => Self::Stopping,
            other => return Err(UnknownValue(u32::from(other))),
        })
    }
}

/// Why an axis is faulted. Travels as `u16` in [`AxisState::fault`]; 0 means no fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u16)]
pub enum FaultCode {
    /// No fault.
    None = 0,
    /// The link to the board is down (unplugged, closed, I/O error).
    LinkDown = 1,
    /// The board stopped answering within its reply budget.
    BoardNotResponding = 2,
    /// The board rebooted (version/reset flag seen): its goals were lost.
    BoardReset = 3,
    /// The board reported an error for a request.
    BoardError = 4,
    /// Replies could not be decoded (garbage, wrong answers) for too long.
    Protocol = 5,
    /// The board reported overspeed, or the encoder glitched.
    Overspeed = 6,
    /// A hard limit or reference switch stopped the axis.
    LimitSwitch = 7,
    /// Stopped because the server overran its tick too many times in a row.
    Overrun = 8,
    /// The measured position left where the axis should be by more than its
    /// `following_error`: away from the held target, or out of the segment of a move.
    FollowingError = 9,
    /// The measured position is beyond a soft limit by more than `following_error`.
    LimitExceeded = 10,
    /// A reference search ended without finding its switch or index (travel limit
    /// reached, or the board reported a search error).
    HomeFailed = 11,
}

impl TryFrom<u16> for FaultCode {
    type Error = UnknownValue;
    fn try_from(value: u16) -> Result<Self, Self::Error> {
        Ok(match value {
            0 => Self::None,
            1 => Self::LinkDown,
            2 => Self::BoardNotResponding,
            3 => Self::BoardReset,
            4 => Self::BoardError,
            5 => Self::Protocol,
            6 => Self::Overspeed,
            7 => Self::LimitSwitch,
            8 => Self::Overrun,
            9 => Self::FollowingError,
            10 => Self::LimitExceeded,
            11 => Self::HomeFailed,
            other => return Err(UnknownValue(u32::from(other))),
        })
    }
}

/// Bit set of an axis's state flags ([`AxisState::flags`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AxisFlags(pub u32);

impl AxisFlags {
    /// The axis is moving (commanded or measured velocity not zero).
    pub const MOVING: Self = Self(1 << 0);
    /// The axis has a valid reference (homed, or its position was set).
    pub const HOMED: Self = Self(1 << 1);
    /// The axis sits at a soft or hard limit.
    pub const AT_LIMIT: Self = Self(1 << 2);
    /// The axis's data is older than its board's refresh budget.
    pub const STALE: Self = Self(1 << 3);
    /// The axis is faulted; see [`AxisState::fault`].
    pub const FAULT: Self = Self(1 << 4);
    /// A client holds an exclusive claim on the axis ([`AxisState::claimed_by`]).
    pub const CLAIMED: Self = Self(1 << 5);
    /// The last position goal has been reached within tolerance.
    pub const ARRIVED: Self = Self(1 << 6);
    /// Stopped by the latched e-stop.
    pub const ESTOPPED: Self = Self(1 << 7);
    /// The last velocity/power goal expired (deadman) and the axis was stopped.
    pub const DEADMAN_EXPIRED: Self = Self(1 << 8);

    /// Whether every bit of `other` is set.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// `self` with the bits of `other` set (`on`) or cleared.
    #[must_use]
    pub const fn with(self, other: Self, on: bool) -> Self {
        if on {
            Self(self.0 | other.0)
        } else {
            Self(self.0 & !other.0)
        }
    }
}

/// One axis in a frame. 64 bytes, alignment 8. Fields in memory order:
///
/// | offset | field | type | meaning |
/// |---|---|---|---|
/// | 0 | `position` | f64 | measured position, axis units |
/// | 8 | `velocity` | f64 | measured velocity, units/s |
/// | 16 | `target` | f64 | position target (position modes) or velocity target (velocity modes) |
/// | 24 | `raw_counts` | i64 | the board's own position counts |
/// | 32 | `last_refresh_tick` | u64 | tick at which fresh data last arrived from the board |
/// | 40 | `flags` | u32 | [`AxisFlags`] bits |
/// | 44 | `fault` | u16 | [`FaultCode`] |
/// | 46 | `mode` | u8 | [`AxisMode`] |
/// | 47 | `reserved` | u8 | zero |
/// | 48 | `claimed_by` | [`ClientId`] | claim holder, zero when unclaimed |
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("motiond::AxisState")]
#[repr(C)]
pub struct AxisState {
    /// Measured position in axis units.
    pub position: f64,
    /// Measured velocity in units/s.
    pub velocity: f64,
    /// Position target (position modes) or velocity target (velocity modes), in units.
    pub target: f64,
    /// Position in the board's own counts.
    pub raw_counts: i64,
    /// Tick at which fresh data last arrived from the board.
    pub last_refresh_tick: u64,
    /// [`AxisFlags`] bits.
    pub flags: u32,
    /// [`FaultCode`] value.
    pub fault: u16,
    /// [`AxisMode`] value.
    pub mode: u8,
    /// Zero.
    pub reserved: u8,
    /// The client holding a claim on the axis; zero when unclaimed.
    pub claimed_by: ClientId,
}

impl AxisState {
    /// An axis that has never been heard from: off, stale, no fault.
    pub const UNKNOWN: Self = Self {
        position: 0.0,
        velocity: 0.0,
        target: 0.0,
        raw_counts: 0,
        last_refresh_tick: 0,
        flags: AxisFlags::STALE.0,
        fault: 0,
        mode: 0,
        reserved: 0,
        claimed_by: ClientId::NONE,
    };

    /// The typed flags.
    pub const fn flags(&self) -> AxisFlags {
        AxisFlags(self.flags)
    }

    /// The typed mode; `Err` for a value this build does not know.
    pub fn mode(&self) -> Result<AxisMode, UnknownValue> {
        AxisMode::try_from(self.mode)
    }

    /// The typed fault code; `Err` for a value this build does not know.
    pub fn fault(&self) -> Result<FaultCode, UnknownValue> {
        FaultCode::try_from(self.fault)
    }
}

impl Default for AxisState {
    fn default() -> Self {
        Self::UNKNOWN
    }
}

/// Bit set of server-wide state in [`MotionFrame::flags`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FrameFlags(pub u32);

impl FrameFlags {
    /// The e-stop is latched: every axis is stopped until a `reset`.
    pub const ESTOP_LATCHED: Self = Self(1 << 0);
    /// This tick started after its deadline plus one period (an overrun).
    pub const OVERRUN: Self = Self(1 << 1);
    /// The server is shutting down: axes are being stopped.
    pub const SHUTTING_DOWN: Self = Self(1 << 2);

    /// Whether every bit of `other` is set.
    pub const fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
}

/// One consistent snapshot of every axis, published once per tick on
/// `motiond/<name>/frame`. 8232 bytes, alignment 8. Fields in memory order:
///
/// | offset | field | type | meaning |
/// |---|---|---|---|
/// | 0 | `schema_version` | u32 | [`SCHEMA_VERSION`] |
/// | 4 | `axis_count` | u32 | valid entries at the start of `axes` |
/// | 8 | `tick` | u64 | tick number, 0 at server start |
/// | 16 | `time_ns` | u64 | the tick's deadline, CLOCK_MONOTONIC ns |
/// | 24 | `publish_ns` | u64 | CLOCK_MONOTONIC ns just before the frame was sent |
/// | 32 | `flags` | u32 | [`FrameFlags`] bits |
/// | 36 | `reserved` | u32 | zero |
/// | 40 | `axes` | [`AxisState`]; [`MAX_AXES`] | axes in config order |
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("motiond::MotionFrame")]
#[repr(C)]
pub struct MotionFrame {
    /// [`SCHEMA_VERSION`] of the writer.
    pub schema_version: u32,
    /// Number of valid entries at the start of `axes`.
    pub axis_count: u32,
    /// Tick number, 0 at server start.
    pub tick: u64,
    /// The tick's deadline on CLOCK_MONOTONIC, ns.
    pub time_ns: u64,
    /// CLOCK_MONOTONIC, ns, taken just before the frame was sent.
    pub publish_ns: u64,
    /// [`FrameFlags`] bits.
    pub flags: u32,
    /// Zero.
    pub reserved: u32,
    /// Axes in config order; entries past `axis_count` are [`AxisState::UNKNOWN`].
    pub axes: [AxisState; MAX_AXES],
}

impl MotionFrame {
    /// An empty frame of the current schema.
    pub const EMPTY: Self = Self {
        schema_version: SCHEMA_VERSION,
        axis_count: 0,
        tick: 0,
        time_ns: 0,
        publish_ns: 0,
        flags: 0,
        reserved: 0,
        axes: [AxisState::UNKNOWN; MAX_AXES],
    };

    /// The valid axes.
    pub fn axes(&self) -> &[AxisState] {
        let count = (self.axis_count as usize).min(MAX_AXES);
        &self.axes[..count]
    }

    /// The typed server flags.
    pub const fn flags(&self) -> FrameFlags {
        FrameFlags(self.flags)
    }
}

impl Default for MotionFrame {
    fn default() -> Self {
        Self::EMPTY
    }
}
