//! Commands: [`CommandRequest`] → [`CommandReply`] on `motiond/<name>/command`.

use core::fmt;

use iceoryx2::prelude::ZeroCopySend;

use crate::SCHEMA_VERSION;

/// A raw enum value this build of the contract does not know.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct UnknownValue(pub u32);

impl fmt::Display for UnknownValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown value {} (client and server schema differ?)",
            self.0
        )
    }
}

impl std::error::Error for UnknownValue {}

payload! {
    /// The iceoryx2 node id of a client (`Node::id().value()`, a u128), split into two
    /// little halves so that the layout is the same for every C ABI. Zero means "no client".
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    #[type_name("motiond::ClientId")]
    pub struct ClientId {
        /// Low 64 bits of the node id.
        pub lo: u64,
        /// High 64 bits of the node id.
        pub hi: u64,
    }
}

impl ClientId {
    /// No client.
    pub const NONE: Self = Self { lo: 0, hi: 0 };

    /// From an iceoryx2 `UniqueNodeId::value()`.
    pub const fn from_u128(value: u128) -> Self {
        Self {
            lo: value as u64,
            hi: (value >> 64) as u64,
        }
    }

    /// Back to the node id value.
    pub const fn as_u128(self) -> u128 {
        ((self.hi as u128) << 64) | self.lo as u128
    }

    /// Whether this is [`ClientId::NONE`].
    pub const fn is_none(self) -> bool {
        self.lo == 0 && self.hi == 0
    }
}

