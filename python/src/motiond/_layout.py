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
    Payload,
    ReasonMethods,
    TextedEnum,
)

# --- constants ---------------------------------------------------------------------------

#: Version of the contract; every payload carries it.
SCHEMA_VERSION = 5
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
    "estop": "motiond/%s/estop",
    "server_node": "motiond-%s",
}

# --- payloads ----------------------------------------------------------------------------


class ClientId(ClientIdMethods, Payload):
    """The iceoryx2 node id of a client (``Node::id().value()``, a u128), split into two little
    halves so that the layout is the same for every C ABI. Zero means "no client".

    16 bytes, alignment 8."""

    _type_name_ = "motiond::ClientId"
    _fields_ = [
        # Low 64 bits of the node id.
        ("lo", ctypes.c_uint64),
        # High 64 bits of the node id.
        ("hi", ctypes.c_uint64),
    ]


class AxisState(Payload):
    """One axis in a frame. 80 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``position`` | f64 | measured
    position, axis units | | 8 | ``velocity`` | f64 | measured velocity, units/s | | 16 |
    ``target`` | f64 | position target (position modes) or velocity target (velocity modes) | |
    24 | ``raw_counts`` | i64 | the board's own position counts | | 32 | ``last_refresh_tick`` |
    u64 | tick at which fresh data last arrived from the board | | 40 | ``flags`` | u32 |
    ``AxisFlags`` bits | | 44 | ``fault`` | u16 | ``FaultCode`` | | 46 | ``mode`` | u8 |
    ``AxisMode`` | | 47 | ``device_state`` | u8 | ``DeviceState`` of the axis's board | | 48 |
    ``claimed_by`` | ``ClientId`` | claim holder, zero when unclaimed | | 64 | ``fault_value`` |
    f64 | the measured figure of the fault (units, units/s), 0 when none | | 72 | ``fault_limit``
    | f64 | the tolerance or limit it broke, 0 when none |

    80 bytes, alignment 8."""

    _type_name_ = "motiond::AxisState"
    _fields_ = [
        # Measured position in axis units.
        ("position", ctypes.c_double),
        # Measured velocity in units/s.
        ("velocity", ctypes.c_double),
        # Position target (position modes) or velocity target (velocity modes), in units.
        ("target", ctypes.c_double),
        # Position in the board's own counts.
        ("raw_counts", ctypes.c_int64),
        # Tick at which fresh data last arrived from the board.
        ("last_refresh_tick", ctypes.c_uint64),
        # ``AxisFlags`` bits.
        ("flags", ctypes.c_uint32),
        # ``FaultCode`` value.
        ("fault", ctypes.c_uint16),
        # ``AxisMode`` value.
        ("mode", ctypes.c_uint8),
        # ``DeviceState`` value of the axis's board.
        ("device_state", ctypes.c_uint8),
        # The client holding a claim on the axis; zero when unclaimed.
        ("claimed_by", ClientId),
        # The measured figure of the latched fault (see ``FaultCode``), 0 when none.
        ("fault_value", ctypes.c_double),
        # The tolerance or limit the fault broke, 0 when none.
        ("fault_limit", ctypes.c_double),
    ]


class SignalState(Payload):
    """One signal in a frame. 48 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``value`` | f64 | logical value:
    digital 0.0/1.0 after ``invert``; analogue raw × scale + offset | | 8 | ``raw`` | f64 | as
    the board reports it: electrical level 0/1, or ADC counts | | 16 | ``last_refresh_tick`` |
    u64 | tick at which the board last reported it (outputs: acknowledged it) | | 24 | ``flags``
    | u32 | ``SignalFlags`` bits | | 28 | ``kind`` | u8 | ``SignalKind`` | | 29 | ``reserved`` |
    u8; 3 | zero | | 32 | ``claimed_by`` | ``ClientId`` | claim holder of an output, zero when
    unclaimed |

    48 bytes, alignment 8."""

    _type_name_ = "motiond::SignalState"
    _fields_ = [
        # Logical value.
        ("value", ctypes.c_double),
        # Raw value as the board reports it.
        ("raw", ctypes.c_double),
        # Tick at which the board last reported (or acknowledged) it.
        ("last_refresh_tick", ctypes.c_uint64),
        # ``SignalFlags`` bits.
        ("flags", ctypes.c_uint32),
        # ``SignalKind`` value.
        ("kind", ctypes.c_uint8),
        # Zero.
        ("reserved", ctypes.c_uint8 * 3),
        # Claim holder of an output; zero when unclaimed.
        ("claimed_by", ClientId),
    ]


