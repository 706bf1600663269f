"""Exceptions of the motiond client.

Everything raised by this package derives from :class:`MotiondError`. A command the server
refused raises a subclass of :class:`Refused` named after the server's reason
(:class:`OutOfRange`, :class:`EstopLatched`, …); each carries the typed
:class:`~motiond.ipc.Reason`, whose ``message`` is the server's own text.
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Sequence, Type, Union

from .ipc import CommandKind, GroupAbort, Reason, to_enum

__all__ = [
    "MotiondError",
    "ConnectError",
    "NoServer",
    "NoInfo",
    "IncompatibleServer",
    "NoSuchAxis",
    "NoSuchSignal",
    "NoSuchGroup",
    "NoSuchDevice",
    "BadPath",
    "GroupAborted",
    "StreamClosed",
    "Refused",
    "ServerGone",
    "NoReply",
    "NoFrame",
    "EstopNotSeen",
    "WaitTimeout",
    "WaitAborted",
    "FramesHeld",
    "IpcError",
    "PortsExhausted",
    "NoBridge",
    "BridgeRefused",
    "RemoteError",
    "refused",
    "REFUSALS",
    "SchemaMismatch",
    "UnknownKind",
    "UnknownAxis",
    "Unsupported",
    "NotFinite",
    "OutOfRange",
    "VelocityLimit",
    "AccelLimit",
    "PowerLimit",
    "ClaimedByOther",
    "NotClaimed",
    "EstopLatched",
    "AxisFaulted",
    "LinkDown",
    "Busy",
    "ShuttingDown",
    "NoClientId",
    "IdentityMismatch",
    "DeviceStarting",
    "DeviceOffline",
    "UnknownSignal",
    "NotAnOutput",
    "UnknownTarget",
    "UnknownGroup",
    "NoPath",
    "PathTimes",
    "PathStart",
    "PathLayout",
    "GroupBusy",
    "NotMoving",
    "BlendTolerance",
    "UnknownDevice",
    "NotRecommissioned",
]


class MotiondError(Exception):
    """Base of every error of this package."""


class ConnectError(MotiondError):
    """Connecting to a server failed."""


class NoServer(ConnectError):
    """No server of that name runs (its frame service does not exist)."""

    def __init__(self, name: str, service: str, waited: float) -> None:
        super().__init__(
            f'no motiond server named "{name}" is running (waited {waited:.1f} s for service '
            f"{service}); start one with `motiond --config config/sim.toml`, or pick another "
            "name"
        )
        self.name = name
        self.service = service
        self.waited = waited


class NoInfo(ConnectError):
    """The server runs but published no server description in time."""

    def __init__(self, name: str, service: str, waited: float) -> None:
        super().__init__(
            f'motiond "{name}" published no server description on {service} within '
            f"{waited:.1f} s; is it still starting up?"
        )
        self.name = name
        self.service = service
        self.waited = waited


class IncompatibleServer(ConnectError):
    """The server speaks another version of the shared-memory contract."""

    def __init__(self, name: str, server: int, client: int) -> None:
        super().__init__(
            f'motiond "{name}" speaks another motion-ipc schema (server {server}, this client '
            f"{client}; 0 = payload types differ): use the motiond package of the same "
            "release as the server"
        )
        self.name = name
        self.server = server
        self.client = client


class NoSuchAxis(MotiondError, LookupError):
    """No axis of that name on the server."""

    def __init__(self, name: str) -> None:
        super().__init__(f'no axis named "{name}" on this server (see `python -m motiond list`)')
        self.name = name


class NoSuchSignal(MotiondError, LookupError):
    """No signal of that name on the server."""

    def __init__(self, name: str) -> None:
        super().__init__(f'no signal named "{name}" on this server (see `python -m motiond list`)')
        self.name = name


class NoSuchGroup(MotiondError, LookupError):
    """No group of that name on the server; ``groups`` are the names it has."""

    def __init__(self, name: str, groups: Sequence[str]) -> None:
        have = ", ".join(groups) if groups else "none: its config has no [[group]]"
        super().__init__(f'no group named "{name}" on this server (its groups: {have})')
        self.name = name
        self.groups = list(groups)


class NoSuchDevice(MotiondError, LookupError):
    """No device of that name on the server."""

    def __init__(self, name: str) -> None:
        super().__init__(f'no device named "{name}" on this server (see `motionctl list`)')
        self.name = name


class BadPath(MotiondError, ValueError):
    """A path or a setpoint that cannot be sent as given (wrong shape, too many points,
    not numbers): found by the client, before anything reached the server."""


#: The :class:`Refused` subclass of every reason but ``ACCEPTED`` (each registers itself
#: by the ``reason`` of its class statement).
REFUSALS: Dict[Reason, Type["Refused"]] = {}


class Refused(MotiondError):
    """The server refused a command. ``reason`` is the typed reason (an ``int`` if this
    package does not know it), ``kind`` the command, ``target`` the axis, signal or group in
    words, ``tick`` the tick in which the server refused it.

    Where the server named what was at fault (a refused path, a claim held by another
    client), ``point`` is the index of the path's point, ``axis`` the axis's name,
    ``value`` the figure at fault and ``limit`` the limit it broke (in the axis's unit,
    ``unit``), ``holder`` the node id of the client holding the claim; ``None`` otherwise.
    """

    reason_code: Optional[Reason] = None

    def __init_subclass__(cls, reason: Optional[Reason] = None, **kwargs: Any) -> None:
        # `class OutOfRange(Refused, reason=Reason.OUT_OF_RANGE)` names its reason once:
        # that is its `reason_code` and its entry in REFUSALS.
        super().__init_subclass__(**kwargs)
        if reason is not None:
            if reason in REFUSALS:
                raise TypeError(f"{reason!r} already raises {REFUSALS[reason].__name__}")
            cls.reason_code = reason
            REFUSALS[reason] = cls

    def __init__(
        self,
        reason: Union[Reason, int],
        kind: Union[CommandKind, int],
        target: str,
        tick: int,
        *,
        point: Optional[int] = None,
        axis: Optional[str] = None,
        value: Optional[float] = None,
        limit: Optional[float] = None,
        unit: str = "",
        holder: Optional[int] = None,
    ) -> None:
        kind_text = kind.text if isinstance(kind, CommandKind) else "command"
        message = reason.message if isinstance(reason, Reason) else f"unknown reason {reason}"
        parts = []
        if point is not None:
            parts.append(f"point {point}")
        if axis is not None:
            parts.append(f"axis {axis}")
        if value is not None and limit is not None:
            suffix = f" {unit}" if unit else ""
            parts.append(f"{value:.6g}{suffix} against the limit {limit:.6g}{suffix}")
        if holder is not None:
            parts.append(f"held by client {holder:#x}")
        detail = f" ({', '.join(parts)})" if parts else ""
        super().__init__(f"{kind_text} on {target} refused: {message}{detail}")
        self.reason = reason
        self.kind = kind
        self.target = target
        self.tick = tick
        self.point = point
        self.axis = axis
        self.value = value
        self.limit = limit
        self.unit = unit
        self.holder = holder


# One class per refusal reason, named after it: ``except motiond.OutOfRange:``.


class SchemaMismatch(Refused, reason=Reason.SCHEMA_MISMATCH):
    """Refused: client and server use different motion-ipc schema versions
    (``Reason.SCHEMA_MISMATCH``).
    """


class UnknownKind(Refused, reason=Reason.UNKNOWN_KIND):
    """Refused: unknown command kind (``Reason.UNKNOWN_KIND``)."""


class UnknownAxis(Refused, reason=Reason.UNKNOWN_AXIS):
    """Refused: no such axis on this server (``Reason.UNKNOWN_AXIS``)."""


class Unsupported(Refused, reason=Reason.UNSUPPORTED):
    """Refused: the axis's board cannot do this command (``Reason.UNSUPPORTED``)."""


