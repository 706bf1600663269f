//! The per-tick snapshot: [`MotionFrame`] and [`AxisState`].

use iceoryx2::prelude::ZeroCopySend;

use crate::command::{ClientId, UnknownValue};
use crate::group::GroupState;
use crate::signal::SignalState;
use crate::{MAX_AXES, MAX_DEVICES, MAX_GROUPS, MAX_SIGNALS, SCHEMA_VERSION};

enumeration! {
    /// Where a board is in its life, as the server sees it. Travels as `u8` in
    /// [`MotionFrame::devices`] and [`AxisState::device_state`], and as `u32` in
    /// [`DeviceInfo::state`](crate::DeviceInfo::state).
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub enum DeviceState(u8) -> name {
        /// Not answering, or its link is down: goals are refused (`DeviceOffline` / `LinkDown`).
        #[default]
        Offline = 0 => "offline",
        /// Answering, configured, start-up stop acknowledged: takes goals.
        Online = 1 => "online",
        /// Link up, the board is being probed and configured, or its start-up stop is not yet
        /// acknowledged: goals are refused with `DeviceStarting`.
        Starting = 2 => "starting",
        /// Answering, but a board-level fault is latched (it rebooted, reported an error).
        Faulted = 3 => "faulted",
    }
}

enumeration! {
    /// What an axis is doing, as the server drives it. Travels as `u8` in [`AxisState::mode`].
    #[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum AxisMode(u8) -> name {
        /// Not driven (motor off / unpowered, or never commanded).
        Off = 0 => "off",
        /// Actively holding its position.
        Hold = 1 => "hold",
        /// Open-loop power (duty) command.
        Power = 2 => "power",
        /// Position target handed straight to the board's controller.
        Position = 3 => "position",
        /// Velocity command (deadman applies).
        Velocity = 4 => "velocity",
        /// Position reached along a velocity/acceleration-limited profile.
        RampPosition = 5 => "ramp-position",
        /// Velocity reached along an acceleration-limited profile (deadman applies).
        RampVelocity = 6 => "ramp-velocity",
        /// Reference search in progress.
        Homing = 7 => "homing",
        /// Decelerating to a stop (stop, deadman expiry, e-stop, fault).
        Stopping = 8 => "stopping",
        /// Following its group's path or stream ([`AxisState::desired_position`]).
        Group = 9 => "group",
    }
}

