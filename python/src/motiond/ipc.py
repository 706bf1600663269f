"""The shared-memory contract of motiond, mirrored with :mod:`ctypes`.

Every payload motiond publishes or takes is a fixed-size ``#[repr(C)]`` Rust struct (crate
``motion-ipc``). The classes below mirror them field by field, in memory order, with the
same iceoryx2 type name (``type_name()``): iceoryx2 refuses to connect a port whose type
name, size or alignment differs from the server's. ``tests/test_layout.py`` checks every
size, offset, field name, field type, type name, enumeration value and text against the
description the Rust crate prints (``cargo run -p motion-ipc --example layout``).

Enumerations travel as plain integers; the :class:`enum.IntEnum` classes here give them
names (``Reason(6) is Reason.OUT_OF_RANGE``). A value unknown to this version of the
package stays an ``int``: use :func:`to_enum` to convert without raising.

The views the client hands out point into shared memory that this process maps read-only:
read them, never assign to their fields (copy first with :meth:`Payload.copy`).
"""

from __future__ import annotations

import ctypes
import enum
from typing import Dict, Type, TypeVar, Union

__all__ = [
    "SCHEMA_VERSION",
    "MAX_AXES",
    "MAX_DEVICES",
    "MAX_LINKS",
    "MAX_SIGNALS",
    "MAX_PARAMS",
    "NAME_LEN",
    "UNIT_LEN",
    "PARAM_TEXT_LEN",
    "ALL_AXES",
    "SERVICES",
    "service_name",
    "server_node_name",
    "read_text",
    "to_enum",
    "Payload",
    "ClientId",
    "AxisState",
    "SignalState",
    "AxisWire",
    "MotionFrame",
    "CommandRequest",
    "CommandReply",
    "AxisInfo",
    "DeviceInfo",
    "SignalInfo",
    "ServerInfo",
    "MachineParam",
    "MachineParams",
    "LatencySummary",
    "LinkStats",
    "LinkIo",
    "ServerStats",
    "PAYLOADS",
    "CommandKind",
    "Reason",
    "Target",
    "DeviceState",
    "AxisMode",
    "FaultCode",
    "SignalKind",
    "EstopCategory",
    "DeviceModel",
    "ParamOwner",
    "AxisFlags",
    "FrameFlags",
    "SignalFlags",
    "SignalInfoFlags",
    "RtFlags",
    "FullServices",
    "ENUMS",
]

# --- constants -----------------------------------------------------------------------------

#: Version of the contract; every payload carries it.
SCHEMA_VERSION = 5
#: Capacity of the axis arrays in :class:`MotionFrame` and :class:`ServerInfo`.
MAX_AXES = 128
#: Capacity of the device array in :class:`ServerInfo`.
MAX_DEVICES = 32
#: Capacity of the link array in :class:`ServerStats`.
MAX_LINKS = 16
#: Capacity of the signal arrays in :class:`MotionFrame` and :class:`ServerInfo`.
MAX_SIGNALS = 64
#: Capacity of :attr:`MachineParams.entries`.
MAX_PARAMS = 2048
#: Bytes of a name field (UTF-8, zero padded).
NAME_LEN = 32
#: Bytes of a unit field (UTF-8, zero padded).
UNIT_LEN = 16
#: Bytes of a parameter key or value text.
PARAM_TEXT_LEN = 40
#: ``CommandRequest.axis`` addressing every axis (stop, e-stop, reset, off).
ALL_AXES = 0xFFFF_FFFF

#: Service name formats of one instance; ``%s`` is the instance name (``[server] name``).
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


def service_name(instance: str, leaf: str) -> str:
    """The iceoryx2 service name ``leaf`` (``"frame"``, ``"command"`` …) of ``instance``."""
    return SERVICES[leaf] % instance


def server_node_name(instance: str) -> str:
    """The iceoryx2 node name the server of ``instance`` runs under."""
    return SERVICES["server_node"] % instance