class NotFinite(Refused, reason=Reason.NOT_FINITE):
    """Refused: a value is NaN or infinite (``Reason.NOT_FINITE``)."""


class OutOfRange(Refused, reason=Reason.OUT_OF_RANGE):
    """Refused: position outside the axis's min..max soft limits, or an output level other
    than 0 or 1 (``Reason.OUT_OF_RANGE``)."""


class VelocityLimit(Refused, reason=Reason.VELOCITY_LIMIT):
    """Refused: velocity above the axis's max_velocity, or below the smallest step its board
    represents (``Reason.VELOCITY_LIMIT``)."""


class AccelLimit(Refused, reason=Reason.ACCEL_LIMIT):
    """Refused: acceleration above the axis's max_accel or not positive, or below the smallest
    step its board represents (``Reason.ACCEL_LIMIT``)."""


class PowerLimit(Refused, reason=Reason.POWER_LIMIT):
    """Refused: power outside -1.0..1.0 (``Reason.POWER_LIMIT``)."""


class ClaimedByOther(Refused, reason=Reason.CLAIMED_BY_OTHER):
    """Refused: the axis is claimed by another client (``Reason.CLAIMED_BY_OTHER``)."""


class NotClaimed(Refused, reason=Reason.NOT_CLAIMED):
    """Refused: this client holds no claim on the axis (``Reason.NOT_CLAIMED``)."""


