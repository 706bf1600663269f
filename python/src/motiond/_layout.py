"""The shared-memory contract of motiond as ctypes mirrors, enumerations and constants.

GENERATED from the Rust description of the contract (crate motion-ipc, src/schema) by
``cargo run -p motion-ipc --example gen`` (or ``scripts/gen``): do not edit; change the Rust
payload and run the generator. Import these names from :mod:`motiond.ipc`.
"""

from __future__ import annotations

import ctypes
import enum
from typing import Dict, Type

from ._mirror_base import (
    AxisInfoMethods,
    ClientIdMethods,
    DeviceInfoMethods,
    Payload,
    ReasonMethods,
    TextedEnum,
)

# --- constants ---------------------------------------------------------------------------

#: Version of the contract; every payload carries it.
SCHEMA_VERSION = 11
#: Capacity of the axis arrays of the frame and the server info.
MAX_AXES = 128
#: Capacity of the device arrays of the frame and the server info.
MAX_DEVICES = 32
#: Capacity of the link arrays of the server stats.
MAX_LINKS = 16
#: Capacity of the signal arrays of the frame and the server info.
MAX_SIGNALS = 64
#: Capacity of the machine parameter table.
MAX_PARAMS = 2048
#: Bytes of a name field (UTF-8, zero padded).
NAME_LEN = 32
#: Bytes of a unit or pin field (UTF-8, zero padded).
UNIT_LEN = 16
#: Bytes of a model id field (UTF-8, zero padded).
MODEL_ID_LEN = 16
#: Capacity of the group arrays of the frame and the server info.
MAX_GROUPS = 16
#: Axes one group may hold.
MAX_GROUP_AXES = 16
#: Points one group path may hold.
MAX_PATH_POINTS = 1024
#: Values of one quantity of a group path: point i, axis j at i * MAX_GROUP_AXES + j.
PATH_VALUES = 16384
#: Bytes of a parameter key or value text.
PARAM_TEXT_LEN = 40
#: ``CommandRequest.axis`` addressing every axis (stop, e-stop, reset, off).
ALL_AXES = 4294967295

#: Service name formats of one instance; ``%s`` is the instance name.
SERVICES: Dict[str, str] = {
    "frame": "motiond/%s/frame",
    "tick": "motiond/%s/tick",
    "command": "motiond/%s/command",
    "info": "motiond/%s/info",
    "stats": "motiond/%s/stats",
    "params": "motiond/%s/params",
    "paths": "motiond/%s/paths",
    "setpoints": "motiond/%s/setpoints",
    "estop": "motiond/%s/estop",
    "server_node": "motiond-%s",
}

# --- payloads ----------------------------------------------------------------------------


class ClientId(ClientIdMethods, Payload):
    """The iceoryx2 node id of a client (``Node.id().value()``, a u128), split into two little
    halves so that the layout is the same for every C ABI. Zero means "no client".

    16 bytes, alignment 8."""

    _type_name_ = "motiond::ClientId"
    _fields_ = [
        ("lo", ctypes.c_uint64),  # Low 64 bits of the node id.
        ("hi", ctypes.c_uint64),  # High 64 bits of the node id.
    ]


class AxisState(Payload):
    """One axis in a frame.

    96 bytes, alignment 8."""

    _type_name_ = "motiond::AxisState"
    _fields_ = [
        ("position", ctypes.c_double),  # Measured position in axis units.
        ("velocity", ctypes.c_double),  # Measured velocity in units/s.
        # Position target (position modes) or velocity target (velocity modes), in units.
        ("target", ctypes.c_double),
        ("raw_counts", ctypes.c_int64),  # Position in the board's own counts.
        # Tick at which fresh data last arrived from the board.
        ("last_refresh_tick", ctypes.c_uint64),
        ("flags", ctypes.c_uint32),  # ``AxisFlags`` bits.
        ("fault", ctypes.c_uint16),  # ``FaultCode`` value; 0 = no fault.
        ("mode", ctypes.c_uint8),  # ``AxisMode`` value.
        ("device_state", ctypes.c_uint8),  # ``DeviceState`` value of the axis's board.
        ("claimed_by", ClientId),  # The client holding a claim on the axis; zero when unclaimed.
        # The measured figure of the latched fault (units, units/s; see ``FaultCode``), 0 when none.
        ("fault_value", ctypes.c_double),
        ("fault_limit", ctypes.c_double),  # The tolerance or limit the fault broke, 0 when none.
        # Where the server wants the axis now, in units: the group's path while the axis follows a
        # group (mode ``group``), the target while it holds or moves to a position, the measured
        # position otherwise.
        ("desired_position", ctypes.c_double),
        # The velocity the server wants now, units/s: the group path's while it follows a group, the
        # velocity target of a velocity mode, 0 otherwise.
        ("desired_velocity", ctypes.c_double),
    ]


class SignalState(Payload):
    """One signal in a frame.

    A ``capture`` or ``trigger`` signal also carries events: every capture (every trigger pulse)
    the board reports adds one to ``sequence``, and ``event_tick`` is the tick that took the
    newest one in. Two events taken in by the same tick show as a step of two (the value is the
    newer one's): a client that remembers the sequence it last saw knows how many it missed.

    64 bytes, alignment 8."""

    _type_name_ = "motiond::SignalState"
    _fields_ = [
        # Logical value: digital 0.0/1.0 after ``invert``; analogue, capture and trigger raw × scale
        # + offset (a capture: the captured position; a trigger: its compare position).
        ("value", ctypes.c_double),
        # Raw value as the board reports it: electrical level 0/1, ADC counts, or counter counts
        # (capture, trigger).
        ("raw", ctypes.c_double),
        # Tick at which the board last reported it (outputs: acknowledged it).
        ("last_refresh_tick", ctypes.c_uint64),
        ("flags", ctypes.c_uint32),  # ``SignalFlags`` bits.
        ("kind", ctypes.c_uint8),  # ``SignalKind`` value.
        ("reserved", ctypes.c_uint8 * 3),  # Zero.
        ("claimed_by", ClientId),  # Claim holder of an output; zero when unclaimed.
        # Tick that took in the newest event (capture, trigger pulse); 0 before the first.
        ("event_tick", ctypes.c_uint64),
        # Events (captures, trigger pulses) the board reported since the server started, wrapping at
        # 2³²; 0 for the other kinds.
        ("sequence", ctypes.c_uint32),
        ("reserved2", ctypes.c_uint32),  # Zero.
    ]


