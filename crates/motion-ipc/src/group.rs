//! Axis groups (`[[group]]`): what a group is doing in every frame ([`GroupState`]), what it
//! is ([`GroupInfo`]), and the paths a client sends it ([`GroupPath`], on
//! `motiond/<name>/paths`).
//!
//! A group moves its axes together: a synchronized straight line in joint space, or a
//! time-parameterised trajectory. The client publishes a [`GroupPath`] with an id of its
//! choosing on the `paths` service (zero-copy: up to [`MAX_PATH_POINTS`] points ×
//! [`MAX_GROUP_AXES`] axes), then sends a `Run` command naming the group and that id; the
//! server takes the newest path of that id published by the same iceoryx2 node (identity
//! from the transport, never from the payload), validates it and answers the command.

use iceoryx2::prelude::ZeroCopySend;

use crate::command::{ClientId, UnknownValue};
use crate::{MAX_GROUP_AXES, MAX_PATH_POINTS, NAME_LEN, SCHEMA_VERSION, read_text};

/// Values of one quantity of a path: point `i`, axis `j` at `i * MAX_GROUP_AXES + j`.
pub const PATH_VALUES: usize = MAX_PATH_POINTS * MAX_GROUP_AXES;

enumeration! {
    /// Where a group's motion is. Travels as `u8` in [`GroupState::motion`].
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub enum GroupMotion(u8) -> name {
        /// No motion of the group runs (its axes may move on their own).
        #[default]
        Idle = 0 => "idle",
        /// Following its path (or a stream).
        Moving = 1 => "moving",
        /// A feed hold is bringing it to rest along its path.
        Holding = 2 => "holding",
        /// At rest on its path after a hold; `Resume` continues.
        Held = 3 => "held",
        /// The path ended and every axis came within its goal tolerance.
        Done = 4 => "done",
        /// Stopped before its end; [`GroupState::abort`] says why.
        Aborted = 5 => "aborted",
    }
}

impl GroupMotion {
    /// Whether the group's axes are owned by its motion (moving, holding or held).
    pub const fn active(self) -> bool {
        matches!(self, Self::Moving | Self::Holding | Self::Held)
    }
}

enumeration! {
    /// Why a group's motion ended before its end. Travels as `u8` in [`GroupState::abort`].
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub enum GroupAbort(u8) -> name {
        /// Not aborted.
        #[default]
        None = 0 => "none",
        /// An axis was farther than its `path_tolerance` from where the path had it when its
        /// board measured ([`GroupState::abort_axis`], `abort_value` / `abort_limit`).
        PathTolerance = 1 => "path-tolerance",
        /// An axis was not within its `goal_tolerance` `goal_time_tolerance` after the path's
        /// end; that axis faults with `GoalTolerance`.
        GoalTolerance = 2 => "goal-tolerance",
        /// An axis of the group faulted (its board, its link, its supervision).
        AxisFault = 3 => "axis-fault",
        /// The e-stop was latched.
        EStop = 4 => "e-stop",
        /// The client that ran the motion lost its claim on an axis of the group.
        ClaimLost = 5 => "claim-lost",
        /// The client that ran the motion died.
        ClientDead = 6 => "client-dead",
        /// A stop command (to the group or one of its axes) stopped it.
        Stopped = 7 => "stopped",
        /// `Cancel`: brought to rest along its path, then ended.
        Cancelled = 8 => "cancelled",
        /// The stream's setpoints stopped coming (`stream_timeout`).
        StreamStale = 9 => "stream-stale",
        /// A streamed setpoint broke a limit under `stream_limit = "abort"`.
        StreamLimit = 10 => "stream-limit",
        /// The server is shutting down.
        ShuttingDown = 11 => "shutting-down",
        /// An axis's board refused the goal that would follow the path (beyond what the board
        /// represents), or is not online ([`GroupState::abort_axis`]).
        GoalRefused = 12 => "goal-refused",
    }
}