def read_text(field: "ctypes.Array[ctypes.c_uint8]") -> str:
    """Reads a zero-padded UTF-8 field: stops at the first zero byte; bytes that are not
    valid UTF-8 end the text there (as the Rust side reads them)."""
    data = bytes(field)
    end = data.find(b"\0")
    if end >= 0:
        data = data[:end]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        return data[: error.start].decode("utf-8")


# --- payloads ------------------------------------------------------------------------------

_u8 = ctypes.c_uint8
_u16 = ctypes.c_uint16
_u32 = ctypes.c_uint32
_u64 = ctypes.c_uint64
_i64 = ctypes.c_int64
_f64 = ctypes.c_double

P = TypeVar("P", bound="Payload")


class Payload(ctypes.Structure):
    """Base of every payload mirror: the iceoryx2 type name and a few helpers."""

    _type_name_: str = ""

    @classmethod
    def type_name(cls) -> str:
        """The iceoryx2 type name, identical to the Rust ``#[type_name(..)]``."""
        return cls._type_name_

    def copy(self: P) -> P:
        """A private copy (detached from shared memory, writable)."""
        return type(self).from_buffer_copy(self)

    def text(self, field: str) -> str:
        """The zero-padded UTF-8 text field ``field`` as ``str``."""
        return read_text(getattr(self, field))

    def __repr__(self) -> str:
        parts = []
        for entry in self._fields_:
            name, kind = entry[0], entry[1]
            value = getattr(self, name)
            if isinstance(value, ctypes.Array):
                element = getattr(kind, "_type_", None)
                if element is _u8:
                    value = read_text(value)
                else:
                    value = f"[{len(value)} × {getattr(element, '__name__', '?')}]"
            parts.append(f"{name}={value!r}")
        return f"{type(self).__name__}({', '.join(parts)})"


class ClientId(Payload):
    """The iceoryx2 node id of a client (a u128) in two halves; zero means "no client"."""

    _type_name_ = "motiond::ClientId"
    _fields_ = [("lo", _u64), ("hi", _u64)]

    @classmethod
    def from_int(cls, value: int) -> "ClientId":
        """From a node id value (``node.id.value``)."""
        return cls(value & 0xFFFF_FFFF_FFFF_FFFF, (value >> 64) & 0xFFFF_FFFF_FFFF_FFFF)

    def __int__(self) -> int:
        return (self.hi << 64) | self.lo


class AxisState(Payload):
    """One axis in a frame. 80 bytes, alignment 8."""

    _type_name_ = "motiond::AxisState"
    _fields_ = [
        ("position", _f64),
        ("velocity", _f64),
        ("target", _f64),
        ("raw_counts", _i64),
        ("last_refresh_tick", _u64),
        ("flags", _u32),
        ("fault", _u16),
        ("mode", _u8),
        ("device_state", _u8),
        ("claimed_by", ClientId),
        ("fault_value", _f64),
        ("fault_limit", _f64),
    ]


class SignalState(Payload):
    """One signal in a frame. 48 bytes, alignment 8."""

    _type_name_ = "motiond::SignalState"
    _fields_ = [
        ("value", _f64),
        ("raw", _f64),
        ("last_refresh_tick", _u64),
        ("flags", _u32),
        ("kind", _u8),
        ("reserved", _u8 * 3),
        ("claimed_by", ClientId),
    ]


class AxisWire(Payload):
    """When an axis's current goal was set and its first request reached the wire.
    24 bytes, alignment 8. Command -> wire: ``wire_ns`` minus the client's
    CLOCK_MONOTONIC at sending, or in ticks ``wire_tick - goal_tick``; ``wire_ns`` is 0
    until the request was written."""

    _type_name_ = "motiond::AxisWire"
    _fields_ = [
        ("goal_tick", _u64),
        ("wire_tick", _u64),
        ("wire_ns", _u64),
    ]