class AxisWire(Payload):
    """When the current goal of one axis was set and when its first request reached the wire
    (``MotionFrame.wire``, same index as ``axes``).

    Command → wire: ``wire_ns`` minus the client's CLOCK_MONOTONIC when it sent the command, or
    in ticks ``wire_tick − goal_tick`` (0: written in the tick that accepted it).

    24 bytes, alignment 8."""

    _type_name_ = "motiond::AxisWire"
    _fields_ = [
        # Tick in which the current goal was set (a client's command: the reply's ``tick_applied``;
        # or the server's own stop).
        ("goal_tick", ctypes.c_uint64),
        # Tick during which the goal's first request was written to the link (its last byte accepted
        # by the transport); 0 until then.
        ("wire_tick", ctypes.c_uint64),
        # CLOCK_MONOTONIC ns of that write; 0 until then (and for a goal that needs no request).
        ("wire_ns", ctypes.c_uint64),
    ]


class GroupState(Payload):
    """One group in a frame (``MotionFrame.groups``, config order).

    152 bytes, alignment 8."""

    _type_name_ = "motiond::GroupState"
    _fields_ = [
        ("owner", ClientId),  # The client whose motion or stream the group runs; zero when none.
        # The id of the path running (or last run), as the client gave it.
        ("path_id", ctypes.c_uint64),
        # Seconds along the path (path time: it advances by the feed each second).
        ("time", ctypes.c_double),
        ("duration", ctypes.c_double),  # The path's length in seconds at feed 1.
        # The feed in effect (0 while held; below the set feed while the path's limits cap it).
        ("feed", ctypes.c_double),
        ("feed_set", ctypes.c_double),  # The feed set by the client (1.0 = 100 %).
        # The figure that aborted the motion (|desired − measured| in the axis's unit).
        ("abort_value", ctypes.c_double),
        ("abort_limit", ctypes.c_double),  # The tolerance it broke.
        ("point", ctypes.c_uint32),  # Index of the point the path is heading to (0 for a line).
        # Config index of the axis that aborted it; ``u32.MAX`` when none.
        ("abort_axis", ctypes.c_uint32),
        ("motion", ctypes.c_uint8),  # ``GroupMotion`` value.
        ("abort", ctypes.c_uint8),  # ``GroupAbort`` value.
        ("kind", ctypes.c_uint8),  # ``PathKind`` value of the path running or last run.
        ("stream", ctypes.c_uint8),  # ``StreamState`` value.
        ("stream_mode", ctypes.c_uint8),  # ``StreamMode`` value of the stream running or last run.
        ("stream_flags", ctypes.c_uint8),  # ``StreamFlags`` bits of this tick.
        # Ticks the stream runs behind its setpoints' own ticks: a setpoint for tick ``k`` is
        # applied in tick ``k + stream_delay``. 0 at the start; grows to the lateness of a setpoint
        # that arrived after its tick (at most ``stream_buffer``), never shrinks while the stream
        # runs (schema 10; saturates at 65535).
        ("stream_delay", ctypes.c_uint16),
        ("last_sequence", ctypes.c_uint64),  # Sequence of the last streamed setpoint applied.
        ("last_applied_tick", ctypes.c_uint64),  # Tick in which it was applied.
        ("applied", ctypes.c_uint64),  # Streamed setpoints applied.
        ("late", ctypes.c_uint64),  # Streamed setpoints dropped because their tick had passed.
        # Streamed setpoints dropped because they were addressed more than ``stream_buffer`` ticks
        # ahead.
        ("early", ctypes.c_uint64),
        # Streamed setpoints clamped to a limit (``stream_limit = "clamp"``).
        ("clamped", ctypes.c_uint64),
        # Streamed setpoints dropped because their sender does not hold the group.
        ("refused", ctypes.c_uint64),
        # When the server took the last applied setpoint from the ``setpoints`` service
        # (CLOCK_MONOTONIC ns, the clock of ``MotionFrame.publish_ns``): a client subtracts its own
        # send stamp, or a frame's ``publish_ns``; 0 until one is applied.
        ("last_received_ns", ctypes.c_uint64),
    ]


class MotionFrame(Payload):
    """One consistent snapshot of every axis, board and signal, published once per tick on
    ``motiond/<name>/frame``.

    21968 bytes, alignment 8."""

    _type_name_ = "motiond::MotionFrame"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the writer.
        ("axis_count", ctypes.c_uint32),  # Number of valid entries at the start of ``axes``.
        ("tick", ctypes.c_uint64),  # Tick number, 0 at server start.
        ("time_ns", ctypes.c_uint64),  # The tick's deadline on CLOCK_MONOTONIC, ns.
        # CLOCK_MONOTONIC, ns, taken just before the frame was sent.
        ("publish_ns", ctypes.c_uint64),
        ("flags", ctypes.c_uint32),  # ``FrameFlags`` bits.
        ("signal_count", ctypes.c_uint32),  # Number of valid entries at the start of ``signals``.
        ("device_count", ctypes.c_uint32),  # Number of valid entries at the start of ``devices``.
        ("group_count", ctypes.c_uint32),  # Number of valid entries at the start of ``groups``.
        # ``DeviceState`` per device, config order; entries past ``device_count`` are zero.
        ("devices", ctypes.c_uint8 * MAX_DEVICES),
        # Axes in config order; entries past ``axis_count`` are ``AxisState.UNKNOWN``.
        ("axes", AxisState * MAX_AXES),
        # Signals in config order; entries past ``signal_count`` are ``SignalState.UNKNOWN``.
        ("signals", SignalState * MAX_SIGNALS),
        # Per axis (same index as ``axes``): when its current goal was set and when its first
        # request reached the wire.
        ("wire", AxisWire * MAX_AXES),
        # Groups in config order; entries past ``group_count`` are ``GroupState.IDLE``.
        ("groups", GroupState * MAX_GROUPS),
    ]