class AxisWire(Payload):
    """When the current goal of one axis was set and when its first request reached the wire
    (``MotionFrame::wire``, same index as ``axes``). 24 bytes, alignment 8.

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``goal_tick`` | u64 | tick in
    which the current goal was set (a client's command: the reply's ``tick_applied``; or the
    server's own stop) | | 8 | ``wire_tick`` | u64 | tick during which the goal's first request
    was written to the link (its last byte accepted by the transport), 0 until then | | 16 |
    ``wire_ns`` | u64 | CLOCK_MONOTONIC ns of that write, 0 until then (and for a goal that needs
    no request) |

    Command → wire: ``wire_ns`` minus the client's CLOCK_MONOTONIC when it sent the command, or
    in ticks ``wire_tick − goal_tick`` (0: written in the tick that accepted it).

    24 bytes, alignment 8."""

    _type_name_ = "motiond::AxisWire"
    _fields_ = [
        # Tick in which the current goal was set.
        ("goal_tick", ctypes.c_uint64),
        # Tick during which its first request was written; 0 until then.
        ("wire_tick", ctypes.c_uint64),
        # CLOCK_MONOTONIC ns of that write; 0 until then.
        ("wire_ns", ctypes.c_uint64),
    ]


class MotionFrame(Payload):
    """One consistent snapshot of every axis, board and signal, published once per tick on
    ``motiond/<name>/frame``. 16464 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``schema_version`` | u32 |
    ``SCHEMA_VERSION`` | | 4 | ``axis_count`` | u32 | valid entries at the start of ``axes`` | |
    8 | ``tick`` | u64 | tick number, 0 at server start | | 16 | ``time_ns`` | u64 | the tick's
    deadline, CLOCK_MONOTONIC ns | | 24 | ``publish_ns`` | u64 | CLOCK_MONOTONIC ns just before
    the frame was sent | | 32 | ``flags`` | u32 | ``FrameFlags`` bits | | 36 | ``signal_count`` |
    u32 | valid entries at the start of ``signals`` | | 40 | ``device_count`` | u32 | valid
    entries at the start of ``devices`` | | 44 | ``reserved`` | u32 | zero | | 48 | ``devices`` |
    u8; ``MAX_DEVICES`` | ``DeviceState`` per device, config order | | 80 | ``axes`` |
    ``AxisState``; ``MAX_AXES`` | axes in config order | | 10320 | ``signals`` | ``SignalState``;
    ``MAX_SIGNALS`` | signals in config order | | 13392 | ``wire`` | ``AxisWire``; ``MAX_AXES`` |
    per axis (same index as ``axes``): when its current goal was set and reached the wire |

    16464 bytes, alignment 8."""

    _type_name_ = "motiond::MotionFrame"
    _fields_ = [
        # ``SCHEMA_VERSION`` of the writer.
        ("schema_version", ctypes.c_uint32),
        # Number of valid entries at the start of ``axes``.
        ("axis_count", ctypes.c_uint32),
        # Tick number, 0 at server start.
        ("tick", ctypes.c_uint64),
        # The tick's deadline on CLOCK_MONOTONIC, ns.
        ("time_ns", ctypes.c_uint64),
        # CLOCK_MONOTONIC, ns, taken just before the frame was sent.
        ("publish_ns", ctypes.c_uint64),
        # ``FrameFlags`` bits.
        ("flags", ctypes.c_uint32),
        # Number of valid entries at the start of ``signals``.
        ("signal_count", ctypes.c_uint32),
        # Number of valid entries at the start of ``devices``.
        ("device_count", ctypes.c_uint32),
        # Zero.
        ("reserved", ctypes.c_uint32),
        # ``DeviceState`` per device, config order.
        ("devices", ctypes.c_uint8 * MAX_DEVICES),
        # Axes in config order; entries past ``axis_count`` are ``AxisState::UNKNOWN``.
        ("axes", AxisState * MAX_AXES),
        # Signals in config order; entries past ``signal_count`` are ``SignalState::UNKNOWN``.
        ("signals", SignalState * MAX_SIGNALS),
        # Per axis (same index as ``axes``): when its current goal was set and when its first
        # request reached the wire.
        ("wire", AxisWire * MAX_AXES),
    ]