enumeration! {
    /// What a request asks for. Travels as `u32` in [`CommandRequest::kind`].
    ///
    /// Meaning of `values` per kind (0.0 in a velocity/acceleration slot means "the axis's
    /// configured maximum"):
    ///
    /// | kind | values[0] | values[1] | values[2] |
    /// |---|---|---|---|
    /// | `Stop` | – | – | – |
    /// | `Power` | power, −1.0..=1.0 of full scale | – | – |
    /// | `Position` | position, units | – | – |
    /// | `Velocity` | velocity, units/s | – | – |
    /// | `RampPosition` | position, units | max velocity, units/s | acceleration, units/s² |
    /// | `RampVelocity` | velocity, units/s | acceleration, units/s² | – |
    /// | `Home` | search velocity, units/s | – | – |
    /// | `SetPosition` | the position the axis is now at, units | – | – |
    /// | `SetOutput` | the output's logical value, 0.0 (off) or 1.0 (on); a trigger's compare position, in the signal's unit | – | – |
    /// | `Claim`, `Release`, `EStop`, `Reset`, `Off`, `Hold`, `Resume` | – | – | – |
    ///
    /// `SetOutput`, and `Claim` / `Release` with [`Target::Signal`], address a signal:
    /// [`CommandRequest::axis`] is then a signal index (config order) and
    /// [`CommandRequest::target`] is [`Target::Signal`]. `Commission` addresses a device
    /// ([`Target::Device`]): `values[0]` is a [`CommissionWhat`](crate::CommissionWhat) value,
    /// `values[1]` the new address or baud rate.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum CommandKind(u32) -> name {
        /// Decelerate to a stop and hold. With [`CommandRequest::ALL_AXES`], every axis.
        Stop = 1 => "stop",
        /// Open-loop power (deadman applies).
        Power = 2 => "power",
        /// Position target for the board's own controller.
        Position = 3 => "position",
        /// Velocity (deadman applies).
        Velocity = 4 => "velocity",
        /// Position along a velocity- and acceleration-limited profile.
        RampPosition = 5 => "ramp-position",
        /// Velocity along an acceleration-limited profile (deadman applies).
        RampVelocity = 6 => "ramp-velocity",
        /// Reference search.
        Home = 7 => "home",
        /// Declare the current position to be `values[0]` (no motion).
        SetPosition = 8 => "set-position",
        /// Take an exclusive claim on the axis for the requesting client.
        Claim = 9 => "claim",
        /// Give a claim back.
        Release = 10 => "release",
        /// Emergency stop: every axis stops and holds, latched until `Reset`.
        EStop = 11 => "e-stop",
        /// Clear a latched e-stop, deadman expiries and faults whose cause is gone; targets of
        /// axes without a running goal become their current positions. Claims are kept.
        Reset = 12 => "reset",
        /// De-energise the motor (it coasts; no holding torque). With
        /// [`CommandRequest::ALL_AXES`], every axis. A board that cannot de-energise refuses
        /// with [`Reason::Unsupported`].
        Off = 13 => "off",
        /// Set a digital output signal (`axis` = signal index, `target` = [`Target::Signal`]),
        /// or a trigger signal's compare position (`values[0]` in the signal's unit).
        SetOutput = 14 => "set-output",
        /// Run the group's path `values[0]` (the id of a [`GroupPath`](crate::GroupPath) the
        /// same node published on `paths`): `axis` = group index, `target` = [`Target::Group`].
        /// A path refused names its point and axis in [`CommandReply::at_point`] /
        /// [`CommandReply::at_axis`].
        Run = 15 => "run",
        /// Feed hold: bring the group to rest along its path at its axes' acceleration limits.
        /// With [`Target::Axis`]: bring the axis's position move (`Position`, `RampPosition`)
        /// to rest and keep it — on a QSB-M running the move itself, its COMMAND 6 ("Pause the
        /// motor using the MD ACCEL rate"); on every other board a stop at the move's
        /// acceleration (`max_accel` for `Position`) — flagged
        /// [`AxisFlags::HELD`](crate::AxisFlags::HELD).
        Hold = 16 => "hold",
        /// Continue a held path at the set feed. With [`Target::Axis`]: continue the held move
        /// to its target with its velocity and acceleration (the QSB-M's COMMAND 7 "Resume
        /// motor operation if previously stopped using the Motor Pause command", else the same
        /// goal again from where the axis stands).
        Resume = 17 => "resume",
        /// Set the group's feed override: `values[0]` = 0.0..=1.5 (1.0 = 100 %); time along the
        /// path runs at this rate, changed within the axes' acceleration limits.
        Feed = 18 => "feed",
        /// Bring the group to rest along its path, then end its motion (`aborted`, `cancelled`);
        /// for a stream: end it, every axis stops and holds.
        Cancel = 19 => "cancel",
        /// Start streaming setpoints to the group (`values[0]` = [`StreamMode`](crate::StreamMode)
        /// value) on `setpoints`; needs the group's claim (every member claimed by the sender).
        Stream = 20 => "stream",
        /// Change a board's own settings (`axis` = device index, `target` = [`Target::Device`],
        /// `values[0]` = [`CommissionWhat`](crate::CommissionWhat), `values[1]` = the new
        /// address or baud rate): the board is told, then found again where it now answers.
        /// Needs the claim of every axis and signal of the device, and no axis of it moving.
        Commission = 21 => "commission",
    }
}