enumeration! {
    /// Where a group's setpoint stream is. Travels as `u8` in [`GroupState::stream`].
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub enum StreamState(u8) -> name {
        /// No stream.
        #[default]
        Idle = 0 => "idle",
        /// Setpoints are being applied.
        Streaming = 1 => "streaming",
        /// Setpoints stopped coming: the group was stopped.
        Stale = 2 => "stale",
        /// A setpoint broke a limit (`stream_limit = "abort"`), or the stream was stopped.
        Aborted = 3 => "aborted",
    }
}

enumeration! {
    /// What a group's streamed setpoints are. Travels as `u32` in [`Setpoint::mode`], as
    /// `values[0]` of a `Stream` command, and as `u8` in [`GroupState::stream_mode`].
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub enum StreamMode(u32) -> name {
        /// No stream.
        #[default]
        None = 0 => "none",
        /// Positions, each axis's unit (cyclic synchronous position).
        Position = 1 => "position",
        /// Velocities, unit/s (cyclic synchronous velocity); the desired position integrates
        /// them.
        Velocity = 2 => "velocity",
        /// Open-loop power, −1.0..=1.0 of full scale (boards that take power goals).
        Power = 3 => "power",
    }
}

flag_set! {
    /// Bits of [`GroupState::stream_flags`]: what happened to the stream in this tick.
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub struct StreamFlags(u8) {
        /// A setpoint was applied in this tick.
        APPLIED = 0, "applied";
        /// The setpoint applied in this tick was clamped to a limit.
        CLAMPED = 1, "clamped";
    }
}

flag_set! {
    /// Bits of [`Setpoint::flags`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct SetpointFlags(u32) {
        /// `velocities` holds a velocity feed-forward per axis (position streams): the boards
        /// that follow by segments or velocities are given it instead of the difference of the
        /// last two setpoints.
        FEED_FORWARD = 0, "feed-forward";
    }
}

payload! {
    /// One setpoint of a group's stream, published on `motiond/<name>/setpoints` by the
    /// client that holds the group's claim and started the stream (`Stream` command); from
    /// any other node it is dropped and counted ([`GroupState::refused`]). The server
    /// applies each setpoint on its own time, once and in order: the one for tick `k` in tick
    /// `k + stream_delay` ([`crate::playout`]); one for a tick more than `stream_buffer`
    /// ahead is dropped (`early`), one more than `stream_buffer` behind, superseded or out of
    /// sequence is dropped (`late`). Velocities and accelerations are judged over the
    /// setpoints' own ticks.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::Setpoint")]
    pub struct Setpoint {
        /// [`SCHEMA_VERSION`] of the sender.
        pub schema_version: u32,
        /// Group index (config order).
        pub group: u32,
        /// The client's sequence number: increasing; a setpoint not above the last applied
        /// one is late.
        pub sequence: u64,
        /// The tick this setpoint is for (a frame's `tick` + the client's lead: 1 is the
        /// next tick).
        pub for_tick: u64,
        /// [`StreamMode`] value: must be the stream's.
        pub mode: u32,
        /// [`SetpointFlags`] bits.
        pub flags: u32,
        /// Per axis, in the group's order: position (unit), velocity (unit/s) or power.
        pub values: [f64; MAX_GROUP_AXES],
        /// Per axis: velocity feed-forward, unit/s (with `FEED_FORWARD`).
        pub velocities: [f64; MAX_GROUP_AXES],
    }
}

impl Setpoint {
    /// An empty setpoint of the current schema.
    pub const EMPTY: Self = Self {
        schema_version: SCHEMA_VERSION,
        group: 0,
        sequence: 0,
        for_tick: 0,
        mode: StreamMode::None as u32,
        flags: 0,
        values: [0.0; MAX_GROUP_AXES],
        velocities: [0.0; MAX_GROUP_AXES],
    };