class CommandRequest(Payload):
    """A command to the server. 64 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``schema_version`` | u32 |
    ``SCHEMA_VERSION`` | | 4 | ``kind`` | u32 | ``CommandKind`` | | 8 | ``client`` | ``ClientId``
    | the sender's iceoryx2 node id, or zero | | 24 | ``sequence`` | u64 | the client's own
    sequence number, echoed in the reply | | 32 | ``axis`` | u32 | axis (or signal) index, config
    order, or ``CommandRequest::ALL_AXES`` | | 36 | ``target`` | u32 | ``Target``: 0 = axis, 1 =
    signal | | 40 | ``values`` | f64; 3 | see ``CommandKind`` |

    Identity comes from the transport: the server knows which iceoryx2 node sent a request and
    owns every claim by that node. ``client`` may be zero ("the sender"); a non-zero ``client``
    that is not the sender's node is refused with ``Reason::IdentityMismatch``.

    64 bytes, alignment 8."""

    _type_name_ = "motiond::CommandRequest"
    _fields_ = [
        # ``SCHEMA_VERSION`` of the sender.
        ("schema_version", ctypes.c_uint32),
        # ``CommandKind`` value.
        ("kind", ctypes.c_uint32),
        # The sender's iceoryx2 node id, or zero.
        ("client", ClientId),
        # The client's sequence number, echoed in the reply.
        ("sequence", ctypes.c_uint64),
        # Axis (or signal) index, or ``CommandRequest::ALL_AXES``.
        ("axis", ctypes.c_uint32),
        # ``Target`` value.
        ("target", ctypes.c_uint32),
        # Arguments; see ``CommandKind``.
        ("values", ctypes.c_double * 3),
    ]


class CommandReply(Payload):
    """The server's answer to one ``CommandRequest``; every request gets exactly one. 32 bytes,
    alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``schema_version`` | u32 |
    ``SCHEMA_VERSION`` | | 4 | ``reason`` | u32 | ``Reason``; 0 = accepted | | 8 | ``sequence`` |
    u64 | the request's sequence | | 16 | ``tick_applied`` | u64 | tick in which the command took
    effect (or was refused) | | 24 | ``axis`` | u32 | the request's axis | | 28 | ``kind`` | u32
    | the request's kind |

    32 bytes, alignment 8."""

    _type_name_ = "motiond::CommandReply"
    _fields_ = [
        # ``SCHEMA_VERSION`` of the server.
        ("schema_version", ctypes.c_uint32),
        # ``Reason`` value; 0 = accepted.
        ("reason", ctypes.c_uint32),
        # The request's sequence.
        ("sequence", ctypes.c_uint64),
        # Tick in which the command took effect (or was refused).
        ("tick_applied", ctypes.c_uint64),
        # The request's axis.
        ("axis", ctypes.c_uint32),
        # The request's kind.
        ("kind", ctypes.c_uint32),
    ]