enumeration! {
    /// Why a request was refused. Travels as `u32` in [`CommandReply::reason`]; 0 = accepted.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum Reason(u32) -> message {
        /// Accepted.
        Accepted = 0 => "accepted",
        /// The request's `schema_version` differs from the server's.
        SchemaMismatch = 1 => "client and server use different motion-ipc schema versions",
        /// `kind` is not a known [`CommandKind`].
        UnknownKind = 2 => "unknown command kind",
        /// `axis` is not an axis of this server.
        UnknownAxis = 3 => "no such axis on this server",
        /// The axis's board cannot do this kind of goal.
        Unsupported = 4 => "the axis's board cannot do this command",
        /// A value is NaN or infinite.
        NotFinite = 5 => "a value is NaN or infinite",
        /// The position is outside the axis's `min..=max`, or a digital output's level is
        /// neither 0 nor 1.
        OutOfRange = 6 => "position outside the axis's min..max soft limits, or an output level other than 0 or 1",
        /// The velocity exceeds the axis's `max_velocity`, or is below the smallest step its
        /// board represents (a slower velocity would be rounded to nothing or up).
        VelocityLimit = 7 => "velocity above the axis's max_velocity, or below the smallest step its board represents",
        /// The acceleration exceeds the axis's `max_accel`, is not positive, or is below the
        /// smallest step its board represents (it would be rounded up: harder than asked).
        AccelLimit = 8 => "acceleration above the axis's max_accel or not positive, or below the smallest step its board represents",
        /// The power is outside −1.0..=1.0.
        PowerLimit = 9 => "power outside -1.0..1.0",
        /// Another client holds a claim on the axis.
        ClaimedByOther = 10 => "the axis is claimed by another client",
        /// A release from a client that does not hold the claim.
        NotClaimed = 11 => "this client holds no claim on the axis",
        /// The e-stop is latched; only `Reset`, `EStop`, `Stop` and claims are taken.
        EstopLatched = 12 => "e-stop is latched: send reset first",
        /// The axis is faulted; a `Reset` (after the cause is gone) is needed.
        AxisFaulted = 13 => "the axis is faulted: clear the cause, then reset",
        /// The axis's link is down.
        LinkDown = 14 => "the axis's link is down",
        /// The server's command queue is full this tick; send again.
        Busy = 15 => "the server's command queue is full: retry",
        /// The server is shutting down.
        ShuttingDown = 16 => "the server is shutting down",
        /// A claim or release without a client id.
        NoClientId = 17 => "claim and release need a client id",
        /// The request's `client` is not the node the server received it from, or that node
        /// was already found dead (a request it sent just before it died; stops still count).
        IdentityMismatch = 18 => "the request's client id is not the sender's iceoryx2 node: ids cannot be borrowed",
        /// The axis's board is still starting (its link not open for the first time yet, or its
        /// first answer, configuration, start-up stop).
        DeviceStarting = 19 => "the axis's board is starting: its link is not open yet, or it awaits its first \
                 answer and its start-up stop",
        /// The axis's board is not answering.
        DeviceOffline = 20 => "the axis's board is not answering",
        /// `axis` is not a signal of this server (for a signal request).
        UnknownSignal = 21 => "no such signal on this server",
        /// The signal is not an output: neither a digital output nor a trigger (whose value
        /// is its compare position).
        NotAnOutput = 22 => "the signal is not an output (a digital output, or a trigger's compare position)",
        /// `target` is not a known [`Target`].
        UnknownTarget = 23 => "unknown target: 0 = axis, 1 = signal, 2 = group, 3 = device",
        /// `axis` is not a group of this server (for a group request).
        UnknownGroup = 24 => "no such group on this server",
        /// No path with the request's id (`values[0]`) for this group was published by the
        /// sender's node on `paths`, or it was already run.
        NoPath = 25 => "no path with this id for this group was published by this client on `paths` \
                 (publish it first; a path runs once)",
        /// A path's point times do not start at ≥ 0 and increase
        /// ([`CommandReply::at_point`]).
        PathTimes = 26 => "the path's point times must start at 0 or later and increase",
        /// A path's first point has time 0 but is not where the group is
        /// ([`CommandReply::at_axis`]).
        PathStart = 27 => "the path's first point has time 0 but is not where the group is",
        /// A path is malformed: no points, more than the contract holds, an axis count other
        /// than the group's, an unknown kind, a scale outside (0, 1].
        PathLayout = 28 => "malformed path: no points, too many, an axis count other than the group's, \
                 an unknown kind, or a scale outside (0, 1]",
        /// An axis of the request is moving with a group, or (for a group's motion) moving on
        /// its own, still stopping after one: cancel that motion or wait for the axis to rest
        /// ([`CommandReply::at_axis`]).
        GroupBusy = 29 => "an axis of this request is moving (with a group, or on its own, still stopping): \
                 cancel that motion or wait for the axis to rest",
        /// Hold, resume, feed or cancel of a group with no motion running; hold of an axis with
        /// no position move on its way, resume of an axis with no held move.
        NotMoving = 30 => "the group has no motion running, or the axis no position move to hold or \
                 held move to resume",
        /// A trajectory of positions alone cannot be blended at a point within an axis's
        /// `path_tolerance` at its max_accel ([`CommandReply::at_point`],
        /// [`CommandReply::at_axis`]; `value` the distance the blend would pass the point at,
        /// `limit` the tolerance).
        BlendTolerance = 31 => "positions alone cannot be blended at this point within the axis's path_tolerance \
                 at its max_accel: space the points further apart, or send velocities",
        /// `axis` is not a device of this server (for a device request).
        UnknownDevice = 32 => "no such device on this server",
    }
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.message())
    }
}