class CommandRequest(Payload):
    """A command to the server, on ``motiond/<name>/command``; ``values`` per kind: see
    ``CommandKind``.

    Identity comes from the transport: the server knows which iceoryx2 node sent a request and
    owns every claim by that node. ``client`` may be zero ("the sender"); a non-zero ``client``
    that is not the sender's node is refused with ``Reason.IdentityMismatch``.

    64 bytes, alignment 8."""

    _type_name_ = "motiond::CommandRequest"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the sender.
        ("kind", ctypes.c_uint32),  # ``CommandKind`` value.
        ("client", ClientId),  # The sender's iceoryx2 node id, or zero.
        ("sequence", ctypes.c_uint64),  # The client's sequence number, echoed in the reply.
        # Axis (or signal) index, config order, or ``CommandRequest.ALL_AXES``.
        ("axis", ctypes.c_uint32),
        # ``Target`` value: 0 = axis, 1 = signal, 2 = group, 3 = device.
        ("target", ctypes.c_uint32),
        ("values", ctypes.c_double * 3),  # Arguments; see ``CommandKind``.
    ]


class CommandReply(Payload):
    """The server's answer to one ``CommandRequest``; every request gets exactly one.

    72 bytes, alignment 8."""

    _type_name_ = "motiond::CommandReply"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the server.
        ("reason", ctypes.c_uint32),  # ``Reason`` value; 0 = accepted.
        ("sequence", ctypes.c_uint64),  # The request's sequence.
        # Tick in which the command took effect (or was refused).
        ("tick_applied", ctypes.c_uint64),
        ("axis", ctypes.c_uint32),  # The request's axis.
        ("kind", ctypes.c_uint32),  # The request's kind.
        # A refused path: the index of the point at fault; ``u32.MAX`` when none.
        ("at_point", ctypes.c_uint32),
        # The config index of the axis at fault (a path's axis, the axis a claim found held, the
        # axis a group motion owns); ``u32.MAX`` when none.
        ("at_axis", ctypes.c_uint32),
        ("holder", ClientId),  # ``ClaimedByOther``: the client holding that axis; zero otherwise.
        # A refused path: the figure at fault (position, velocity, acceleration, distance).
        ("value", ctypes.c_double),
        ("limit", ctypes.c_double),  # The limit it broke.
    ]


class AxisInfo(AxisInfoMethods, Payload):
    """One axis's static description.

    160 bytes, alignment 8."""

    _type_name_ = "motiond::AxisInfo"
    _fields_ = [
        ("name", ctypes.c_uint8 * NAME_LEN),  # Axis name, UTF-8, zero padded.
        ("unit", ctypes.c_uint8 * UNIT_LEN),  # Unit of positions ("mm", "deg"), UTF-8, zero padded.
        ("device", ctypes.c_uint8 * NAME_LEN),  # Name of the device that drives the axis.
        ("counts_per_unit", ctypes.c_double),  # Device counts per unit.
        ("min", ctypes.c_double),  # Lower soft limit, units.
        ("max", ctypes.c_double),  # Upper soft limit, units.
        ("max_velocity", ctypes.c_double),  # Velocity limit, units/s.
        ("max_accel", ctypes.c_double),  # Acceleration limit, units/s².
        ("capabilities", ctypes.c_uint32),  # ``Capabilities`` bits.
        ("channel", ctypes.c_uint16),  # Motor number on the device.
        ("device_index", ctypes.c_uint16),  # Index into ``ServerInfo.devices``.
        # Following error tolerance, units; 0 = not supervised.
        ("following_error", ctypes.c_double),
        # Overspeed factor (× ``max_velocity``); 0 = not supervised.
        ("overspeed_factor", ctypes.c_double),
        # Travel limit of a reference search, units; 0 = not supervised.
        ("home_max_travel", ctypes.c_double),
        ("estop", ctypes.c_uint32),  # ``EstopCategory`` value.
        ("reserved", ctypes.c_uint32),  # Zero.
    ]


class DeviceInfo(DeviceInfoMethods, Payload):
    """One device's description.

    128 bytes, alignment 4."""

    _type_name_ = "motiond::DeviceInfo"
    _fields_ = [
        ("name", ctypes.c_uint8 * NAME_LEN),  # Device name.
        ("link", ctypes.c_uint8 * NAME_LEN),  # Link name.
        # Firmware version as the board reported it ("" until known).
        ("firmware", ctypes.c_uint8 * NAME_LEN),
        ("model", ctypes.c_uint32),  # ``DeviceModel`` value.
        ("address", ctypes.c_uint32),  # Bus address, 0 when the model has none.
        ("axis_count", ctypes.c_uint32),  # Axes configured on the device.
        # ``DeviceState`` value when the info was published (the frame has the current one).
        ("state", ctypes.c_uint32),
        # The model's config id (``tmcpack``, ``example``), UTF-8, zero padded: names the model of
        # any board, built in or not.
        ("model_id", ctypes.c_uint8 * MODEL_ID_LEN),
    ]