class AxisInfo(AxisInfoMethods, Payload):
    """One axis's static description. 160 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``name`` | u8; 32 | axis name,
    UTF-8, zero padded | | 32 | ``unit`` | u8; 16 | unit, UTF-8, zero padded | | 48 | ``device``
    | u8; 32 | device name | | 80 | ``counts_per_unit`` | f64 | device counts per unit | | 88 |
    ``min`` | f64 | soft limit, units | | 96 | ``max`` | f64 | soft limit, units | | 104 |
    ``max_velocity`` | f64 | units/s | | 112 | ``max_accel`` | f64 | units/s² | | 120 |
    ``capabilities`` | u32 | ``Capabilities`` bits | | 124 | ``channel`` | u16 | motor number on
    the device | | 126 | ``device_index`` | u16 | index into ``ServerInfo::devices`` | | 128 |
    ``following_error`` | f64 | units; 0 = not supervised | | 136 | ``overspeed_factor`` | f64 |
    × max_velocity; 0 = not supervised | | 144 | ``home_max_travel`` | f64 | units; 0 = not
    supervised | | 152 | ``estop`` | u32 | ``EstopCategory`` | | 156 | ``reserved`` | u32 | zero
    |

    160 bytes, alignment 8."""

    _type_name_ = "motiond::AxisInfo"
    _fields_ = [
        # Axis name.
        ("name", ctypes.c_uint8 * NAME_LEN),
        # Unit of positions ("mm", "deg").
        ("unit", ctypes.c_uint8 * UNIT_LEN),
        # Name of the device that drives the axis.
        ("device", ctypes.c_uint8 * NAME_LEN),
        # Device counts per unit.
        ("counts_per_unit", ctypes.c_double),
        # Lower soft limit, units.
        ("min", ctypes.c_double),
        # Upper soft limit, units.
        ("max", ctypes.c_double),
        # Velocity limit, units/s.
        ("max_velocity", ctypes.c_double),
        # Acceleration limit, units/s².
        ("max_accel", ctypes.c_double),
        # ``Capabilities`` bits.
        ("capabilities", ctypes.c_uint32),
        # Motor number on the device.
        ("channel", ctypes.c_uint16),
        # Index into ``ServerInfo::devices``.
        ("device_index", ctypes.c_uint16),
        # Following error tolerance, units; 0 = not supervised.
        ("following_error", ctypes.c_double),
        # Overspeed factor; 0 = not supervised.
        ("overspeed_factor", ctypes.c_double),
        # Travel limit of a reference search, units; 0 = not supervised.
        ("home_max_travel", ctypes.c_double),
        # ``EstopCategory`` value.
        ("estop", ctypes.c_uint32),
        # Zero.
        ("reserved", ctypes.c_uint32),
    ]


class DeviceInfo(Payload):
    """One device's description. 112 bytes, alignment 4. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``name`` | u8; 32 | device name |
    | 32 | ``link`` | u8; 32 | link name | | 64 | ``firmware`` | u8; 32 | firmware version as the
    board reported it ("" until known) | | 96 | ``model`` | u32 | ``DeviceModel`` | | 100 |
    ``address`` | u32 | bus address (0 when the model has none) | | 104 | ``axis_count`` | u32 |
    axes configured on the device | | 108 | ``state`` | u32 | ``DeviceState`` when the info was
    published (the frame has the current one) |

    112 bytes, alignment 4."""

    _type_name_ = "motiond::DeviceInfo"
    _fields_ = [
        # Device name.
        ("name", ctypes.c_uint8 * NAME_LEN),
        # Link name.
        ("link", ctypes.c_uint8 * NAME_LEN),
        # Firmware version as reported by the board.
        ("firmware", ctypes.c_uint8 * NAME_LEN),
        # ``DeviceModel`` value.
        ("model", ctypes.c_uint32),
        # Bus address, 0 when the model has none.
        ("address", ctypes.c_uint32),
        # Axes configured on the device.
        ("axis_count", ctypes.c_uint32),
        # ``DeviceState`` value when the info was published.
        ("state", ctypes.c_uint32),
    ]


class SignalInfo(Payload):
    """One signal's static description. 128 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``name`` | u8; 32 | signal name,
    UTF-8, zero padded | | 32 | ``unit`` | u8; 16 | unit of an analogue value ("" for digital) |
    | 48 | ``device`` | u8; 32 | device name | | 80 | ``scale`` | f64 | analogue: value = raw ×
    scale + offset | | 88 | ``offset`` | f64 | analogue: value = raw × scale + offset | | 96 |
    ``full_scale`` | f64 | raw full scale (1023 for a 10-bit converter; 1 for digital) | | 104 |
    ``kind`` | u8 | ``SignalKind`` | | 105 | ``flags`` | u8 | ``SignalInfoFlags`` bits | | 106 |
    ``device_index`` | u16 | index into ``ServerInfo::devices`` | | 108 | ``pin`` | u8; 16 | the
    board's pin name ("ttlio1"), zero padded | | 124 | ``reserved`` | u32 | zero |

    128 bytes, alignment 8."""

    _type_name_ = "motiond::SignalInfo"
    _fields_ = [
        # Signal name.
        ("name", ctypes.c_uint8 * NAME_LEN),
        # Unit of an analogue value.
        ("unit", ctypes.c_uint8 * UNIT_LEN),
        # Device name.
        ("device", ctypes.c_uint8 * NAME_LEN),
        # Analogue scale.
        ("scale", ctypes.c_double),
        # Analogue offset.
        ("offset", ctypes.c_double),
        # Raw full scale.
        ("full_scale", ctypes.c_double),
        # ``SignalKind`` value.
        ("kind", ctypes.c_uint8),
        # ``SignalInfoFlags`` bits.
        ("flags", ctypes.c_uint8),
        # Index into the device array.
        ("device_index", ctypes.c_uint16),
        # The board's pin name.
        ("pin", ctypes.c_uint8 * UNIT_LEN),
        # Zero.
        ("reserved", ctypes.c_uint32),
    ]