enumeration! {
    /// What [`CommandRequest::axis`] indexes. Travels as `u32` in [`CommandRequest::target`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub enum Target(u32) -> name {
        /// An axis (config order); every kind but `SetOutput`, `Run`, `Feed`, `Cancel` and
        /// `Stream` (`Hold` and `Resume` act on the axis's own position move).
        #[default]
        Axis = 0 => "axis",
        /// A signal (config order): `SetOutput`, `Claim`, `Release`.
        Signal = 1 => "signal",
        /// A group (config order): `Claim`, `Release` (every axis of it, all or none), `Stop`,
        /// `Run`, `Hold`, `Resume`, `Feed`, `Cancel`.
        Group = 2 => "group",
        /// A device (config order): `Commission`.
        Device = 3 => "device",
    }
}

payload! {
    /// A command to the server, on `motiond/<name>/command`; `values` per kind: see
    /// [`CommandKind`].
    ///
    /// Identity comes from the transport: the server knows which iceoryx2 node sent a request and
    /// owns every claim by that node. `client` may be zero ("the sender"); a non-zero `client` that
    /// is not the sender's node is refused with [`Reason::IdentityMismatch`].
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::CommandRequest")]
    pub struct CommandRequest {
        /// [`SCHEMA_VERSION`] of the sender.
        pub schema_version: u32,
        /// [`CommandKind`] value.
        pub kind: u32,
        /// The sender's iceoryx2 node id, or zero.
        pub client: ClientId,
        /// The client's sequence number, echoed in the reply.
        pub sequence: u64,
        /// Axis (or signal) index, config order, or [`CommandRequest::ALL_AXES`].
        pub axis: u32,
        /// [`Target`] value: 0 = axis, 1 = signal, 2 = group, 3 = device.
        pub target: u32,
        /// Arguments; see [`CommandKind`].
        pub values: [f64; 3],
    }
}

impl CommandRequest {
    /// `axis` value addressing every axis (stop, e-stop, reset).
    pub const ALL_AXES: u32 = u32::MAX;

    /// A request of the current schema with zero values.
    pub const fn new(client: ClientId, sequence: u64, axis: u32, kind: CommandKind) -> Self {
        Self {
            schema_version: SCHEMA_VERSION,
            kind: kind as u32,
            client,
            sequence,
            axis,
            target: Target::Axis as u32,
            values: [0.0; 3],
        }
    }

    /// A request of the current schema about signal `signal`.
    pub const fn for_signal(
        client: ClientId,
        sequence: u64,
        signal: u32,
        kind: CommandKind,
    ) -> Self {
        let mut request = Self::new(client, sequence, signal, kind);
        request.target = Target::Signal as u32;
        request
    }

    /// The typed target.
    pub fn target(&self) -> Result<Target, UnknownValue> {
        Target::try_from(self.target)
    }

    /// The same request with `values`.
    #[must_use]
    pub const fn with_values(mut self, values: [f64; 3]) -> Self {
        self.values = values;
        self
    }

    /// The typed kind.
    pub fn kind(&self) -> Result<CommandKind, UnknownValue> {
        CommandKind::try_from(self.kind)
    }
}

