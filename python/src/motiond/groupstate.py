"""One group's state in one frame: :class:`GroupStatus`, and the error of an aborted group
(what :class:`~motiond.group.Group` and :class:`~motiond.stream.SetpointStream` share)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple, Union

from .errors import GroupAborted
from .ipc import (
    GroupAbort,
    GroupMotion,
    GroupState,
    PathKind,
    ServerInfo,
    StreamFlags,
    StreamMode,
    StreamState,
    to_enum,
)

__all__ = ["GroupStatus", "NO_AXIS"]

#: ``GroupState.abort_axis`` (and ``CommandReply.at_axis``) when no axis is named.
NO_AXIS = 0xFFFF_FFFF


def axis_name_unit(info: ServerInfo, index: int) -> Tuple[Optional[str], str]:
    """The name and unit of config axis ``index``; ``(None, "")`` for :data:`NO_AXIS`."""
    if index == NO_AXIS:
        return None, ""
    if index < min(int(info.axis_count), len(info.axes)):
        entry = info.axes[index]
        return entry.text("name"), entry.text("unit")
    return f"#{index}", ""


@dataclass(frozen=True)
class GroupStatus:
    """One group's state in one frame (a copy; see :class:`~motiond.ipc.GroupState`).

    The enumerations are typed (an ``int`` when this package does not know the value);
    their ``.text`` is the server's name: ``status.stream.text == "streaming"``,
    ``status.abort.text == "path-tolerance"``."""

    #: Group index, config order.
    index: int
    #: The group's name.
    name: str
    #: The frame's tick.
    tick: int
    #: Where the group's motion is: idle, moving, holding, held, done, aborted.
    motion: Union[GroupMotion, int]
    #: Why it aborted (``GroupAbort.NONE`` when it did not).
    abort: Union[GroupAbort, int]
    #: The name of the axis that aborted it; ``None`` when none.
    abort_axis: Optional[str]
    #: The figure that aborted it (a tolerance: |desired − measured|), the axis's unit.
    abort_value: float
    #: The tolerance or limit it broke.
    abort_limit: float
    #: The id of the path running (or last run).
    path_id: int
    #: Index of the point the path is heading to (0 for a line).
    point: int
    #: Seconds along the path (path time: it advances by the feed each second).
    time: float
    #: The path's length in seconds at feed 1.
    duration: float
    #: The feed in effect (0 while held).
    feed: float
    #: The feed set by the client.
    feed_set: float
    #: Node id of the client whose motion or stream the group runs; 0 when none.
    owner: int
    #: What runs (or last ran): line, trajectory, stream.
    kind: Union[PathKind, int]
    #: Where the group's setpoint stream is: idle, streaming, stale, aborted.
    stream: Union[StreamState, int]
    #: The mode of the stream running or last run.
    stream_mode: Union[StreamMode, int]
    #: ``StreamFlags`` of this tick (a setpoint applied, clamped).
    stream_flags: StreamFlags
    #: Sequence of the last streamed setpoint applied.
    last_sequence: int
    #: Tick in which it was applied.
    last_applied_tick: int
    #: When the server took it from the setpoints service (CLOCK_MONOTONIC ns, the clock of
    #: the frame's ``publish_ns`` and of ``time.monotonic_ns()``); 0 until one is applied.
    last_received_ns: int
    #: Ticks the stream runs behind its setpoints' own ticks: the setpoint for tick ``k``
    #: is applied in tick ``k + stream_delay``; grows to the lateness of one that arrived
    #: after its tick (at most ``stream_buffer``), never shrinks while the stream runs.
    stream_delay: int
    #: Streamed setpoints applied.
    applied: int
    #: Streamed setpoints dropped because they could no longer apply: more than
    #: ``stream_buffer`` ticks behind, superseded by a newer sequence for the same tick, or
    #: not above the last applied tick and sequence.
    late: int
    #: Streamed setpoints dropped because they were for a tick too far ahead.
    early: int
    #: Streamed setpoints clamped to a limit.
    clamped: int
    #: Streamed setpoints dropped because their sender does not hold the group.
    refused: int

    @classmethod
    def of(cls, info: ServerInfo, index: int, tick: int, state: GroupState) -> "GroupStatus":
        """A snapshot of ``state`` (group ``index`` in the frame of ``tick``)."""
        axis, _ = axis_name_unit(info, int(state.abort_axis))
        return cls(
            index=index,
            name=info.groups[index].text("name"),
            tick=tick,
            motion=to_enum(GroupMotion, state.motion),
            abort=to_enum(GroupAbort, state.abort),
            abort_axis=axis,
            abort_value=float(state.abort_value),
            abort_limit=float(state.abort_limit),
            path_id=int(state.path_id),
            point=int(state.point),
            time=float(state.time),
            duration=float(state.duration),
            feed=float(state.feed),
            feed_set=float(state.feed_set),
            owner=int(state.owner),
            kind=to_enum(PathKind, state.kind),
            stream=to_enum(StreamState, state.stream),
            stream_mode=to_enum(StreamMode, state.stream_mode),
            stream_flags=StreamFlags(state.stream_flags),
            last_sequence=int(state.last_sequence),
            last_applied_tick=int(state.last_applied_tick),
            last_received_ns=int(state.last_received_ns),
            stream_delay=int(state.stream_delay),
            applied=int(state.applied),
            late=int(state.late),
            early=int(state.early),
            clamped=int(state.clamped),
            refused=int(state.refused),
        )

    @property
    def active(self) -> bool:
        """A motion or stream owns the group's axes (moving, holding or held)."""
        return self.motion in (GroupMotion.MOVING, GroupMotion.HOLDING, GroupMotion.HELD)

    @property
    def done(self) -> bool:
        """The path ended with every axis within its goal tolerance (or a stream was
        cancelled)."""
        return self.motion == GroupMotion.DONE

    @property
    def aborted(self) -> bool:
        """The motion ended early: :attr:`abort` says why."""
        return self.motion == GroupMotion.ABORTED

    @property
    def streaming(self) -> bool:
        """The group's stream runs."""
        return self.stream == StreamState.STREAMING


def aborted_error(
    info: ServerInfo, name: str, what: str, state: GroupState, tick: int
) -> GroupAborted:
    """The :class:`~motiond.errors.GroupAborted` of an aborted ``state``."""
    abort = to_enum(GroupAbort, state.abort)
    axis, unit = axis_name_unit(info, int(state.abort_axis))
    if abort not in (GroupAbort.PATH_TOLERANCE, GroupAbort.GOAL_TOLERANCE):
        unit = ""  # a stream's figure may be a velocity or a power
    return GroupAborted(
        name,
        what,
        abort,
        axis,
        float(state.abort_value),
        float(state.abort_limit),
        unit,
        int(state.path_id),
        tick,
    )