class EstopLatched(Refused, reason=Reason.ESTOP_LATCHED):
    """Refused: e-stop is latched: send reset first (``Reason.ESTOP_LATCHED``)."""


class AxisFaulted(Refused, reason=Reason.AXIS_FAULTED):
    """Refused: the axis is faulted: clear the cause, then reset (``Reason.AXIS_FAULTED``)."""


class LinkDown(Refused, reason=Reason.LINK_DOWN):
    """Refused: the axis's link is down (``Reason.LINK_DOWN``)."""


class Busy(Refused, reason=Reason.BUSY):
    """Refused: the server's command queue is full: retry (``Reason.BUSY``)."""


class ShuttingDown(Refused, reason=Reason.SHUTTING_DOWN):
    """Refused: the server is shutting down (``Reason.SHUTTING_DOWN``)."""


class NoClientId(Refused, reason=Reason.NO_CLIENT_ID):
    """Refused: claim and release need a client id (``Reason.NO_CLIENT_ID``)."""


class IdentityMismatch(Refused, reason=Reason.IDENTITY_MISMATCH):
    """Refused: the request's client id is not the sender's iceoryx2 node: ids cannot be borrowed
    (``Reason.IDENTITY_MISMATCH``).
    """


class DeviceStarting(Refused, reason=Reason.DEVICE_STARTING):
    """Refused: the axis's board is starting: its link is not open yet, or it awaits its first
    answer and its start-up stop (``Reason.DEVICE_STARTING``).
    """


class DeviceOffline(Refused, reason=Reason.DEVICE_OFFLINE):
    """Refused: the axis's board is not answering (``Reason.DEVICE_OFFLINE``)."""


class UnknownSignal(Refused, reason=Reason.UNKNOWN_SIGNAL):
    """Refused: no such signal on this server (``Reason.UNKNOWN_SIGNAL``)."""


class NotAnOutput(Refused, reason=Reason.NOT_AN_OUTPUT):
    """Refused: the signal is not an output: neither a digital output nor a trigger
    (``Reason.NOT_AN_OUTPUT``)."""


class UnknownTarget(Refused, reason=Reason.UNKNOWN_TARGET):
    """Refused: unknown target: 0 = axis, 1 = signal (``Reason.UNKNOWN_TARGET``)."""


class UnknownGroup(Refused, reason=Reason.UNKNOWN_GROUP):
    """Refused: no such group on this server (``Reason.UNKNOWN_GROUP``)."""


class NoPath(Refused, reason=Reason.NO_PATH):
    """Refused: no path with this id for this group was published by this client on
    ``paths`` (``Reason.NO_PATH``)."""


class PathTimes(Refused, reason=Reason.PATH_TIMES):
    """Refused: the path's point times must start at 0 or later and increase; ``point``
    names the first one that does not (``Reason.PATH_TIMES``)."""


class PathStart(Refused, reason=Reason.PATH_START):
    """Refused: the path's first point has time 0 but is not where the group is; ``axis``,
    ``value`` (the distance) and ``limit`` (the tolerance) say by how much
    (``Reason.PATH_START``)."""


class PathLayout(Refused, reason=Reason.PATH_LAYOUT):
    """Refused: malformed path: no points, too many, an axis count other than the group's,
    an unknown kind, or a scale outside (0, 1] (``Reason.PATH_LAYOUT``)."""


class GroupBusy(Refused, reason=Reason.GROUP_BUSY):
    """Refused: an axis of this request is moving with a group (or the group streams):
    cancel that motion or wait for it (``Reason.GROUP_BUSY``)."""