payload! {
    /// The server's answer to one [`CommandRequest`]; every request gets exactly one.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::CommandReply")]
    pub struct CommandReply {
        /// [`SCHEMA_VERSION`] of the server.
        pub schema_version: u32,
        /// [`Reason`] value; 0 = accepted.
        pub reason: u32,
        /// The request's sequence.
        pub sequence: u64,
        /// Tick in which the command took effect (or was refused).
        pub tick_applied: u64,
        /// The request's axis.
        pub axis: u32,
        /// The request's kind.
        pub kind: u32,
        /// A refused path: the index of the point at fault; `u32::MAX` when none.
        pub at_point: u32,
        /// The config index of the axis at fault (a path's axis, the axis a claim found held,
        /// the axis a group motion owns); `u32::MAX` when none.
        pub at_axis: u32,
        /// `ClaimedByOther`: the client holding that axis; zero otherwise.
        pub holder: ClientId,
        /// A refused path: the figure at fault (position, velocity, acceleration, distance).
        pub value: f64,
        /// The limit it broke.
        pub limit: f64,
    }
}

impl CommandReply {
    /// The reply to `request` with `reason`, applied at `tick`.
    pub const fn to(request: &CommandRequest, reason: Reason, tick: u64) -> Self {
        Self {
            schema_version: SCHEMA_VERSION,
            reason: reason as u32,
            sequence: request.sequence,
            tick_applied: tick,
            axis: request.axis,
            kind: request.kind,
            at_point: u32::MAX,
            at_axis: u32::MAX,
            holder: ClientId::NONE,
            value: 0.0,
            limit: 0.0,
        }
    }

    /// The same reply naming the axis at fault (and the claim holder, if any).
    #[must_use]
    pub const fn at_axis(mut self, axis: u32, holder: ClientId) -> Self {
        self.at_axis = axis;
        self.holder = holder;
        self
    }

    /// The same reply naming the point, the axis, the figure and the limit at fault.
    #[must_use]
    pub const fn at_point(mut self, point: u32, axis: u32, value: f64, limit: f64) -> Self {
        self.at_point = point;
        self.at_axis = axis;
        self.value = value;
        self.limit = limit;
        self
    }

    /// `Ok(())` when accepted, the typed reason otherwise.
    pub fn result(&self) -> Result<(), Reason> {
        match Reason::try_from(self.reason) {
            Ok(Reason::Accepted) => Ok(()),
            Ok(reason) => Err(reason),
            Err(_) => Err(Reason::SchemaMismatch),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn client_id_round_trips_u128() {
        let value = 0x0123_4567_89AB_CDEF_FEDC_BA98_7654_3210_u128;
        assert_eq!(ClientId::from_u128(value).as_u128(), value);
        assert!(ClientId::NONE.is_none());
        assert!(!ClientId::from_u128(1).is_none());
    }

    #[test]
    fn enums_round_trip_and_reject_unknown_values() {
        for kind in CommandKind::ALL {
            assert_eq!(CommandKind::try_from(kind as u32), Ok(kind));
        }
        assert_eq!(CommandKind::try_from(0), Err(UnknownValue(0)));
        assert_eq!(CommandKind::try_from(21), Ok(CommandKind::Commission));
        assert_eq!(CommandKind::try_from(22), Err(UnknownValue(22)));
        assert_eq!(Target::try_from(2), Ok(Target::Group));
        assert_eq!(Target::try_from(3), Ok(Target::Device));
        assert_eq!(Target::try_from(4), Err(UnknownValue(4)));
        for (index, reason) in Reason::ALL.iter().enumerate() {
            assert_eq!(*reason as usize, index);
            assert_eq!(Reason::try_from(*reason as u32), Ok(*reason));
            assert!(!reason.message().is_empty());
        }
        assert!(Reason::try_from(Reason::ALL.len() as u32).is_err());
    }

    #[test]
    fn reply_echoes_request_and_reports_result() {
        let request = CommandRequest::new(ClientId::from_u128(9), 42, 3, CommandKind::Velocity);
        let ok = CommandReply::to(&request, Reason::Accepted, 7);
        assert_eq!((ok.sequence, ok.axis, ok.tick_applied), (42, 3, 7));
        assert_eq!(ok.result(), Ok(()));
        let refused = CommandReply::to(&request, Reason::VelocityLimit, 7);
        assert_eq!(refused.result(), Err(Reason::VelocityLimit));
        let garbled = CommandReply {
            reason: 999,
            ..refused
        };
        assert_eq!(garbled.result(), Err(Reason::SchemaMismatch));
    }
}