class MotionFrame(Payload):
    """One consistent snapshot of every axis, board and signal, once per tick.
    16464 bytes, alignment 8."""

    _type_name_ = "motiond::MotionFrame"
    _fields_ = [
        ("schema_version", _u32),
        ("axis_count", _u32),
        ("tick", _u64),
        ("time_ns", _u64),
        ("publish_ns", _u64),
        ("flags", _u32),
        ("signal_count", _u32),
        ("device_count", _u32),
        ("reserved", _u32),
        ("devices", _u8 * MAX_DEVICES),
        ("axes", AxisState * MAX_AXES),
        ("signals", SignalState * MAX_SIGNALS),
        ("wire", AxisWire * MAX_AXES),
    ]


class CommandRequest(Payload):
    """A command to the server. 64 bytes, alignment 8. ``values`` per kind: see
    :class:`CommandKind`."""

    _type_name_ = "motiond::CommandRequest"
    _fields_ = [
        ("schema_version", _u32),
        ("kind", _u32),
        ("client", ClientId),
        ("sequence", _u64),
        ("axis", _u32),
        ("target", _u32),
        ("values", _f64 * 3),
    ]


class CommandReply(Payload):
    """The server's answer to one request. 32 bytes, alignment 8."""

    _type_name_ = "motiond::CommandReply"
    _fields_ = [
        ("schema_version", _u32),
        ("reason", _u32),
        ("sequence", _u64),
        ("tick_applied", _u64),
        ("axis", _u32),
        ("kind", _u32),
    ]


class AxisInfo(Payload):
    """One axis's static description. 160 bytes, alignment 8."""

    _type_name_ = "motiond::AxisInfo"
    _fields_ = [
        ("name", _u8 * NAME_LEN),
        ("unit", _u8 * UNIT_LEN),
        ("device", _u8 * NAME_LEN),
        ("counts_per_unit", _f64),
        ("min", _f64),
        ("max", _f64),
        ("max_velocity", _f64),
        ("max_accel", _f64),
        ("capabilities", _u32),
        ("channel", _u16),
        ("device_index", _u16),
        ("following_error", _f64),
        ("overspeed_factor", _f64),
        ("home_max_travel", _f64),
        ("estop", _u32),
        ("reserved", _u32),
    ]

    def supports(self, kind: "CommandKind") -> bool:
        """Whether the axis accepts commands of ``kind``."""
        return bool(self.capabilities & (1 << int(kind)))


class DeviceInfo(Payload):
    """One device's description. 112 bytes, alignment 4."""

    _type_name_ = "motiond::DeviceInfo"
    _fields_ = [
        ("name", _u8 * NAME_LEN),
        ("link", _u8 * NAME_LEN),
        ("firmware", _u8 * NAME_LEN),
        ("model", _u32),
        ("address", _u32),
        ("axis_count", _u32),
        ("state", _u32),
    ]


class SignalInfo(Payload):
    """One signal's static description. 128 bytes, alignment 8."""

    _type_name_ = "motiond::SignalInfo"
    _fields_ = [
        ("name", _u8 * NAME_LEN),
        ("unit", _u8 * UNIT_LEN),
        ("device", _u8 * NAME_LEN),
        ("scale", _f64),
        ("offset", _f64),
        ("full_scale", _f64),
        ("kind", _u8),
        ("flags", _u8),
        ("device_index", _u16),
        ("pin", _u8 * UNIT_LEN),
        ("reserved", _u32),
    ]


class ServerInfo(Payload):
    """The server's static description. 32328 bytes, alignment 8."""

    _type_name_ = "motiond::ServerInfo"
    _fields_ = [
        ("schema_version", _u32),
        ("axis_count", _u32),
        ("device_count", _u32),
        ("tick_hz", _u32),
        ("command_timeout_ms", _u32),
        ("max_clients", _u32),
        ("server_pid", _u32),
        ("signal_count", _u32),
        ("name", _u8 * NAME_LEN),
        ("start_time_ns", _u64),
        ("axes", AxisInfo * MAX_AXES),
        ("devices", DeviceInfo * MAX_DEVICES),
        ("signals", SignalInfo * MAX_SIGNALS),
    ]


