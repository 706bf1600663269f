"""Axes that move together: :class:`Group` (lines, trajectories, hold/resume/feed/cancel,
claims, setpoint streams) and :class:`PathStarted`.

A group is a ``[[group]]`` of the server's config. :meth:`Group.move_to` and
:meth:`Group.follow` publish a :class:`~motiond.ipc.GroupPath` on the server's ``paths``
service from this client's own iceoryx2 node (written in place into the loaned sample:
≈400 KB, never copied element by element) and then send ``Run`` naming its id; the server
plans it, refuses it naming the point, the axis and the figures, or starts it::

    gantry = client.group("gantry")
    gantry.move_to([100.0, 250.0, 20.0], velocity_scale=0.5)
    gantry.wait_done(timeout=30)          # raises GroupAborted naming reason, axis, figures
"""

from __future__ import annotations

import ctypes
from array import array
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from .errors import BadPath, MotiondError, NotClaimed, WaitAborted
from .frames import Frame
from .groupstate import GroupStatus, aborted_error
from .ipc import (
    AxisFlags,
    MAX_GROUP_AXES,
    MAX_PATH_POINTS,
    SCHEMA_VERSION,
    CommandKind,
    GroupInfo,
    GroupMotion,
    GroupPath,
    GroupState,
    PathFlags,
    PathKind,
    StreamMode,
    Target,
    to_enum,
)
from .session import Accepted, EntryHandle, Session
from .stream import SetpointStream

__all__ = ["Group", "GroupClaim", "PathStarted"]

_DOUBLE = ctypes.sizeof(ctypes.c_double)
_TIMES = GroupPath.times.offset
_POSITIONS = GroupPath.positions.offset
_VELOCITIES = GroupPath.velocities.offset
_ACCELERATIONS = GroupPath.accelerations.offset

Rows = Any  # a sequence of rows (sequences of numbers), or a 2-D NumPy array


@dataclass(frozen=True)
class PathStarted(Accepted):
    """A path the server accepted and started (``Run``)."""

    #: The id this client gave the path (``GroupStatus.path_id`` while it runs).
    path_id: int


def _numpy() -> Any:
    try:
        import numpy
    except ImportError:  # pragma: no cover - depends on the environment
        return None
    return numpy


def pack_rows(rows: Rows, points: int, axes: int, what: str) -> Any:
    """``rows`` (``points`` rows of ``axes`` numbers) laid out as the path wants them,
    ``points × MAX_GROUP_AXES`` doubles, the unused columns zero: a buffer for
    ``ctypes.memmove`` (an ``array('d')`` or a C-contiguous NumPy array)."""
    numpy = _numpy()
    if numpy is not None and isinstance(rows, numpy.ndarray):
        if rows.ndim != 2 or rows.shape != (points, axes):
            raise BadPath(
                f"{what} has shape {rows.shape}; the path needs {points} rows of {axes} "
                "values (one row per point, one value per axis of the group)"
            )
        packed = numpy.zeros((points, MAX_GROUP_AXES), dtype=numpy.float64)
        try:
            packed[:, :axes] = rows
        except (TypeError, ValueError) as error:
            raise BadPath(f"{what} are not numbers: {error}") from None
        return packed
    if isinstance(rows, (str, bytes)):
        raise BadPath(f"{what} must be a sequence of rows of numbers, not {rows!r}")
    try:
        listed = list(rows)
    except TypeError:
        raise BadPath(f"{what} must be a sequence of rows, not {type(rows).__name__}") from None
    if len(listed) != points:
        raise BadPath(f"{what} has {len(listed)} rows; the path has {points} points")
    packed = array("d", bytes(_DOUBLE * points * MAX_GROUP_AXES))
    for point, row in enumerate(listed):
        try:
            if isinstance(row, (str, bytes)):
                raise TypeError(row)
            values = array("d", row)
        except TypeError:
            raise BadPath(
                f"{what}[{point}] must be a sequence of {axes} numbers, not {row!r}"
            ) from None
        if len(values) != axes:
            raise BadPath(
                f"{what}[{point}] has {len(values)} values; the group has {axes} axes"
            )
        start = point * MAX_GROUP_AXES
        packed[start : start + axes] = values
    return packed