    /// The typed mode.
    pub fn mode(&self) -> Result<StreamMode, UnknownValue> {
        StreamMode::try_from(self.mode)
    }

    /// The typed flags.
    pub const fn flags(&self) -> SetpointFlags {
        SetpointFlags(self.flags)
    }
}

impl Default for Setpoint {
    fn default() -> Self {
        Self::EMPTY
    }
}

enumeration! {
    /// What a [`GroupPath`] holds. Travels as `u32` in [`GroupPath::kind`] and as `u8` in
    /// [`GroupState::kind`].
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub enum PathKind(u32) -> name {
        /// Nothing (a group that never moved).
        #[default]
        None = 0 => "none",
        /// A synchronized straight line in joint space from where the group is to point 0's
        /// positions: every axis starts and arrives in the same tick, the slowest sets the
        /// time; `velocity_scale` and `accel_scale` scale every axis's limits.
        Line = 1 => "line",
        /// A trajectory: `point_count` points at `times` (seconds from the start), positions,
        /// optional velocities and accelerations (cubic with velocities, quintic with
        /// accelerations, a C2 spline through positions alone, or straight segments blended at
        /// the points within `path_tolerance` when that spline exceeds a limit); it ends at rest.
        Trajectory = 2 => "trajectory",
        /// Setpoints streamed every tick (`motiond/<name>/setpoints`).
        Stream = 3 => "stream",
    }
}

payload! {
    /// One group in a frame ([`MotionFrame::groups`](crate::MotionFrame::groups), config
    /// order).
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::GroupState")]
    pub struct GroupState {
        /// The client whose motion or stream the group runs; zero when none.
        pub owner: ClientId,
        /// The id of the path running (or last run), as the client gave it.
        pub path_id: u64,
        /// Seconds along the path (path time: it advances by the feed each second).
        pub time: f64,
        /// The path's length in seconds at feed 1.
        pub duration: f64,
        /// The feed in effect (0 while held; below the set feed while the path's limits
        /// cap it).
        pub feed: f64,
        /// The feed set by the client (1.0 = 100 %).
        pub feed_set: f64,
        /// The figure that aborted the motion (|desired − measured| in the axis's unit).
        pub abort_value: f64,
        /// The tolerance it broke.
        pub abort_limit: f64,
        /// Index of the point the path is heading to (0 for a line).
        pub point: u32,
        /// Config index of the axis that aborted it; `u32::MAX` when none.
        pub abort_axis: u32,
        /// [`GroupMotion`] value.
        pub motion: u8,
        /// [`GroupAbort`] value.
        pub abort: u8,
        /// [`PathKind`] value of the path running or last run.
        pub kind: u8,
        /// [`StreamState`] value.
        pub stream: u8,
        /// [`StreamMode`] value of the stream running or last run.
        pub stream_mode: u8,
        /// [`StreamFlags`] bits of this tick.
        pub stream_flags: u8,
        /// Ticks the stream runs behind its setpoints' own ticks: a setpoint for tick `k` is
        /// applied in tick `k + stream_delay`. 0 at the start; grows to the lateness of a
        /// setpoint that arrived after its tick (at most `stream_buffer`), never shrinks
        /// while the stream runs (schema 10; saturates at 65535).
        pub stream_delay: u16,
        /// Sequence of the last streamed setpoint applied.
        pub last_sequence: u64,
        /// Tick in which it was applied.
        pub last_applied_tick: u64,
        /// Streamed setpoints applied.
        pub applied: u64,
        /// Streamed setpoints dropped because their tick had passed.
        pub late: u64,
        /// Streamed setpoints dropped because they were addressed more than `stream_buffer`
        /// ticks ahead.
        pub early: u64,
        /// Streamed setpoints clamped to a limit (`stream_limit = "clamp"`).
        pub clamped: u64,
        /// Streamed setpoints dropped because their sender does not hold the group.
        pub refused: u64,
        /// When the server took the last applied setpoint from the `setpoints` service
        /// (CLOCK_MONOTONIC ns, the clock of [`MotionFrame::publish_ns`](crate::MotionFrame::publish_ns)):
        /// a client subtracts its own send stamp, or a frame's `publish_ns`; 0 until one is
        /// applied.
        pub last_received_ns: u64,
    }
}