class MachineParam(Payload):
    """One effective machine parameter. 88 bytes, alignment 4."""

    _type_name_ = "motiond::MachineParam"
    _fields_ = [
        ("key", _u8 * PARAM_TEXT_LEN),
        ("value", _u8 * PARAM_TEXT_LEN),
        ("owner_index", _u16),
        ("owner_kind", _u8),
        ("from_config", _u8),
        ("reserved", _u32),
    ]


class MachineParams(Payload):
    """Every machine parameter in effect. 180240 bytes, alignment 4."""

    _type_name_ = "motiond::MachineParams"
    _fields_ = [
        ("schema_version", _u32),
        ("count", _u32),
        ("truncated", _u32),
        ("reserved", _u32),
        ("entries", MachineParam * MAX_PARAMS),
    ]


class LatencySummary(Payload):
    """Percentiles of one latency distribution, ns. 40 bytes."""

    _type_name_ = "motiond::LatencySummary"
    _fields_ = [
        ("samples", _u64),
        ("p50_ns", _u64),
        ("p99_ns", _u64),
        ("p999_ns", _u64),
        ("max_ns", _u64),
    ]


class LinkStats(Payload):
    """Counters of one link since start. 80 bytes, alignment 8."""

    _type_name_ = "motiond::LinkStats"
    _fields_ = [
        ("name", _u8 * NAME_LEN),
        ("bytes_in", _u64),
        ("bytes_out", _u64),
        ("frames", _u64),
        ("errors", _u64),
        ("reconnects", _u64),
        ("up", _u32),
        ("reserved", _u32),
    ]


class LinkIo(Payload):
    """The I/O side of one link: CLOCK_MONOTONIC ns of the last write and read that moved
    bytes (0: never), messages written whole (SPI: transactions), reads that returned
    bytes. 32 bytes, alignment 8."""

    _type_name_ = "motiond::LinkIo"
    _fields_ = [
        ("last_write_ns", _u64),
        ("last_read_ns", _u64),
        ("transactions", _u64),
        ("reads", _u64),
    ]


class ServerStats(Payload):
    """Server figures, published about once a second. 1992 bytes, alignment 8."""

    _type_name_ = "motiond::ServerStats"
    _fields_ = [
        ("schema_version", _u32),
        ("link_count", _u32),
        ("tick", _u64),
        ("time_ns", _u64),
        ("wakeup", LatencySummary),
        ("work", LatencySummary),
        ("overruns", _u64),
        ("max_consecutive_overruns", _u64),
        ("commands", _u64),
        ("rejected", _u64),
        ("clients", _u32),
        ("rt_flags", _u32),
        ("links", LinkStats * MAX_LINKS),
        ("faults", _u64),
        ("frames_lost", _u64),
        ("full_services", _u32),
        ("full_events", _u32),
        ("publish_failures", _u64),
        ("replies_lost", _u64),
        ("events_dropped", _u64),
        ("link_io", LinkIo * MAX_LINKS),
        ("nodes_cleaned", _u64),
    ]


#: Every payload mirror, by Rust type name.
PAYLOADS: Dict[str, Type[Payload]] = {
    cls.__name__: cls
    for cls in (
        ClientId,
        AxisState,
        SignalState,
        AxisWire,
        MotionFrame,
        CommandRequest,
        CommandReply,
        AxisInfo,
        DeviceInfo,
        SignalInfo,
        ServerInfo,
        MachineParam,
        MachineParams,
        LatencySummary,
        LinkStats,
        LinkIo,
        ServerStats,
    )
}

# --- enumerations --------------------------------------------------------------------------


class _Texted(enum.IntEnum):
    """An enumeration whose values have a text (a name the CLI prints, or a message)."""

    @property
    def text(self) -> str:
        """The text the Rust side gives this value (``name()``, ``message()``, ``id()``)."""
        return _TEXTS[type(self)].get(self, self.name.lower())