class NotMoving(Refused, reason=Reason.NOT_MOVING):
    """Refused: the group has no motion running (``Reason.NOT_MOVING``)."""


class BlendTolerance(Refused, reason=Reason.BLEND_TOLERANCE):
    """Refused: a trajectory of positions alone cannot be blended at a point within the
    axis's ``path_tolerance`` at its max_accel; ``at_point`` / ``at_axis`` name it, ``value``
    and ``limit`` give the distance and the tolerance (``Reason.BLEND_TOLERANCE``)."""


class UnknownDevice(Refused, reason=Reason.UNKNOWN_DEVICE):
    """Refused: no such device on this server (``Reason.UNKNOWN_DEVICE``)."""


class NotRecommissioned(MotiondError, TimeoutError):
    """A commissioned device did not answer again in time (not found at its new address
    or rate, or after its factory reset); ``state`` is its
    :class:`~motiond.ipc.DeviceState` then."""

    def __init__(self, device: str, state: Any, waited: float) -> None:
        text = getattr(state, "text", str(state))
        super().__init__(
            f"device `{device}` did not answer again within {waited:.3f} s (it is {text}); "
            "the server keeps asking where it should now answer"
        )
        self.device = device
        self.state = state
        self.waited = waited


def refused(
    reason: int,
    kind: int,
    target: str,
    tick: int,
    *,
    point: Optional[int] = None,
    axis: Optional[str] = None,
    value: Optional[float] = None,
    limit: Optional[float] = None,
    unit: str = "",
    holder: Optional[int] = None,
) -> Refused:
    """The exception for a refusal with raw ``reason`` of a command of raw ``kind``, with
    what the server named at fault (see :class:`Refused`)."""
    typed_reason = to_enum(Reason, reason)
    typed_kind = to_enum(CommandKind, kind)
    cls = REFUSALS.get(typed_reason, Refused) if isinstance(typed_reason, Reason) else Refused
    return cls(
        typed_reason,
        typed_kind,
        target,
        tick,
        point=point,
        axis=axis,
        value=value,
        limit=limit,
        unit=unit,
        holder=holder,
    )


def _kind_text(kind: Union[CommandKind, int]) -> str:
    return kind.text if isinstance(kind, CommandKind) else f"command {kind}"


class ServerGone(MotiondError):
    """No server listens on the command service any more."""

    def __init__(self, kind: Union[CommandKind, int]) -> None:
        super().__init__(
            f"{_kind_text(kind)} not sent: no motiond serves the command service any more "
            "(did it stop?)"
        )
        self.kind = kind


class NoReply(MotiondError, TimeoutError):
    """The server did not answer a command in time."""

    def __init__(self, kind: Union[CommandKind, int], waited: float) -> None:
        super().__init__(
            f"no reply from the server to {_kind_text(kind)} within {waited:.3f} s; "
            "is motiond still running?"
        )
        self.kind = kind
        self.waited = waited


class NoFrame(MotiondError, TimeoutError):
    """No frame arrived in time."""

    def __init__(self, waited: float) -> None:
        super().__init__(
            f"no frame from the server within {waited:.3f} s; is motiond still running?"
        )
        self.waited = waited


class EstopNotSeen(MotiondError, TimeoutError):
    """The server accepted an e-stop, but no frame of that tick or later showed it latched
    in time (another client's reset in between, or frames stopped): it is not reported as
    in force."""

    def __init__(self, tick: int, waited: float, newest: Optional[int]) -> None:
        seen = "no frame came" if newest is None else f"newest frame: tick {newest}"
        super().__init__(
            f"the server accepted the e-stop in tick {tick}, but no frame showed it latched "
            f"within {waited:.3f} s ({seen}); check the machine"
        )
        self.tick = tick
        self.waited = waited
        self.newest = newest


class WaitTimeout(MotiondError, TimeoutError):
    """A wait for a condition ran out of time."""

    def __init__(self, subject: str, what: str, waited: float) -> None:
        super().__init__(f"{subject} did not {what} within {waited:.3f} s")
        self.subject = subject
        self.what = what
        self.waited = waited