impl GroupState {
    /// A group that never moved.
    pub const IDLE: Self = Self {
        owner: ClientId::NONE,
        path_id: 0,
        time: 0.0,
        duration: 0.0,
        feed: 0.0,
        feed_set: 1.0,
        abort_value: 0.0,
        abort_limit: 0.0,
        point: 0,
        abort_axis: u32::MAX,
        motion: 0,
        abort: 0,
        kind: 0,
        stream: 0,
        stream_mode: 0,
        stream_flags: 0,
        stream_delay: 0,
        last_sequence: 0,
        last_applied_tick: 0,
        applied: 0,
        late: 0,
        early: 0,
        clamped: 0,
        refused: 0,
        last_received_ns: 0,
    };

    /// The typed motion state; `Err` for a value this build does not know.
    pub fn motion(&self) -> Result<GroupMotion, UnknownValue> {
        GroupMotion::try_from(self.motion)
    }

    /// The typed abort reason.
    pub fn abort(&self) -> Result<GroupAbort, UnknownValue> {
        GroupAbort::try_from(self.abort)
    }

    /// The typed stream state.
    pub fn stream(&self) -> Result<StreamState, UnknownValue> {
        StreamState::try_from(self.stream)
    }

    /// The typed stream mode.
    pub fn stream_mode(&self) -> Result<StreamMode, UnknownValue> {
        StreamMode::try_from(u32::from(self.stream_mode))
    }

    /// The typed stream flags of this tick.
    pub const fn stream_flags(&self) -> StreamFlags {
        StreamFlags(self.stream_flags)
    }

    /// The config index of the axis that aborted the motion.
    pub const fn abort_axis(&self) -> Option<u32> {
        if self.abort_axis == u32::MAX {
            None
        } else {
            Some(self.abort_axis)
        }
    }
}

impl Default for GroupState {
    fn default() -> Self {
        Self::IDLE
    }
}

payload! {
    /// One group as configured ([`ServerInfo::groups`](crate::ServerInfo::groups)).
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::GroupInfo")]
    pub struct GroupInfo {
        /// Group name, UTF-8, zero padded.
        pub name: [u8; NAME_LEN],
        /// Valid entries in `axes` and the tolerance arrays.
        pub axis_count: u32,
        /// `stream_limit`: 0 = clamp, 1 = abort.
        pub stream_limit: u32,
        /// Ticks without a streamed setpoint before the group stops.
        pub stream_timeout: u32,
        /// Ticks ahead a streamed setpoint may wait.
        pub stream_buffer: u32,
        /// Seconds after the path's end every axis has to come within its goal tolerance.
        pub goal_time_tolerance: f64,
        /// Config indices of the member axes, in the group's order.
        pub axes: [u32; MAX_GROUP_AXES],
        /// Per member axis: the path tolerance, its unit (0 = not checked).
        pub path_tolerance: [f64; MAX_GROUP_AXES],
        /// Per member axis: the goal tolerance, its unit.
        pub goal_tolerance: [f64; MAX_GROUP_AXES],
    }
}

impl GroupInfo {
    /// An unused entry.
    pub const EMPTY: Self = Self {
        name: [0; NAME_LEN],
        axis_count: 0,
        stream_limit: 1,
        stream_timeout: 0,
        stream_buffer: 0,
        goal_time_tolerance: 0.0,
        axes: [0; MAX_GROUP_AXES],
        path_tolerance: [0.0; MAX_GROUP_AXES],
        goal_tolerance: [0.0; MAX_GROUP_AXES],
    };

    /// The group's name.
    pub fn name(&self) -> &str {
        read_text(&self.name)
    }