def _address(buffer: Any) -> int:
    """The address of a buffer made by :func:`pack_rows` (or an ``array('d')``)."""
    if isinstance(buffer, array):
        return int(buffer.buffer_info()[0])
    return int(buffer.ctypes.data)


class GroupClaim:
    """An exclusive claim on every axis of a group, released when the ``with`` block ends
    (or by :meth:`release`). Made by :meth:`Group.claim`, which takes it at once (all the
    axes or none: :class:`~motiond.errors.ClaimedByOther` names the axis held and its
    holder)."""

    def __init__(self, group: "Group") -> None:
        self._group = group
        #: The server's answer to the claim.
        self.accepted = group._command(CommandKind.CLAIM)
        self.active = True

    def release(self) -> None:
        """Gives the claim back (a claim the server no longer has is not an error)."""
        if not self.active:
            return
        self.active = False
        try:
            self._group.release()
        except NotClaimed:
            pass

    def __enter__(self) -> "GroupClaim":
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    def __repr__(self) -> str:
        state = "held" if self.active else "released"
        return f"GroupClaim({self._group.name!r}, {state})"


class Group(EntryHandle):
    """One group of the server (``[[group]]``), found by name with :meth:`Client.group`.

    Positions, tolerances and values are per axis in the group's order (:attr:`axes`).
    Every command returns :class:`~motiond.Accepted` (a path: :class:`PathStarted`) or
    raises the :class:`~motiond.errors.Refused` subclass of the server's reason, naming
    the point, the axis and the figures where the server named them.
    """

    __slots__ = ("_run",)
    _table = "groups"

    def __init__(self, client: Session, index: int) -> None:
        super().__init__(client, index)
        #: (path id, tick of its Run) of the last path this handle started.
        self._run: Optional[Tuple[int, int]] = None

    # --- description -----------------------------------------------------------------------

    @property
    def info(self) -> GroupInfo:
        """The group's description as configured (a copy)."""
        return self._entry().copy()

    @property
    def axis_indices(self) -> List[int]:
        """Config indices of the member axes, in the group's order."""
        entry = self._entry()
        return [int(entry.axes[i]) for i in range(self._count(entry))]

    @property
    def axes(self) -> List[str]:
        """Names of the member axes, in the group's order."""
        info = self._client.info
        return [info.axes[i].text("name") for i in self.axis_indices]

    @staticmethod
    def _count(entry: GroupInfo) -> int:
        return min(int(entry.axis_count), MAX_GROUP_AXES)

    def _per_axis(self, field: str) -> Dict[str, float]:
        entry = self._entry()
        values = getattr(entry, field)
        return {name: float(values[i]) for i, name in enumerate(self.axes)}

    @property
    def path_tolerance(self) -> Dict[str, float]:
        """Per axis: how far from the path the axis may be while it runs (0: not
        checked), the axis's unit."""
        return self._per_axis("path_tolerance")

    @property
    def goal_tolerance(self) -> Dict[str, float]:
        """Per axis: how close to the path's end the axis must come, the axis's unit."""
        return self._per_axis("goal_tolerance")

    @property
    def goal_time_tolerance(self) -> float:
        """Seconds after the path's end every axis has to be within its goal tolerance."""
        return float(self._entry().goal_time_tolerance)

    @property
    def stream_limit(self) -> str:
        """What a streamed setpoint beyond a limit does: ``"clamp"`` or ``"abort"``."""
        return "abort" if int(self._entry().stream_limit) == 1 else "clamp"

    @property
    def stream_timeout(self) -> int:
        """Ticks without a streamed setpoint before the server stops the group."""
        return int(self._entry().stream_timeout)

    @property
    def stream_buffer(self) -> int:
        """Ticks ahead a streamed setpoint may be sent."""
        return int(self._entry().stream_buffer)

    # --- state -----------------------------------------------------------------------------

    def _state_in(self, frame: Frame) -> GroupState:
        return frame.group(self._index)

    def state(self, frame: Optional[Frame] = None) -> GroupStatus:
        """The group's state in ``frame`` (default: the newest frame), a copy."""
        if frame is None:
            frame = self._client.latest()
        return GroupStatus.of(self._client.info, self._index, frame.tick, self._state_in(frame))

    # --- commands --------------------------------------------------------------------------

    def _command(self, kind: CommandKind, *values: float) -> Accepted:
        return self._client.command(
            self._index, kind, values, Target.GROUP, label=f"group {self.name}"
        )

    def claim(self) -> GroupClaim:
        """Claims every axis of the group (all or none) for this client; other clients'
        commands on them are refused until the claim is released. Use it as a context
        manager: ``with group.claim(): ...`` releases it at the end."""
        return GroupClaim(self)

    def release(self) -> Accepted:
        """Gives back this client's claims on the group's axes."""
        return self._command(CommandKind.RELEASE)

    def stop(self) -> Accepted:
        """Stops the group: its motion (or stream) aborts (``stopped``), every axis
        decelerates and holds."""
        return self._command(CommandKind.STOP)

    def hold(self) -> Accepted:
        """Feed hold: the group slows to rest along its path (``holding``, then ``held``);
        :meth:`resume` continues. Refused with :class:`~motiond.errors.NotMoving` when no
        motion runs."""
        return self._command(CommandKind.HOLD)

    def resume(self) -> Accepted:
        """Continues a held (or holding) path at the set feed."""
        return self._command(CommandKind.RESUME)

    def set_feed(self, fraction: float) -> Accepted:
        """The feed override, 0.0..1.5 of the path's speed, for the running path and the
        next ones."""
        if not 0.0 <= fraction <= 1.5:
            raise BadPath(f"feed {fraction} outside 0.0..1.5")
        return self._command(CommandKind.FEED, fraction)

    def cancel(self) -> Accepted:
        """Ends the motion: the group comes to rest along its path, then the motion ends
        (``aborted``, reason ``cancelled``). A stream ends at once (motion ``done``,
        stream ``idle``)."""
        return self._command(CommandKind.CANCEL)

    def _positions(self, positions: Union[Sequence[float], Mapping[str, float]]) -> List[float]:
        names = self.axes
        if isinstance(positions, Mapping):
            unknown = sorted(set(positions) - set(names))
            missing = [name for name in names if name not in positions]
            if unknown or missing:
                raise BadPath(
                    f"group {self.name} has axes {names}: "
                    + "; ".join(
                        part
                        for part in (
                            f"not in it: {unknown}" if unknown else "",
                            f"missing: {missing}" if missing else "",
                        )
                        if part
                    )
                )
            return [float(positions[name]) for name in names]
        values = list(positions)
        if len(values) != len(names):
            raise BadPath(
                f"group {self.name} has {len(names)} axes {names}; {len(values)} positions given"
            )
        try:
            return [float(value) for value in values]
        except (TypeError, ValueError):
            raise BadPath(f"positions must be numbers: {values!r}") from None

    def move_to(
        self,
        positions: Union[Sequence[float], Mapping[str, float]],
        velocity_scale: Optional[float] = None,
        accel_scale: Optional[float] = None,
    ) -> PathStarted:
        """A synchronized straight line (in joint space) to ``positions`` (one per axis in
        the group's order, or a mapping by axis name), every axis starting and ending
        together, at ``velocity_scale`` / ``accel_scale`` (0, 1] of each axis's maximum
        (default 1). A path running already is replaced from where it has the group."""
        goal = self._positions(positions)
        scales = []
        for what, scale in (("velocity_scale", velocity_scale), ("accel_scale", accel_scale)):
            if scale is not None and not 0.0 < scale <= 1.0:
                raise BadPath(f"{what} {scale} outside (0, 1]")
            scales.append(0.0 if scale is None else float(scale))
        return self._run_path(
            PathKind.LINE, 1, array("d", [0.0]), array("d", goal), None, None, scales
        )

    def follow(
        self,
        times: Sequence[float],
        positions: Rows,
        velocities: Optional[Rows] = None,
        accelerations: Optional[Rows] = None,
    ) -> PathStarted:
        """A time-parameterised trajectory: point ``i`` at ``times[i]`` seconds from its
        start (increasing; a first point at 0 must be where the group is), ``positions[i]``
        one value per axis in the group's order; optional ``velocities`` (and with them
        ``accelerations``) per point and axis. Up to ``MAX_PATH_POINTS`` (1024) points;
        rows may be lists or a 2-D NumPy array. The server checks every point against the
        axes' limits and refuses the first that breaks one, naming it."""
        try:
            stamps = array("d", times)
        except TypeError:
            raise BadPath("times must be a sequence of numbers (seconds)") from None
        points = len(stamps)
        if not 1 <= points <= MAX_PATH_POINTS:
            raise BadPath(f"a path has 1..{MAX_PATH_POINTS} points; {points} times given")
        if accelerations is not None and velocities is None:
            raise BadPath("accelerations need velocities (give both, or velocities alone)")
        count = len(self.axis_indices)
        packed = pack_rows(positions, points, count, "positions")
        packed_v = (
            None if velocities is None else pack_rows(velocities, points, count, "velocities")
        )
        packed_a = (
            None
            if accelerations is None
            else pack_rows(accelerations, points, count, "accelerations")
        )
        return self._run_path(
            PathKind.TRAJECTORY, points, stamps, packed, packed_v, packed_a, [0.0, 0.0]
        )

    def _run_path(
        self,
        kind: PathKind,
        points: int,
        times: Any,
        positions: Any,
        velocities: Any,
        accelerations: Any,
        scales: Sequence[float],
    ) -> PathStarted:
        publisher = self._client._paths_port()
        path_id = self._client._next_path_id()
        count = len(self.axis_indices)
        try:
            sample = publisher.loan_uninit()
        except Exception as error:
            raise MotiondError(f"could not loan a path sample: {error!r}") from error
        base = int(sample.payload_ptr)
        path = GroupPath.from_address(base)
        path.schema_version = SCHEMA_VERSION
        path.kind = int(kind)
        path.id = path_id
        path.group = self._index
        path.point_count = points
        path.axis_count = count
        flags = 0
        if velocities is not None:
            flags |= PathFlags.VELOCITIES
        if accelerations is not None:
            flags |= PathFlags.ACCELERATIONS
        path.flags = int(flags)
        path.velocity_scale = scales[0]
        path.accel_scale = scales[1]
        del path
        ctypes.memmove(base + _TIMES, _address(times), _DOUBLE * points)
        if kind == PathKind.LINE:
            # One point, the group's axes only: the rest of the row is never read.
            ctypes.memmove(base + _POSITIONS, _address(positions), _DOUBLE * count)
        else:
            size = _DOUBLE * points * MAX_GROUP_AXES
            ctypes.memmove(base + _POSITIONS, _address(positions), size)
            if velocities is not None:
                ctypes.memmove(base + _VELOCITIES, _address(velocities), size)
            if accelerations is not None:
                ctypes.memmove(base + _ACCELERATIONS, _address(accelerations), size)
        try:
            sample.assume_init().send()
        except Exception as error:
            raise MotiondError(f"could not publish the path: {error!r}") from error
        accepted = self._command(CommandKind.RUN, float(path_id))
        self._run = (path_id, accepted.tick)
        return PathStarted(sequence=accepted.sequence, tick=accepted.tick, path_id=path_id)

    # --- waits -----------------------------------------------------------------------------

    def _wait_group(
        self,
        what: str,
        timeout: float,
        reached: "Any",
    ) -> Frame:
        """Waits until ``reached(state)`` for a frame at or after this handle's last Run;
        raises :class:`~motiond.errors.GroupAborted` when the motion aborts and
        :class:`~motiond.errors.WaitAborted` when this handle's path was replaced or the
        group stopped running it."""
        client = self._client
        subject = f"group {self.name}"
        run = self._run
        own = int(client.id)

        def check(frame: Frame) -> bool:
            state = self._state_in(frame)
            if run is not None and (int(state.path_id) != run[0] or int(state.owner) != own):
                if int(state.owner) != own:
                    raise WaitAborted(subject, what, "another client's motion replaced its path")
                raise WaitAborted(subject, what, f"its path was replaced by path {state.path_id}")
            motion = to_enum(GroupMotion, state.motion)
            if reached(motion):
                return True
            if motion == GroupMotion.ABORTED:
                raise aborted_error(client.info, self.name, what, state, frame.tick)
            if motion == GroupMotion.IDLE:
                raise WaitAborted(subject, what, "no motion runs")
            if motion == GroupMotion.DONE:
                raise WaitAborted(subject, what, "its path is done")
            return False

        since = 0 if run is None else run[1]
        return client.wait_frames(what, timeout, check, subject=subject, since=since)

    def wait_done(self, timeout: float = 30.0) -> Frame:
        """Waits until the path this handle started last (or the group's current motion)
        is done: its end reached with every axis within its goal tolerance. Returns that
        frame. Raises :class:`~motiond.errors.GroupAborted` (the reason, the axis's name,
        the figures) when it aborts, :class:`~motiond.errors.WaitAborted` when another path
        replaced it, :class:`~motiond.errors.WaitTimeout` after ``timeout`` s (a held path
        is not done)."""
        return self._wait_group(
            "finish its path", timeout, lambda motion: motion == GroupMotion.DONE
        )

    def wait_held(self, timeout: float = 10.0) -> Frame:
        """Waits until a hold brought the group to rest on its path (``held``)."""
        return self._wait_group(
            "come to rest on its path", timeout, lambda motion: motion == GroupMotion.HELD
        )

    def wait_stopped(self, timeout: float = 10.0) -> Frame:
        """Waits until every axis of the group is at rest (no ``MOVING`` flag): after a
        stop, a cancel or an abort the axes brake first, and a new motion or stream of
        the group is refused (:class:`~motiond.errors.GroupBusy`) until then."""
        indices = self.axis_indices

        def still(frame: Frame) -> bool:
            return not any(frame.axis(i).flags & AxisFlags.MOVING for i in indices)

        return self._client.wait_frames(
            "come to rest", timeout, still, subject=f"the axes of group {self.name}"
        )

    def wait_aborted(self, timeout: float = 10.0) -> Frame:
        """Waits until the motion ended early (a cancel, a stop); returns that frame
        (``state(frame).abort`` says why) instead of raising."""
        return self._wait_group(
            "abort", timeout, lambda motion: motion == GroupMotion.ABORTED
        )

    # --- streaming -------------------------------------------------------------------------

    def stream(
        self, mode: Union[str, StreamMode] = "position", *, lead: Optional[int] = None
    ) -> SetpointStream:
        """Claims the group, starts a setpoint stream of ``mode`` (``"position"``,
        ``"velocity"`` or ``"power"``) and returns it; leaving its ``with`` block ends the
        stream (cancel) and releases the claim. ``lead``: ticks ahead of the frame read that
        :meth:`~motiond.stream.SetpointStream.run_each_tick` sends for (default
        :data:`~motiond.stream.DEFAULT_LEAD`). See :class:`~motiond.stream.SetpointStream`."""
        return SetpointStream(
            self._client, self._index, self.name, len(self.axis_indices), mode, lead=lead
        )

    def __repr__(self) -> str:
        return f"Group({self.name!r}, index={self._index}, axes={self.axes})"