class SignalInfo(Payload):
    """One signal's static description.

    128 bytes, alignment 8."""

    _type_name_ = "motiond::SignalInfo"
    _fields_ = [
        ("name", ctypes.c_uint8 * NAME_LEN),  # Signal name.
        ("unit", ctypes.c_uint8 * UNIT_LEN),  # Unit of an analogue value ("" for digital).
        ("device", ctypes.c_uint8 * NAME_LEN),  # Device name.
        ("scale", ctypes.c_double),  # Analogue: value = raw × scale + offset.
        ("offset", ctypes.c_double),  # Analogue: value = raw × scale + offset.
        # Raw full scale (1023 for a 10-bit converter; 1 for digital).
        ("full_scale", ctypes.c_double),
        ("kind", ctypes.c_uint8),  # ``SignalKind`` value.
        ("flags", ctypes.c_uint8),  # ``SignalInfoFlags`` bits.
        ("device_index", ctypes.c_uint16),  # Index into ``ServerInfo.devices``.
        ("pin", ctypes.c_uint8 * UNIT_LEN),  # The board's pin name ("ttlio1"), zero padded.
        ("reserved", ctypes.c_uint32),  # Zero.
    ]


class GroupInfo(Payload):
    """One group as configured (``ServerInfo.groups``).

    376 bytes, alignment 8."""

    _type_name_ = "motiond::GroupInfo"
    _fields_ = [
        ("name", ctypes.c_uint8 * NAME_LEN),  # Group name, UTF-8, zero padded.
        ("axis_count", ctypes.c_uint32),  # Valid entries in ``axes`` and the tolerance arrays.
        ("stream_limit", ctypes.c_uint32),  # ``stream_limit``: 0 = clamp, 1 = abort.
        # Ticks without a streamed setpoint before the group stops.
        ("stream_timeout", ctypes.c_uint32),
        ("stream_buffer", ctypes.c_uint32),  # Ticks ahead a streamed setpoint may wait.
        # Seconds after the path's end every axis has to come within its goal tolerance.
        ("goal_time_tolerance", ctypes.c_double),
        # Config indices of the member axes, in the group's order.
        ("axes", ctypes.c_uint32 * MAX_GROUP_AXES),
        # Per member axis: the path tolerance, its unit (0 = not checked).
        ("path_tolerance", ctypes.c_double * MAX_GROUP_AXES),
        # Per member axis: the goal tolerance, its unit.
        ("goal_tolerance", ctypes.c_double * MAX_GROUP_AXES),
    ]


class ServerInfo(Payload):
    """The server's static description, published with history 1 on ``motiond/<name>/info``.

    38864 bytes, alignment 8."""

    _type_name_ = "motiond::ServerInfo"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the server.
        ("axis_count", ctypes.c_uint32),  # Valid entries in ``axes``.
        ("device_count", ctypes.c_uint32),  # Valid entries in ``devices``.
        ("tick_hz", ctypes.c_uint32),  # Tick rate, Hz.
        # Deadman for velocity and power goals, ms; 0 = disabled.
        ("command_timeout_ms", ctypes.c_uint32),
        ("max_clients", ctypes.c_uint32),  # Configured client limit.
        ("server_pid", ctypes.c_uint32),  # Process id of motiond.
        ("signal_count", ctypes.c_uint32),  # Valid entries in ``signals``.
        ("name", ctypes.c_uint8 * NAME_LEN),  # Instance name.
        ("start_time_ns", ctypes.c_uint64),  # CLOCK_MONOTONIC ns of tick 0.
        ("axes", AxisInfo * MAX_AXES),  # Axes in config order.
        ("devices", DeviceInfo * MAX_DEVICES),  # Devices in config order.
        ("signals", SignalInfo * MAX_SIGNALS),  # Signals in config order.
        ("group_count", ctypes.c_uint32),  # Valid entries in ``groups``.
        ("reserved", ctypes.c_uint32),  # Zero.
        ("groups", GroupInfo * MAX_GROUPS),  # Groups in config order.
    ]


class GroupPath(Payload):
    """A path for a group, published on ``motiond/<name>/paths`` and run by a ``Run`` command
    (``values[0]`` = ``id``). Point ``i``, axis ``j`` (the group's order) is at ``i *
    MAX_GROUP_AXES + j`` of ``positions``, ``velocities`` and ``accelerations``.

    401456 bytes, alignment 8."""

    _type_name_ = "motiond::GroupPath"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the sender.
        ("kind", ctypes.c_uint32),  # ``PathKind`` value: line or trajectory.
        # The client's id for this path (echoed in ``GroupState.path_id``); the newest path with
        # this id from the sender is the one run.
        ("id", ctypes.c_uint64),
        # Group index (config order), as the ``Run`` command must name it too.
        ("group", ctypes.c_uint32),
        ("point_count", ctypes.c_uint32),  # Valid points (1 for a line).
        ("axis_count", ctypes.c_uint32),  # Axes per point: the group's axis count.
        ("flags", ctypes.c_uint32),  # ``PathFlags`` bits.
        # A line: fraction (0, 1] of every axis's ``max_velocity``; 0 means 1.
        ("velocity_scale", ctypes.c_double),
        # A line: fraction (0, 1] of every axis's ``max_accel``; 0 means 1.
        ("accel_scale", ctypes.c_double),
        # Per point: seconds from the start of the trajectory (ignored for a line).
        ("times", ctypes.c_double * MAX_PATH_POINTS),
        # Per point and axis: position, the axis's unit.
        ("positions", ctypes.c_double * PATH_VALUES),
        # Per point and axis: velocity, unit/s (with ``VELOCITIES``).
        ("velocities", ctypes.c_double * PATH_VALUES),
        # Per point and axis: acceleration, unit/s² (with ``ACCELERATIONS``).
        ("accelerations", ctypes.c_double * PATH_VALUES),
    ]