enumeration! {
    /// Why an axis is faulted. Travels as `u16` in [`AxisState::fault`]; 0 means no fault.
    ///
    /// Every fault stops the axis at once with its e-stop category (hold, stop-off or off) and
    /// stays latched until a `Reset` that finds its cause gone. [`AxisState::fault_value`] and
    /// [`AxisState::fault_limit`] carry the measured figure and the tolerance where the fault
    /// has one ([`FaultCode::explain`] turns them into a sentence).
    ///
    /// | code | name | raised by | figure / tolerance | cleared when |
    /// |---|---|---|---|---|
    /// | 1 | `LinkDown` | the link failed (unplugged, I/O error) | – | link up and fresh data |
    /// | 2 | `BoardNotResponding` | the board missed its reply budget repeatedly | – | fresh data |
    /// | 3 | `BoardReset` | the board rebooted (goals lost) | – | fresh data, then reset |
    /// | 4 | `BoardError` | the board answered with an error status | – | fresh data |
    /// | 5 | `Protocol` | undecodable replies for too long | – | fresh data |
    /// | 6 | `Overspeed` | board overspeed flag, or measured \|v\| > `overspeed_factor` × `max_velocity` for 3 fresh samples | \|v\| / limit, units/s | reset with \|v\| within the limit |
    /// | 7 | `LimitSwitch` | a limit or reference switch stopped the axis | – | switch released |
    /// | 8 | `Overrun` | the server overran `max_consecutive_overruns` ticks in a row | – | reset |
    /// | 9 | `FollowingError` | holding: \|position − target\| > `following_error`; moving: position left the segment [start, target] widened by `following_error` | distance / `following_error`, units | reset (the target becomes the position) |
    /// | 10 | `LimitExceeded` | position beyond a soft limit by more than `following_error` | position / the limit passed, units | reset once back within the limits (moves back inside are accepted meanwhile) |
    /// | 11 | `HomeFailed` | a reference search travelled `home_max_travel` without its switch or index, or the board reported a search error | travel / `home_max_travel`, units | reset |
    /// | 12 | `GoalTolerance` | a group's path ended and the axis was not within its `goal_tolerance` `goal_time_tolerance` later | distance / `goal_tolerance`, units | reset |
    #[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum FaultCode(u16) -> name {
        /// No fault.
        None = 0 => "none",
        /// The link to the board is down (unplugged, closed, I/O error).
        LinkDown = 1 => "link-down",
        /// The board stopped answering within its reply budget.
        BoardNotResponding = 2 => "board-not-responding",
        /// The board rebooted (version/reset flag seen): its goals were lost.
        BoardReset = 3 => "board-reset",
        /// The board reported an error for a request.
        BoardError = 4 => "board-error",
        /// Replies could not be decoded (garbage, wrong answers) for too long.
        Protocol = 5 => "protocol",
        /// The board reported overspeed, or the encoder glitched.
        Overspeed = 6 => "overspeed",
        /// A hard limit or reference switch stopped the axis.
        LimitSwitch = 7 => "limit-switch",
        /// Stopped because the server overran its tick too many times in a row.
        Overrun = 8 => "overrun",
        /// The measured position left where the axis should be by more than its
        /// `following_error`: away from the held target, or out of the segment of a move.
        FollowingError = 9 => "following-error",
        /// The measured position is beyond a soft limit by more than `following_error`.
        LimitExceeded = 10 => "limit-exceeded",
        /// A reference search ended without finding its switch or index (travel limit
        /// reached, or the board reported a search error).
        HomeFailed = 11 => "home-failed",
        /// A group's path ended and the axis did not come within its `goal_tolerance` within the
        /// group's `goal_time_tolerance`.
        GoalTolerance = 12 => "goal-tolerance",
    }
}

impl FaultCode {
    /// One sentence about axis `axis` with this fault, the measured `value` and the
    /// `limit` it broke (as in [`AxisState::fault_value`] / [`AxisState::fault_limit`]),
    /// in `unit`.
    pub fn explain(self, axis: &str, value: f64, limit: f64, unit: &str) -> String {
        match self {
            Self::None => format!("axis `{axis}` has no fault"),
            Self::LinkDown => format!("axis `{axis}`: its link is down"),
            Self::BoardNotResponding => format!("axis `{axis}`: its board is not answering"),
            Self::BoardReset => {
                format!(
                    "axis `{axis}`: its board rebooted; its goals were lost (reset, then command again)"
                )
            }
            Self::BoardError => format!("axis `{axis}`: its board reported an error"),
            Self::Protocol => format!("axis `{axis}`: its board's replies could not be decoded"),
            Self::Overspeed if limit > 0.0 => format!(
                "axis `{axis}`: overspeed: measured {value:.4} {unit}/s, limit {limit:.4} {unit}/s"
            ),
            Self::Overspeed => {
                format!("axis `{axis}`: its board reported overspeed or an encoder glitch")
            }
            Self::LimitSwitch => format!("axis `{axis}`: a limit or reference switch stopped it"),
            Self::Overrun => format!("axis `{axis}`: stopped because the server overran its tick"),
            Self::FollowingError => format!(
                "axis `{axis}`: following error: {value:.4} {unit} from where it should be, tolerance {limit:.4} {unit}"
            ),
            Self::LimitExceeded => format!(
                "axis `{axis}`: position {value:.4} {unit} is beyond its soft limit {limit:.4} {unit}"
            ),
            Self::HomeFailed if limit > 0.0 => format!(
                "axis `{axis}`: home search failed: travelled {value:.4} {unit} without finding its reference, limit {limit:.4} {unit}"
            ),
            Self::HomeFailed => {
                format!("axis `{axis}`: home search failed: the board reported a search error")
            }
            Self::GoalTolerance => format!(
                "axis `{axis}`: its group's path ended and it stayed {value:.4} {unit} from its goal, tolerance {limit:.4} {unit}"
            ),
        }
    }
}

