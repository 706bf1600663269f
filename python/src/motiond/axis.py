"""One axis of the server: :class:`Axis` (typed commands and waits) and :class:`AxisStatus`."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Optional, Union

from .errors import WaitAborted
from .frames import Frame
from .ipc import (
    AxisFlags,
    AxisInfo,
    AxisMode,
    AxisState,
    CommandKind,
    DeviceState,
    FaultCode,
    FrameFlags,
    to_enum,
)

from .jog import Jog
from .session import EntryHandle

if TYPE_CHECKING:  # pragma: no cover
    from .session import Accepted

__all__ = ["Axis", "AxisStatus"]


@dataclass(frozen=True)
class AxisStatus:
    """One axis's state in one frame (a copy; see :class:`~motiond.ipc.AxisState`)."""

    #: Axis index, config order.
    index: int
    #: The frame's tick.
    tick: int
    #: Measured position, units.
    position: float
    #: Measured velocity, units/s.
    velocity: float
    #: Position target (position modes) or velocity target (velocity modes).
    target: float
    #: The board's own position counts.
    raw_counts: int
    #: Tick at which fresh data last arrived from the board.
    last_refresh_tick: int
    #: State flags.
    flags: AxisFlags
    #: Latched fault (``FaultCode.NONE`` when none); an ``int`` if unknown to this package.
    fault: Union[FaultCode, int]
    #: What the axis is doing.
    mode: Union[AxisMode, int]
    #: State of the axis's board.
    device_state: Union[DeviceState, int]
    #: Node id of the client holding a claim, 0 when unclaimed.
    claimed_by: int
    #: The measured figure of the latched fault, 0 when none.
    fault_value: float
    #: The tolerance or limit the fault broke, 0 when none.
    fault_limit: float
    #: Where the server wants the axis now: the group's path while it follows a group
    #: (mode ``GROUP``), the target while it holds or moves to a position, the measured
    #: position otherwise.
    desired_position: float = 0.0
    #: The velocity the server wants now (the group path's, a velocity mode's target, 0).
    desired_velocity: float = 0.0

    @classmethod
    def of(cls, index: int, tick: int, state: AxisState) -> "AxisStatus":
        """A snapshot of ``state`` (axis ``index`` in the frame of ``tick``)."""
        return cls(
            index=index,
            tick=tick,
            position=float(state.position),
            velocity=float(state.velocity),
            target=float(state.target),
            raw_counts=int(state.raw_counts),
            last_refresh_tick=int(state.last_refresh_tick),
            flags=AxisFlags(state.flags),
            fault=to_enum(FaultCode, state.fault),
            mode=to_enum(AxisMode, state.mode),
            device_state=to_enum(DeviceState, state.device_state),
            claimed_by=int(state.claimed_by),
            fault_value=float(state.fault_value),
            fault_limit=float(state.fault_limit),
            desired_position=float(state.desired_position),
            desired_velocity=float(state.desired_velocity),
        )

    @property
    def moving(self) -> bool:
        """Commanded or measured velocity is not zero."""
        return AxisFlags.MOVING in self.flags

    @property
    def arrived(self) -> bool:
        """The last position goal has been reached within tolerance."""
        return AxisFlags.ARRIVED in self.flags

    @property
    def held(self) -> bool:
        """A position move is held (:meth:`Axis.hold`): :meth:`Axis.resume` continues it."""
        return AxisFlags.HELD in self.flags

    @property
    def homed(self) -> bool:
        """The axis has a valid reference."""
        return AxisFlags.HOMED in self.flags

    @property
    def faulted(self) -> bool:
        """The axis is faulted (see :attr:`fault`)."""
        return AxisFlags.FAULT in self.flags

    @property
    def estopped(self) -> bool:
        """Stopped by the latched e-stop."""
        return AxisFlags.ESTOPPED in self.flags

    @property
    def claimed(self) -> bool:
        """A client holds a claim on the axis."""
        return AxisFlags.CLAIMED in self.flags

    @property
    def stale(self) -> bool:
        """The data is older than the board's refresh budget."""
        return AxisFlags.STALE in self.flags

    @property
    def deadman_expired(self) -> bool:
        """The last velocity or power goal was not renewed in time and was stopped."""
        return AxisFlags.DEADMAN_EXPIRED in self.flags