class Setpoint(Payload):
    """One setpoint of a group's stream, published on ``motiond/<name>/setpoints`` by the client
    that holds the group's claim and started the stream (``Stream`` command); from any other node
    it is dropped and counted (``GroupState.refused``). The server applies each setpoint on its
    own time, once and in order: the one for tick ``k`` in tick ``k + stream_delay``
    (``crate.playout``); one for a tick more than ``stream_buffer`` ahead is dropped (``early``),
    one more than ``stream_buffer`` behind, superseded or out of sequence is dropped (``late``).
    Velocities and accelerations are judged over the setpoints' own ticks.

    288 bytes, alignment 8."""

    _type_name_ = "motiond::Setpoint"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the sender.
        ("group", ctypes.c_uint32),  # Group index (config order).
        # The client's sequence number: increasing; a setpoint not above the last applied one is
        # late.
        ("sequence", ctypes.c_uint64),
        # The tick this setpoint is for (a frame's ``tick`` + the client's lead: 1 is the next
        # tick).
        ("for_tick", ctypes.c_uint64),
        ("mode", ctypes.c_uint32),  # ``StreamMode`` value: must be the stream's.
        ("flags", ctypes.c_uint32),  # ``SetpointFlags`` bits.
        # Per axis, in the group's order: position (unit), velocity (unit/s) or power.
        ("values", ctypes.c_double * MAX_GROUP_AXES),
        # Per axis: velocity feed-forward, unit/s (with ``FEED_FORWARD``).
        ("velocities", ctypes.c_double * MAX_GROUP_AXES),
    ]


class MachineParam(Payload):
    """One effective machine parameter.

    88 bytes, alignment 4."""

    _type_name_ = "motiond::MachineParam"
    _fields_ = [
        # The config key, dotted for tables (``current.standstill``).
        ("key", ctypes.c_uint8 * PARAM_TEXT_LEN),
        # The value in effect, with its unit (``50 %``).
        ("value", ctypes.c_uint8 * PARAM_TEXT_LEN),
        ("owner_index", ctypes.c_uint16),  # Device or axis index.
        ("owner_kind", ctypes.c_uint8),  # ``ParamOwner`` value.
        ("from_config", ctypes.c_uint8),  # 1: the config file set it; 0: the default.
        ("reserved", ctypes.c_uint32),  # Zero.
    ]


class MachineParams(Payload):
    """Every machine parameter in effect, published with history 1 on ``motiond/<name>/params``.

    180240 bytes, alignment 4."""

    _type_name_ = "motiond::MachineParams"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the server.
        ("count", ctypes.c_uint32),  # Valid entries.
        # 1 when more parameters existed than ``MAX_PARAMS`` (entries were left out).
        ("truncated", ctypes.c_uint32),
        ("reserved", ctypes.c_uint32),  # Zero.
        ("entries", MachineParam * MAX_PARAMS),  # Devices' then axes' parameters, config order.
    ]


class LatencySummary(Payload):
    """Percentiles of one latency distribution, in nanoseconds.

    40 bytes, alignment 8."""

    _type_name_ = "motiond::LatencySummary"
    _fields_ = [
        ("samples", ctypes.c_uint64),  # Number of samples.
        ("p50_ns", ctypes.c_uint64),  # Median.
        ("p99_ns", ctypes.c_uint64),  # 99th percentile.
        ("p999_ns", ctypes.c_uint64),  # 99.9th percentile.
        ("max_ns", ctypes.c_uint64),  # Maximum.
    ]


class LinkStats(Payload):
    """Counters of one link since start.

    80 bytes, alignment 8."""

    _type_name_ = "motiond::LinkStats"
    _fields_ = [
        ("name", ctypes.c_uint8 * NAME_LEN),  # Link name.
        ("bytes_in", ctypes.c_uint64),  # Bytes received.
        ("bytes_out", ctypes.c_uint64),  # Bytes sent.
        ("frames", ctypes.c_uint64),  # Replies decoded.
        ("errors", ctypes.c_uint64),  # Bad frames, I/O errors, timeouts.
        ("reconnects", ctypes.c_uint64),  # Successful reopens.
        ("up", ctypes.c_uint32),  # 1 when the link is open.
        # Messages a link the tick runs itself (``io = "tick"``) put off to a later tick because the
        # tick's wire-time budget was spent (saturating; 0 on other links).
        ("deferred", ctypes.c_uint32),
    ]


class LinkIo(Payload):
    """The I/O side of one link: when bytes last went out and came in, and how often. Stamps are
    CLOCK_MONOTONIC ns taken by the link's I/O thread right after the transport accepted or
    returned the bytes; 0 when it never did.

    32 bytes, alignment 8."""

    _type_name_ = "motiond::LinkIo"
    _fields_ = [
        # CLOCK_MONOTONIC ns of the last write that moved bytes; 0: never.
        ("last_write_ns", ctypes.c_uint64),
        # CLOCK_MONOTONIC ns of the last read that returned bytes; 0: never.
        ("last_read_ns", ctypes.c_uint64),
        ("transactions", ctypes.c_uint64),  # Messages written whole (SPI: transactions).
        ("reads", ctypes.c_uint64),  # Reads that returned bytes.
    ]