flag_set! {
    /// Bit set of an axis's state flags ([`AxisState::flags`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct AxisFlags(u32) {
        /// The axis is moving (commanded or measured velocity not zero).
        MOVING = 0, "moving";
        /// The axis has a valid reference (homed, or its position was set).
        HOMED = 1, "homed";
        /// The axis sits at a soft or hard limit.
        AT_LIMIT = 2, "at-limit";
        /// The axis's data is older than its board's refresh budget.
        STALE = 3, "stale";
        /// The axis is faulted; see [`AxisState::fault`].
        FAULT = 4, "fault";
        /// A client holds an exclusive claim on the axis ([`AxisState::claimed_by`]).
        CLAIMED = 5, "claimed";
        /// The last position goal has been reached within tolerance.
        ARRIVED = 6, "arrived";
        /// Stopped by the latched e-stop.
        ESTOPPED = 7, "estopped";
        /// The last velocity/power goal expired (deadman) and the axis was stopped.
        DEADMAN_EXPIRED = 8, "deadman-expired";
        /// The axis's position move is held (`Hold` with `Target::Axis`): a `Resume` continues
        /// it to its target.
        HELD = 9, "held";
    }
}

payload! {
    /// One axis in a frame.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::AxisState")]
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
        /// [`FaultCode`] value; 0 = no fault.
        pub fault: u16,
        /// [`AxisMode`] value.
        pub mode: u8,
        /// [`DeviceState`] value of the axis's board.
        pub device_state: u8,
        /// The client holding a claim on the axis; zero when unclaimed.
        pub claimed_by: ClientId,
        /// The measured figure of the latched fault (units, units/s; see [`FaultCode`]), 0 when
        /// none.
        pub fault_value: f64,
        /// The tolerance or limit the fault broke, 0 when none.
        pub fault_limit: f64,
        /// Where the server wants the axis now, in units: the group's path while the axis
        /// follows a group (mode `group`), the target while it holds or moves to a position,
        /// the measured position otherwise.
        pub desired_position: f64,
        /// The velocity the server wants now, units/s: the group path's while it follows a
        /// group, the velocity target of a velocity mode, 0 otherwise.
        pub desired_velocity: f64,
    }
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
        device_state: 0,
        claimed_by: ClientId::NONE,
        fault_value: 0.0,
        fault_limit: 0.0,
        desired_position: 0.0,
        desired_velocity: 0.0,
    };

    /// The typed flags.
    pub const fn flags(&self) -> AxisFlags {
        AxisFlags(self.flags)
    }

    /// The typed mode; `Err` for a value this build does not know.
    pub fn mode(&self) -> Result<AxisMode, UnknownValue> {
        AxisMode::try_from(self.mode)
    }

    /// The mode as clients print it (`ramp-position`), `mode N` for a value this build
    /// does not know.
    pub fn mode_name(&self) -> String {
        self.mode().map_or_else(
            |error| format!("mode {}", error.0),
            |mode| mode.name().to_owned(),
        )
    }

    /// The fault's name (`following-error`), `None` when the axis has none, `fault N` for a
    /// code this build does not know.
    pub fn fault_name(&self) -> Option<String> {
        match self.fault() {
            Ok(FaultCode::None) => None,
            Ok(code) => Some(code.name().to_owned()),
            Err(error) => Some(format!("fault {}", error.0)),
        }
    }

    /// The typed fault code; `Err` for a value this build does not know.
    pub fn fault(&self) -> Result<FaultCode, UnknownValue> {
        FaultCode::try_from(self.fault)
    }

    /// The typed state of the axis's board; `Err` for a value this build does not know.
    pub fn device_state(&self) -> Result<DeviceState, UnknownValue> {
        DeviceState::try_from(self.device_state)
    }
}

impl Default for AxisState {
    fn default() -> Self {
        Self::UNKNOWN
    }
}

