"""The server's answers named from its description (:class:`~motiond.ipc.ServerInfo`), as a
:class:`~motiond.Client` hands them on:

- :func:`label`, the words for a command's target (``axis x``, ``signal door``, ``all
  axes``);
- :func:`refusal`, the exception of a refused reply, naming the point, the axis (by name,
  with its unit), the figures and the claim holder the server named;
- :func:`params_of`, a :class:`~motiond.ipc.MachineParams` table as :class:`Param` rows
  with their owners named.

Pure functions of the description and the answer: no port, no wait.
"""

from __future__ import annotations

from typing import List, Optional, Union

from . import errors
from .ipc import (
    ALL_AXES,
    CommandReply,
    MachineParams,
    ParamOwner,
    Reason,
    ServerInfo,
    Target,
    to_enum,
)
from .session import Param

__all__ = ["NO_INDEX", "label", "refusal", "params_of"]

# ``CommandReply.at_point`` / ``at_axis`` when the server named none.
NO_INDEX = 0xFFFF_FFFF


def label(info: ServerInfo, index: int, target: Union[Target, int]) -> str:
    """The words for target ``index`` of kind ``target``, by its config name."""
    if index == ALL_AXES:
        return "all axes"
    if target == Target.SIGNAL:
        if index < info.signal_count:
            return f"signal {info.signals[index].text('name')}"
        return f"signal #{index}"
    if target == Target.GROUP:
        if index < min(int(info.group_count), len(info.groups)):
            return f"group {info.groups[index].text('name')}"
        return f"group #{index}"
    if index < info.axis_count:
        return f"axis {info.axes[index].text('name')}"
    return f"axis #{index}"


def refusal(info: ServerInfo, reply: CommandReply, target: str) -> errors.Refused:
    """The exception of a refused ``reply`` to a command on ``target`` (its
    :func:`label`), naming the point, the axis (by name), the figures and the claim holder
    the server named."""
    point = None if reply.at_point == NO_INDEX else int(reply.at_point)
    axis: Optional[str] = None
    unit = ""
    if reply.at_axis != NO_INDEX:
        if reply.at_axis < min(int(info.axis_count), len(info.axes)):
            entry = info.axes[reply.at_axis]
            axis, unit = entry.text("name"), entry.text("unit")
        else:
            axis = f"#{reply.at_axis}"
    reason = int(reply.reason)
    if unit and reason == Reason.VELOCITY_LIMIT:
        unit += "/s"
    elif unit and reason == Reason.ACCEL_LIMIT:
        unit += "/s²"
    figures = reply.value != 0.0 or reply.limit != 0.0
    holder = int(reply.holder)
    return errors.refused(
        reason,
        int(reply.kind),
        target,
        int(reply.tick_applied),
        point=point,
        axis=axis,
        value=float(reply.value) if figures else None,
        limit=float(reply.limit) if figures else None,
        unit=unit,
        holder=holder if holder else None,
    )


def params_of(info: ServerInfo, table: MachineParams) -> List[Param]:
    """The entries of ``table``, each owner (a device or an axis) named."""
    params = []
    for index in range(min(int(table.count), len(table.entries))):
        entry = table.entries[index]
        owner = to_enum(ParamOwner, entry.owner_kind)
        if owner == ParamOwner.DEVICE and entry.owner_index < info.device_count:
            owner_name = info.devices[entry.owner_index].text("name")
        elif owner == ParamOwner.AXIS and entry.owner_index < info.axis_count:
            owner_name = info.axes[entry.owner_index].text("name")
        else:
            owner_name = ""
        params.append(
            Param(
                owner=owner,
                owner_index=int(entry.owner_index),
                owner_name=owner_name,
                key=entry.text("key"),
                value=entry.text("value"),
                from_config=bool(entry.from_config),
            )
        )
    return params