class ServerStats(Payload):
    """Server figures, published about once a second on ``motiond/<name>/stats``.

    2016 bytes, alignment 8."""

    _type_name_ = "motiond::ServerStats"
    _fields_ = [
        ("schema_version", ctypes.c_uint32),  # ``SCHEMA_VERSION`` of the server.
        ("link_count", ctypes.c_uint32),  # Valid entries in ``links``.
        ("tick", ctypes.c_uint64),  # Tick at which these figures were taken.
        ("time_ns", ctypes.c_uint64),  # CLOCK_MONOTONIC ns of that tick.
        ("wakeup", LatencySummary),  # Wake-up latency (actual wake − deadline) since start.
        ("work", LatencySummary),  # Tick work time since start.
        ("overruns", ctypes.c_uint64),  # Ticks that missed their deadline since start.
        ("max_consecutive_overruns", ctypes.c_uint64),  # Longest run of consecutive overruns.
        ("commands", ctypes.c_uint64),  # Requests answered.
        ("rejected", ctypes.c_uint64),  # Requests refused.
        ("clients", ctypes.c_uint32),  # Live client nodes at the last liveness check.
        # Real-time set-up bits (``RtFlags``): bit 0 SCHED_FIFO, bit 1 memory locked, bit 2 pinned,
        # bit 3 cpu_dma_latency held.
        ("rt_flags", ctypes.c_uint32),
        ("links", LinkStats * MAX_LINKS),  # Per-link counters.
        ("faults", ctypes.c_uint64),  # Axis faults latched by the server's supervision since start.
        # Ticks whose frame could not be loaned or sent, since start.
        ("frames_lost", ctypes.c_uint64),
        # Services whose port slots are all taken now (``FullServices`` bits, the ``FULL_*``
        # constants): new clients are refused there until a slot frees.
        ("full_services", ctypes.c_uint32),
        # Times a service was found with all its slots taken, since start.
        ("full_events", ctypes.c_uint32),
        # Info, stats and params samples that could not be loaned or sent, and tick notifications
        # that failed, since start (a lost frame counts in ``frames_lost``).
        ("publish_failures", ctypes.c_uint64),
        # Command replies that could not be sent (the client vanished before its answer), since
        # start.
        ("replies_lost", ctypes.c_uint64),
        # Log reports the main thread's queue had no room for, and failed iceoryx2 housekeeping
        # (connection updates, e-stop event reads), since start.
        ("events_dropped", ctypes.c_uint64),
        # Per link (same index as ``links``): the I/O thread's stamps.
        ("link_io", LinkIo * MAX_LINKS),
        # Records of dead iceoryx2 nodes removed from the service root (crashed clients, clients
        # killed while they started), since start.
        ("nodes_cleaned", ctypes.c_uint64),
        # Black-box records the tick dropped because the recorder's queue was full, since start: a
        # saved black box has a hole there, and a replay stops at it.
        ("blackbox_lost", ctypes.c_uint64),
        # Paths taken from the ``paths`` service and dropped, since start: no room left for their
        # node or among the claimants' paths, or their publisher gone before the tick looked
        # (docs/SECURITY.md "Paths and setpoints no other process can starve").
        ("paths_dropped", ctypes.c_uint64),
        # Setpoints taken from the ``setpoints`` service and dropped unread, since start: beyond
        # their node's budget of the tick, or their publisher gone before the tick looked (the
        # engine's own refusals count in ``GroupState.refused``).
        ("setpoints_dropped", ctypes.c_uint64),
    ]


#: Every payload mirror, by Rust type name.
PAYLOADS: Dict[str, Type[Payload]] = {
    "ClientId": ClientId,
    "AxisState": AxisState,
    "SignalState": SignalState,
    "AxisWire": AxisWire,
    "GroupState": GroupState,
    "MotionFrame": MotionFrame,
    "CommandRequest": CommandRequest,
    "CommandReply": CommandReply,
    "AxisInfo": AxisInfo,
    "DeviceInfo": DeviceInfo,
    "SignalInfo": SignalInfo,
    "GroupInfo": GroupInfo,
    "ServerInfo": ServerInfo,
    "GroupPath": GroupPath,
    "Setpoint": Setpoint,
    "MachineParam": MachineParam,
    "MachineParams": MachineParams,
    "LatencySummary": LatencySummary,
    "LinkStats": LinkStats,
    "LinkIo": LinkIo,
    "ServerStats": ServerStats,
}

# --- enumerations ------------------------------------------------------------------------


class CommandKind(TextedEnum):
    """What a request asks for (``CommandRequest.kind``). ``values`` per kind; 0.0 in a velocity or
    acceleration slot means the axis's configured maximum: STOP -; POWER [power -1..1]; POSITION
    [position]; VELOCITY [velocity]; RAMP_POSITION [position, max velocity, acceleration];
    RAMP_VELOCITY [velocity, acceleration]; HOME [search velocity]; SET_POSITION [position];
    SET_OUTPUT [0.0 or 1.0] (``axis`` = signal index, ``target`` = SIGNAL); CLAIM, RELEASE,
    E_STOP, RESET, OFF -; with ``target`` = GROUP (``axis`` = group index): CLAIM, RELEASE, STOP,
    RUN [path id], HOLD, RESUME, FEED [0.0..1.5], CANCEL, STREAM [stream mode]; with ``target`` =
    DEVICE (``axis`` = device index): COMMISSION [what, new value]."""

    STOP = 1, "stop"
    POWER = 2, "power"
    POSITION = 3, "position"
    VELOCITY = 4, "velocity"
    RAMP_POSITION = 5, "ramp-position"
    RAMP_VELOCITY = 6, "ramp-velocity"
    HOME = 7, "home"
    SET_POSITION = 8, "set-position"
    CLAIM = 9, "claim"
    RELEASE = 10, "release"
    E_STOP = 11, "e-stop"
    RESET = 12, "reset"
    OFF = 13, "off"
    SET_OUTPUT = 14, "set-output"
    RUN = 15, "run"
    HOLD = 16, "hold"
    RESUME = 17, "resume"
    FEED = 18, "feed"
    CANCEL = 19, "cancel"
    STREAM = 20, "stream"
    COMMISSION = 21, "commission"


