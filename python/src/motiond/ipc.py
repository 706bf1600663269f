"""The shared-memory contract of motiond, mirrored with :mod:`ctypes`.

Every payload motiond publishes or takes is a fixed-size ``#[repr(C)]`` Rust struct (crate
``motion-ipc``). The classes here mirror them field by field, in memory order, with the
same iceoryx2 type name (``type_name()``): iceoryx2 refuses to connect a port whose type
name, size or alignment differs from the server's. The mirrors, enumerations and constants
are generated from the Rust description of the contract into ``_layout.py`` (``scripts/gen``)
and re-exported here; ``tests/test_layout.py`` checks every size, offset, field name, field
type, type name, enumeration value and text against the description the Rust crate prints
(``cargo run -p motion-ipc --example layout``).

Enumerations travel as plain integers; the :class:`enum.IntEnum` classes here give them
names (``Reason(6) is Reason.OUT_OF_RANGE``). A value unknown to this version of the
package stays an ``int``: use :func:`to_enum` to convert without raising.

The views the client hands out point into shared memory that this process maps read-only:
read them, never assign to their fields (copy first with :meth:`Payload.copy`).
"""

from __future__ import annotations

import enum
from typing import Type, TypeVar, Union

from ._layout import (
    ALL_AXES,
    ENUMS,
    MAX_AXES,
    MAX_DEVICES,
    MAX_GROUP_AXES,
    MAX_GROUPS,
    MAX_LINKS,
    MAX_PATH_POINTS,
    MAX_PARAMS,
    MAX_SIGNALS,
    MODEL_ID_LEN,
    NAME_LEN,
    PARAM_TEXT_LEN,
    PATH_VALUES,
    PAYLOADS,
    SCHEMA_VERSION,
    SERVICES,
    UNIT_LEN,
    AxisFlags,
    AxisInfo,
    AxisMode,
    AxisState,
    AxisWire,
    ClientId,
    CommandKind,
    CommandReply,
    CommandRequest,
    CommissionWhat,
    DeviceInfo,
    DeviceModel,
    DeviceState,
    EstopCategory,
    FaultCode,
    FrameFlags,
    FullServices,
    GroupAbort,
    GroupInfo,
    GroupMotion,
    GroupPath,
    GroupState,
    LatencySummary,
    LinkIo,
    LinkStats,
    MachineParam,
    MachineParams,
    MotionFrame,
    ParamOwner,
    PathFlags,
    PathKind,
    Reason,
    RtFlags,
    ServerInfo,
    ServerStats,
    Setpoint,
    SetpointFlags,
    SignalFlags,
    SignalInfo,
    SignalInfoFlags,
    SignalKind,
    SignalState,
    StreamFlags,
    StreamMode,
    StreamState,
    Target,
)
from ._mirror_base import Payload, TextedEnum, read_text

__all__ = [
    "SCHEMA_VERSION",
    "MAX_AXES",
    "MAX_DEVICES",
    "MAX_LINKS",
    "MAX_SIGNALS",
    "MAX_PARAMS",
    "MAX_GROUPS",
    "MAX_GROUP_AXES",
    "MAX_PATH_POINTS",
    "PATH_VALUES",
    "NAME_LEN",
    "UNIT_LEN",
    "MODEL_ID_LEN",
    "PARAM_TEXT_LEN",
    "ALL_AXES",
    "SERVICES",
    "service_name",
    "server_node_name",
    "read_text",
    "to_enum",
    "Payload",
    "TextedEnum",
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
    "GroupState",
    "GroupInfo",
    "GroupPath",
    "Setpoint",
    "MachineParam",
    "MachineParams",
    "LatencySummary",
    "LinkStats",
    "LinkIo",
    "ServerStats",
    "PAYLOADS",
    "CommandKind",
    "CommissionWhat",
    "Reason",
    "Target",
    "DeviceState",
    "AxisMode",
    "FaultCode",
    "SignalKind",
    "EstopCategory",
    "DeviceModel",
    "ParamOwner",
    "GroupMotion",
    "GroupAbort",
    "StreamState",
    "StreamMode",
    "PathKind",
    "PathFlags",
    "StreamFlags",
    "SetpointFlags",
    "AxisFlags",
    "FrameFlags",
    "SignalFlags",
    "SignalInfoFlags",
    "RtFlags",
    "FullServices",
    "ENUMS",
]


def service_name(instance: str, leaf: str) -> str:
    """The iceoryx2 service name ``leaf`` (``"frame"``, ``"command"`` …) of ``instance``."""
    return SERVICES[leaf] % instance


def server_node_name(instance: str) -> str:
    """The iceoryx2 node name the server of ``instance`` runs under."""
    return SERVICES["server_node"] % instance


E = TypeVar("E", bound=enum.IntEnum)


def to_enum(cls: Type[E], value: int) -> Union[E, int]:
    """``cls(value)``, or the plain ``value`` when this package does not know it."""
    try:
        return cls(value)
    except ValueError:
        return value