class ServerInfo(Payload):
    """The server's static description. 32328 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``schema_version`` | u32 |
    ``SCHEMA_VERSION`` | | 4 | ``axis_count`` | u32 | valid entries in ``axes`` | | 8 |
    ``device_count`` | u32 | valid entries in ``devices`` | | 12 | ``tick_hz`` | u32 | tick rate
    | | 16 | ``command_timeout_ms`` | u32 | deadman; 0 = disabled | | 20 | ``max_clients`` | u32
    | configured client limit | | 24 | ``server_pid`` | u32 | process id of motiond | | 28 |
    ``signal_count`` | u32 | valid entries in ``signals`` | | 32 | ``name`` | u8; 32 | instance
    name | | 64 | ``start_time_ns`` | u64 | CLOCK_MONOTONIC ns of tick 0 | | 72 | ``axes`` |
    ``AxisInfo``; ``MAX_AXES`` | axes in config order | | 20552 | ``devices`` | ``DeviceInfo``;
    ``MAX_DEVICES`` | devices in config order | | 24136 | ``signals`` | ``SignalInfo``;
    ``MAX_SIGNALS`` | signals in config order |

    32328 bytes, alignment 8."""

    _type_name_ = "motiond::ServerInfo"
    _fields_ = [
        # ``SCHEMA_VERSION`` of the server.
        ("schema_version", ctypes.c_uint32),
        # Valid entries in ``axes``.
        ("axis_count", ctypes.c_uint32),
        # Valid entries in ``devices``.
        ("device_count", ctypes.c_uint32),
        # Tick rate, Hz.
        ("tick_hz", ctypes.c_uint32),
        # Deadman for velocity and power goals, ms; 0 = disabled.
        ("command_timeout_ms", ctypes.c_uint32),
        # Configured client limit.
        ("max_clients", ctypes.c_uint32),
        # Process id of motiond.
        ("server_pid", ctypes.c_uint32),
        # Valid entries in ``signals``.
        ("signal_count", ctypes.c_uint32),
        # Instance name.
        ("name", ctypes.c_uint8 * NAME_LEN),
        # CLOCK_MONOTONIC ns of tick 0.
        ("start_time_ns", ctypes.c_uint64),
        # Axes in config order.
        ("axes", AxisInfo * MAX_AXES),
        # Devices in config order.
        ("devices", DeviceInfo * MAX_DEVICES),
        # Signals in config order.
        ("signals", SignalInfo * MAX_SIGNALS),
    ]


class MachineParam(Payload):
    """One effective machine parameter. 88 bytes, alignment 4. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``key`` | u8; 40 | the config
    key, dotted for tables (``current.standstill``) | | 40 | ``value`` | u8; 40 | the value in
    effect, with its unit (``50 %``) | | 80 | ``owner_index`` | u16 | device or axis index | | 82
    | ``owner_kind`` | u8 | ``ParamOwner`` | | 83 | ``from_config`` | u8 | 1: the config file set
    it; 0: the default | | 84 | ``reserved`` | u32 | zero |

    88 bytes, alignment 4."""

    _type_name_ = "motiond::MachineParam"
    _fields_ = [
        # Config key.
        ("key", ctypes.c_uint8 * PARAM_TEXT_LEN),
        # Effective value.
        ("value", ctypes.c_uint8 * PARAM_TEXT_LEN),
        # Device or axis index.
        ("owner_index", ctypes.c_uint16),
        # ``ParamOwner`` value.
        ("owner_kind", ctypes.c_uint8),
        # 1 when the config file set it.
        ("from_config", ctypes.c_uint8),
        # Zero.
        ("reserved", ctypes.c_uint32),
    ]