    /// The member axes' config indices.
    pub fn axes(&self) -> &[u32] {
        &self.axes[..(self.axis_count as usize).min(MAX_GROUP_AXES)]
    }
}

impl Default for GroupInfo {
    fn default() -> Self {
        Self::EMPTY
    }
}

flag_set! {
    /// Bits of [`GroupPath::flags`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct PathFlags(u32) {
        /// `velocities` holds a velocity per point and axis.
        VELOCITIES = 0, "velocities";
        /// `accelerations` holds an acceleration per point and axis (needs `VELOCITIES`).
        ACCELERATIONS = 1, "accelerations";
    }
}

payload! {
    /// A path for a group, published on `motiond/<name>/paths` and run by a `Run` command
    /// (`values[0]` = `id`). Point `i`, axis `j` (the group's order) is at
    /// `i * MAX_GROUP_AXES + j` of `positions`, `velocities` and `accelerations`.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::GroupPath")]
    pub struct GroupPath {
        /// [`SCHEMA_VERSION`] of the sender.
        pub schema_version: u32,
        /// [`PathKind`] value: line or trajectory.
        pub kind: u32,
        /// The client's id for this path (echoed in [`GroupState::path_id`]); the newest
        /// path with this id from the sender is the one run.
        pub id: u64,
        /// Group index (config order), as the `Run` command must name it too.
        pub group: u32,
        /// Valid points (1 for a line).
        pub point_count: u32,
        /// Axes per point: the group's axis count.
        pub axis_count: u32,
        /// [`PathFlags`] bits.
        pub flags: u32,
        /// A line: fraction (0, 1] of every axis's `max_velocity`; 0 means 1.
        pub velocity_scale: f64,
        /// A line: fraction (0, 1] of every axis's `max_accel`; 0 means 1.
        pub accel_scale: f64,
        /// Per point: seconds from the start of the trajectory (ignored for a line).
        pub times: [f64; MAX_PATH_POINTS],
        /// Per point and axis: position, the axis's unit.
        pub positions: [f64; PATH_VALUES],
        /// Per point and axis: velocity, unit/s (with `VELOCITIES`).
        pub velocities: [f64; PATH_VALUES],
        /// Per point and axis: acceleration, unit/s² (with `ACCELERATIONS`).
        pub accelerations: [f64; PATH_VALUES],
    }
}

impl GroupPath {
    /// An empty path of the current schema.
    pub const EMPTY: Self = Self {
        schema_version: SCHEMA_VERSION,
        kind: PathKind::None as u32,
        id: 0,
        group: 0,
        point_count: 0,
        axis_count: 0,
        flags: 0,
        velocity_scale: 0.0,
        accel_scale: 0.0,
        times: [0.0; MAX_PATH_POINTS],
        positions: [0.0; PATH_VALUES],
        velocities: [0.0; PATH_VALUES],
        accelerations: [0.0; PATH_VALUES],
    };

    /// The typed kind.
    pub fn kind(&self) -> Result<PathKind, UnknownValue> {
        PathKind::try_from(self.kind)
    }

    /// The typed flags.
    pub const fn flags(&self) -> PathFlags {
        PathFlags(self.flags)
    }

    /// Fills `self` (in place: the payload is large, loan it uninitialised and write it
    /// here) as a line of `group` to `targets` (the group's order).
    pub fn set_line(&mut self, group: u32, id: u64, targets: &[f64], scales: (f64, f64)) {
        self.schema_version = SCHEMA_VERSION;
        self.kind = PathKind::Line as u32;
        self.id = id;
        self.group = group;
        self.point_count = 1;
        self.axis_count = targets.len().min(MAX_GROUP_AXES) as u32;
        self.flags = 0;
        self.velocity_scale = scales.0;
        self.accel_scale = scales.1;
        self.times[0] = 0.0;
        for (slot, value) in self.positions.iter_mut().zip(targets) {
            *slot = *value;
        }
    }
}