class Axis(EntryHandle):
    """One axis of the server, found by name with :meth:`Client.axis`.

    Velocities and accelerations of ``0.0`` mean "the axis's configured maximum". Every
    command returns :class:`~motiond.client.Accepted` or raises the
    :class:`~motiond.errors.Refused` subclass of the server's reason.
    """

    __slots__ = ()
    _table = "axes"

    # --- description (index and name: EntryHandle) ------------------------------------------

    @property
    def info(self) -> AxisInfo:
        """The axis's static description (a copy): unit, limits, capabilities, device."""
        return self._entry().copy()

    @property
    def unit(self) -> str:
        """The unit of positions ("mm", "deg")."""
        return self._entry().text("unit")

    @property
    def device(self) -> str:
        """The name of the device that drives it."""
        return self._entry().text("device")

    def supports(self, kind: CommandKind) -> bool:
        """Whether the axis's board accepts ``kind``."""
        return bool(self._entry().supports(kind))

    # --- state -----------------------------------------------------------------------------

    def state(self, frame: Optional[Frame] = None) -> AxisStatus:
        """The axis's state in ``frame`` (default: the newest frame), a copy."""
        if frame is None:
            frame = self._client.latest()
        return AxisStatus.of(self._index, frame.tick, frame.axis(self._index))

    # --- commands --------------------------------------------------------------------------

    def _command(self, kind: CommandKind, *values: float) -> "Accepted":
        return self._client.command(self._index, kind, values)

    def position(self, position: float) -> "Accepted":
        """Position target handed to the board's own controller (``Position``), without
        the server's ramp; ``motionctl move`` (a limited ramp) is :meth:`ramp_to`."""
        return self._command(CommandKind.POSITION, position)

    def move_to(self, position: float) -> "Accepted":
        """Deprecated: the old name of :meth:`position`."""
        warnings.warn(
            "Axis.move_to is renamed Axis.position (a board-controlled target); "
            "`motionctl move` is Axis.ramp_to",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.position(position)

    def ramp_to(self, position: float, velocity: float = 0.0, accel: float = 0.0) -> "Accepted":
        """Position along a velocity- and acceleration-limited profile (``RampPosition``)."""
        return self._command(CommandKind.RAMP_POSITION, position, velocity, accel)

    def velocity(self, velocity: float) -> "Accepted":
        """Velocity in units/s (``Velocity``). The server's deadman stops it unless
        renewed: prefer :meth:`jog`."""
        return self._command(CommandKind.VELOCITY, velocity)

    def ramp_velocity(self, velocity: float, accel: float = 0.0) -> "Accepted":
        """Velocity reached with ``accel`` (``RampVelocity``; deadman applies)."""
        return self._command(CommandKind.RAMP_VELOCITY, velocity, accel)

    def power(self, power: float) -> "Accepted":
        """Open-loop power, −1.0..1.0 of full scale (``Power``; deadman applies)."""
        return self._command(CommandKind.POWER, power)

    def stop(self) -> "Accepted":
        """Decelerate to a stop and hold."""
        return self._command(CommandKind.STOP)

    def off(self) -> "Accepted":
        """De-energise the motor (it coasts, no holding torque)."""
        return self._command(CommandKind.OFF)

    def home(self, velocity: float = 0.0) -> "Accepted":
        """Reference search at ``velocity`` units/s (0.0: the server's default speed)."""
        return self._command(CommandKind.HOME, velocity)

    def hold(self) -> "Accepted":
        """Brings the axis's position move (:meth:`position`, :meth:`ramp_to`) to rest and
        keeps it (``Hold`` with the axis as target): a QSB-M pauses its own move (COMMAND
        6), any other board stops at the move's acceleration. The status shows
        :attr:`AxisStatus.held` until :meth:`resume`, a stop or another goal. Raises
        :class:`~motiond.errors.NotMoving` when no position move is on its way (a jog is
        stopped, not held)."""
        return self._command(CommandKind.HOLD)

    def resume(self) -> "Accepted":
        """Continues the move :meth:`hold` brought to rest, to its target with its
        velocity and acceleration. Raises :class:`~motiond.errors.NotMoving` when nothing
        is held."""
        return self._command(CommandKind.RESUME)

    def set_position(self, position: float) -> "Accepted":
        """Declares the current position to be ``position`` (no motion)."""
        return self._command(CommandKind.SET_POSITION, position)

    def claim(self) -> "Accepted":
        """Takes an exclusive claim: other clients' commands on this axis are refused."""
        return self._command(CommandKind.CLAIM)

    def release(self) -> "Accepted":
        """Gives a claim back."""
        return self._command(CommandKind.RELEASE)

    def jog(self, velocity: float, accel: float = 0.0) -> "Jog":
        """Starts a jog at ``velocity`` units/s reached with ``accel`` (``RampVelocity``) and
        returns a :class:`~motiond.jog.Jog` that renews it while the program calls into
        the client, and stops the axis when it ends (``with axis.jog(5.0): ...``)."""
        return Jog(self._client, self._index, CommandKind.RAMP_VELOCITY, (velocity, accel, 0.0))

    def jog_power(self, power: float) -> "Jog":
        """Open-loop power under a :class:`~motiond.jog.Jog`, like :meth:`jog`."""
        return Jog(self._client, self._index, CommandKind.POWER, (power, 0.0, 0.0))

    # --- waits -----------------------------------------------------------------------------

    def _blocked(self, state: AxisState, frame: Frame) -> Optional[str]:
        flags = AxisFlags(state.flags)
        if AxisFlags.FAULT in flags:
            fault = to_enum(FaultCode, state.fault)
            text = fault.text if isinstance(fault, FaultCode) else f"fault {fault}"
            return f"it is faulted ({text})"
        if AxisFlags.ESTOPPED in flags or FrameFlags.ESTOP_LATCHED in frame.flags:
            return "the e-stop is latched"
        if FrameFlags.SHUTTING_DOWN in frame.flags:
            return "the server is shutting down"
        return None

    def _wait(
        self,
        what: str,
        timeout: float,
        done: Callable[[AxisState, Frame], Union[bool, str]],
    ) -> Frame:
        """Waits until ``done`` returns ``True``; a text it returns aborts the wait."""
        subject = f"axis {self.name}"

        def check(frame: Frame) -> bool:
            outcome = done(frame.axis(self._index), frame)
            if isinstance(outcome, str):
                raise WaitAborted(subject, what, outcome)
            return bool(outcome)

        return self._client.wait_frames(
            what, timeout, check, subject=subject, since=self._client.goal_tick(self._index)
        )

    def wait_until_arrived(self, timeout: float = 10.0) -> Frame:
        """Waits until the last position goal is reached (the server's ``ARRIVED`` flag,
        from a frame at or after the goal's tick); raises
        :class:`~motiond.errors.WaitAborted` as soon as the axis can no longer get there
        (fault, e-stop, another goal) and :class:`~motiond.errors.WaitTimeout` after
        ``timeout`` s."""

        def done(state: AxisState, frame: Frame) -> Union[bool, str]:
            flags = AxisFlags(state.flags)
            if AxisFlags.ARRIVED in flags and AxisFlags.MOVING not in flags:
                return True
            blocked = self._blocked(state, frame)
            if blocked is not None:
                return blocked
            mode = to_enum(AxisMode, state.mode)
            if mode in (AxisMode.POSITION, AxisMode.RAMP_POSITION):
                return False
            name = mode.name if isinstance(mode, AxisMode) else str(mode)
            return f"its goal was replaced (mode is now {name})"

        return self._wait("arrive", timeout, done)

    def wait_until_homed(self, timeout: float = 30.0) -> Frame:
        """Waits until the reference search started by :meth:`home` has finished with the
        axis homed."""

        def done(state: AxisState, frame: Frame) -> Union[bool, str]:
            homing = state.mode == AxisMode.HOMING
            if AxisFlags.HOMED in AxisFlags(state.flags) and not homing:
                return True
            blocked = self._blocked(state, frame)
            if blocked is not None:
                return blocked
            return False if homing else "the reference search ended without a reference"

        return self._wait("finish homing", timeout, done)

    def wait_until_stopped(self, timeout: float = 5.0) -> Frame:
        """Waits until the axis is at rest (its ``MOVING`` flag clear)."""

        def done(state: AxisState, frame: Frame) -> Union[bool, str]:
            return AxisFlags.MOVING not in AxisFlags(state.flags)

        return self._wait("come to rest", timeout, done)

    def wait_ready(self, timeout: float = 5.0) -> Frame:
        """Waits until the axis's board is online (it takes goals)."""
        return self._client.wait_ready(timeout, axes=[self.name])