class MachineParams(Payload):
    """Every machine parameter in effect. 180240 bytes, alignment 4. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``schema_version`` | u32 |
    ``SCHEMA_VERSION`` | | 4 | ``count`` | u32 | valid entries | | 8 | ``truncated`` | u32 | 1
    when more parameters existed than ``MAX_PARAMS`` | | 12 | ``reserved`` | u32 | zero | | 16 |
    ``entries`` | ``MachineParam``; ``MAX_PARAMS`` | devices' then axes' parameters, config order
    |

    180240 bytes, alignment 4."""

    _type_name_ = "motiond::MachineParams"
    _fields_ = [
        # ``SCHEMA_VERSION`` of the server.
        ("schema_version", ctypes.c_uint32),
        # Valid entries.
        ("count", ctypes.c_uint32),
        # 1 when entries were left out for lack of room.
        ("truncated", ctypes.c_uint32),
        # Zero.
        ("reserved", ctypes.c_uint32),
        # The parameters.
        ("entries", MachineParam * MAX_PARAMS),
    ]


class LatencySummary(Payload):
    """Percentiles of one latency distribution, in nanoseconds. 40 bytes.

    | offset | field | type | |---|---|---| | 0 | ``samples`` | u64 | | 8 | ``p50_ns`` | u64 | |
    16 | ``p99_ns`` | u64 | | 24 | ``p999_ns`` | u64 | | 32 | ``max_ns`` | u64 |

    40 bytes, alignment 8."""

    _type_name_ = "motiond::LatencySummary"
    _fields_ = [
        # Number of samples.
        ("samples", ctypes.c_uint64),
        # Median.
        ("p50_ns", ctypes.c_uint64),
        # 99th percentile.
        ("p99_ns", ctypes.c_uint64),
        # 99.9th percentile.
        ("p999_ns", ctypes.c_uint64),
        # Maximum.
        ("max_ns", ctypes.c_uint64),
    ]


class LinkStats(Payload):
    """Counters of one link since start. 80 bytes, alignment 8.

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``name`` | u8; 32 | link name | |
    32 | ``bytes_in`` | u64 | bytes received | | 40 | ``bytes_out`` | u64 | bytes sent | | 48 |
    ``frames`` | u64 | replies decoded | | 56 | ``errors`` | u64 | bad frames, I/O errors,
    timeouts | | 64 | ``reconnects`` | u64 | successful reopens | | 72 | ``up`` | u32 | 1 when
    the link is open | | 76 | ``reserved`` | u32 | zero |

    80 bytes, alignment 8."""

    _type_name_ = "motiond::LinkStats"
    _fields_ = [
        # Link name.
        ("name", ctypes.c_uint8 * NAME_LEN),
        # Bytes received.
        ("bytes_in", ctypes.c_uint64),
        # Bytes sent.
        ("bytes_out", ctypes.c_uint64),
        # Replies decoded.
        ("frames", ctypes.c_uint64),
        # Bad frames, I/O errors, timeouts.
        ("errors", ctypes.c_uint64),
        # Successful reopens.
        ("reconnects", ctypes.c_uint64),
        # 1 when the link is open.
        ("up", ctypes.c_uint32),
        # Zero.
        ("reserved", ctypes.c_uint32),
    ]


class LinkIo(Payload):
    """The I/O side of one link: when bytes last went out and came in, and how often. 32 bytes,
    alignment 8. Stamps are CLOCK_MONOTONIC ns taken by the link's I/O thread right after the
    transport accepted or returned the bytes; 0 when it never did.

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``last_write_ns`` | u64 | the
    last write that moved bytes | | 8 | ``last_read_ns`` | u64 | the last read that returned
    bytes | | 16 | ``transactions`` | u64 | messages written whole since start (SPI:
    transactions) | | 24 | ``reads`` | u64 | reads that returned bytes since start |

    32 bytes, alignment 8."""

    _type_name_ = "motiond::LinkIo"
    _fields_ = [
        # CLOCK_MONOTONIC ns of the last write that moved bytes; 0: never.
        ("last_write_ns", ctypes.c_uint64),
        # CLOCK_MONOTONIC ns of the last read that returned bytes; 0: never.
        ("last_read_ns", ctypes.c_uint64),
        # Messages written whole (SPI: transactions).
        ("transactions", ctypes.c_uint64),
        # Reads that returned bytes.
        ("reads", ctypes.c_uint64),
    ]