class CommandKind(_Texted):
    """What a request asks for (``CommandRequest.kind``). ``values`` per kind: Stop –;
    Power [power −1..1]; Position [position]; Velocity [velocity]; RampPosition
    [position, max velocity, acceleration]; RampVelocity [velocity, acceleration]; Home
    [search velocity]; SetPosition [position]; SetOutput [0.0 or 1.0]; 0.0 in a velocity
    or acceleration slot means the axis's configured maximum."""

    STOP = 1
    POWER = 2
    POSITION = 3
    VELOCITY = 4
    RAMP_POSITION = 5
    RAMP_VELOCITY = 6
    HOME = 7
    SET_POSITION = 8
    CLAIM = 9
    RELEASE = 10
    E_STOP = 11
    RESET = 12
    OFF = 13
    SET_OUTPUT = 14


class Reason(_Texted):
    """Why a request was refused (``CommandReply.reason``); 0 = accepted."""

    ACCEPTED = 0
    SCHEMA_MISMATCH = 1
    UNKNOWN_KIND = 2
    UNKNOWN_AXIS = 3
    UNSUPPORTED = 4
    NOT_FINITE = 5
    OUT_OF_RANGE = 6
    VELOCITY_LIMIT = 7
    ACCEL_LIMIT = 8
    POWER_LIMIT = 9
    CLAIMED_BY_OTHER = 10
    NOT_CLAIMED = 11
    ESTOP_LATCHED = 12
    AXIS_FAULTED = 13
    LINK_DOWN = 14
    BUSY = 15
    SHUTTING_DOWN = 16
    NO_CLIENT_ID = 17
    IDENTITY_MISMATCH = 18
    DEVICE_STARTING = 19
    DEVICE_OFFLINE = 20
    UNKNOWN_SIGNAL = 21
    NOT_AN_OUTPUT = 22
    UNKNOWN_TARGET = 23

    @property
    def message(self) -> str:
        """One line saying what is wrong and what to do (the server's text)."""
        return self.text


class Target(_Texted):
    """What ``CommandRequest.axis`` indexes."""

    AXIS = 0
    SIGNAL = 1


class DeviceState(_Texted):
    """Where a board is in its life, as the server sees it."""

    OFFLINE = 0
    ONLINE = 1
    STARTING = 2
    FAULTED = 3


class AxisMode(_Texted):
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


class FaultCode(_Texted):
    """Why an axis is faulted (``AxisState.fault``); 0 = no fault."""

    NONE = 0
    LINK_DOWN = 1
    BOARD_NOT_RESPONDING = 2
    BOARD_RESET = 3
    BOARD_ERROR = 4
    PROTOCOL = 5
    OVERSPEED = 6
    LIMIT_SWITCH = 7
    OVERRUN = 8
    FOLLOWING_ERROR = 9
    LIMIT_EXCEEDED = 10
    HOME_FAILED = 11


class SignalKind(_Texted):
    """What a signal is."""

    DIGITAL_IN = 1
    DIGITAL_OUT = 2
    ANALOG_IN = 3


class EstopCategory(_Texted):
    """What an e-stop (and a fault) does to an axis (IEC 60204-1 stop categories)."""

    HOLD = 0
    STOP_OFF = 1
    OFF = 2


class DeviceModel(_Texted):
    """The board model of a device; ``text`` is the config's model id."""

    QQ2DRV = 1
    TMCPACK = 2
    SPIMOTOR = 3
    QSB = 4


class ParamOwner(_Texted):
    """What a machine parameter belongs to."""

    DEVICE = 1
    AXIS = 2