class Reason(ReasonMethods, TextedEnum):
    """Why a request was refused (``CommandReply.reason``); 0 = accepted. The text is the server's
    one-line explanation."""

    ACCEPTED = 0, "accepted"
    SCHEMA_MISMATCH = 1, "client and server use different motion-ipc schema versions"
    UNKNOWN_KIND = 2, "unknown command kind"
    UNKNOWN_AXIS = 3, "no such axis on this server"
    UNSUPPORTED = 4, "the axis's board cannot do this command"
    NOT_FINITE = 5, "a value is NaN or infinite"
    OUT_OF_RANGE = (
        6,
        "position outside the axis's min..max soft limits, or an output level other than 0 or 1",
    )
    VELOCITY_LIMIT = (
        7,
        "velocity above the axis's max_velocity, or below the smallest step its board represents",
    )
    ACCEL_LIMIT = (
        8,
        "acceleration above the axis's max_accel or not positive, or below the smallest step its board represents",
    )
    POWER_LIMIT = 9, "power outside -1.0..1.0"
    CLAIMED_BY_OTHER = 10, "the axis is claimed by another client"
    NOT_CLAIMED = 11, "this client holds no claim on the axis"
    ESTOP_LATCHED = 12, "e-stop is latched: send reset first"
    AXIS_FAULTED = 13, "the axis is faulted: clear the cause, then reset"
    LINK_DOWN = 14, "the axis's link is down"
    BUSY = 15, "the server's command queue is full: retry"
    SHUTTING_DOWN = 16, "the server is shutting down"
    NO_CLIENT_ID = 17, "claim and release need a client id"
    IDENTITY_MISMATCH = (
        18,
        "the request's client id is not the sender's iceoryx2 node: ids cannot be borrowed",
    )
    DEVICE_STARTING = (
        19,
        "the axis's board is starting: its link is not open yet, or it awaits its first answer and its start-up stop",
    )
    DEVICE_OFFLINE = 20, "the axis's board is not answering"
    UNKNOWN_SIGNAL = 21, "no such signal on this server"
    NOT_AN_OUTPUT = (
        22,
        "the signal is not an output (a digital output, or a trigger's compare position)",
    )
    UNKNOWN_TARGET = 23, "unknown target: 0 = axis, 1 = signal, 2 = group, 3 = device"
    UNKNOWN_GROUP = 24, "no such group on this server"
    NO_PATH = (
        25,
        "no path with this id for this group was published by this client on `paths` (publish it first; a path runs once)",
    )
    PATH_TIMES = 26, "the path's point times must start at 0 or later and increase"
    PATH_START = 27, "the path's first point has time 0 but is not where the group is"
    PATH_LAYOUT = (
        28,
        "malformed path: no points, too many, an axis count other than the group's, an unknown kind, or a scale outside (0, 1]",
    )
    GROUP_BUSY = (
        29,
        "an axis of this request is moving (with a group, or on its own, still stopping): cancel that motion or wait for the axis to rest",
    )
    NOT_MOVING = (
        30,
        "the group has no motion running, or the axis no position move to hold or held move to resume",
    )
    BLEND_TOLERANCE = (
        31,
        "positions alone cannot be blended at this point within the axis's path_tolerance at its max_accel: space the points further apart, or send velocities",
    )
    UNKNOWN_DEVICE = 32, "no such device on this server"


class Target(TextedEnum):
    """What ``CommandRequest.axis`` indexes (``CommandRequest.target``)."""

    AXIS = 0
    SIGNAL = 1
    GROUP = 2
    DEVICE = 3


class DeviceState(TextedEnum):
    """Where a board is in its life (``MotionFrame.devices``, ``AxisState.device_state``,
    ``DeviceInfo.state``)."""

    OFFLINE = 0, "offline"
    ONLINE = 1, "online"
    STARTING = 2, "starting"
    FAULTED = 3, "faulted"


class AxisMode(TextedEnum):
    """What an axis is doing (``AxisState.mode``)."""

    OFF = 0
    HOLD = 1
    POWER = 2
    POSITION = 3
    VELOCITY = 4
    RAMP_POSITION = 5
    RAMP_VELOCITY = 6
    HOMING = 7
    STOPPING = 8
    GROUP = 9


class FaultCode(TextedEnum):
    """Why an axis is faulted (``AxisState.fault``); 0 = no fault."""

    NONE = 0, "none"
    LINK_DOWN = 1, "link-down"
    BOARD_NOT_RESPONDING = 2, "board-not-responding"
    BOARD_RESET = 3, "board-reset"
    BOARD_ERROR = 4, "board-error"
    PROTOCOL = 5, "protocol"
    OVERSPEED = 6, "overspeed"
    LIMIT_SWITCH = 7, "limit-switch"
    OVERRUN = 8, "overrun"
    FOLLOWING_ERROR = 9, "following-error"
    LIMIT_EXCEEDED = 10, "limit-exceeded"
    HOME_FAILED = 11, "home-failed"
    GOAL_TOLERANCE = 12, "goal-tolerance"


class SignalKind(TextedEnum):
    """What a signal is (``SignalState.kind``, ``SignalInfo.kind``); the text is its config name."""

    DIGITAL_IN = 1, "digital-in"
    DIGITAL_OUT = 2, "digital-out"
    ANALOG_IN = 3, "analog-in"
    CAPTURE = 4, "capture"
    TRIGGER = 5, "trigger"


class EstopCategory(TextedEnum):
    """What an e-stop (and a fault) does to an axis, IEC 60204-1 stop categories
    (``AxisInfo.estop``); the text is its config name."""

    HOLD = 0, "hold"
    STOP_OFF = 1, "stop-off"
    OFF = 2, "off"


class DeviceModel(TextedEnum):
    """The built-in board models (``DeviceInfo.model``); the text is its config id. Any board's id
    travels in ``DeviceInfo.model_id``."""

    QQ2DRV = 1, "qq2drv"
    TMCPACK = 2, "tmcpack"
    SPIMOTOR = 3, "spimotor"
    QSB = 4, "qsb"