class WaitAborted(MotiondError):
    """A wait ended because the condition can no longer come true (stopped, faulted,
    e-stop)."""

    def __init__(self, subject: str, what: str, why: str) -> None:
        super().__init__(f"{subject} will not {what}: {why}")
        self.subject = subject
        self.what = what
        self.why = why


class GroupAborted(WaitAborted):
    """A group's motion or stream ended before its end (``GroupMotion.ABORTED``).

    ``abort`` is the server's :class:`~motiond.ipc.GroupAbort` (``path-tolerance``,
    ``e-stop``, ``stream-stale`` …), ``axis`` the name of the axis at fault (``None`` when
    none), ``value`` the figure that aborted it (for a tolerance: how far the axis was from
    where the path had it) and ``limit`` the tolerance or limit it broke, in the axis's
    ``unit``; ``path_id`` the path that ran, ``tick`` the frame that showed it."""

    def __init__(
        self,
        group: str,
        what: str,
        abort: Union[GroupAbort, int],
        axis: Optional[str],
        value: float,
        limit: float,
        unit: str,
        path_id: int,
        tick: int,
    ) -> None:
        text = abort.text if isinstance(abort, GroupAbort) else f"abort reason {abort}"
        why = f"aborted ({text})"
        if axis is not None:
            why += f" on axis {axis}"
            if value or limit:
                suffix = f" {unit}" if unit else ""
                why += f": {value:.6g}{suffix} against the limit {limit:.6g}{suffix}"
        why += f" in tick {tick}"
        super().__init__(f"group {group}", what, why)
        self.group = group
        self.abort = abort
        self.axis = axis
        self.value = value
        self.limit = limit
        self.unit = unit
        self.path_id = path_id
        self.tick = tick


class StreamClosed(MotiondError):
    """A setpoint stream was used after it ended (its ``with`` block left, or
    :meth:`~motiond.SetpointStream.close` called)."""

    def __init__(self, group: str) -> None:
        super().__init__(f"the setpoint stream of group {group} has ended")
        self.group = group


class FramesHeld(MotiondError):
    """Receiving failed because this process holds too many samples of one service."""

    def __init__(self, service: str, detail: str) -> None:
        super().__init__(
            f"cannot receive from {service}: this client holds as many of its samples as "
            f"iceoryx2 allows ({detail}); drop older Frame objects or keep copies "
            "(frame.copy()) instead"
        )
        self.service = service


class IpcError(MotiondError):
    """iceoryx2 failed to create, send, receive or wait."""

    def __init__(self, what: str, error: BaseException) -> None:
        super().__init__(f"iceoryx2 could not {what}: {error!r}")
        self.what = what
        self.error = error


class PortsExhausted(IpcError):
    """Every port of a kind that a service of the server allows is taken (by other clients,
    or by another process of the server's user holding them)."""

    def __init__(self, service: str, port: str, error: BaseException) -> None:
        super().__init__(f"take a {port} on {service}", error)
        self.args = (
            f"the server's service {service} has no free {port} ([server] max_clients is "
            "reached): end another client or raise max_clients",
        )
        self.service = service
        self.port = port


class NoBridge(ConnectError):
    """No ``motion-bridge`` answers at the endpoint a remote client was given (nothing
    listens there, the bridge serves another instance, or zenoh's access control keeps this
    user out)."""

    def __init__(self, name: str, endpoint: str, why: str) -> None:
        super().__init__(f'no motion-bridge for server "{name}" at {endpoint}: {why}')
        self.name = name
        self.endpoint = endpoint
        self.why = why


class BridgeRefused(MotiondError):
    """The bridge refused a command itself; the server never saw it. ``code`` is one of
    ``not-allowed`` (not on this identity's allow-list), ``rate-limited``, ``late`` (held up
    in the network for longer than the bridge accepts), ``bad-request``, ``busy``,
    ``no-session`` (the bridge opened no session for this client)."""

    def __init__(self, kind: Union[CommandKind, int], code: str, message: str) -> None:
        super().__init__(f"{_kind_text(kind)} refused by the bridge ({code}): {message}")
        self.kind = kind
        self.code = code
        self.message = message


class RemoteError(MotiondError):
    """zenoh failed to open, send, receive or decode for a remote client."""

    def __init__(self, what: str, error: BaseException) -> None:
        super().__init__(f"zenoh could not {what}: {error}")
        self.what = what
        self.error = error