_TEXTS: Dict[type, Dict[enum.IntEnum, str]] = {
    CommandKind: {
        CommandKind.STOP: "stop",
        CommandKind.POWER: "power",
        CommandKind.POSITION: "position",
        CommandKind.VELOCITY: "velocity",
        CommandKind.RAMP_POSITION: "ramp-position",
        CommandKind.RAMP_VELOCITY: "ramp-velocity",
        CommandKind.HOME: "home",
        CommandKind.SET_POSITION: "set-position",
        CommandKind.CLAIM: "claim",
        CommandKind.RELEASE: "release",
        CommandKind.E_STOP: "e-stop",
        CommandKind.RESET: "reset",
        CommandKind.OFF: "off",
        CommandKind.SET_OUTPUT: "set-output",
    },
    Reason: {
        Reason.ACCEPTED: "accepted",
        Reason.SCHEMA_MISMATCH: "client and server use different motion-ipc schema versions",
        Reason.UNKNOWN_KIND: "unknown command kind",
        Reason.UNKNOWN_AXIS: "no such axis on this server",
        Reason.UNSUPPORTED: "the axis's board cannot do this command",
        Reason.NOT_FINITE: "a value is NaN or infinite",
        Reason.OUT_OF_RANGE: (
            "position outside the axis's min..max soft limits, or "
            "an output level other than 0 or 1"
        ),
        Reason.VELOCITY_LIMIT: (
            "velocity above the axis's max_velocity, or "
            "below the smallest step its board represents"
        ),
        Reason.ACCEL_LIMIT: (
            "acceleration above the axis's max_accel or not positive, or "
            "below the smallest step its board represents"
        ),
        Reason.POWER_LIMIT: "power outside -1.0..1.0",
        Reason.CLAIMED_BY_OTHER: "the axis is claimed by another client",
        Reason.NOT_CLAIMED: "this client holds no claim on the axis",
        Reason.ESTOP_LATCHED: "e-stop is latched: send reset first",
        Reason.AXIS_FAULTED: "the axis is faulted: clear the cause, then reset",
        Reason.LINK_DOWN: "the axis's link is down",
        Reason.BUSY: "the server's command queue is full: retry",
        Reason.SHUTTING_DOWN: "the server is shutting down",
        Reason.NO_CLIENT_ID: "claim and release need a client id",
        Reason.IDENTITY_MISMATCH: (
            "the request's client id is not the sender's iceoryx2 node: " "ids cannot be borrowed"
        ),
        Reason.DEVICE_STARTING: (
            "the axis's board is starting: its link is not open yet, or it awaits its first "
            "answer and its start-up stop"
        ),
        Reason.DEVICE_OFFLINE: "the axis's board is not answering",
        Reason.UNKNOWN_SIGNAL: "no such signal on this server",
        Reason.NOT_AN_OUTPUT: "the signal is not a digital output",
        Reason.UNKNOWN_TARGET: "unknown target: 0 = axis, 1 = signal",
    },
    Target: {},
    DeviceState: {},
    AxisMode: {},
    FaultCode: {
        FaultCode.NONE: "none",
        FaultCode.LINK_DOWN: "link-down",
        FaultCode.BOARD_NOT_RESPONDING: "board-not-responding",
        FaultCode.BOARD_RESET: "board-reset",
        FaultCode.BOARD_ERROR: "board-error",
        FaultCode.PROTOCOL: "protocol",
        FaultCode.OVERSPEED: "overspeed",
        FaultCode.LIMIT_SWITCH: "limit-switch",
        FaultCode.OVERRUN: "overrun",
        FaultCode.FOLLOWING_ERROR: "following-error",
        FaultCode.LIMIT_EXCEEDED: "limit-exceeded",
        FaultCode.HOME_FAILED: "home-failed",
    },
    SignalKind: {
        SignalKind.DIGITAL_IN: "digital-in",
        SignalKind.DIGITAL_OUT: "digital-out",
        SignalKind.ANALOG_IN: "analog-in",
    },
    EstopCategory: {
        EstopCategory.HOLD: "hold",
        EstopCategory.STOP_OFF: "stop-off",
        EstopCategory.OFF: "off",
    },
    DeviceModel: {},
    ParamOwner: {},
}


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
    cls.__name__: cls
    for cls in (
        CommandKind,
        Reason,
        Target,
        DeviceState,
        AxisMode,
        FaultCode,
        SignalKind,
        EstopCategory,
        DeviceModel,
        ParamOwner,
        AxisFlags,
        FrameFlags,
        SignalFlags,
        SignalInfoFlags,
        RtFlags,
        FullServices,
    )
}

E = TypeVar("E", bound=enum.IntEnum)


def to_enum(cls: Type[E], value: int) -> Union[E, int]:
    """``cls(value)``, or the plain ``value`` when this package does not know it."""
    try:
        return cls(value)
    except ValueError:
        return value