class GroupMotion(TextedEnum):
    """Where a group's motion is (``GroupState.motion``)."""

    IDLE = 0, "idle"
    MOVING = 1, "moving"
    HOLDING = 2, "holding"
    HELD = 3, "held"
    DONE = 4, "done"
    ABORTED = 5, "aborted"


class GroupAbort(TextedEnum):
    """Why a group's motion ended early (``GroupState.abort``); 0 = not aborted."""

    NONE = 0, "none"
    PATH_TOLERANCE = 1, "path-tolerance"
    GOAL_TOLERANCE = 2, "goal-tolerance"
    AXIS_FAULT = 3, "axis-fault"
    E_STOP = 4, "e-stop"
    CLAIM_LOST = 5, "claim-lost"
    CLIENT_DEAD = 6, "client-dead"
    STOPPED = 7, "stopped"
    CANCELLED = 8, "cancelled"
    STREAM_STALE = 9, "stream-stale"
    STREAM_LIMIT = 10, "stream-limit"
    SHUTTING_DOWN = 11, "shutting-down"
    GOAL_REFUSED = 12, "goal-refused"


class StreamState(TextedEnum):
    """Where a group's setpoint stream is (``GroupState.stream``)."""

    IDLE = 0, "idle"
    STREAMING = 1, "streaming"
    STALE = 2, "stale"
    ABORTED = 3, "aborted"


class CommissionWhat(TextedEnum):
    """What a COMMISSION request changes (``values[0]``; ``values[1]`` is the new address or baud
    rate)."""

    ADDRESS = 1, "address"
    BAUD = 2, "baud"
    FACTORY_RESET = 3, "factory-reset"


class StreamMode(TextedEnum):
    """What a group's streamed setpoints are (``Setpoint.mode``, ``GroupState.stream_mode``,
    ``values[0]`` of a STREAM command)."""

    NONE = 0, "none"
    POSITION = 1, "position"
    VELOCITY = 2, "velocity"
    POWER = 3, "power"


class PathKind(TextedEnum):
    """What a group path is (``GroupPath.kind``, ``GroupState.kind``)."""

    NONE = 0, "none"
    LINE = 1, "line"
    TRAJECTORY = 2, "trajectory"
    STREAM = 3, "stream"


class ParamOwner(TextedEnum):
    """What a machine parameter belongs to (``MachineParam.owner_kind``)."""

    DEVICE = 1
    AXIS = 2


class AxisFlags(enum.IntFlag):
    """Bits of ``AxisState.flags``."""

    MOVING = 1 << 0
    HOMED = 1 << 1
    AT_LIMIT = 1 << 2
    STALE = 1 << 3
    FAULT = 1 << 4
    CLAIMED = 1 << 5
    ARRIVED = 1 << 6
    ESTOPPED = 1 << 7
    DEADMAN_EXPIRED = 1 << 8
    HELD = 1 << 9


class FrameFlags(enum.IntFlag):
    """Bits of ``MotionFrame.flags``."""

    ESTOP_LATCHED = 1 << 0
    OVERRUN = 1 << 1
    SHUTTING_DOWN = 1 << 2


class SignalFlags(enum.IntFlag):
    """Bits of ``SignalState.flags``."""

    STALE = 1 << 0
    CLAIMED = 1 << 1
    SAFE_STATE = 1 << 2
    PENDING = 1 << 3


class PathFlags(enum.IntFlag):
    """Bits of ``GroupPath.flags``."""

    VELOCITIES = 1 << 0
    ACCELERATIONS = 1 << 1


class StreamFlags(enum.IntFlag):
    """Bits of ``GroupState.stream_flags``."""

    APPLIED = 1 << 0
    CLAMPED = 1 << 1


class SetpointFlags(enum.IntFlag):
    """Bits of ``Setpoint.flags``."""

    FEED_FORWARD = 1 << 0


class SignalInfoFlags(enum.IntFlag):
    """Bits of ``SignalInfo.flags``."""

    INVERT = 1 << 0
    HAS_SAFE_STATE = 1 << 1
    SAFE_ON = 1 << 2


class RtFlags(enum.IntFlag):
    """Bits of ``ServerStats.rt_flags``."""

    FIFO = 1 << 0
    LOCKED = 1 << 1
    PINNED = 1 << 2
    DMA_LATENCY = 1 << 3


class FullServices(enum.IntFlag):
    """Bits of ``ServerStats.full_services``: services whose port slots are all taken."""

    FRAME = 1 << 0
    TICK = 1 << 1
    COMMAND = 1 << 2
    INFO = 1 << 3
    STATS = 1 << 4
    PARAMS = 1 << 5
    ESTOP = 1 << 6
    PATHS = 1 << 7
    SETPOINTS = 1 << 8


#: Every enumeration and flag set, by Rust type name.
ENUMS: Dict[str, type] = {
    "CommandKind": CommandKind,
    "Reason": Reason,
    "Target": Target,
    "DeviceState": DeviceState,
    "AxisMode": AxisMode,
    "FaultCode": FaultCode,
    "SignalKind": SignalKind,
    "EstopCategory": EstopCategory,
    "DeviceModel": DeviceModel,
    "GroupMotion": GroupMotion,
    "GroupAbort": GroupAbort,
    "StreamState": StreamState,
    "CommissionWhat": CommissionWhat,
    "StreamMode": StreamMode,
    "PathKind": PathKind,
    "ParamOwner": ParamOwner,
    "AxisFlags": AxisFlags,
    "FrameFlags": FrameFlags,
    "SignalFlags": SignalFlags,
    "PathFlags": PathFlags,
    "StreamFlags": StreamFlags,
    "SetpointFlags": SetpointFlags,
    "SignalInfoFlags": SignalInfoFlags,
    "RtFlags": RtFlags,
    "FullServices": FullServices,
}