class ServerStats(Payload):
    """Server figures. 1992 bytes, alignment 8. Fields in memory order:

    | offset | field | type | meaning | |---|---|---|---| | 0 | ``schema_version`` | u32 |
    ``SCHEMA_VERSION`` | | 4 | ``link_count`` | u32 | valid entries in ``links`` | | 8 | ``tick``
    | u64 | tick at which these figures were taken | | 16 | ``time_ns`` | u64 | CLOCK_MONOTONIC
    ns of that tick | | 24 | ``wakeup`` | ``LatencySummary`` | actual wake − deadline, since
    start | | 64 | ``work`` | ``LatencySummary`` | tick work time, since start | | 104 |
    ``overruns`` | u64 | ticks that missed their deadline, since start | | 112 |
    ``max_consecutive_overruns`` | u64 | longest run of overruns | | 120 | ``commands`` | u64 |
    requests answered | | 128 | ``rejected`` | u64 | requests refused | | 136 | ``clients`` | u32
    | live client nodes seen at the last liveness check | | 140 | ``rt_flags`` | u32 | bit 0
    SCHED_FIFO, 1 memory locked, 2 pinned, 3 cpu_dma_latency held | | 144 | ``links`` |
    ``LinkStats``; ``MAX_LINKS`` | per link | | 1424 | ``faults`` | u64 | axis faults latched by
    the server's supervision, since start | | 1432 | ``frames_lost`` | u64 | ticks whose frame
    could not be loaned or sent, since start | | 1440 | ``full_services`` | u32 | bit set of
    services whose port slots are all taken now (``ServerStats::FULL_FRAME`` …) | | 1444 |
    ``full_events`` | u32 | times a service was found with all its slots taken, since start | |
    1448 | ``publish_failures`` | u64 | info, stats and params samples that could not be loaned
    or sent, and tick notifications that failed, since start (a lost frame counts in
    ``frames_lost``) | | 1456 | ``replies_lost`` | u64 | command replies that could not be sent
    (the client vanished before its answer), since start | | 1464 | ``events_dropped`` | u64 |
    log reports the main thread's queue had no room for, and failed iceoryx2 housekeeping
    (connection updates, e-stop event reads), since start | | 1472 | ``link_io`` | ``LinkIo``;
    ``MAX_LINKS`` | per link (same index as ``links``): the I/O thread's stamps | | 1984 |
    ``nodes_cleaned`` | u64 | records of dead iceoryx2 nodes removed from the service root
    (crashed clients, clients killed while they started), since start |

    1992 bytes, alignment 8."""

    _type_name_ = "motiond::ServerStats"
    _fields_ = [
        # ``SCHEMA_VERSION`` of the server.
        ("schema_version", ctypes.c_uint32),
        # Valid entries in ``links``.
        ("link_count", ctypes.c_uint32),
        # Tick at which these figures were taken.
        ("tick", ctypes.c_uint64),
        # CLOCK_MONOTONIC ns of that tick.
        ("time_ns", ctypes.c_uint64),
        # Wake-up latency (actual wake − deadline) since start.
        ("wakeup", LatencySummary),
        # Tick work time since start.
        ("work", LatencySummary),
        # Ticks that missed their deadline since start.
        ("overruns", ctypes.c_uint64),
        # Longest run of consecutive overruns.
        ("max_consecutive_overruns", ctypes.c_uint64),
        # Requests answered.
        ("commands", ctypes.c_uint64),
        # Requests refused.
        ("rejected", ctypes.c_uint64),
        # Live client nodes at the last liveness check.
        ("clients", ctypes.c_uint32),
        # Bit 0 SCHED_FIFO, bit 1 memory locked, bit 2 pinned, bit 3 cpu_dma_latency held.
        ("rt_flags", ctypes.c_uint32),
        # Per-link counters.
        ("links", LinkStats * MAX_LINKS),
        # Axis faults latched by the server's supervision since start.
        ("faults", ctypes.c_uint64),
        # Ticks whose frame could not be loaned or sent, since start.
        ("frames_lost", ctypes.c_uint64),
        # Services whose port slots are all taken now (bits ``FULL_*``): new clients are refused
        # there until a slot frees.
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
    ]