flag_set! {
    /// Bit set of server-wide state in [`MotionFrame::flags`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct FrameFlags(u32) {
        /// The e-stop is latched: every axis is stopped until a `reset`.
        ESTOP_LATCHED = 0, "estop-latched";
        /// This tick started after its deadline plus one period (an overrun).
        OVERRUN = 1, "overrun";
        /// The server is shutting down: axes are being stopped.
        SHUTTING_DOWN = 2, "shutting-down";
    }
}

payload! {
    /// When the current goal of one axis was set and when its first request reached the wire
    /// ([`MotionFrame::wire`], same index as `axes`).
    ///
    /// Command → wire: `wire_ns` minus the client's CLOCK_MONOTONIC when it sent the command, or in
    /// ticks `wire_tick − goal_tick` (0: written in the tick that accepted it).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    #[type_name("motiond::AxisWire")]
    pub struct AxisWire {
        /// Tick in which the current goal was set (a client's command: the reply's `tick_applied`;
        /// or the server's own stop).
        pub goal_tick: u64,
        /// Tick during which the goal's first request was written to the link (its last byte
        /// accepted by the transport); 0 until then.
        pub wire_tick: u64,
        /// CLOCK_MONOTONIC ns of that write; 0 until then (and for a goal that needs no request).
        pub wire_ns: u64,
    }
}

impl AxisWire {
    /// No goal yet.
    pub const NONE: Self = Self {
        goal_tick: 0,
        wire_tick: 0,
        wire_ns: 0,
    };

    /// Whether the current goal's first request has been written.
    pub const fn written(&self) -> bool {
        self.wire_ns != 0
    }
}

payload! {
    /// One consistent snapshot of every axis, board and signal, published once per tick on
    /// `motiond/<name>/frame`.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::MotionFrame")]
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
        /// Number of valid entries at the start of `signals`.
        pub signal_count: u32,
        /// Number of valid entries at the start of `devices`.
        pub device_count: u32,
        /// Number of valid entries at the start of `groups`.
        pub group_count: u32,
        /// [`DeviceState`] per device, config order; entries past `device_count` are zero.
        pub devices: [u8; MAX_DEVICES],
        /// Axes in config order; entries past `axis_count` are [`AxisState::UNKNOWN`].
        pub axes: [AxisState; MAX_AXES],
        /// Signals in config order; entries past `signal_count` are [`SignalState::UNKNOWN`].
        pub signals: [SignalState; MAX_SIGNALS],
        /// Per axis (same index as `axes`): when its current goal was set and when its first
        /// request reached the wire.
        pub wire: [AxisWire; MAX_AXES],
        /// Groups in config order; entries past `group_count` are [`GroupState::IDLE`].
        pub groups: [GroupState; MAX_GROUPS],
    }
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
        signal_count: 0,
        device_count: 0,
        group_count: 0,
        devices: [0; MAX_DEVICES],
        axes: [AxisState::UNKNOWN; MAX_AXES],
        signals: [SignalState::UNKNOWN; MAX_SIGNALS],
        wire: [AxisWire::NONE; MAX_AXES],
        groups: [GroupState::IDLE; MAX_GROUPS],
    };

    /// The valid axes.
    pub fn axes(&self) -> &[AxisState] {
        let count = (self.axis_count as usize).min(MAX_AXES);
        &self.axes[..count]
    }

    /// The goal stamps of the valid axes.
    pub fn wire(&self) -> &[AxisWire] {
        let count = (self.axis_count as usize).min(MAX_AXES);
        &self.wire[..count]
    }

    /// The valid groups.
    pub fn groups(&self) -> &[GroupState] {
        let count = (self.group_count as usize).min(MAX_GROUPS);
        &self.groups[..count]
    }

    /// The valid signals.
    pub fn signals(&self) -> &[SignalState] {
        let count = (self.signal_count as usize).min(MAX_SIGNALS);
        &self.signals[..count]
    }

    /// The state of device `index` (`Offline` for an index past `device_count` or a value
    /// this build does not know).
    pub fn device_state(&self, index: usize) -> DeviceState {
        if index >= (self.device_count as usize).min(MAX_DEVICES) {
            return DeviceState::Offline;
        }
        DeviceState::try_from(self.devices[index]).unwrap_or_default()
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