#: Every payload mirror, by Rust type name.
PAYLOADS: Dict[str, Type[Payload]] = {
    "ClientId": ClientId,
    "AxisState": AxisState,
    "SignalState": SignalState,
    "AxisWire": AxisWire,
    "MotionFrame": MotionFrame,
    "CommandRequest": CommandRequest,
    "CommandReply": CommandReply,
    "AxisInfo": AxisInfo,
    "DeviceInfo": DeviceInfo,
    "SignalInfo": SignalInfo,
    "ServerInfo": ServerInfo,
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
    E_STOP, RESET, OFF -."""

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


class Reason(ReasonMethods, TextedEnum):
    """Why a request was refused (``CommandReply.reason``); 0 = accepted. The text is the server's
    one-line explanation."""

    ACCEPTED = 0, "accepted"
    SCHEMA_MISMATCH = 1, "client and server use different motion-ipc schema versions"
    UNKNOWN_KIND = 2, "unknown command kind"
    UNKNOWN_AXIS = 3, "no such axis on this server"
    UNSUPPORTED = 4, "the axis's board cannot do this command"
    NOT_FINITE = 5, "a value is NaN or infinite"
    OUT_OF_RANGE = 6, "position outside the axis's min..max soft limits, or an output level other than 0 or 1"
    VELOCITY_LIMIT = 7, "velocity above the axis's max_velocity, or below the smallest step its board represents"
    ACCEL_LIMIT = 8, "acceleration above the axis's max_accel or not positive, or below the smallest step its board represents"
    POWER_LIMIT = 9, "power outside -1.0..1.0"
    CLAIMED_BY_OTHER = 10, "the axis is claimed by another client"
    NOT_CLAIMED = 11, "this client holds no claim on the axis"
    ESTOP_LATCHED = 12, "e-stop is latched: send reset first"
    AXIS_FAULTED = 13, "the axis is faulted: clear the cause, then reset"
    LINK_DOWN = 14, "the axis's link is down"
    BUSY = 15, "the server's command queue is full: retry"
    SHUTTING_DOWN = 16, "the server is shutting down"
    NO_CLIENT_ID = 17, "claim and release need a client id"
    IDENTITY_MISMATCH = 18, "the request's client id is not the sender's iceoryx2 node: ids cannot be borrowed"
    DEVICE_STARTING = 19, "the axis's board is starting: its link is not open yet, or it awaits its first answer and its start-up stop"
    DEVICE_OFFLINE = 20, "the axis's board is not answering"
    UNKNOWN_SIGNAL = 21, "no such signal on this server"
    NOT_AN_OUTPUT = 22, "the signal is not a digital output"
    UNKNOWN_TARGET = 23, "unknown target: 0 = axis, 1 = signal"


class Target(TextedEnum):
    """What ``CommandRequest.axis`` indexes (``CommandRequest.target``)."""

    AXIS = 0
    SIGNAL = 1


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


class SignalKind(TextedEnum):
    """What a signal is (``SignalState.kind``, ``SignalInfo.kind``); the text is its config name."""

    DIGITAL_IN = 1, "digital-in"
    DIGITAL_OUT = 2, "digital-out"
    ANALOG_IN = 3, "analog-in"


class EstopCategory(TextedEnum):
    """What an e-stop (and a fault) does to an axis, IEC 60204-1 stop categories
    (``AxisInfo.estop``); the text is its config name."""

    HOLD = 0, "hold"
    STOP_OFF = 1, "stop-off"
    OFF = 2, "off"


class DeviceModel(TextedEnum):
    """The board model of a device (``DeviceInfo.model``); the text is its config id."""

    QQ2DRV = 1, "qq2drv"
    TMCPACK = 2, "tmcpack"
    SPIMOTOR = 3, "spimotor"
    QSB = 4, "qsb"


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
    "ParamOwner": ParamOwner,
    "AxisFlags": AxisFlags,
    "FrameFlags": FrameFlags,
    "SignalFlags": SignalFlags,
    "SignalInfoFlags": SignalInfoFlags,
    "RtFlags": RtFlags,
    "FullServices": FullServices,
}
